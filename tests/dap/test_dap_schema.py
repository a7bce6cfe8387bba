"""Every message of whole debugging sessions, checked against the Debug Adapter
Protocol's official JSON schema (``debugAdapterProtocol.json``, JSON Schema
Draft 4; issue 25).

The schema comes from an installed package, never from this repository: the
``debugpy`` wheel (PyPI) ships Microsoft's file as
``debugpy/_vendored/pydevd/_pydevd_bundle/_debug_adapter/debugProtocol.json``
(no npm package carries it: ``@vscode/debugprotocol`` has only its TypeScript
declarations). Both ``debugpy`` and ``jsonschema`` are pinned in the test
extras; without them the tests skip, saying which is missing.

Sessions: a launch with breakpoints set before the launch (a ``breakpoint``
event) and after it (a condition, a hit count, a logpoint, two refused),
threads, stack, every scope's variables (paged too), evaluate, setVariable,
step over/into/out/back, back to the previous hit, a refused and an unknown
request, to the procedure's end and disconnect; a fault; an attach with a
pause and a resume made by another client of the controller (``continued``).
"""

from __future__ import annotations

import importlib.metadata
import json

import pytest

from tests.dap._dap import DapClient, frames, initialize, make_project, start, values


def _schema() -> dict:
    try:
        import jsonschema  # noqa: F401
    except ImportError:
        pytest.skip("jsonschema is not installed (pip install -e '.[test]')")
    try:
        files = importlib.metadata.files("debugpy") or []
    except importlib.metadata.PackageNotFoundError:
        pytest.skip("debugpy, which ships the DAP schema (debugProtocol.json), is not installed "
                    "(pip install -e '.[test]')")
    found = [f for f in files if f.name == "debugProtocol.json"]
    if not found:
        pytest.skip("this debugpy does not ship debugProtocol.json")
    return json.loads(found[0].locate().read_text(encoding="utf-8"))


@pytest.fixture(scope="module")
def validate():
    import jsonschema
    schema = _schema()
    defs = schema["definitions"]
    assert schema["$schema"] == "http://json-schema.org/draft-04/schema#"
    assert schema["title"] == "Debug Adapter Protocol"
    validators: dict[str, jsonschema.Draft4Validator] = {}

    def definition(msg: dict) -> str:
        kind = msg.get("type")
        if kind == "request":
            name = msg["command"][:1].upper() + msg["command"][1:] + "Request"
        elif kind == "response":
            if not msg.get("success"):
                return "ErrorResponse"
            name = msg["command"][:1].upper() + msg["command"][1:] + "Response"
        else:
            name = msg["event"][:1].upper() + msg["event"][1:] + "Event"
        if name not in defs:            # a request the protocol does not have ("fly")
            return {"request": "Request", "response": "Response"}.get(kind, "Event")
        return name

    def check(log: list[dict]) -> dict[str, int]:
        """Every message of the log against its definition; how many of each."""
        seen: dict[str, int] = {}
        errors = []
        for msg in log:
            msg = {k: v for k, v in msg.items() if k != "_sent"}
            name = definition(msg)
            v = validators.get(name)
            if v is None:
                v = validators[name] = jsonschema.Draft4Validator(
                    {"$ref": f"#/definitions/{name}", "definitions": defs})
            for e in v.iter_errors(msg):
                errors.append(f"{name}: {e.message} at {list(e.absolute_path)} in "
                              f"{json.dumps(msg)[:300]}")
            seen[name] = seen.get(name, 0) + 1
        assert not errors, "\n".join(errors[:20]) + f"\n({len(errors)} errors)"
        return seen
    return check


def test_the_schema_catches_what_issue_25_found(validate):
    """The checker is not blind: the message the adapter used to send fails it."""
    bad = {"seq": 9, "type": "response", "request_seq": 4, "command": "variables",
           "success": True, "body": {"variables": [
               {"name": "in 0", "value": "0", "variablesReference": 0, "evaluateName": None}]}}
    with pytest.raises(AssertionError, match="None is not of type 'string'"):
        validate([bad])


def test_a_launched_session(tmp_path, validate):
    project = make_project(tmp_path / "proj")
    m03 = str(project / "hardware" / "M03.plc")
    dap = start(project)
    try:
        initialize(dap)
        early = dap.ok("setBreakpoints", {"source": {"path": m03},
                                          "breakpoints": [{"line": 8}]})["breakpoints"]
        assert not early[0]["verified"]
        dap.ok("launch", {"project": str(project), "program": m03, "eparam": 7})
        dap.event("initialized")
        changed = dap.event("breakpoint")
        assert changed["breakpoint"]["id"] == early[0]["id"] and changed["breakpoint"]["verified"]
        bps = dap.ok("setBreakpoints", {"source": {"path": m03}, "breakpoints": [
            {"line": 5, "condition": "count == 2"},
            {"line": 13, "hitCondition": ">=5"},
            {"line": 6, "logMessage": "count is {count}"},
            {"line": 7, "condition": "count =="},
            {"line": 40}]})["breakpoints"]
        assert [b["verified"] for b in bps] == [True, True, True, False, False]
        dap.ok("setExceptionBreakpoints", {"filters": []})
        dap.ok("configurationDone")
        tid = dap.event("stopped")["threadId"]
        dap.ok("threads")
        top = frames(dap, tid)[0]
        assert top["line"] == 5
        for s in dap.ok("scopes", {"frameId": top["id"]})["scopes"]:
            dap.ok("variables", {"variablesReference": s["variablesReference"]})
            dap.ok("variables", {"variablesReference": s["variablesReference"], "start": 1,
                                 "count": 2})
        ref, vs = values(dap, top["id"])
        assert vs["count"] == "2"
        dap.ok("evaluate", {"expression": "count * 10 + eparam", "frameId": top["id"],
                            "context": "watch"})
        dap.ok("evaluate", {"expression": "count", "frameId": top["id"], "context": "hover"})
        assert not dap.request("evaluate", {"expression": "nope(", "frameId": top["id"],
                                            "context": "repl"})["success"]
        dap.ok("setVariable", {"variablesReference": ref, "name": "count", "value": "2"})
        axes = next(s for s in dap.ok("scopes", {"frameId": top["id"]})["scopes"]
                    if s["name"] == "Axes")["variablesReference"]
        assert not dap.request("setVariable", {"variablesReference": axes, "name": "X",
                                               "value": "1"})["success"]
        for step in ("next", "stepIn", "stepOut", "stepBack"):
            dap.ok(step, {"threadId": tid})
            dap.event("stopped", pred=lambda b: b["reason"] == "step")
            frames(dap, tid)
        r = dap.request("reverseContinue", {"threadId": tid})
        if r["success"]:
            dap.event("stopped")
        assert not dap.request("fly", {})["success"]
        dap.ok("setBreakpoints", {"source": {"path": m03}, "breakpoints": []})
        dap.ok("continue", {"threadId": tid})
        assert dap.event("exited")["exitCode"] == 99
        dap.event("terminated")
        dap.ok("disconnect", {"terminateDebuggee": True})
        dap.proc.wait(20)
    finally:
        dap.close()
    seen = validate(dap.log)
    for name in ("InitializeResponse", "LaunchResponse", "InitializedEvent", "BreakpointEvent",
                 "SetBreakpointsResponse", "StoppedEvent", "StackTraceResponse",
                 "ScopesResponse", "VariablesResponse", "EvaluateResponse", "ErrorResponse",
                 "SetVariableResponse", "NextResponse", "StepInResponse", "StepOutResponse",
                 "StepBackResponse", "ContinueResponse", "OutputEvent", "ExitedEvent",
                 "TerminatedEvent", "DisconnectResponse", "ThreadsResponse"):
        assert seen.get(name), (name, seen)
    assert sum(seen.values()) > 80


def test_a_fault(tmp_path, validate):
    project = make_project(tmp_path / "proj")
    dap = start(project)
    try:
        initialize(dap)
        dap.ok("launch", {"project": str(project), "procedure": "M04"})
        dap.event("initialized")
        dap.ok("setBreakpoints", {"source": {"path": str(project / "hardware" / "M04.plc")},
                                  "breakpoints": [{"line": 6, "condition": "n == 0"}]})
        dap.ok("configurationDone")
        tid = dap.event("stopped")["threadId"]
        dap.ok("continue", {"threadId": tid})
        fault = dap.event("stopped", pred=lambda b: b["reason"] == "exception")
        assert "division by zero" in fault["text"]
        frames(dap, tid)
        dap.ok("disconnect")
        dap.proc.wait(20)
    finally:
        dap.close()
    assert validate(dap.log)["StoppedEvent"] == 2


def test_an_attached_session(tmp_path, validate):
    from plcbuilder.link.process import ControllerProcess
    from plcbuilder.project import Project, build_project

    project = make_project(tmp_path / "proj", software=True)
    build = build_project(Project.open(project))
    assert build.ok
    ctl = ControllerProcess.start(image=build.image_path)
    try:
        ep = ctl.wait_endpoint()
        dap: DapClient = start(project)
        other = ctl.connect()
        try:
            initialize(dap)
            dap.ok("attach", {"controller": f"{ep.host}:{ep.port}", "token": ep.token,
                              "project": str(project)})
            dap.event("initialized")
            lube = str(project / "software" / "LUBE.plc")
            dap.ok("setBreakpoints", {"source": {"path": lube},
                                      "breakpoints": [{"line": 4, "hitCondition": "%3"}]})
            dap.ok("configurationDone")
            tid = dap.event("stopped")["threadId"]
            frames(dap, tid)
            dap.ok("setBreakpoints", {"source": {"path": lube}, "breakpoints": []})
            other.debug_continue()                # another client goes on: told as continued
            assert dap.event("continued")["allThreadsContinued"]
            dap.ok("pause", {"threadId": tid})
            assert dap.event("stopped")["reason"] == "pause"
            dap.ok("continue", {"threadId": tid})
            dap.ok("disconnect", {})
            dap.proc.wait(20)
        finally:
            other.close()
            dap.close()
    finally:
        ctl.stop()
    seen = validate(dap.log)
    assert seen["AttachResponse"] == 1 and seen["ContinuedEvent"] == 1 and seen["PauseResponse"]
