"""Stepping back and running back (SPEC §7): by running the session again.

The controller is deterministic and records everything done to it from outside
(controller/recorder.py) and every image it loaded (``Controller.images``), so
the state at any earlier point is found by running the recording again on a
fresh controller of the same machine:

    new = step_back(controller, factory, "tick")       # halted one tick earlier
    new = step_back(controller, factory, "statement")  # one statement earlier
    new = run_back(controller, factory, pool)          # the previous breakpoint hit

Each returns a new controller, halted there, that replaces the old one; its
recording holds the actions up to there (what came later is dropped: from
there on the session is written anew). The breakpoints are the old
controller's, counted as if they had been set from the start. Nothing is
changed when a request is refused (:class:`RewindError`).

Checkpoints (:class:`Checkpoints`): a running procedure is a generator, whose
state cannot be copied, so a checkpoint is a whole controller that already ran
the session to a tick k * 30 s, made in the simulation's idle time (while it is
halted or paced to real time). A step back starts from the latest one before
where it goes and uses it up; without one it runs from t = 0, as long as
simulating the session at Max speed takes (``scripts/bench_rewind.py``). Run
back looks for the previous hit from the checkpoints back (:func:`_previous_hit`)
and then runs to it from the latest one left before it.
"""

from __future__ import annotations

import time
from typing import Callable, Optional

from plcbuilder.controller.debugger import Halt
from plcbuilder.controller.scenario import aim, apply, at_halt, due_before

#: ticks run at most in one go while running the session again
CHUNK_MS = 10_000
#: ... while making a checkpoint in idle time (a few milliseconds of wall time)
BUILD_CHUNK_MS = 1000
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
           count_from: int = 0, pool: Optional["Checkpoints"] = None,
           start: Optional[tuple] = None):
    """A fresh controller that ran ``old``'s recording up to tick ``until``
    (between ticks, the actions at ``until`` not done) or, with ``through``,
    into tick ``until`` until ``on_halt(new)`` says a halt is the one wanted.
    Any other halt is continued. ``counter`` counts statements from tick
    ``count_from`` on (counting makes the procedure run watched code, slower).
    With ``pool``, it starts from the latest checkpoint that fits, when there is
    one; ``start`` is a (controller, next action) to start from instead (see
    :func:`_begin`). Returns the controller (halted or between ticks)."""
    actions = _actions(old, until, through)
    end = until + 1 if through else until
    count_from = min(max(0, count_from), end) if counter is not None else end + 1
    new, i = start if start is not None else _begin(old, factory, pool, min(until, count_from))
    for _ in _run(old, new, actions, i, end, on_halt, counter, count_from):
        pass
    new.replay_image = None
    new.drain_events()
    new.drain_sample_rows()
    return new


def _begin(old, factory: Callable, pool: Optional["Checkpoints"], before: int) -> tuple:
    """Where a replay starts: (controller, next action's index) of the latest
    checkpoint at or before tick ``before`` (used up), or a fresh controller at
    t = 0 and the first action."""
    spare = pool.take(old, before) if pool is not None and before >= 0 else None
    return spare if spare is not None else (_fresh(old, factory), 0)


def _actions(old, until: int, through: bool = False) -> list:
    actions = [a for a in old.recorder.actions if a.t_ms < until or through and a.t_ms == until]
    for a in actions:
        if a.kind == "upload" and a.name not in old.images:
            raise RewindError(f"the image {a.name} loaded at {a.t_ms} ms is not kept")
    return actions


def _run(old, new, actions: list, i: int, end: int, on_halt=None, counter=None,
         count_from: int = 1 << 62, chunk: int = CHUNK_MS):
    """Run ``new`` on ``actions[i:]`` up to tick ``end`` (see :func:`replay`);
    yields after each chunk of ticks. An action done while the tick was halted
    at a statement (``Action.at``) is done when ``new`` halts there again."""
    dbg = new.debugger
    n = len(actions)
    while True:
        t = new.t_ms
        if dbg.halt is not None:
            i = _at_halt(old, new, actions, i)
            if on_halt is not None and on_halt(new):
                break
            dbg.halt = None
            aim(dbg, actions, i, t)
            new.plc.resume_tick()
            continue
        if t >= count_from and dbg.counter is None:
            dbg.counter = counter
            dbg._remark()
        if t >= end:
            break
        # the actions of this tick done before it runs (one done mid-tick in a
        # tick already over, which cannot happen, is done now rather than never)
        while i < n and due_before(actions[i], t):
            _do(old, new, actions[i])
            i += 1
        aim(dbg, actions, i, t)
        stop = end if i >= n else min(end, max(actions[i].t_ms, t + 1))
        if t < count_from < stop:
            stop = count_from
        new.step(min(stop - t, chunk))
        new.drain_events()
        yield
    dbg.counter = None
    aim(dbg, actions, n, -1)
    dbg._remark()


def _do(old, new, action) -> None:
    if action.kind == "upload":
        new.replay_image = old.images[action.name]
    apply(new, action)


def _at_halt(old, new, actions: list, i: int) -> int:
    """``new`` halted: do the actions done live where it halted (see
    :func:`~plcbuilder.controller.scenario.at_halt`)."""
    dbg = new.debugger
    counted = dbg.counter is not None and dbg.counter.done
    return at_halt(new, actions, i, lambda c, a: _do(old, c, a), counted)


def _breakpoints_key(dbg) -> tuple:
    """What a checkpoint's breakpoints must equal to be used (hits count from 0)."""
    return (dbg.halt_on_fault,) + tuple(
        (bp.file, bp.line, bp.enabled, bp.condition, bp.code, bp.hit, bp.log)
        for file in sorted(dbg._bps) for bp in dbg._bps[file])


class Checkpoints:
    """Controllers that already ran the session to ticks k * ``every_ms``
    (between ticks), made in the simulation's idle time by :meth:`work`; a
    step back starts from the latest one at or before where it goes (and uses
    it up: :meth:`work` makes it again). A checkpoint is used only while the
    session's recording up to it and the breakpoints are what they were."""

    def __init__(self, factory: Callable, every_ms: int = 30_000, keep: int = 16):
        self.factory = factory
        self.every_ms = every_ms
        self.keep = keep
        self.ready: dict[int, tuple] = {}     # tick -> (controller, actions applied, bp key)
        self._job = None              # (tick, controller, actions, breakpoints, generator)

    def wanted(self, old) -> list[int]:
        """The ticks to have checkpoints at, latest first."""
        last = (old.t_ms - 1) // self.every_ms
        return [k * self.every_ms for k in range(last, max(0, last - self.keep), -1)]

    def clear(self) -> None:
        self.ready.clear()
        self._job = None

    def _latest(self, old, before: int) -> Optional[int]:
        """The tick of the latest checkpoint at or before tick ``before`` that
        fits ``old``'s recording and breakpoints, or None."""
        key = _breakpoints_key(old.debugger)
        acts = old.recorder.actions
        if old.recorder.dropped:
            return None
        for tick in sorted(self.ready, reverse=True):
            if tick > before:
                continue
            _c, applied, bps = self.ready[tick]
            k = len(applied)
            if bps == key and acts[:k] == applied and (k == len(acts) or acts[k].t_ms >= tick):
                return tick
        return None

    def take(self, old, before: int) -> Optional[tuple]:
        """(controller, next action's index) of the latest fitting checkpoint at
        or before tick ``before``, removed from the pool; or None."""
        tick = self._latest(old, before)
        if tick is None:
            return None
        c, applied, _bps = self.ready.pop(tick)
        return c, len(applied)

    def work(self, old, budget_s: float) -> bool:
        """Make checkpoints for about ``budget_s`` seconds; False when there is
        nothing to do (every wanted checkpoint is there, or out of reach).

        A checkpoint is made from the latest fitting one before it (used up,
        and made again in turn), or from t = 0 when there is none, so moving
        the window on by one checkpoint runs the session over the window once
        (``keep`` x ``every_ms``), not from t = 0 again. The latest one is
        always made; an older one only when it is at most ``keep`` x
        ``every_ms`` from where it would start (after hours at Max speed with
        no idle time, that leaves only the latest: one run of the session,
        not ``keep``)."""
        if old.target is not None or old.recorder.dropped:
            return False
        deadline = time.perf_counter() + budget_s
        wanted = self.wanted(old)
        key = _breakpoints_key(old.debugger)
        acts = old.recorder.actions
        for tick, (_c, applied, bps) in list(self.ready.items()):
            if bps != key or acts[:len(applied)] != applied:
                del self.ready[tick]                 # of no use any more: made again
        spare = [t for t in self.ready if t not in wanted]
        for tick in sorted(spare)[:-1]:
            del self.ready[tick]    # out of the window: the latest is kept to start from
        if self._job is not None and self._job[3] != key:
            self._job = None
        reach = self.keep * self.every_ms
        while time.perf_counter() < deadline:
            if self._job is None:
                job = None
                for tick in wanted:
                    if tick in self.ready:
                        continue
                    base = self._latest(old, tick)
                    if tick == wanted[0] or tick - (base or 0) <= reach:
                        job = tick
                        break
                if job is None:
                    return False
                tick = job
                try:
                    actions = _actions(old, tick)
                    start = self.take(old, tick) or (_fresh(old, self.factory), 0)
                except RewindError:
                    return False
                c, i = start
                self._job = (tick, c, actions, key,
                             _run(old, c, actions, i, tick, chunk=BUILD_CHUNK_MS))
            tick, c, actions, key, gen = self._job
            try:
                next(gen)
            except StopIteration:
                self._job = None
                c.replay_image = None
                c.drain_events()
                self.ready[tick] = (c, actions, key)
        return True


def _halted(new, halt: Halt):
    new.debugger.halt = halt
    return _announce(new)


def _announce(new):
    """The new controller's halt, announced as new (a ``halted`` event), and
    what is forced there (a ``forces`` event: the replay's own were drained)."""
    new.forces._changed()
    new.debugger._told = None
    new.debugger.settle()
    return new


def step_back(old, factory: Callable, kind: str = "tick",
              pool: Optional[Checkpoints] = None):
    """The controller one tick (or one statement of the procedure halted) earlier."""
    if kind not in KINDS:
        raise RewindError(f"unknown step back {kind!r} (one of {', '.join(KINDS)})")
    if kind == "tick":
        t = old.t_ms if old.plc.mid_tick else old.t_ms - 1
        if t < 0:
            raise RewindError("nothing to go back to: the session is at its start (t = 0 ms)")
        return _halted(replay(old, factory, t, pool=pool), Halt("step"))
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
           on_halt=lambda _c: first.done, pool=pool)
    if not first.done:
        raise RewindError(f"running the session again did not reach {name} at {t} ms "
                          f"(was something done that is not recorded?)")
    target = (t, first.found - 1) if first.found > 1 else first.last
    if target is None:
        raise RewindError(f"nothing to go back to: {name} ran no statement before this one "
                          f"(in the last {LOOK_BACK_MS} ms)")
    again = _Counter(name, stop_at=target)
    new = replay(old, factory, target[0], through=True, counter=again, count_from=target[0],
                 on_halt=lambda _c: again.done, pool=pool)
    if not again.done:                                    # pragma: no cover - determinism
        raise RewindError(f"running the session again did not reach {name} at {target[0]} ms")
    return _announce(new)


def run_back(old, factory: Callable, pool: Optional[Checkpoints] = None):
    """The controller halted at the last breakpoint hit before now (the
    breakpoints counted from the session's start). With ``pool``, the hit is
    looked for from the latest checkpoint before now, then from the one
    before that over the time up to the first, and so on; and the session is
    run again to it from the latest checkpoint left before it (see
    :func:`_previous_hit`). Without one, or before the first, from t = 0."""
    if not any(bp["enabled"] for bp in old.debugger.breakpoints()):
        raise RewindError("no breakpoint is set: nothing to run back to")
    hit = _previous_hit(old, factory, pool)
    if hit is None:
        raise RewindError("no breakpoint was hit before now: nothing to run back to")
    t, rank = hit
    seen = [0]

    def at_hit(c) -> bool:
        if c.t_ms == t and c.debugger.halt.reason == "breakpoint":
            seen[0] += 1
        return seen[0] == rank
    new = replay(old, factory, t, through=True, on_halt=at_hit, pool=pool)
    if seen[0] != rank:                                   # pragma: no cover - determinism
        raise RewindError("running the session again did not reach the breakpoint hit")
    return _announce(new)


def _previous_hit(old, factory: Callable, pool: Optional[Checkpoints]) -> Optional[tuple]:
    """(tick, n) of the last breakpoint hit before now: the n-th breakpoint halt
    of that tick; None when there was none since t = 0.

    The session runs again over spans that end where the last one began: from
    the latest checkpoint to now, then from the one before to that checkpoint,
    and so on (the last span from t = 0). A checkpoint ran the session from
    t = 0 with these breakpoints, so its hit counts hold every hit before it:
    the hits a span finds are the ones running from t = 0 would find there. A
    hit is named by its tick and its rank in that tick, which do not depend on
    where the run began."""
    h = old.debugger.halt
    mid = h is not None and h.process is not None and h.pc is not None and old.plc.mid_tick
    upto = old.t_ms
    first = True
    while True:
        new, i = _begin(old, factory, pool, upto if first and mid else upto - 1)
        begin = new.t_ms
        hits: list[tuple[int, int]] = []

        def note(c) -> bool:
            if c.debugger.halt.reason == "breakpoint":
                t = c.t_ms
                hits.append((t, hits[-1][1] + 1 if hits and hits[-1][0] == t else 1))
            return False
        if first and mid:
            # this tick up to the statement halted at (the hits before it in the tick count)
            now = _Counter(h.process.name, find=(upto, h.pc, tuple(h.rets)))
            replay(old, factory, upto, through=True, counter=now, count_from=upto,
                   on_halt=lambda c: now.done or note(c), start=(new, i))
        else:
            replay(old, factory, upto, on_halt=note, start=(new, i))
        if hits:
            return hits[-1]
        if begin <= 0:
            return None
        upto, first = begin, False
