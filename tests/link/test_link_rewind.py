"""Stepping back over the link (docs/protocol.md, "Debugging"): debug_step_back
and debug_run_back, and the requests refused with nothing changed."""

from __future__ import annotations

import time

import pytest

from plcbuilder.controller.controller import Controller
from plcbuilder.link.client import Client, RefusedError
from plcbuilder.link.server import ControllerServer
from tests.link.linkkit import counter_image, wait_note

def _serve(**kw):
    srv = ControllerServer(port=0, speed="pause", image=counter_image(),
                           frame_timeout=0.2, hello_timeout=1.0, **kw)
    srv.start()
    return srv, Client.connect(*srv.address, srv.token, timeout=10.0)


@pytest.fixture
def served():
    srv, c = _serve()
    c.subscribe(lambda batch: None)
    yield srv, c
    c.close()
    srv.close()


def _n(state: dict) -> int:
    return next(p for p in state["procedures"] if p["name"] == "M10")["vars"]["n"]


def test_step_back_a_tick_and_a_statement_and_run_back(served):
    """SPEC §7: 'Step back (one tick, or one statement) and run back (to the
    previous breakpoint hit) work by deterministic re-execution from the recording'."""
    srv, c = served
    c.start("M10")
    c.step(40)
    before = c.state()
    answer = c.debug_step_back("tick")
    assert answer["t_ms"] == before.t_ms - 1
    assert answer["halted"]["reason"] == "step"
    assert _n(answer["halted"]) == 39                 # M10 ran 40 ticks: n++ each
    assert wait_note(c, "halted")["state"]["t_ms"] == answer["t_ms"]
    assert srv.controller.t_ms == answer["t_ms"]          # the new controller took over
    c.set_breakpoints("M10.plc", [{"line": 6}])
    c.debug_continue()
    c.step(5)                                       # paused speed: time moves by steps
    here = c.debug_state()
    assert here["line"] == 6
    back = c.debug_step_back("statement")
    # the statement before n++ is the loop's condition, at the end of the tick before
    assert back["halted"]["line"] == 8 and back["t_ms"] == here["t_ms"] - 1
    assert _n(back["halted"]) == _n(here)
    run = c.debug_run_back()
    assert run["halted"]["reason"] == "breakpoint" and run["halted"]["line"] == 6
    assert run["t_ms"] == here["t_ms"] - 1
    assert _n(run["halted"]) == _n(here) - 1


def test_bad_step_back_requests_are_refused_and_change_nothing(served):
    srv, c = served
    t = c.state().t_ms
    with pytest.raises(RefusedError, match="nothing to go back to"):
        c.debug_step_back("tick")
    with pytest.raises(RefusedError, match="kind must be one of tick, statement"):
        c.debug_step_back("line")
    with pytest.raises(RefusedError, match="no breakpoint is set"):
        c.debug_run_back()
    c.set_breakpoints("M10.plc", [{"line": 6}])
    with pytest.raises(RefusedError, match="no breakpoint was hit before now"):
        c.debug_run_back()
    with pytest.raises(RefusedError, match="needs a halt at a statement"):
        c.debug_step_back("statement")
    assert c.state().t_ms == t
    with pytest.raises(RefusedError, match="'kind' must be a string"):
        c.request("debug_step_back", kind=5)


def test_without_a_factory_stepping_back_is_refused():
    srv = ControllerServer(Controller(), port=0, speed="pause")
    srv.start()
    c = Client.connect(*srv.address, srv.token, timeout=10.0)
    try:
        c.step(5)
        with pytest.raises(RefusedError, match="not available on this controller"):
            c.debug_step_back()
        assert c.state().t_ms == 5
    finally:
        c.close()
        srv.close()


def test_checkpoints_are_made_while_idle_and_used_by_a_step_back(served):
    """SPEC §7: '… with checkpoints so that stepping back in a ten-minute session
    answers in well under a second.' The served controller makes them in its idle
    time (here: paused) and a step back starts from the latest one."""
    srv, c = served
    pool = srv.service.checkpoints
    pool.every_ms = 100
    c.start("M10")
    c.step(450)
    end = time.monotonic() + 20
    while sorted(pool.ready) != [100, 200, 300, 400] and time.monotonic() < end:
        time.sleep(0.05)
    assert sorted(pool.ready) == [100, 200, 300, 400]
    t = c.state().t_ms
    spare = pool.ready[400][0]
    answer = c.debug_step_back("tick")
    assert t == 450 and answer["t_ms"] == 449
    assert _n(answer["halted"]) == 449              # M10 started at 0: n++ each tick
    assert srv.controller is spare                  # the checkpoint at 400 went on to 449


def test_run_back_starts_from_the_checkpoints(served):
    """SPEC §7: run back too uses the checkpoints: the hit before now is looked
    for from the latest checkpoint back, and the session runs again to it from
    a checkpoint before it, not from t = 0; the hit counts hold every hit since
    t = 0 (every 150th time line 6 runs)."""
    srv, c = served
    pool = srv.service.checkpoints
    pool.every_ms = 100
    c.set_breakpoints("M10.plc", [{"line": 6, "hit": {"mode": "every", "n": 150}}])
    c.start("M10")
    hits = []
    while len(hits) < 3:
        c.step(200)
        here = c.debug_state()
        if here is not None and here.get("reason") == "breakpoint":
            hits.append((here["t_ms"], _n(here)))
            if len(hits) < 3:
                c.debug_continue()
    assert [t for t, _n in hits] == [149, 299, 449]
    end = time.monotonic() + 20
    while sorted(pool.ready) != [100, 200, 300, 400] and time.monotonic() < end:
        time.sleep(0.05)
    assert sorted(pool.ready) == [100, 200, 300, 400]
    spares = {t: pool.ready[t][0] for t in pool.ready}
    run = c.debug_run_back()
    assert run["halted"]["reason"] == "breakpoint" and run["halted"]["line"] == 6
    assert (run["t_ms"], _n(run["halted"])) == hits[1]
    # the hit was found from 400, 300 and 200, and reached from 100
    assert srv.controller is spares[100]
    assert [bp["hits"] for bp in srv.controller.debugger.breakpoints()] == [300]
