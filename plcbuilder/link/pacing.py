"""The simulation thread: a controller run on its own thread, paced to the wall clock.

:class:`Simulation` owns the :class:`~plcbuilder.controller.controller.Controller`
and runs it on its own thread (real time, N times real time, as fast as it
computes, or paused). Everything that touches the controller runs on that
thread, between batches of ticks: other threads hand it work with
:meth:`Simulation.call`. After every batch the new events and samples go to the
:class:`TelemetryQueue` of each subscribed client; a queue is bounded, drops the
oldest samples when full and counts them, so a slow client never holds the
simulation up.

Real-time pacing uses absolute deadlines: the ticks due are computed from a
monotonic start time (``base_t + (now - base_wall) * rate``), run, and the
thread sleeps until the next batch is due, so no error accumulates. When the
simulation falls more than :attr:`Simulation.max_lag` seconds behind (it cannot
keep up, or the process was stopped, suspended or held by a long pause) it
skips the whole backlog at once: pacing restarts from now, the ticks skipped
are added to ``state.speed.dropped_ms`` once, and the simulation never runs
ahead of the wall clock. Time comes from :attr:`Simulation.clock` (replaceable
in tests) and one pacing decision is :meth:`Simulation.pace`.

A controller with nothing to do (no hardware procedure, the machine still,
nothing due: :func:`quiet_ticks`) is not woken every batch: the thread sleeps
until the next tick where something happens (a software tick, a start due) or
at most :attr:`Simulation.idle_sleep`, and the quiet ticks in between are run
in one go (the controller counts them without running anything) when it
wakes, or before it answers a request that comes first (:meth:`Simulation.call`
then sees the time the wall clock says). The ticks run and everything they
produce are the same as when paced batch by batch: only the wake-ups go.

Idle work (stepping back's checkpoints, :attr:`Simulation.idle_work`) gets at
most :attr:`Simulation.idle_share` of the wall time while a run is paced, so
that a long session (or one run at Max for hours) cannot keep a core busy at
1x; while halted or paused it gets the time it wants.
"""

from __future__ import annotations

import queue
import threading
import time
import traceback
from collections import deque
from dataclasses import dataclass, field
from typing import Callable, Optional

from plcbuilder.controller.controller import Controller
from plcbuilder.controller.plc import SOFTWARE_PERIOD_MS
from plcbuilder.link import protocol
from plcbuilder.link.protocol import debug as _debug

__all__ = ["Simulation", "SimulationDown", "TelemetryQueue", "quiet_ticks"]

#: quiet_ticks() when nothing at all is due
FOREVER = 1 << 62


class SimulationDown(RuntimeError):
    """The simulation thread is not running any more."""


# ===================================================================== telemetry

def _append(q, items: list) -> int:
    """Append items to the bounded deque q; how many of its oldest fell out."""
    over = max(len(q) + len(items) - q.maxlen, 0)
    q.extend(items)
    return over


class TelemetryQueue:
    """One subscriber's bounded queue of sample changes and events.

    The samples are the controller's raw rows (``t_ms, running, proc, message,
    fields``), recorded only on ticks where something changed. :meth:`push`
    (the simulation thread) never blocks for longer than a list append; when
    more than ``max_samples`` rows wait, the oldest go and are counted in
    ``missed`` (likewise events beyond ``max_events``). A ``lossless`` queue
    makes a simulation at Max speed wait for it instead (see
    :meth:`Simulation.room`), for at most :attr:`Simulation.lossless_wait`
    seconds at a time.

    When only time went on (no change, no event), :meth:`take` hands out the
    new time at most every :attr:`busy_time_interval` seconds while a procedure
    runs (or is due; the IDE's plots scroll 10 times a second at most), and every
    :attr:`idle_time_interval` seconds while the controller is idle: a
    controller where nothing changes costs its subscribers (the IDE) little.
    """

    #: Seconds between two time-only takes while a procedure runs.
    busy_time_interval = 0.1
    #: Seconds between two time-only takes while no procedure runs.
    idle_time_interval = 1.0

    def __init__(self, max_samples: int = 1000, max_events: int = 20000, samples: bool = True,
                 events: bool = True, lossless: bool = False,
                 notify: Optional[Callable[[], None]] = None):
        self.want_samples = samples
        self.want_events = events
        self.lossless = lossless
        self.max_samples = max(1, max_samples)
        self._samples: deque = deque(maxlen=self.max_samples)
        self._events: deque = deque(maxlen=max(1, max_events))
        self._lock = threading.Lock()
        self.missed = 0
        self.missed_events = 0
        self.t_ms = -1                  # nothing pushed yet: nothing to take
        self.active = True              # a procedure runs or is due (time-only takes are due)
        self._time_only_at = 0.0        # monotonic time of the last time-only take
        #: called (from the simulation thread) when something new arrives after a
        #: take, once until the next take: the server's loop sleeps until then
        self.notify = notify
        self._told = False

    @property
    def room(self) -> int:
        """Rows that fit before the oldest would be dropped."""
        return self.max_samples - len(self._samples)

    def push(self, samples: list, events: list, t_ms: int, active: bool = True) -> None:
        """Add what one batch of ticks produced; ``active``: a procedure runs or is due."""
        with self._lock:
            tell = not self._told and (t_ms != self.t_ms or self.want_samples and samples
                                       or self.want_events and events)
            self.t_ms = t_ms
            self.active = active
            if self.want_samples and samples:
                self.missed += _append(self._samples, samples)
            if self.want_events and events:
                self.missed_events += _append(self._events, events)
            if tell:
                self._told = True
        if tell and self.notify is not None:
            self.notify()

    def ready_at(self) -> Optional[float]:
        """The monotonic time from which :meth:`take` has something to hand out
        (0.0: now), or None while nothing new came."""
        if self._samples or self._events or self.missed or self.missed_events:
            return 0.0
        if self.t_ms == self._taken_t:
            return None
        return self._time_only_at + (self.busy_time_interval if self.active
                                     else self.idle_time_interval)

    def take(self, limit: Optional[int] = None) -> Optional[tuple[list, list, int, int, int]]:
        """(samples, events, missed, missed_events, t_ms) since the last take (the
        oldest ``limit`` samples and events at most; ``t_ms`` is then the time of the
        next sample left), or None when there is nothing new."""
        with self._lock:
            self._told = False
            if not self._samples and not self._events and not self.missed \
                    and not self.missed_events:
                if self.t_ms == self._taken_t:
                    return None
                now = time.monotonic()
                every = self.busy_time_interval if self.active else self.idle_time_interval
                if now - self._time_only_at < every:
                    return None                 # only time went on: it goes out at a low rate
                self._time_only_at = now
            sq, eq = self._samples, self._events
            if limit is None or (len(sq) <= limit and len(eq) <= limit):
                samples, events, t = list(sq), list(eq), self.t_ms
                sq.clear()
                eq.clear()
            else:
                samples = [sq.popleft() for _ in range(min(limit, len(sq)))]
                events = [eq.popleft() for _ in range(min(limit, len(eq)))]
                t = sq[0][0] if sq else self.t_ms
            out = (samples, events, self.missed, self.missed_events, t)
            self.missed = self.missed_events = 0
            self._taken_t = t
            return out

    _taken_t = -1


# ===================================================================== quiet stretches

def quiet_ticks(c) -> int:
    """Ticks from ``c.t_ms`` on that only count time: no procedure runs in
    them, the machine does not move, nothing is due (0: the next tick does
    something; :data:`FOREVER`: nothing is due at all). Running them later,
    in one go, gives exactly what running them one by one would (the
    controller already runs such stretches as one count, PLC._machine_alone).
    Conservative: anything it does not know (another target, a machine
    without ``quiet``, a step or a run-to going on, a watched variable, a
    pending force, a bound input about to start something) is 0."""
    if getattr(c, "target", None) is not None:
        return 0
    plc = getattr(c, "plc", None)
    machine = getattr(c, "machine", None)
    if plc is None or machine is None or plc.hw is not None or plc.watching:
        return 0
    if getattr(machine, "pending_notes", True):
        return 0
    end = FOREVER
    if not getattr(machine, "quiet", False):
        # still only a delayed input to come (an output's follower, such as an
        # arc-OK sensor): nothing happens before the tick whose end applies it
        sensors, motion = getattr(machine, "sensors", None), getattr(machine, "motion", None)
        if sensors is None or motion is None or motion.needs_advance or sensors.dynamic_adc \
                or not sensors.pending:
            return 0
        end = min(due for due, _level in sensors.pending.values()) - 1
    dbg = c.debugger
    if dbg is not None and dbg.halt is not None:
        return 0
    if c.forces.pending or c.watch:
        return 0
    if plc.record_samples and (not plc.sample_changes_only or not plc._same_row(
            None, plc.proc, machine.sample_fields())):
        return 0                        # the next tick's sample is recorded (a subscriber's first)
    if plc.bindings and plc._edge_due():
        return 0
    t = plc.t
    if plc.sw:
        end = min(end, t + (plc.grid - t) % SOFTWARE_PERIOD_MS)
    due = c.next_due()
    if due is not None:
        end = min(end, due)
    return FOREVER if end >= FOREVER else max(0, end - t)


# ===================================================================== simulation

@dataclass
class _Call:
    fn: Callable
    done: threading.Event = field(default_factory=threading.Event)
    result: object = None
    error: Optional[BaseException] = None


class Simulation:
    """Runs a controller on its own thread, paced to the wall clock."""

    #: Seconds between paced batches (real time: about 4 ticks a batch).
    batch = 0.004
    #: Wall time one batch of ticks may take before the thread looks at its queue again.
    slice = 0.002
    #: Seconds of backlog after which a paced simulation drops the ticks it could not run.
    max_lag = 1.0
    #: Seconds a simulation at Max speed waits for a lossless subscriber before dropping.
    lossless_wait = 1.0
    #: Longest sleep of a paced controller with nothing to do (its subscribers see the
    #: time move at least this often; a request wakes it at once).
    idle_sleep = 0.25
    #: Seconds a quiet sleep lasts beyond the tick it waits for (rounding).
    wake_margin = 0.0002
    #: Quiet ticks slept over at most (a millisecond or two of work to run them).
    lazy_ticks = 20_000
    #: Share of the wall time idle work may take while a run is paced (not halted or
    #: paused), and the most it may save up (seconds).
    idle_share = 0.01
    idle_burst = 0.05

    def __init__(self, controller: Controller, mode: str = "realtime", factor: float = 1.0):
        self.controller = controller
        self._commands: "queue.SimpleQueue[Optional[_Call]]" = queue.SimpleQueue()
        self._queues: list[TelemetryQueue] = []
        self._qlock = threading.Lock()
        self._inline = threading.RLock()        # used while the thread is not running
        self._thread: Optional[threading.Thread] = None
        self._stop = False
        self._closing = threading.Lock()        # held to queue a call, and for the last drain
        self._closed = False                    # the thread takes no more calls
        self._shutdown_on_stop = True
        self.mode = "pause"
        self.factor = 1.0
        self.dropped_ms = 0
        self.error: Optional[str] = None
        self._tick_cost = 2e-6                  # seconds a tick takes, averaged
        self._held_since: Optional[float] = None  # waiting for a lossless subscriber since
        self._was_halted = False
        self._lazy = False                      # asleep over quiet ticks: catch up before a call
        self._idle_tokens = 0.0                 # seconds of idle work allowed while paced
        self._idle_refill = time.monotonic()
        #: paced wake-ups (batches run or quiet sleeps ended), for tests and benchmarks
        self.wakeups = 0
        self.clock: Callable[[], float] = time.monotonic
        self._base_wall = self.clock()
        self._base_t = controller.t_ms
        #: work for the simulation's idle time (stepping back's checkpoints):
        #: ``idle_work(seconds) -> bool``, False when there is nothing to do
        self.idle_work: Optional[Callable[[float], bool]] = None
        #: called with the events of every batch, on the simulation thread (listen)
        self._listeners: list[Callable[[list], None]] = []
        self.set_speed(mode, factor)
        self._update_recording()

    # ---------------------------------------------------------------- threads
    @property
    def running(self) -> bool:
        return self._thread is not None and self._thread.is_alive()

    def start(self) -> None:
        if self._thread is not None:
            return
        self._rebase()
        self._thread = threading.Thread(target=self._run, name="plcbuilder-simulation",
                                        daemon=True)
        self._thread.start()

    def stop(self, shutdown: bool = True, timeout: float = 15.0) -> None:
        """Stop the thread; with ``shutdown`` run ``__HANDLER_EXIT`` first
        (Controller.shutdown) and publish its events."""
        if self._thread is None:
            if shutdown:
                with self._inline:
                    self._shutdown_controller()
            return
        self._shutdown_on_stop = shutdown
        self._stop = True
        self._commands.put(None)
        self._thread.join(timeout)

    def call(self, fn: Callable, timeout: float = 30.0):
        """Run ``fn()`` on the simulation thread between two batches; return
        its result or raise its exception."""
        t = self._thread
        if t is None or threading.current_thread() is t:
            with self._inline:
                return fn()
        c = _Call(fn)
        with self._closing:         # the thread's last drain cannot slip in between
            if self._closed or not t.is_alive():
                raise SimulationDown("the simulation has stopped")
            self._commands.put(c)
        if not c.done.wait(timeout):
            raise SimulationDown(f"the simulation did not answer within {timeout:g} s")
        if c.error is not None:
            raise c.error
        return c.result

    # ---------------------------------------------------------------- speed
    def set_speed(self, mode: str, factor: Optional[float] = None) -> None:
        """realtime, factor (with ``factor``), max or pause. Call on the
        simulation thread (through :meth:`call`) once it runs."""
        if mode not in protocol.SPEED_MODES:
            raise ValueError(f"unknown speed mode {mode!r}")
        if mode == "realtime":
            factor = 1.0
        elif mode == "factor":
            if factor is None or not protocol.MIN_FACTOR <= factor <= protocol.MAX_FACTOR:
                raise ValueError(f"a speed factor must be from {protocol.MIN_FACTOR:g} "
                                 f"to {protocol.MAX_FACTOR:g}")
            if factor == 1.0:
                mode = "realtime"
        else:
            factor = self.factor if factor is None else factor
        self.mode = mode
        self.factor = float(factor)
        self._rebase()

    def speed(self) -> dict:
        return {"mode": self.mode, "factor": self.factor if self.mode in ("realtime", "factor")
                else None, "dropped_ms": self.dropped_ms}

    def _rebase(self) -> None:
        self._base_wall = self.clock()
        self._base_t = self.controller.t_ms

    def rebase(self) -> None:
        """Restart pacing from now (after ticks were run by hand, or a new controller)."""
        self._rebase()

    # ---------------------------------------------------------------- subscribers
    def subscribe(self, q: TelemetryQueue) -> None:
        """Add a subscriber (on the simulation thread); its first change holds
        the whole sample of the next tick."""
        self.publish()                          # what happened before is not for it
        with self._qlock:
            if q not in self._queues:
                self._queues = self._queues + [q]
        self._update_recording()
        try:
            self.controller.record_next_sample()
        except AttributeError:
            pass

    def unsubscribe(self, q: TelemetryQueue) -> None:
        with self._qlock:
            self._queues = [x for x in self._queues if x is not q]
        self._update_recording()

    @property
    def subscribers(self) -> int:
        return len(self._queues)

    def _update_recording(self) -> None:
        want = any(q.want_samples for q in self._queues)
        try:
            self.controller.record_samples = want      # samples cost; record only when wanted
            self.controller.sample_changes_only = True  # and only the ticks that change
        except AttributeError:
            pass

    def listen(self, fn: Callable[[list], None]) -> None:
        """Call ``fn(events)`` with the events of every batch, on the simulation
        thread (it must be quick: the Server API keeps the last PLC message)."""
        self._listeners.append(fn)

    def publish(self) -> None:
        """Hand the controller's new events and sample changes to every subscriber."""
        c = self.controller
        events = c.drain_events()
        samples = c.drain_sample_rows()
        if events:
            for fn in self._listeners:
                try:
                    fn(events)
                except Exception:  # noqa: BLE001 - a listener's bug costs nothing here
                    _debug(traceback.format_exc())
        queues = self._queues
        if queues:
            t = c.t_ms
            idle = getattr(c, "idle", None)
            active = not idle() if idle is not None and not samples and not events else True
            for q in queues:
                q.push(samples, events, t, active)

    def room(self) -> Optional[int]:
        """Ticks that may run before a lossless subscriber's queue could overflow
        (a tick records one change at most); None without one."""
        rooms = [q.room for q in self._queues if q.lossless and q.want_samples]
        return min(rooms) if rooms else None

    def replace_controller(self, controller: Controller) -> None:
        """Swap the controller (reset, a step back, another target); on the
        simulation thread. The new one watches the variables the old one did."""
        self.publish()
        watch = getattr(self.controller, "watch", None)
        if watch and controller is not self.controller:
            controller.watch_variables(watch.names, check=False)
        self.controller = controller
        self._update_recording()
        self._rebase()

    # ---------------------------------------------------------------- the thread
    def _run_ticks(self, n: int, measure: bool = True) -> None:
        t0 = time.perf_counter()
        try:
            self.controller.step(n)
        except Exception as exc:  # noqa: BLE001 - a controller bug must not kill the server
            self.error = f"{type(exc).__name__}: {exc}"
            _debug(traceback.format_exc())
            self.mode = "pause"
            return
        if measure:
            dt = time.perf_counter() - t0
            self._tick_cost = 0.8 * self._tick_cost + 0.2 * (dt / n)
        self.publish()

    def _chunk(self) -> int:
        """Ticks that fit one slice of wall time."""
        return max(1, min(100_000, int(self.slice / max(self._tick_cost, 1e-8))))

    def _exec(self, c: _Call) -> None:
        if self._lazy:              # asleep over quiet ticks: first the ticks due by now
            self.catch_up()
        try:
            c.result = c.fn()
        except BaseException as exc:  # noqa: BLE001 - handed back to the caller
            c.error = exc
        finally:
            c.done.set()
        time.sleep(0)            # let the waiting thread take the GIL and answer now

    def _drain_commands(self) -> None:
        while True:
            try:
                c = self._commands.get_nowait()
            except queue.Empty:
                return
            if c is not None:
                self._exec(c)

    def _wait(self, timeout: float) -> None:
        try:
            c = self._commands.get(timeout=max(0.0, timeout))
        except queue.Empty:
            return
        if c is not None:
            self._exec(c)

    def pace(self) -> Optional[float]:
        """One real-time pacing decision: run the ticks that are due (at most one
        chunk) and return None, or return the seconds to wait for the next one.

        When more than :attr:`max_lag` seconds of ticks are due, the backlog is
        skipped: pacing restarts from now and the skipped ticks are counted in
        ``dropped_ms``, so the simulation neither races to catch up nor ever runs
        ahead of the wall clock.

        When the ticks ahead are quiet (:func:`quiet_ticks`) the wait runs to
        the end of the tick where something happens next, or
        :attr:`idle_sleep` at most; the quiet ticks are run when it ends (or
        before a request, :meth:`catch_up`)."""
        rate = 1000.0 * self.factor                      # ticks per second
        now = self.clock()
        c = self.controller
        t = c.t_ms
        due = self._base_t + int((now - self._base_wall) * rate) - t
        if due > 0:
            self._lazy = False
            self.wakeups += 1
            if due > max(1, int(self.max_lag * rate)):  # stalled, or cannot keep up: skip it
                self.dropped_ms += due
                self._base_wall = now
                self._base_t = t
                return self.batch
            self._run_ticks(min(due, self._chunk()))
            return None
        # at most lazy_ticks at a time: at a high factor the ticks slept over are
        # many, and a request that comes first runs them before it is answered
        quiet = min(quiet_ticks(c), self.lazy_ticks)
        if quiet > 0:
            # nothing happens before tick t + quiet: wake when it is due (it runs
            # once the wall clock has passed its end), a request wakes us sooner
            self._lazy = True
            wake = self._base_wall + (t + quiet + 1 - self._base_t) / rate
            # (a hair late rather than a hair early: the tick is due then for sure)
            return min(max(wake - now + self.wake_margin, self.batch), self.idle_sleep)
        self._lazy = False
        next_due = self._base_wall + (t + 1 - self._base_t) / rate
        return max(next_due - now, self.batch)

    def catch_up(self) -> None:
        """Run the quiet ticks a paced simulation slept over (see :meth:`pace`),
        so that a request acts at the time the wall clock says. On the
        simulation thread, before each request; it runs ticks only when all
        that are due are quiet (but the last), never a backlog of busy ones."""
        if self.mode not in ("realtime", "factor") or self._halted():
            return
        rate = 1000.0 * self.factor
        c = self.controller
        due = self._base_t + int((self.clock() - self._base_wall) * rate) - c.t_ms
        if 0 < due <= max(1, int(self.max_lag * rate)) and due <= quiet_ticks(c) + 1:
            # cheap (they are counted, not run), and not what a tick costs:
            # they do not count in _tick_cost
            self._run_ticks(due, measure=False)

    def _halted(self) -> bool:
        """The debugger halted the controller: time stands still (requests are
        still answered); when it goes on, pacing starts again from then."""
        dbg = getattr(self.controller, "debugger", None)
        halted = dbg is not None and dbg.halt is not None
        if halted:
            self._was_halted = True
        elif self._was_halted:
            self._was_halted = False
            self._rebase()
        return halted

    def _idle(self, seconds: float, paced: bool = False) -> bool:
        """Do idle work for about ``seconds``; False when there was none (or,
        ``paced``, when its share of the wall time is used up)."""
        work = self.idle_work
        if work is None or not self._commands.empty():
            return False
        if paced:
            now = time.monotonic()
            self._idle_tokens = min(self.idle_burst, self._idle_tokens
                                    + (now - self._idle_refill) * self.idle_share)
            self._idle_refill = now
            if self._idle_tokens <= 0:
                return False
            seconds = min(seconds, self._idle_tokens)
        t0 = time.perf_counter()
        try:
            return bool(work(seconds))
        except Exception:  # noqa: BLE001 - idle work must not bring the simulation down
            _debug(traceback.format_exc())
            self.idle_work = None
            return False
        finally:
            if paced:
                self._idle_tokens -= time.perf_counter() - t0

    def _shutdown_controller(self) -> None:
        try:
            self.controller.shutdown()
        except Exception:  # noqa: BLE001
            _debug(traceback.format_exc())
        self.publish()

    def _run(self) -> None:
        self._rebase()
        while not self._stop:
            self._drain_commands()
            if self._stop:
                break
            mode = self.mode
            if mode == "pause" or self._halted():
                if not self._idle(0.02):
                    self._wait(0.5 if mode == "pause" else 0.05)
                continue
            if mode == "max":
                n = self._chunk()
                room = self.room()
                if room is not None:
                    # a lossless subscriber: never run more ticks than its queue
                    # holds; wait (answering requests) while it takes them, but
                    # not for ever
                    now = time.monotonic()
                    if room < min(n, 64):
                        if self._held_since is None:
                            self._held_since = now
                        if now - self._held_since < self.lossless_wait:
                            self._wait(0.001)
                            continue
                    else:
                        self._held_since = None
                        n = min(n, room)
                self._run_ticks(n)
                time.sleep(0)        # give the network thread the GIL between batches
                continue
            wait = self.pace()
            if wait is not None:
                if wait < 0.002 or not self._idle(wait / 2, paced=True):
                    self._wait(wait)
        self._drain_commands()
        if self._shutdown_on_stop:
            self._shutdown_controller()
        # Whoever still waits gets an answer rather than a timeout.
        with self._closing:
            self._closed = True
        while True:
            try:
                c = self._commands.get_nowait()
            except queue.Empty:
                break
            if c is not None:
                c.error = SimulationDown("the simulation has stopped")
                c.done.set()
