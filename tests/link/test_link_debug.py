"""The debugger over the link (docs/protocol.md, "Debugging"): set_breakpoints,
debug_continue/pause/step/run_to, debug_state, the halted/resumed
notifications, logpoints as events, and bad requests refused without change."""

from __future__ import annotations

import base64
import time

import pytest

from plcbuilder import api
from plcbuilder.link.client import Client, RefusedError
from plcbuilder.link.server import ControllerServer
from tests.link.linkkit import counter_image, wait_note

@pytest.fixture
def served():
    srv = ControllerServer(port=0, speed="factor", factor=50.0, image=counter_image(),
                           frame_timeout=0.2, hello_timeout=1.0)
    srv.sim.batch = 0.001
    srv.start()
    c = Client.connect(*srv.address, srv.token, timeout=10.0)
    c.subscribe(lambda batch: None)
    yield srv, c
    c.close()
    srv.close()


def test_a_breakpoint_halts_and_the_server_sends_halted_with_the_state(served):
    """"Execution halts *before* the first instruction of that line runs, in
    whichever procedure reaches it" — and over the link a ``halted {state}``
    notification goes to every subscriber."""
    srv, c = served
    answer = c.set_breakpoints("M10.plc", [{"line": 6}])
    assert answer == [{"id": answer[0]["id"], "file": "M10.plc", "line": 6, "verified": True,
                       "reason": None}]
    c.start("M10")
    note = wait_note(c, "halted")
    st = note["state"]
    assert st["reason"] == "breakpoint" and st["procedure"] == "M10" and st["line"] == 6
    m10 = next(p for p in st["procedures"] if p["name"] == "M10")
    assert m10["vars"]["n"] == 0                   # before n++ ran
    assert c.debug_state()["line"] == 6


def test_while_halted_time_stands_still_and_requests_are_answered(served):
    """"halting stops the whole controller (every procedure, the machine,
    motion, timers), so nothing moves while the user looks." """
    srv, c = served
    c.set_breakpoints("M10.plc", [{"line": 7}])
    c.start("M10")
    wait_note(c, "halted")
    t0 = c.state().t_ms
    time.sleep(0.3)                                # 50x: 15 s of simulated time if it ran
    assert c.state().t_ms == t0
    assert c.variables()["M10"]["n"] == 1
    assert c.debug_state()["t_ms"] == t0


def test_continue_resumes_and_halts_again_next_tick(served):
    """"Continue" goes on: a ``resumed`` notification, then the next halt."""
    srv, c = served
    c.set_breakpoints("M10.plc", [{"line": 6}])
    c.start("M10")
    first = wait_note(c, "halted")["state"]
    c.debug_continue()
    assert wait_note(c, "resumed")["t_ms"] >= first["t_ms"]
    second = wait_note(c, "halted")["state"]
    assert second["t_ms"] == first["t_ms"] + 1
    vars2 = next(p for p in second["procedures"] if p["name"] == "M10")["vars"]
    assert vars2["n"] == 1


def test_step_over_and_step_tick(served):
    """"step over" runs one statement; "step tick" runs exactly one 1 ms tick."""
    srv, c = served
    c.set_breakpoints("M10.plc", [{"line": 6}])
    c.start("M10")
    st = wait_note(c, "halted")["state"]
    c.set_breakpoints("M10.plc", [])
    r = c.debug_step("over")
    assert r["halted"]["reason"] == "step" and r["halted"]["line"] == 7
    r = c.debug_step("tick")
    assert r["halted"]["reason"] == "step" and r["t_ms"] == st["t_ms"] + 1


def test_pause_halts_between_ticks_and_run_to_line(served):
    """"pause (halts at the end of the current tick)" and "run to line"."""
    srv, c = served
    started = c.start("M10")["t_ms"]
    while c.state().t_ms < started + 5:           # M10 has run (at 50x time was past 5 ms)
        time.sleep(0.01)
    r = c.debug_pause()
    assert r["halted"]["reason"] == "pause" and r["halted"]["procedure"] is None
    m10 = next(p for p in r["halted"]["procedures"] if p["name"] == "M10")
    assert m10["line"] == 8 and m10["at_loop_end"] is True
    wait_note(c, "halted")                        # (the pause's)
    c.debug_run_to("M10.plc", 7)                   # runs on, halts at the next tick
    st = wait_note(c, "halted")["state"]
    assert st["reason"] == "step" and st["line"] == 7


def test_a_condition_travels_compiled(served):
    """"A breakpoint may have a condition (an expression in the PLC language over
    the procedure's variables and built-in names, checked each time the line is
    reached" — compiled by the client, bound by name on the controller."""
    srv, c = served
    code = api.compile_condition("n == 5")
    assert isinstance(code, bytes)
    c.set_breakpoints("M10.plc", [{"line": 7, "condition": {"text": "n == 5", "code": code}}])
    c.start("M10")
    st = wait_note(c, "halted")["state"]
    assert next(p for p in st["procedures"] if p["name"] == "M10")["vars"]["n"] == 5


def test_a_logpoint_is_a_log_event_and_no_halt(served):
    """"or be a logpoint (a message with `{name}` placeholders written to the log;
    no halt)" — a ``log`` event in the telemetry."""
    srv, c = served
    logs = []
    c.subscribe(lambda b: logs.extend(e for e in b.events if getattr(e, "type", "") == "log"))
    c.set_breakpoints("M10.plc", [{"line": 7, "log": "n is {n}", "hit": {"mode": "eq", "n": 3}}])
    c.start("M10")
    end = time.monotonic() + 10
    while not logs and time.monotonic() < end:
        time.sleep(0.02)
    assert [(e.source, e.text) for e in logs] == [("M10", "n is 3")]
    assert c.debug_state() is None


@pytest.mark.parametrize("file, bps, why", [
    ("NOPE.plc", [{"line": 3}], "no loaded procedure is built from 'NOPE.plc'"),
    ("M10.plc", [{"line": 99}], "M10.plc has no code on line 99 or after it"),
    ("M10.plc", [{"line": 0}], "line must be a whole number from 1"),
    ("M10.plc", [{"line": 6, "hit": {"mode": "twice", "n": 2}}], "hit must be"),
])
def test_bad_breakpoints_are_refused_and_change_nothing(served, file, bps, why):
    """"bad requests (unknown procedure, line out of range, a condition that
    does not compile) get a clear error and change nothing." """
    srv, c = served
    c.set_breakpoints("M10.plc", [{"line": 6}])
    with pytest.raises(RefusedError) as exc:
        c.set_breakpoints(file, bps)
    assert why in str(exc.value)
    assert [b["line"] for b in srv.controller.debugger.breakpoints()] == [6]


def test_a_condition_that_does_not_bind_or_is_damaged_is_refused(served):
    srv, c = served
    code = api.compile_condition("ghost == 1")
    with pytest.raises(RefusedError, match="'ghost', which is not a variable of M10"):
        c.set_breakpoints("M10.plc", [{"line": 6, "condition": {"text": "ghost == 1",
                                                                 "code": code}}])
    with pytest.raises(RefusedError, match="damaged"):
        c.request("set_breakpoints", file="M10.plc", breakpoints=[
            {"line": 6, "condition": {"text": "x", "code": base64.b64encode(b"junk").decode()}}])
    with pytest.raises(RefusedError, match="not base64"):
        c.request("set_breakpoints", file="M10.plc", breakpoints=[
            {"line": 6, "condition": {"text": "x", "code": "%%%"}}])
    assert srv.controller.debugger.breakpoints() == []


def test_steps_need_a_halt_and_a_known_kind(served):
    srv, c = served
    with pytest.raises(RefusedError, match="not halted"):
        c.debug_step("over")
    with pytest.raises(RefusedError, match="kind must be one of"):
        c.debug_step("sideways")
    with pytest.raises(RefusedError, match="not halted"):
        c.debug_continue()


def test_a_reply_callback_runs_in_stream_order_before_a_later_notification():
    """A request's ``on_reply`` is called on the reader thread as its answer is
    read, before the ``halted`` notification that follows it in the stream is
    passed on, however late the requesting thread wakes (the IDE posts the
    halted state this way: posted after the wake, a stale "not halted" hid a
    newer halt)."""
    import socket
    import threading

    from plcbuilder.link import protocol
    ours, theirs = socket.socketpair()
    client = Client(ours, timeout=5.0)
    order: list[str] = []
    client.notification_callback = lambda msg: order.append(msg["type"])
    client._reader = threading.Thread(target=client._read_loop, daemon=True)
    client._reader.start()

    def server():
        req = protocol.recv_msg(theirs)
        protocol.send_msg(theirs, {"type": "result", "id": req["id"],
                                   "result": {"t_ms": 5, "halted": None}})
        protocol.send_msg(theirs, {"type": "halted", "state": {"line": 31}})
    threading.Thread(target=server, daemon=True).start()
    got = client.request("debug_state",
                         on_reply=lambda r: order.append(f"reply {r['halted']}"))
    deadline = time.monotonic() + 5
    while len(order) < 2 and time.monotonic() < deadline:
        time.sleep(0.01)
    assert got == {"t_ms": 5, "halted": None}
    assert order == ["reply None", "halted"]
    client.close()
    theirs.close()
