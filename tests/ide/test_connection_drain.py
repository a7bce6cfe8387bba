"""The window's side of the controller connection at Max speed: a controller
makes sample changes faster than the window can take them. Without a bound,
the worker's queue grew by the second and one drain of it held the window for
1.3 s (an output toggling every tick; the run panels' model fed as the IDE
feeds it). Now a drain hands on for at most DRAIN_BUDGET_S (a step of
DRAIN_STEP_SAMPLES samples at a time, a big batch split), the rest at the next
drain, in order; and the client's reader waits while MAX_PENDING_SAMPLES wait
for the window, so a lossless controller waits too."""

from __future__ import annotations

import threading

import pytest

pytest.importorskip("PySide6")

from plcbuilder.controller import events as ev  # noqa: E402
from plcbuilder.ide import connection  # noqa: E402
from plcbuilder.ide.connection import ControllerConnection  # noqa: E402
from plcbuilder.link.client import Telemetry  # noqa: E402


def _sample(t: int) -> ev.Sample:
    z8 = (0,) * 8
    return ev.Sample(t, "TOGGLE", 0, 0, z8, (t % 2,) + (0,) * 7, z8, z8, z8, (0,) * 9, (0,) * 9)


class Clock:
    """time.monotonic for connection.py: each sample handed on costs 20 µs."""

    def __init__(self):
        self.now = 1000.0

    def monotonic(self) -> float:
        return self.now


@pytest.fixture
def flooded(qtbot, monkeypatch):
    """A connection whose worker posted 20 batches of 5,000 samples (one with
    a print event), a state between the 10th and the 11th: (connection,
    what it handed on: [("samples", first t, last t) | ("events", n) | ("state", t)],
    the fake clock)."""
    clock = Clock()
    monkeypatch.setattr(connection, "time", clock)
    c = ControllerConnection()
    got = []

    def on_samples(batch):
        clock.now += 20e-6 * len(batch)
        got.append(("samples", batch[0].t_ms, batch[-1].t_ms))
    c.sig_samples.connect(on_samples)
    c.sig_events.connect(lambda evs: got.append(("events", len(evs))))
    c.sig_state.connect(lambda st, _missed: got.append(("state", st)))
    t = 0
    for i in range(20):
        batch = Telemetry(t_ms=t + 5000, samples=[_sample(t + k) for k in range(5000)],
                          events=[ev.Print(t, 20000, i, "TOGGLE")] if i == 3 else [])
        t += 5000
        c._inbox.put(("telemetry", batch))
        if i == 9:
            c._inbox.put(("state", "after the 10th"))
    yield c, got, clock
    c.shutdown()


def test_a_drain_hands_on_for_its_budget_then_the_rest_comes_in_order(qtbot, flooded):
    c, got, clock = flooded
    began = clock.now
    c._drain()
    spent = clock.now - began
    handed = sum(b - a + 1 for _kind, a, b in (g for g in got if g[0] == "samples"))
    # one step past the budget at most: 20 ms + one step's 10 ms, not 100,000 samples' 2 s
    assert spent <= connection.DRAIN_BUDGET_S + connection.DRAIN_STEP_SAMPLES * 20e-6 + 1e-9
    assert 0 < handed < 100_000
    assert c._pump.isActive()                       # the rest, soon
    while c._carry or not c._inbox.empty():
        c._drain()
    # every sample once, in order; the event with its batch; the state between
    firsts = [g for g in got if g[0] == "samples"]
    assert firsts[0][1] == 0 and firsts[-1][2] == 99_999
    assert all(b[1] == a[2] + 1 for a, b in zip(firsts, firsts[1:]))
    assert max(b - a + 1 for _k, a, b in firsts) <= connection.DRAIN_STEP_SAMPLES
    state = got.index(("state", "after the 10th"))
    assert got[state - 1][0] == "samples" and got[state - 1][2] == 49_999
    assert ("events", 1) in got and got.index(("events", 1)) < state


def test_closing_hands_on_everything_that_came(qtbot, flooded):
    c, got, _clock = flooded
    c.shutdown()
    assert [g for g in got if g[0] == "samples"][-1][2] == 99_999
    assert not c._carry and c._inbox.empty()


def test_the_reader_waits_while_the_window_has_too_much_to_take(monkeypatch):
    monkeypatch.setattr(connection, "MAX_READER_WAIT_S", 60.0)     # (see the next test)
    backlog = connection._Backlog()
    stop = threading.Event()
    backlog.add(connection.MAX_PENDING_SAMPLES + 1, stop)         # (the first never waits)
    done = threading.Event()
    reader = threading.Thread(target=lambda: (backlog.add(10, stop), done.set()))
    reader.start()
    assert not done.wait(0.3)                       # waits ...
    backlog.take(5000)                              # ... until the window takes enough
    assert done.wait(5)
    assert backlog.samples == connection.MAX_PENDING_SAMPLES + 1 - 5000 + 10
    # and a worker that stops is not held by it
    backlog.add(connection.MAX_PENDING_SAMPLES, stop)
    stopped = threading.Event()
    reader = threading.Thread(target=lambda: (backlog.add(10, stop), stopped.set()))
    reader.start()
    assert not stopped.wait(0.2)
    stop.set()
    assert stopped.wait(5)
    reader.join(5)


def test_a_window_held_up_keeps_the_reader_waiting_only_so_long(monkeypatch):
    """The controller waits for a lossless subscriber for at most a second,
    then drops changes: the reader never waits longer than MAX_READER_WAIT_S
    (the changes are then late, not lost)."""
    monkeypatch.setattr(connection, "MAX_READER_WAIT_S", 0.3)
    backlog = connection._Backlog()
    stop = threading.Event()
    backlog.add(connection.MAX_PENDING_SAMPLES + 1, stop)
    done = threading.Event()
    reader = threading.Thread(target=lambda: (backlog.add(10, stop), done.set()))
    reader.start()
    assert not done.wait(0.1)
    assert done.wait(5)                             # nobody took any: in anyway
    reader.join(5)
    assert backlog.samples == connection.MAX_PENDING_SAMPLES + 11
