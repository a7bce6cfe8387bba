"""Stepping back and running back (SPEC §7): by running the session again.

The controller is deterministic and records everything done to it from outside
(controller/recorder.py) and every image it loaded (``Controller.images``), so
the state at any earlier point is found by running the recording again on a
fresh controller of the same machine:

    new = step_back(controller, factory, "tick")       # halted one tick earlier
    new = step_back(controller, factory, "statement")  # one statement earlier
    new = run_back(controller, factory)                # the previous breakpoint hit

Each returns a new controller, halted there, that replaces the old one; its
recording holds the actions up to there (what came later is dropped: from
there on the session is written anew). The breakpoints are the old
controller's, counted as if they had been set from the start. Nothing is
changed when a request is refused (:class:`RewindError`).

There are no checkpoints: running the session again is the whole cost. A
generator's state (a running procedure) cannot be copied, and running again
is fast enough (docs/debugging.md, "Stepping back", gives the figure and
``scripts/bench_rewind.py`` measures it).
"""

from __future__ import annotations

from typing import Callable, Optional

from plcbuilder.controller.debugger import Halt
from plcbuilder.controller.scenario import apply

#: ticks run at most in one go while running the session again
CHUNK_MS = 10_000
KINDS = ("tick", "statement")
#: how far back a statement back looks for the procedure's previous statement
#: (a software procedure runs every 100 ms)
LOOK_BACK_MS = 101


class RewindError(Exception):
    """A step back that cannot be done; the message says why. Nothing changed."""


class _Counter:
    """Counts the statements procedure ``name`` reaches, per tick (Debugger.counter)."""

    def __init__(self, name: str, find=None, stop_at=None):
        self.name = name
        self.find = find            # (tick, pc, rets): halt there; ``found`` is its number
        self.stop_at = stop_at      # (tick, n): halt at the n-th statement of that tick
        self.tick = -1
        self.n = 0
        self.last: Optional[tuple[int, int]] = None   # (tick, statements) before ``tick``
        self.found: Optional[int] = None
        self.done = False

    def reach(self, t: int, pc: int, rets) -> bool:
        if t != self.tick:
            if self.n:
                self.last = (self.tick, self.n)
            self.tick, self.n = t, 0
        self.n += 1
        if self.find is not None and (t, pc, tuple(rets)) == self.find:
            self.found = self.n
            self.done = True
        elif self.stop_at == (t, self.n):
            self.done = True
        return self.done


def _fresh(old, factory: Callable):
    """A controller of the same machine with the old one's breakpoints."""
    if old.target is not None:
        raise RewindError(f"stepping back works on the myCNC target only, not on "
                          f"{old.target.name}")
    if old.recorder.dropped:
        raise RewindError(f"the recording lost its first {old.recorder.dropped} actions: "
                          f"the session cannot be run again")
    new = factory()
    new.record_samples = False         # nobody looks at what is run again
    new.debugger.copy_breakpoints(old.debugger)
    return new


def replay(old, factory: Callable, until: int, *, through: bool = False,
           on_halt: Optional[Callable] = None, counter: Optional[_Counter] = None,
           count_from: int = 0):
    """A fresh controller that ran ``old``'s recording up to tick ``until``
    (between ticks, the actions at ``until`` not done) or, with ``through``,
    into tick ``until`` until ``on_halt(new)`` says a halt is the one wanted.
    Any other halt is continued. ``counter`` counts statements from tick
    ``count_from`` on (counting makes the procedure run watched code, slower).
    Returns the controller (halted or between ticks)."""
    new = _fresh(old, factory)
    actions = [a for a in old.recorder.actions if a.t_ms < until or through and a.t_ms == until]
    for a in actions:
        if a.kind == "upload" and a.name not in old.images:
            raise RewindError(f"the image {a.name} loaded at {a.t_ms} ms is not kept")
    dbg = new.debugger
    end = until + 1 if through else until
    count_from = min(max(0, count_from), end) if counter is not None else end + 1
    i, n = 0, len(actions)
    while True:
        t = new.t_ms
        if dbg.halt is not None:
            if on_halt is not None and on_halt(new):
                break
            dbg.halt = None
            new.plc.resume_tick()
            continue
        if t >= count_from and dbg.counter is None:
            dbg.counter = counter
            dbg._remark()
        if t >= end:
            break
        while i < n and actions[i].t_ms <= t:
            a = actions[i]
            if a.kind == "upload":
                new.replay_image = old.images[a.name]
            apply(new, a)
            i += 1
        stop = end if i >= n else min(end, max(actions[i].t_ms, t + 1))
        if t < count_from < stop:
            stop = count_from
        new.step(min(stop - t, CHUNK_MS))
        new.drain_events()
    dbg.counter = None
    dbg._remark()
    new.replay_image = None
    new.drain_events()
    new.drain_sample_rows()
    return new


def _halted(new, halt: Halt):
    new.debugger.halt = halt
    return _announce(new)


def _announce(new):
    """The new controller's halt, announced as new (a ``halted`` event)."""
    new.debugger._told = None
    new.debugger.settle()
    return new


def step_back(old, factory: Callable, kind: str = "tick"):
    """The controller one tick (or one statement of the procedure halted) earlier."""
    if kind not in KINDS:
        raise RewindError(f"unknown step back {kind!r} (one of {', '.join(KINDS)})")
    if kind == "tick":
        t = old.t_ms if old.plc.mid_tick else old.t_ms - 1
        if t < 0:
            raise RewindError("nothing to go back to: the session is at its start (t = 0 ms)")
        return _halted(replay(old, factory, t), Halt("step"))
    h = old.debugger.halt
    if h is None or h.process is None or h.pc is None or not old.plc.mid_tick:
        raise RewindError("a statement back needs a halt at a statement (halted between "
                          "ticks: step back a tick)")
    name, t = h.process.name, old.t_ms
    first = _Counter(name, find=(t, h.pc, tuple(h.rets)))
    # the statement before is in this tick, or in the last tick it ran before:
    # the tick before (hardware) or the software tick before (100 ms)
    since = t - LOOK_BACK_MS
    replay(old, factory, t, through=True, counter=first, count_from=since,
           on_halt=lambda _c: first.done)
    if not first.done:
        raise RewindError(f"running the session again did not reach {name} at {t} ms "
                          f"(was something done that is not recorded?)")
    target = (t, first.found - 1) if first.found > 1 else first.last
    if target is None:
        raise RewindError(f"nothing to go back to: {name} ran no statement before this one "
                          f"(in the last {LOOK_BACK_MS} ms)")
    again = _Counter(name, stop_at=target)
    new = replay(old, factory, target[0], through=True, counter=again, count_from=target[0],
                 on_halt=lambda _c: again.done)
    if not again.done:                                    # pragma: no cover - determinism
        raise RewindError(f"running the session again did not reach {name} at {target[0]} ms")
    return _announce(new)


def run_back(old, factory: Callable):
    """The controller halted at the last breakpoint hit before now (the
    breakpoints counted from the session's start)."""
    if not any(bp["enabled"] for bp in old.debugger.breakpoints()):
        raise RewindError("no breakpoint is set: nothing to run back to")
    hits = [0]

    def count(c) -> bool:
        if c.debugger.halt.reason == "breakpoint":
            hits[0] += 1
        return False
    h = old.debugger.halt
    if h is not None and h.process is not None and h.pc is not None and old.plc.mid_tick:
        now = _Counter(h.process.name, find=(old.t_ms, h.pc, tuple(h.rets)))
        replay(old, factory, old.t_ms, through=True, counter=now, count_from=old.t_ms,
               on_halt=lambda c: now.done or count(c))
    else:
        replay(old, factory, old.t_ms, on_halt=count)
    if not hits[0]:
        raise RewindError("no breakpoint was hit before now: nothing to run back to")
    seen = [0]

    def last(c) -> bool:
        if c.debugger.halt.reason == "breakpoint":
            seen[0] += 1
        return seen[0] == hits[0]
    new = replay(old, factory, old.t_ms, through=True, on_halt=last)
    if seen[0] != hits[0]:                                # pragma: no cover - determinism
        raise RewindError("running the session again did not reach the breakpoint hit")
    return _announce(new)
