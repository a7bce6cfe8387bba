"""``plcbuilder dap`` driven as an editor drives it: the adapter is a child
process, the test sends DAP requests over its stdin and reads responses and
events from its stdout; the adapter builds the project, starts its own
controller and debugs a real procedure on it."""

import time
from pathlib import Path

import pytest

from tests.dap._dap import DapClient, frames as _frames, initialize, make_project, start, \
    values as _vars
from tests.lsp._client import frame, spawn


@pytest.fixture
def project(tmp_path):
    return make_project(tmp_path / "proj")


@pytest.fixture
def dap(project):
    c = start(project)
    yield c
    c.close()


def _launch(dap, project, **extra):
    caps = initialize(dap)
    assert caps["supportsConditionalBreakpoints"] and caps["supportsLogPoints"]
    assert caps["supportsHitConditionalBreakpoints"] and caps["supportsSetVariable"]
    assert caps["supportsStepBack"]
    dap.ok("launch", {"project": str(project), "program": str(project / "hardware" / "M03.plc"),
                      "eparam": 7, **extra})
    dap.event("initialized")
    return str(project / "hardware" / "M03.plc")


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
        dap = start(project)
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


# ---------------------------------------------------------------- order (issue 25.2)

def _index(log, pred) -> int:
    return next(i for i, m in enumerate(log) if pred(m))


def test_a_fault_on_continue_comes_after_the_continue_response(dap, project):
    """The wire had event continued, event stopped, then the continue response:
    a request's response comes before the events it causes, and a resume the
    client asked for is not told back to it as continued."""
    initialize(dap)
    dap.ok("launch", {"project": str(project), "procedure": "M04"})
    dap.event("initialized")
    m04 = str(project / "hardware" / "M04.plc")
    dap.ok("setBreakpoints", {"source": {"path": m04},
                              "breakpoints": [{"line": 6, "condition": "n == 0"}]})
    dap.ok("configurationDone")
    tid = dap.event("stopped")["threadId"]
    r = dap.request("continue", {"threadId": tid})
    fault = dap.event("stopped", pred=lambda b: b["reason"] == "exception")
    assert fault["description"] == "Fault" and "division by zero" in fault["text"]
    log = dap.received()
    responded = _index(log, lambda m: m.get("request_seq") == r["request_seq"])
    stopped = _index(log, lambda m: m.get("event") == "stopped"
                     and m["body"]["reason"] == "exception")
    assert responded < stopped
    assert [m for m in log if m.get("event") == "continued"] == []
    assert _frames(dap, tid)[0]["line"] == 6
    dap.ok("disconnect")


def test_nothing_follows_terminated_but_exited(dap, project):
    path = _launch(dap, project)
    dap.ok("setBreakpoints", {"source": {"path": path}, "breakpoints": [{"line": 8}]})
    dap.ok("configurationDone")
    tid = dap.event("stopped")["threadId"]
    dap.ok("continue", {"threadId": tid})
    dap.event("terminated")
    dap.ok("terminate")                  # after the end: answered, and nothing more is told
    dap.ok("disconnect", {"terminateDebuggee": True})
    dap.proc.wait(20)
    log = dap.received()
    after = log[_index(log, lambda m: m.get("event") == "terminated") + 1:]
    assert [m["event"] for m in after if m["type"] == "event"] == []
    events = [m["event"] for m in log if m["type"] == "event"]
    assert events.index("exited") < events.index("terminated")
    assert "continued" not in events


# ------------------------------------------------- what the halted state shows (25.1, 25.3, 25.4)

def test_variables_page_and_every_evaluate_name_evaluates(dap, project):
    path = _launch(dap, project)
    dap.ok("setBreakpoints", {"source": {"path": path}, "breakpoints": [{"line": 13}]})
    dap.ok("configurationDone")
    tid = dap.event("stopped")["threadId"]
    top = _frames(dap, tid)[0]["id"]
    scopes = {s["name"]: s for s in dap.ok("scopes", {"frameId": top})["scopes"]}
    inputs = scopes["Inputs"]
    assert inputs["indexedVariables"] > 5 and "namedVariables" not in inputs
    assert scopes["Variables"]["namedVariables"] >= 3
    ref = inputs["variablesReference"]
    page = dap.ok("variables", {"variablesReference": ref, "filter": "indexed", "start": 2,
                                "count": 3})["variables"]
    assert [v["name"] for v in page] == ["in 2", "in 3", "in 4"]
    assert dap.ok("variables", {"variablesReference": ref, "filter": "named"})["variables"] == []
    whole = dap.ok("variables", {"variablesReference": ref})["variables"]
    assert len(whole) == inputs["indexedVariables"]
    bad = dap.request("variables", {"variablesReference": ref, "start": -1})
    assert not bad["success"] and "start must be a whole number from 0" in bad["message"]
    dap.ok("setVariable", {"variablesReference": ref, "name": "in 3", "value": "1"})
    checked = 0
    for name, s in scopes.items():
        for v in dap.ok("variables", {"variablesReference": s["variablesReference"]})["variables"]:
            assert v.get("evaluateName", "") is not None, v
            if "evaluateName" in v:
                got = dap.ok("evaluate", {"expression": v["evaluateName"], "frameId": top,
                                          "context": "watch"})["result"]
                assert got == v["value"], (name, v)
                checked += 1
    assert checked > 20
    dap.ok("disconnect")


def test_a_procedure_at_its_loop_end_is_an_ordinary_frame(tmp_path):
    """The procedure that did not halt ended its tick at its loop's end: its
    frame said presentationHint "label" (meant for separators)."""
    project = make_project(tmp_path / "proj", software=True)
    dap = start(project)
    try:
        initialize(dap)
        dap.ok("launch", {"project": str(project), "procedure": "M05"})
        dap.event("initialized")
        lube = str(project / "software" / "LUBE.plc")
        dap.ok("setBreakpoints", {"source": {"path": lube},
                                  "breakpoints": [{"line": 4, "hitCondition": "3"}]})
        dap.ok("configurationDone")
        dap.event("stopped")
        threads = {t["name"]: t["id"] for t in dap.ok("threads")["threads"]}
        m05 = _frames(dap, threads["M05"])
        assert m05[0]["name"] == "main() (at the loop's end)" and m05[0]["line"] == 5
        assert "presentationHint" not in m05[0]
        dap.ok("disconnect")
    finally:
        dap.close()


def test_evaluate_speaks_of_what_was_typed_and_refusals_pop_no_dialog(dap, project):
    path = _launch(dap, project)
    dap.ok("setBreakpoints", {"source": {"path": path}, "breakpoints": [{"line": 5}]})
    dap.ok("configurationDone")
    top = _frames(dap, dap.event("stopped")["threadId"])[0]["id"]
    r = dap.request("evaluate", {"expression": "nope(", "frameId": top, "context": "repl"})
    assert not r["success"] and r["message"] == \
        "the '(' at column 5 is not closed: a ')' is missing"
    assert ";" not in r["message"]
    for command in ("fly", "source", "gotoTargets"):       # not supported: no dialog each time
        r = dap.request(command, {})
        assert not r["success"] and "unknown request" in r["message"]
        assert r["body"]["error"]["showUser"] is False
    dap.ok("disconnect")


# -------------------------------------------------------- hostile input (issue 24.2, 24.5)

def test_a_hostile_condition_keeps_no_request_waiting(dap, project):
    """800/1,600/3,200 '(' took 2.2/5.6/16.4 s to compile and the next request
    waited 77.7 s: each is refused at once, and a cheap request is answered
    promptly behind them."""
    path = _launch(dap, project)
    t0 = time.monotonic()
    for n in (800, 1600, 3200):
        bp = dap.ok("setBreakpoints", {"source": {"path": path}, "breakpoints": [
            {"line": 5, "condition": "(" * n}]})["breakpoints"][0]
        assert not bp["verified"] and ("nest at most 16 deep" in bp["message"]
                                       or "at most 1000 characters" in bp["message"])
        r = dap.request("evaluate", {"expression": "(" * n, "context": "repl"})
        assert not r["success"]
    assert dap.ok("threads")["threads"] == []
    assert time.monotonic() - t0 < 5.0
    dap.ok("disconnect")


def test_launch_refuses_a_folder_that_is_not_a_project(tmp_path):
    """The launch built into any folder (/build, /etc/build got an eeprom.rom)."""
    stray = tmp_path / "stray"
    stray.mkdir()
    (stray / "notes.txt").write_text("x\n")
    dap = start(stray)
    try:
        initialize(dap)
        for args in ({}, {"project": str(stray)}, {"cwd": str(stray), "procedure": "M03"}):
            r = dap.request("launch", args)
            assert not r["success"], r
            assert r["message"] == (f"cannot open the project: {stray if args else '.'}: not a "
                                    "project: it has no plcbuilder.toml, hardware/ or software/ "
                                    "(plcbuilder new DIR makes one in a new or empty folder)")
            assert r["body"]["error"]["showUser"] is True      # the session did not start
        assert sorted(p.name for p in stray.iterdir()) == ["notes.txt"]
        dap.ok("disconnect")
    finally:
        dap.close()


def _children(pid: int) -> list[int]:
    out = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[1]) == pid:
            out.append(int(stat.parent.name))
    return out


def _cmdline(pid: int) -> str:
    try:
        return Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ").decode()
    except OSError:
        return f"{pid} (gone)"


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="needs Linux's /proc")
def test_a_relaunch_stops_the_controller_the_previous_launch_started(dap, project):
    """Five launches left five controllers running until disconnect."""
    initialize(dap)
    for _ in range(3):
        dap.ok("launch", {"project": str(project), "procedure": "M03"})
        dap.event("initialized")
        dap.ok("configurationDone")
        deadline = time.monotonic() + 30
        while len(_children(dap.proc.pid)) != 1 and time.monotonic() < deadline:
            time.sleep(0.1)
        kids = _children(dap.proc.pid)
        assert len(kids) == 1, [_cmdline(k) for k in kids]
    dap.ok("disconnect")
    dap.proc.wait(20)
