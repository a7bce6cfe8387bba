"""Watched variables over the link (docs/protocol.md, ``watch``): the controller
records a procedure's variable at the end of every tick and sends its changes
as ``watch`` events, which a trigger on a variable needs (SPEC §7)."""

from __future__ import annotations

import threading

import pytest

from plcbuilder import api
from plcbuilder.controller.events import Watched
from plcbuilder.link.client import Client, RefusedError
from plcbuilder.link.server import ControllerServer
from tests.link.linkkit import compile_programs, image_of, wait_for

# n counts the ticks M10 ran; bit 2 of n rises every 8 ticks
COUNTER = "main(){ n = 0; do { n++; } while (n < 100000); exit(99); }\n"


@pytest.fixture
def served():
    r = api.compile_source(COUNTER, "M10.plc", api.CompileOptions(kind=api.Kind.HARDWARE))
    assert r.ok
    srv = ControllerServer(port=0, speed="pause",
                           image=image_of([*compile_programs(["M05"], overrides={}), r.program]))
    srv.start()
    c = Client.connect(*srv.address, srv.token, timeout=10.0)
    got: list = []
    lock = threading.Lock()

    def take(batch):
        with lock:
            got.extend(e for e in batch.events if isinstance(e, Watched))
    c.subscribe(take, lossless=True)
    yield srv, c, got
    c.close()
    srv.close()


def test_a_watched_variable_goes_out_each_tick_it_changes(served):
    """SPEC §7: a trigger on 'a variable's bit' — the controller records the
    variable (``watch``) and its changes travel as events, tick by tick."""
    srv, c, got = served
    assert c.watch(["M10.n"]) == ["M10.n"]
    c.start("M10")
    c.step(50)
    wait_for(lambda: len(got) >= 49)
    values = {(e.t_ms, e.value) for e in got}
    start = min(t for t, _v in values)
    # M10 starts at the tick after the start request; n is its ticks so far
    assert sorted(values)[:5] == [(start + i, i + 1) for i in range(5)]
    assert all(e.name == "M10.n" for e in got)
    # [] stops: nothing more comes
    assert c.watch([]) == []
    n = len(got)
    c.step(20)
    c.state()
    assert len(got) == n


def test_a_bad_variable_is_refused_and_nothing_changes(served):
    srv, c, _got = served
    c.watch(["M10.n"])
    with pytest.raises(RefusedError, match="M10.nope: M10 has no variable named nope"):
        c.watch(["M10.n", "M10.nope"])
    with pytest.raises(RefusedError, match="M99.n: no procedure named M99"):
        c.watch(["M99.n"])
    with pytest.raises(RefusedError, match="name a variable as PROC.var"):
        c.watch(["timer"])
    with pytest.raises(RefusedError, match="must be a list"):
        c.request("watch", variables="M10.n")
    assert srv.controller.watch.names == ["M10.n"]


def test_the_watch_goes_on_after_a_reset_and_a_step_back(served):
    """The controller that takes over (Reset, Step Back) watches the same variables."""
    srv, c, got = served
    c.watch(["M10.n"])
    c.reset()
    assert srv.controller.watch.names == ["M10.n"]
    c.start("M10")
    c.step(30)
    back = c.debug_step_back("tick")
    assert srv.controller.watch.names == ["M10.n"]
    t = back["t_ms"]
    c.debug_continue()
    c.step(3)
    wait_for(lambda: got and got[-1].t_ms == t + 2)
    # the new controller's first event is the value held now (at the end of the
    # tick before), then one a tick
    tail = [(e.t_ms, e.value) for e in got[-4:]]
    assert [x for x, _v in tail] == [t - 1, t, t + 1, t + 2]
    assert [v for _x, v in tail] == list(range(tail[0][1], tail[0][1] + 4))
