"""``plcbuilder dap`` driven as an editor drives it: the adapter is a child
process, the test sends DAP requests over its stdin and reads responses and
events from its stdout; the adapter builds the project, starts its own
controller and debugs a real procedure on it."""

from pathlib import Path

import pytest

from tests.lsp._client import Client, frame, spawn

M03 = """main()
{
  count = 0;
  do {
    count = count + 1;
    helper();
  } while (count < 5);
  gvarset(20001, total);
  exit(99);
}
helper()
{
  total = total + count;
}
"""


class DapClient(Client):
    def request(self, command: str, arguments=None, timeout: float = 60.0) -> dict:
        seq = self.next_id()
        self.send({"seq": seq, "type": "request", "command": command,
                   "arguments": arguments or {}})
        return self.wait(lambda m: m.get("type") == "response" and m.get("request_seq") == seq,
                         timeout)

    def ok(self, command: str, arguments=None) -> dict:
        r = self.request(command, arguments)
        assert r["success"], r
        return r.get("body") or {}

    def event(self, name: str, timeout: float = 60.0, pred=lambda b: True) -> dict:
        m = self.wait(lambda m: m.get("type") == "event" and m.get("event") == name
                      and pred(m.get("body") or {}), timeout)
        return m.get("body") or {}


@pytest.fixture
def project(tmp_path):
    root = tmp_path / "proj"
    (root / "hardware").mkdir(parents=True)
    (root / "software").mkdir()
    (root / "include").mkdir()
    (root / "plcbuilder.toml").write_text('name = "dap"\n')
    (root / "hardware" / "M03.plc").write_text(M03)
    return root


@pytest.fixture
def dap(project):
    c = DapClient(spawn("dap", cwd=project))
    yield c
    c.close()


def _launch(dap, project, **extra):
    caps = dap.ok("initialize", {"clientID": "test", "adapterID": "plcbuilder",
                                 "linesStartAt1": True, "columnsStartAt1": True,
                                 "pathFormat": "path"})
    assert caps["supportsConditionalBreakpoints"] and caps["supportsLogPoints"]
    assert caps["supportsHitConditionalBreakpoints"] and caps["supportsSetVariable"]
    dap.ok("launch", {"project": str(project), "program": str(project / "hardware" / "M03.plc"),
                      "eparam": 7, **extra})
    dap.event("initialized")
    return str(project / "hardware" / "M03.plc")


def _frames(dap, tid):
    return dap.ok("stackTrace", {"threadId": tid})["stackFrames"]


def _vars(dap, frame_id, scope="Variables"):
    scopes = dap.ok("scopes", {"frameId": frame_id})["scopes"]
    ref = next(s["variablesReference"] for s in scopes if s["name"] == scope)
    return ref, {v["name"]: v["value"] for v in dap.ok("variables", {"variablesReference": ref})["variables"]}


def test_a_debugging_session_as_an_editor_runs_it(dap, project):
    path = _launch(dap, project)
    bps = dap.ok("setBreakpoints", {"source": {"path": path},
                                    "breakpoints": [{"line": 5, "condition": "count == 2"}]})
    assert bps["breakpoints"][0]["verified"] and bps["breakpoints"][0]["line"] == 5
    dap.ok("configurationDone")
    stopped = dap.event("stopped")
    assert stopped["reason"] == "breakpoint" and stopped["allThreadsStopped"]
    assert stopped["hitBreakpointIds"] == [bps["breakpoints"][0]["id"]]
    tid = stopped["threadId"]
    threads = dap.ok("threads")["threads"]
    assert {"id": tid, "name": "M03"} in threads
    frames = _frames(dap, tid)
    assert frames[0]["line"] == 5 and Path(frames[0]["source"]["path"]) == Path(path).resolve()
    ref, values = _vars(dap, frames[0]["id"])
    assert values["count"] == "2"                 # the third time line 5 is reached
    assert values["eparam"] == "7"
    assert dap.ok("evaluate", {"expression": "count * 10 + eparam", "frameId": frames[0]["id"],
                               "context": "watch"})["result"] == "27"
    _ref, outs = _vars(dap, frames[0]["id"], "Outputs")
    assert outs["out 0"] == "0"
    # write a variable: the program goes on from the new value
    assert dap.ok("setVariable", {"variablesReference": ref, "name": "count",
                                  "value": "3"})["value"] == "3"
    dap.ok("next", {"threadId": tid})
    stopped = dap.event("stopped", pred=lambda b: b["reason"] == "step")
    frames = _frames(dap, stopped["threadId"])
    assert frames[0]["line"] == 6
    assert _vars(dap, frames[0]["id"])[1]["count"] == "4"
    dap.ok("stepIn", {"threadId": tid})
    dap.event("stopped", pred=lambda b: b["reason"] == "step")
    frames = _frames(dap, tid)
    assert [f["line"] for f in frames] == [13, 6] and frames[0]["name"] == "helper()"
    dap.ok("stepOut", {"threadId": tid})
    dap.event("stopped", pred=lambda b: b["reason"] == "step")
    assert _frames(dap, tid)[0]["name"] == "main()"
    dap.ok("continue", {"threadId": tid})
    dap.event("continued")
    out = dap.event("output", pred=lambda b: "print 20001" in b.get("output", ""))
    assert out["output"].startswith("M03: print 20001 = ")
    assert dap.event("exited")["exitCode"] == 99
    dap.event("terminated")
    dap.ok("disconnect", {"terminateDebuggee": True})
    dap.proc.wait(20)
    assert dap.proc.returncode == 0


def test_hit_counts_logpoints_and_bad_breakpoints(dap, project):
    path = _launch(dap, project)
    bps = dap.ok("setBreakpoints", {"source": {"path": path}, "breakpoints": [
        {"line": 13, "logMessage": "total is {total}, count {count}"},
        {"line": 5, "hitCondition": ">=4"},
        {"line": 6, "condition": "count =="},
        {"line": 40}]})["breakpoints"]
    assert [b["verified"] for b in bps] == [True, True, False, False]
    assert "condition" in bps[2]["message"]
    assert "no code on line 40" in bps[3]["message"]
    dap.ok("configurationDone")
    logs = [dap.event("output", pred=lambda b: "total is" in b.get("output", ""))["output"]
            for _ in range(3)]
    assert logs == ["M03: total is 0, count 1\n", "M03: total is 1, count 2\n",
                    "M03: total is 3, count 3\n"]
    stopped = dap.event("stopped")
    frames = _frames(dap, stopped["threadId"])
    assert frames[0]["line"] == 5 and _vars(dap, frames[0]["id"])[1]["count"] == "3"
    err = dap.request("setVariable", {"variablesReference": _vars(dap, frames[0]["id"], "Axes")[0],
                                      "name": "X", "value": "1"})
    assert not err["success"] and "cannot be written" in err["message"]
    err = dap.request("evaluate", {"expression": "count +", "frameId": frames[0]["id"]})
    assert not err["success"]
    dap.ok("pause", {"threadId": stopped["threadId"]})
    dap.ok("disconnect", {})
    dap.proc.wait(20)


def test_bad_frames_and_unknown_requests(dap, project):
    dap.send_raw(frame(b"{nope"))
    assert "not JSON" in dap.event("output")["output"]
    huge = 17 << 20                     # over the 16 MiB limit: skipped unread
    dap.send_raw(b"Content-Length: %d\r\n\r\n" % huge + b" " * huge)
    assert "over the limit" in dap.event("output")["output"]
    dap.send_raw(b"Content-Length: 12\r\n\r\n[1, 2, 3, 4]")
    assert "not list" in dap.event("output")["output"]
    dap.send({"seq": 5, "type": "request"})
    r = dap.wait(lambda m: m.get("type") == "response" and m.get("request_seq") == 5)
    assert not r["success"] and '"command"' in r["message"]
    dap.send({"seq": 6, "type": "request", "command": "fly", "arguments": {}})
    r = dap.wait(lambda m: m.get("type") == "response" and m.get("request_seq") == 6)
    assert not r["success"] and "unknown request 'fly'" in r["message"]
    r = dap.request("stackTrace", {"threadId": 1})
    assert not r["success"] and "launch or attach first" in r["message"]
    r = dap.request("launch", {"project": str(project / "nowhere")})
    assert not r["success"] and "cannot open the project" in r["message"]
    assert dap.ok("initialize", {"adapterID": "plcbuilder"})["supportsConfigurationDoneRequest"]
    dap.ok("disconnect")
    dap.proc.wait(20)
    assert dap.proc.returncode == 0


def test_a_build_error_is_reported_and_nothing_starts(dap, project):
    (project / "hardware" / "M04.plc").write_text("main() { x = gvarset(1); }\n")
    dap.ok("initialize", {"adapterID": "plcbuilder"})
    r = dap.request("launch", {"project": str(project), "procedure": "M03"})
    assert not r["success"] and "the build failed: 1 errors" in r["message"]
    out = dap.event("output", pred=lambda b: "M04.plc" in b.get("output", "")
                    and "error:" in b["output"])
    assert out["category"] == "stderr" and "gvarset" in out["output"]
    dap.ok("disconnect")


def test_attach_to_a_running_controller(project, tmp_path):
    """attach joins a controller that runs already (its address and token):
    breakpoints and pause reach the procedure it runs; disconnect leaves it running."""
    from plcbuilder.link.process import ControllerProcess
    from plcbuilder.project import Project, build_project

    (project / "software").joinpath("LUBE.plc").write_text(
        "main()\n{\n  do {\n    n = n + 1;\n  } while (1);\n}\n")
    build = build_project(Project.open(project))
    assert build.ok
    ctl = ControllerProcess.start(image=build.image_path)
    try:
        ep = ctl.wait_endpoint()
        dap = DapClient(spawn("dap", cwd=project))
        try:
            dap.ok("initialize", {"adapterID": "plcbuilder"})
            dap.ok("attach", {"controller": f"{ep.host}:{ep.port}", "token": ep.token,
                              "project": str(project)})
            dap.event("initialized")
            threads = dap.ok("threads")["threads"]
            assert [t["name"] for t in threads] == ["LUBE"]
            lube = str(project / "software" / "LUBE.plc")
            bp = dap.ok("setBreakpoints", {"source": {"path": lube},
                                           "breakpoints": [{"line": 4, "condition": "n > 20"}]})
            assert bp["breakpoints"][0]["verified"]
            dap.ok("configurationDone")
            stopped = dap.event("stopped")
            frames = _frames(dap, stopped["threadId"])
            assert frames[0]["line"] == 4 and frames[0]["source"]["name"] == "LUBE.plc"
            assert int(_vars(dap, frames[0]["id"])[1]["n"]) > 20      # the condition held
            dap.ok("setBreakpoints", {"source": {"path": lube}, "breakpoints": []})
            dap.ok("continue", {"threadId": stopped["threadId"]})
            dap.event("continued")
            dap.ok("pause", {"threadId": stopped["threadId"]})
            assert dap.event("stopped")["reason"] == "pause"
            dap.ok("disconnect", {})
            dap.proc.wait(20)
        finally:
            dap.close()
        c = ctl.connect()
        try:
            assert c.debug_state() is None            # left running
            assert c.state().software == ("LUBE",)
        finally:
            c.close()
    finally:
        ctl.stop()
