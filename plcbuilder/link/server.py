"""The simulated controller as a TCP server.

Three parts, each usable alone:

:class:`Simulation`
    Owns the :class:`~plcbuilder.controller.controller.Controller` and runs it on
    its own thread, paced to the wall clock (real time, N times real time, as
    fast as it computes, or paused). Everything that touches the controller
    runs on that thread, between batches of ticks: other threads hand it work
    with :meth:`Simulation.call`. After every batch the new events and samples
    go to the telemetry queues of the subscribed clients; a queue is bounded,
    drops the oldest samples when full and counts them, so a slow client never
    holds the simulation up.

    Real-time pacing uses absolute deadlines: the ticks due are computed from a
    monotonic start time (``base_t + (now - base_wall) * rate``), run, and the
    thread sleeps until the next batch is due, so no error accumulates. When the
    simulation cannot keep up for more than :attr:`Simulation.max_lag` seconds it
    drops the backlog (counted in ``state.speed.dropped_ms``) instead of racing.

:class:`Service`
    The verbs: one ``handle_<type>(msg, session)`` method per request type,
    returning the ``result`` object or raising :class:`Refused` /
    :class:`~plcbuilder.link.protocol.BadRequest`. No sockets: tests call it
    directly.

:class:`Server`
    The network side: one thread with a selector serves every connection
    (non-blocking sockets, per-connection output buffers). It checks frames and
    the hello, dispatches requests to the service, and sends telemetry at most
    every 20 ms. A bad frame, a wrong token, a frame left half sent beyond
    ``frame_timeout`` or a client that does not read its replies closes that
    connection only.

:class:`ControllerServer` puts the three together; ``plcbuilder controller``
runs one.
"""

from __future__ import annotations

import hmac
import os
import queue
import selectors
import socket
import sys
import threading
import time
import traceback
import zlib
from collections import deque
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Optional

from plcbuilder.controller.machine_config import ConfigError
from plcbuilder.controller.controller import Controller, ControllerError
from plcbuilder.image.manifest import Image, ImageError, Limits, read_image
from plcbuilder.link import protocol
from plcbuilder.link.protocol import (MAX_FRAME, MAX_IMAGE, PROTOCOL_VERSION, REQUESTS,
                                      SAMPLE_FIELDS, BadRequest, ErrorCode, FrameDecoder,
                                      ProtocolError, encode_frame)

__all__ = ["ConfigError", "Controller", "ControllerError", "ControllerServer", "Limits",
           "Refused", "Server", "Service", "Session", "Simulation", "SimulationDown",
           "TelemetryQueue", "make_controller"]

#: Handlers that a host may start with the ``event`` request.
EVENT_HANDLERS = ("__HANDLER_GCODE_START", "__HANDLER_GCODE_STOP")
DEBUG_ENV = "PLCBUILDER_DEBUG"


class Refused(Exception):
    """The controller refuses a request; ``reason`` goes back to the client."""

    def __init__(self, reason: str):
        super().__init__(reason)
        self.reason = reason


class SimulationDown(RuntimeError):
    """The simulation thread is not running any more."""


def _debug(text: str) -> None:
    if os.environ.get(DEBUG_ENV):
        print(text, file=sys.stderr, flush=True)


# ===================================================================== telemetry

class TelemetryQueue:
    """One subscriber's bounded queue of samples and events.

    :meth:`push` (the simulation thread) never blocks for longer than a list
    append; when more than ``max_samples`` samples wait, the oldest go and are
    counted in ``missed`` (likewise events beyond ``max_events``).
    """

    def __init__(self, max_samples: int = 1000, max_events: int = 20000, samples: bool = True,
                 events: bool = True):
        self.want_samples = samples
        self.want_events = events
        self._samples: deque = deque(maxlen=max(1, max_samples))
        self._events: deque = deque(maxlen=max(1, max_events))
        self._lock = threading.Lock()
        self.missed = 0
        self.missed_events = 0
        self.t_ms = 0

    def push(self, samples: list, events: list, t_ms: int) -> None:
        with self._lock:
            self.t_ms = t_ms
            if self.want_samples and samples:
                q = self._samples
                over = len(q) + len(samples) - q.maxlen
                if over > 0:
                    self.missed += over
                q.extend(samples)
            if self.want_events and events:
                q = self._events
                over = len(q) + len(events) - q.maxlen
                if over > 0:
                    self.missed_events += over
                q.extend(events)

    def take(self) -> Optional[tuple[list, list, int, int, int]]:
        """(samples, events, missed, missed_events, t_ms) since the last take, or
        None when there is nothing new."""
        with self._lock:
            if not self._samples and not self._events and not self.missed \
                    and not self.missed_events:
                return None
            out = (list(self._samples), list(self._events), self.missed, self.missed_events,
                   self.t_ms)
            self._samples.clear()
            self._events.clear()
            self.missed = self.missed_events = 0
            return out


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

    def __init__(self, controller: Controller, mode: str = "realtime", factor: float = 1.0):
        self.controller = controller
        self._commands: "queue.SimpleQueue[Optional[_Call]]" = queue.SimpleQueue()
        self._queues: list[TelemetryQueue] = []
        self._qlock = threading.Lock()
        self._inline = threading.RLock()        # used while the thread is not running
        self._thread: Optional[threading.Thread] = None
        self._stop = False
        self._shutdown_on_stop = True
        self.mode = "pause"
        self.factor = 1.0
        self.dropped_ms = 0
        self.error: Optional[str] = None
        self._tick_cost = 2e-6                  # seconds a tick takes, averaged
        self._base_wall = time.monotonic()
        self._base_t = controller.t_ms
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
        if not t.is_alive():
            raise SimulationDown("the simulation has stopped")
        c = _Call(fn)
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
        self._base_wall = time.monotonic()
        self._base_t = self.controller.t_ms

    def rebase(self) -> None:
        """Restart pacing from now (after ticks were run by hand, or a new controller)."""
        self._rebase()

    # ---------------------------------------------------------------- subscribers
    def subscribe(self, q: TelemetryQueue) -> None:
        with self._qlock:
            if q not in self._queues:
                self._queues = self._queues + [q]
        self._update_recording()

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
        except AttributeError:
            pass

    def publish(self) -> None:
        """Hand the controller's new events and samples to every subscriber."""
        c = self.controller
        events = c.drain_events()
        samples = c.drain_samples()
        queues = self._queues
        if queues and (events or samples):
            t = c.t_ms
            for q in queues:
                q.push(samples, events, t)

    def replace_controller(self, controller: Controller) -> None:
        """Swap the controller (reset); on the simulation thread."""
        self.publish()
        self.controller = controller
        self._update_recording()
        self._rebase()

    # ---------------------------------------------------------------- the thread
    def _run_ticks(self, n: int) -> None:
        t0 = time.perf_counter()
        try:
            self.controller.step(n)
        except Exception as exc:  # noqa: BLE001 - a controller bug must not kill the server
            self.error = f"{type(exc).__name__}: {exc}"
            _debug(traceback.format_exc())
            self.mode = "pause"
            return
        dt = time.perf_counter() - t0
        self._tick_cost = 0.8 * self._tick_cost + 0.2 * (dt / n)
        self.publish()

    def _chunk(self) -> int:
        """Ticks that fit one slice of wall time."""
        return max(1, min(100_000, int(self.slice / max(self._tick_cost, 1e-8))))

    def _exec(self, c: _Call) -> None:
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
            if mode == "pause":
                self._wait(0.5)
                continue
            if mode == "max":
                self._run_ticks(self._chunk())
                time.sleep(0)        # give the network thread the GIL between batches
                continue
            rate = 1000.0 * self.factor                  # ticks per second
            now = time.monotonic()
            due = self._base_t + int((now - self._base_wall) * rate) - self.controller.t_ms
            if due > 0:
                lag = int(self.max_lag * rate)
                if due > lag:                            # cannot keep up: drop the backlog
                    self.dropped_ms += due - lag
                    self._base_t += due - lag
                    due = lag
                self._run_ticks(min(due, self._chunk()))
                continue
            next_due = self._base_wall + (self.controller.t_ms + 1 - self._base_t) / rate
            self._wait(max(next_due - now, self.batch))
        self._drain_commands()
        if self._shutdown_on_stop:
            self._shutdown_controller()
        # Whoever still waits gets an answer rather than a timeout.
        while True:
            try:
                c = self._commands.get_nowait()
            except queue.Empty:
                break
            if c is not None:
                c.error = SimulationDown("the simulation has stopped")
                c.done.set()


# ===================================================================== the verbs

@dataclass
class Session:
    """What the service keeps per client."""
    telemetry: Optional[TelemetryQueue] = None
    peer: str = ""


def image_summary(image: Optional[Image]) -> list[dict]:
    if image is None:
        return []
    return [{"name": p.name, "kind": p.kind.label, "size": p.code_size, "code_size": p.code_size,
             "file_size": p.file_size, "crc32": f"{p.crc32:08x}"} for p in image.procedures]


class Service:
    """The controller's verbs, one ``handle_<type>`` per request type.

    ``controller_factory`` makes a fresh controller for ``reset`` (None: reset
    is refused). ``limits`` are the controller's code size limits that an
    uploaded image is checked against.
    """

    def __init__(self, sim: Simulation, *, limits: Optional[Limits] = None,
                 controller_factory: Optional[Callable[[], Controller]] = None,
                 max_image: int = MAX_IMAGE):
        self.sim = sim
        self.limits = limits or Limits()
        self.controller_factory = controller_factory
        self.max_image = max_image
        self.image: Optional[Image] = None
        self.image_crc32: Optional[int] = None
        self.image_size = 0
        self.uploads = 0
        self.refused = 0
        self.clients = 0            # kept up to date by the Server
        self.step_budget = 2.0      # seconds of wall time one step request may take

    # ---------------------------------------------------------------- dispatch
    def dispatch(self, msg: dict, session: Session) -> dict:
        mtype = msg.get("type")
        if mtype not in REQUESTS:
            raise ProtocolError(f"unknown request type {mtype!r}", ErrorCode.UNKNOWN_TYPE)
        handler = getattr(self, f"handle_{mtype}", None)
        if handler is None:
            raise ProtocolError(f"{mtype} is not handled here", ErrorCode.UNKNOWN_TYPE)
        return handler(msg, session)

    def _on_sim(self, fn: Callable):
        """Run fn on the simulation thread; a ControllerError becomes Refused."""
        try:
            return self.sim.call(fn)
        except ControllerError as exc:
            raise Refused(str(exc)) from None
        except SimulationDown as exc:
            raise Refused(str(exc)) from None

    # ---------------------------------------------------------------- image
    def check_image(self, data: bytes) -> Image:
        """read_image against the controller's limits; Refused with the reason."""
        if len(data) > self.max_image:
            raise Refused(f"image refused: it is {len(data)} bytes, more than {self.max_image}")
        try:
            return read_image(data, self.limits)
        except ImageError as exc:
            raise Refused(f"image refused: {exc}") from None
        except Exception as exc:  # noqa: BLE001 - a reader bug still means "refused"
            _debug(traceback.format_exc())
            raise Refused(f"image refused: unreadable ({type(exc).__name__}: {exc})") from None

    def load_image(self, data: bytes) -> dict:
        """Validate a whole image, then load it at once; on refusal nothing changes."""
        try:
            image = self.check_image(data)
        except Refused:
            self.refused += 1
            raise

        def swap():
            controller = self.sim.controller
            previous = list(controller.programs.values())
            try:
                controller.load([p.program for p in image.procedures])
            except ControllerError:
                raise
            except Exception as exc:  # noqa: BLE001 - a loader bug: put the old image back
                _debug(traceback.format_exc())
                try:
                    controller.load(previous)
                except Exception:  # noqa: BLE001
                    _debug(traceback.format_exc())
                raise ControllerError(f"the controller could not load it "
                                      f"({type(exc).__name__}: {exc})") from None
            self.image = image
            self.image_crc32 = zlib.crc32(data)
            self.image_size = len(data)
            return self.sim.controller.t_ms

        try:
            t = self._on_sim(swap)
        except Refused as exc:
            self.refused += 1
            raise Refused(f"image refused: {exc.reason}") from None
        self.uploads += 1
        return {"accepted": True, "t_ms": t, "size": len(data),
                "image_crc32": f"{self.image_crc32:08x}", "procedures": image_summary(image),
                "hw_total": image.hw_total}

    def handle_upload(self, msg: dict, session: Session) -> dict:
        try:
            data = protocol.decode_image(msg, self.max_image)
        except BadRequest:
            self.refused += 1
            raise
        return self.load_image(data)

    # ---------------------------------------------------------------- procedures
    def handle_start(self, msg: dict, session: Session) -> dict:
        eparam = protocol.field_int(msg, "eparam", 0)
        has_name, has_mcode = "name" in msg, "mcode" in msg
        if has_name == has_mcode:
            raise BadRequest("start: give either 'name' or 'mcode'")
        if has_name:
            name = protocol.field_str(msg, "name", max_len=128)

            def go():
                self.sim.controller.start(name, eparam)
                return name, self.sim.controller.t_ms
        else:
            n = protocol.field_int(msg, "mcode", lo=0, hi=1_000_000)

            def go():
                started = self.sim.controller.start_mcode(n, eparam)
                return started, self.sim.controller.t_ms
        started, t = self._on_sim(go)
        return {"started": started, "eparam": eparam, "t_ms": t}

    def handle_stop(self, msg: dict, session: Session) -> dict:
        def go():
            return self.sim.controller.stop(), self.sim.controller.t_ms
        started, t = self._on_sim(go)
        return {"started": started, "t_ms": t}

    def handle_event(self, msg: dict, session: Session) -> dict:
        handler = protocol.field_str(msg, "handler", max_len=64)
        if handler not in EVENT_HANDLERS:
            raise BadRequest(f"event: handler must be one of {', '.join(EVENT_HANDLERS)}")
        started = self._on_sim(lambda: self.sim.controller.event(handler))
        return {"handler": handler, "started": bool(started)}

    # ---------------------------------------------------------------- I/O
    def handle_input(self, msg: dict, session: Session) -> dict:
        pin = protocol.field_int(msg, "pin", lo=0, hi=1 << 16)
        value = protocol.field_int(msg, "value", lo=0, hi=1)
        t = self._on_sim(lambda: (self.sim.controller.set_input(pin, value),
                                  self.sim.controller.t_ms)[1])
        return {"pin": pin, "value": value, "t_ms": t}

    def handle_adc(self, msg: dict, session: Session) -> dict:
        ch = protocol.field_int(msg, "channel", lo=0, hi=1 << 16)
        value = protocol.field_int(msg, "value")
        t = self._on_sim(lambda: (self.sim.controller.set_adc(ch, value),
                                  self.sim.controller.t_ms)[1])
        return {"channel": ch, "value": value, "t_ms": t}

    # ---------------------------------------------------------------- state
    def state(self) -> dict:
        def go():
            st = dict(self.sim.controller.state())
            st["t_ms"] = self.sim.controller.t_ms
            return st
        st = self._on_sim(go)
        st.setdefault("running", None)
        st.setdefault("software", [])
        st["image"] = image_summary(self.image)
        st["image_crc32"] = None if self.image_crc32 is None else f"{self.image_crc32:08x}"
        st["speed"] = self.sim.speed()
        st["server"] = {"clients": self.clients, "subscribers": self.sim.subscribers,
                        "uploads": self.uploads, "refused": self.refused, "pid": os.getpid(),
                        "error": self.sim.error}
        return st

    def handle_state(self, msg: dict, session: Session) -> dict:
        return self.state()

    def handle_variables(self, msg: dict, session: Session) -> dict:
        return {"variables": self._on_sim(self.sim.controller.variables)}

    # ---------------------------------------------------------------- time
    def handle_speed(self, msg: dict, session: Session) -> dict:
        mode = protocol.field_str(msg, "mode", max_len=16)
        if mode not in protocol.SPEED_MODES:
            raise BadRequest(f"speed: mode must be one of {', '.join(protocol.SPEED_MODES)}")
        factor = None
        if mode == "factor":
            factor = protocol.field_number(msg, "factor", protocol.MIN_FACTOR, protocol.MAX_FACTOR)

        def go():
            self.sim.set_speed(mode, factor)
            return self.sim.speed()
        return self._on_sim(go)

    def handle_step(self, msg: dict, session: Session) -> dict:
        ms = protocol.field_int(msg, "ms", lo=1, hi=600_000)
        budget = self.step_budget

        def go():
            # In slices, and at most ``step_budget`` seconds of wall time, so that
            # a runaway procedure cannot hold every client up for minutes.
            c = self.sim.controller
            start, done = time.perf_counter(), 0
            while done < ms:
                n = min(ms - done, self.sim._chunk())
                c.step(n)
                done += n
                self.sim.publish()
                if time.perf_counter() - start > budget:
                    break
            self.sim.rebase()
            return c.t_ms, done
        t, done = self._on_sim(go)
        return {"t_ms": t, "stepped": done, "complete": done == ms}

    def handle_reset(self, msg: dict, session: Session) -> dict:
        if self.controller_factory is None:
            raise Refused("reset is not available on this controller")
        factory = self.controller_factory

        def go():
            new = factory()
            if self.image is not None:
                new.load([p.program for p in self.image.procedures])
            self.sim.replace_controller(new)
            return new.t_ms
        return {"t_ms": self._on_sim(go)}

    def handle_ping(self, msg: dict, session: Session) -> dict:
        return {"pong": True}

    # ---------------------------------------------------------------- telemetry
    def handle_subscribe(self, msg: dict, session: Session) -> dict:
        samples = protocol.field_bool(msg, "samples", True)
        events = protocol.field_bool(msg, "events", True)
        size = protocol.field_int(msg, "queue", 1000, lo=16, hi=100_000)
        if session.telemetry is not None:
            self.sim.unsubscribe(session.telemetry)
        q = TelemetryQueue(max_samples=size, samples=samples, events=events)
        session.telemetry = q
        self.sim.call(lambda: self.sim.subscribe(q))
        return {"sample_fields": list(SAMPLE_FIELDS), "interval_ms": 20, "samples": samples,
                "events": events, "queue": size}

    def handle_unsubscribe(self, msg: dict, session: Session) -> dict:
        self.end_session(session)
        return {}

    def end_session(self, session: Session) -> None:
        if session.telemetry is not None:
            q, session.telemetry = session.telemetry, None
            try:
                self.sim.call(lambda: self.sim.unsubscribe(q), timeout=5.0)
            except SimulationDown:
                self.sim.unsubscribe(q)


# ===================================================================== the network

class _Conn:
    __slots__ = ("sock", "peer", "decoder", "out", "authed", "opened", "last_rx",
                 "frame_started", "close_at", "session", "closed", "mask")

    def __init__(self, sock: socket.socket, peer: str, now: float, max_frame: int):
        self.sock = sock
        self.peer = peer
        self.decoder = FrameDecoder(max_frame)
        self.out = bytearray()
        self.authed = False
        self.opened = now
        self.last_rx = now
        self.frame_started: Optional[float] = None
        self.close_at: Optional[float] = None      # set: closing once out is sent
        self.session = Session(peer=peer)
        self.closed = False
        self.mask = 0


class Server:
    """Serves a :class:`Service` over TCP (one selector thread, many clients)."""

    #: Seconds the telemetry of a subscriber is batched.
    telemetry_interval = 0.02
    #: Output waiting for a client above which no telemetry is added (it is counted missed).
    telemetry_high_water = 1 << 20
    #: Output waiting for a client above which the connection is closed.
    max_outbuf = 32 << 20
    #: Seconds a closing connection gets to take its last message.
    close_grace = 1.0

    def __init__(self, service: Service, host: str = "127.0.0.1", port: int = 0,
                 token: Optional[str] = None, *, max_frame: int = MAX_FRAME,
                 frame_timeout: float = 10.0, hello_timeout: float = 10.0, max_clients: int = 64):
        if not token:
            from plcbuilder.link.runtime import new_token
            token = new_token()
        self.service = service
        self.token = token
        self._token_bytes = token.encode("utf-8")
        self.max_frame = max_frame
        self.frame_timeout = frame_timeout
        self.hello_timeout = hello_timeout
        self.max_clients = max_clients
        self._sel = selectors.DefaultSelector()
        infos = socket.getaddrinfo(host, port, type=socket.SOCK_STREAM)
        family, _t, _p, _c, addr = infos[0]
        lsock = socket.socket(family, socket.SOCK_STREAM)
        try:
            if os.name != "nt":
                lsock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            lsock.bind(addr)
            lsock.listen(64)
            lsock.setblocking(False)
        except OSError:
            lsock.close()
            raise
        self._lsock = lsock
        self.address: tuple[str, int] = lsock.getsockname()[:2]
        self._wake_r, self._wake_w = socket.socketpair()
        self._wake_r.setblocking(False)
        self._wake_w.setblocking(False)
        self._sel.register(lsock, selectors.EVENT_READ, "listen")
        self._sel.register(self._wake_r, selectors.EVENT_READ, "wake")
        self._conns: dict[int, _Conn] = {}
        self._thread: Optional[threading.Thread] = None
        self._stopping = False
        self._next_flush = time.monotonic()
        self.stats = {"accepted": 0, "closed": 0, "bad_frames": 0, "unauthorized": 0,
                      "timeouts": 0, "requests": 0, "telemetry_frames": 0}

    # ---------------------------------------------------------------- lifecycle
    @property
    def host(self) -> str:
        return self.address[0]

    @property
    def port(self) -> int:
        return self.address[1]

    @property
    def clients(self) -> int:
        return len(self._conns)

    def start(self) -> None:
        if self._thread is None:
            self._thread = threading.Thread(target=self._loop, name="plcbuilder-server",
                                            daemon=True)
            self._thread.start()

    def stop(self, reason: str = "the controller is shutting down", timeout: float = 5.0) -> None:
        """Flush telemetry, say bye to every client, close everything."""
        if self._thread is None:
            self._close_all(reason)
            return
        self._stopping = reason or "stopped"
        self._wake()
        self._thread.join(timeout)

    def _wake(self) -> None:
        try:
            self._wake_w.send(b"x")
        except OSError:
            pass

    # ---------------------------------------------------------------- the loop
    def _loop(self) -> None:
        try:
            while not self._stopping:
                timeout = self._timeout()
                for key, mask in self._sel.select(timeout):
                    tag = key.data
                    if tag == "listen":
                        self._accept()
                    elif tag == "wake":
                        try:
                            while self._wake_r.recv(4096):
                                pass
                        except OSError:
                            pass
                    else:
                        conn: _Conn = tag
                        try:
                            if mask & selectors.EVENT_READ and not conn.closed:
                                self._read(conn)
                            if mask & selectors.EVENT_WRITE and not conn.closed:
                                self._write(conn)
                            if not conn.closed:
                                self._update(conn)
                        except Exception:  # noqa: BLE001 - a bug here costs one connection
                            traceback.print_exc()
                            self._drop(conn)
                try:
                    self._timers(time.monotonic())
                except Exception:  # noqa: BLE001 - keep serving
                    traceback.print_exc()
        except Exception:  # noqa: BLE001 - log it; the finally closes everything
            traceback.print_exc()
        finally:
            self._flush_telemetry(time.monotonic())
            self._close_all(self._stopping if isinstance(self._stopping, str) else "stopped")

    def _timeout(self) -> float:
        now = time.monotonic()
        t = 0.5
        if any(c.session.telemetry is not None for c in self._conns.values()):
            t = min(t, max(0.0, self._next_flush - now))
        for c in self._conns.values():
            if c.close_at is not None:
                t = min(t, max(0.0, c.close_at - now))
            elif not c.authed:
                t = min(t, max(0.0, c.opened + self.hello_timeout - now))
            if c.decoder.mid_frame:
                t = min(t, max(0.0, c.last_rx + self.frame_timeout - now))
        return max(t, 0.001)

    def _timers(self, now: float) -> None:
        for c in list(self._conns.values()):
            if c.closed:
                continue
            if c.close_at is not None:
                if now >= c.close_at:
                    self._drop(c)
                continue
            if c.decoder.mid_frame and (now - c.last_rx > self.frame_timeout or
                                        c.frame_started is not None and
                                        now - c.frame_started > 6 * self.frame_timeout):
                self.stats["timeouts"] += 1
                self._fatal(c, ErrorCode.BAD_FRAME,
                            f"frame left unfinished for more than {self.frame_timeout:g} s")
            elif not c.authed and now - c.opened > self.hello_timeout:
                self.stats["timeouts"] += 1
                self._fatal(c, ErrorCode.UNAUTHORIZED,
                            f"no hello within {self.hello_timeout:g} s")
        if now >= self._next_flush:
            self._flush_telemetry(now)
            self._next_flush = now + self.telemetry_interval

    # ---------------------------------------------------------------- connections
    def _accept(self) -> None:
        while True:
            try:
                sock, addr = self._lsock.accept()
            except (BlockingIOError, InterruptedError):
                return
            except OSError:
                return
            self.stats["accepted"] += 1
            sock.setblocking(False)
            try:
                sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            except OSError:
                pass
            peer = f"{addr[0]}:{addr[1]}" if isinstance(addr, tuple) else str(addr)
            if len(self._conns) >= self.max_clients or self._stopping:
                try:
                    sock.send(encode_frame({"type": "error", "id": None, "code": ErrorCode.BUSY,
                                            "reason": f"too many clients ({self.max_clients})"}))
                except OSError:
                    pass
                sock.close()
                continue
            now = time.monotonic()
            conn = _Conn(sock, peer, now, self.max_frame)
            self._conns[sock.fileno()] = conn
            conn.mask = selectors.EVENT_READ
            self._sel.register(sock, conn.mask, conn)
            self.service.clients = len(self._conns)

    def _update(self, conn: _Conn) -> None:
        mask = 0 if conn.close_at is not None else selectors.EVENT_READ
        if conn.out:
            mask |= selectors.EVENT_WRITE
        if conn.close_at is not None and not conn.out:
            self._drop(conn)
            return
        if mask == 0:
            mask = selectors.EVENT_READ     # keep it registered; reads are ignored
        if mask != conn.mask:
            conn.mask = mask
            self._sel.modify(conn.sock, mask, conn)

    def _drop(self, conn: _Conn) -> None:
        if conn.closed:
            return
        conn.closed = True
        self.stats["closed"] += 1
        self._conns.pop(conn.sock.fileno(), None)
        try:
            self._sel.unregister(conn.sock)
        except (KeyError, ValueError, OSError):
            pass
        try:
            conn.sock.close()
        except OSError:
            pass
        try:
            self.service.end_session(conn.session)
        except Exception:  # noqa: BLE001
            _debug(traceback.format_exc())
        self.service.clients = len(self._conns)

    def _close_all(self, reason: str) -> None:
        for c in list(self._conns.values()):
            if not c.closed:
                try:
                    c.sock.setblocking(True)
                    c.sock.settimeout(0.2)
                    if c.out:
                        c.sock.sendall(bytes(c.out))
                    if c.authed:
                        c.sock.sendall(encode_frame({"type": "bye", "reason": reason}))
                except OSError:
                    pass
                self._drop(c)
        for s in (self._lsock, self._wake_r, self._wake_w):
            try:
                s.close()
            except OSError:
                pass
        try:
            self._sel.close()
        except (OSError, RuntimeError):
            pass

    # ---------------------------------------------------------------- reading
    def _read(self, conn: _Conn) -> None:
        try:
            data = conn.sock.recv(256 * 1024)
        except (BlockingIOError, InterruptedError):
            return
        except OSError:
            self._drop(conn)
            return
        if not data:
            self._drop(conn)
            return
        if conn.close_at is not None:
            return                                  # closing: ignore what comes
        now = time.monotonic()
        conn.last_rx = now
        try:
            payloads = conn.decoder.feed(data)
        except ProtocolError as exc:
            self.stats["bad_frames"] += 1
            self._fatal(conn, exc.code, exc.reason)
            return
        for payload in payloads:
            if conn.close_at is not None or conn.closed:
                return
            self._on_payload(conn, payload)
        if not conn.decoder.mid_frame:
            conn.frame_started = None
        elif payloads or conn.frame_started is None:
            conn.frame_started = now

    def _on_payload(self, conn: _Conn, payload: bytes) -> None:
        try:
            msg = protocol.decode_payload(payload)
        except ProtocolError as exc:
            self.stats["bad_frames"] += 1
            self._fatal(conn, exc.code, exc.reason)
            return
        mtype, mid = msg["type"], msg.get("id")
        if not conn.authed:
            if mtype != "hello":
                self.stats["unauthorized"] += 1
                self._fatal(conn, ErrorCode.UNAUTHORIZED,
                            "the first message must be hello {version, token}", mid)
                return
            self.handle_hello(conn, msg)
            return
        self.stats["requests"] += 1
        if mtype not in REQUESTS:
            self._error(conn, ErrorCode.UNKNOWN_TYPE, f"unknown request type {mtype!r}", mid)
            return
        handler = getattr(self, f"handle_{mtype}", None)
        try:
            if handler is not None:
                result = handler(conn, msg)
            else:
                result = self.service.dispatch(msg, conn.session)
        except ProtocolError as exc:
            if exc.code in protocol.FATAL_CODES:
                self._fatal(conn, exc.code, exc.reason, mid)
            else:
                self._error(conn, exc.code, exc.reason, mid)
            return
        except Refused as exc:
            self._error(conn, ErrorCode.REFUSED, exc.reason, mid)
            return
        except Exception as exc:  # noqa: BLE001 - the client gets a reason, the server lives
            _debug(traceback.format_exc())
            self._error(conn, ErrorCode.INTERNAL, f"internal error: {type(exc).__name__}: {exc}",
                        mid)
            return
        if result is not None:
            self._send(conn, {"type": "result", "id": mid, "result": result})

    def handle_hello(self, conn: _Conn, msg: dict) -> None:
        mid = msg.get("id")
        token = msg.get("token")
        version = msg.get("version")
        if not isinstance(token, str) or not hmac.compare_digest(
                token.encode("utf-8", "surrogatepass"), self._token_bytes):
            self.stats["unauthorized"] += 1
            self._fatal(conn, ErrorCode.UNAUTHORIZED, "wrong or missing token", mid)
            return
        if type(version) is not int or version != PROTOCOL_VERSION:
            self._fatal(conn, ErrorCode.VERSION,
                        f"protocol version {version!r} is not supported; this controller speaks "
                        f"version {PROTOCOL_VERSION}", mid)
            return
        conn.authed = True
        try:
            t = self.service.sim.call(lambda: self.service.sim.controller.t_ms, timeout=5.0)
        except Exception:  # noqa: BLE001
            t = None
        self._send(conn, {"type": "welcome", "id": mid, "version": PROTOCOL_VERSION,
                          "server": protocol.SERVER_NAME, "pid": os.getpid(), "t_ms": t,
                          "speed": self.service.sim.speed()})

    # ---------------------------------------------------------------- writing
    def _send(self, conn: _Conn, msg: dict) -> None:
        if conn.closed:
            return
        try:
            frame = encode_frame(msg, self.max_frame)
        except (ProtocolError, TypeError, ValueError) as exc:
            frame = encode_frame({"type": "error", "id": msg.get("id"), "code": ErrorCode.INTERNAL,
                                  "reason": f"the answer could not be sent: {exc}"})
        conn.out += frame
        if len(conn.out) > self.max_outbuf:
            self._drop(conn)                  # a client that does not read its answers
            return
        self._write(conn)
        if not conn.closed:
            self._update(conn)

    def _write(self, conn: _Conn) -> None:
        while conn.out:
            try:
                n = conn.sock.send(conn.out[:1 << 20])
            except (BlockingIOError, InterruptedError):
                return
            except OSError:
                self._drop(conn)
                return
            if n <= 0:
                return
            del conn.out[:n]

    def _error(self, conn: _Conn, code: ErrorCode, reason: str, mid=None) -> None:
        self._send(conn, {"type": "error", "id": mid, "code": code, "reason": reason})

    def _fatal(self, conn: _Conn, code: ErrorCode, reason: str, mid=None) -> None:
        """Answer with an error, then close the connection once that is sent."""
        if conn.close_at is None:
            conn.close_at = time.monotonic() + self.close_grace
            self._send(conn, {"type": "error", "id": mid, "code": code, "reason": reason})
            if not conn.closed:
                self._update(conn)

    def _flush_telemetry(self, now: float) -> None:
        for conn in list(self._conns.values()):
            q = conn.session.telemetry
            if q is None or conn.closed or conn.close_at is not None:
                continue
            if len(conn.out) > self.telemetry_high_water:
                continue                       # it is not reading: the queue drops and counts
            got = q.take()
            if got is None:
                continue
            samples, events, missed, missed_events, t_ms = got
            # Keep frames well under the size limit: split very large batches.
            ns, ne = 4000, 4000
            parts = max(1, -(-len(samples) // ns), -(-len(events) // ne))
            for i in range(parts):
                msg = {"type": "telemetry", "t_ms": t_ms, "sample_fields": SAMPLE_FIELDS,
                       "samples": [protocol.sample_row(s) for s in samples[i * ns:(i + 1) * ns]],
                       "events": [protocol.event_dict(e) for e in events[i * ne:(i + 1) * ne]],
                       "missed": missed if i == 0 else 0,
                       "missed_events": missed_events if i == 0 else 0}
                self.stats["telemetry_frames"] += 1
                self._send(conn, msg)
                if conn.closed:
                    break


# ===================================================================== together

def make_controller(machine=None, variables=None, **kwargs) -> Callable[[], Controller]:
    """A factory of controllers for a machine file and a plc-variables.xml (paths
    or None for the defaults). Raises ConfigError on a bad file."""
    from plcbuilder.controller import machine_config, variables_xml
    mc = machine_config.load_machine(machine) if machine else machine_config.default_machine()
    vs = variables_xml.load_variables(variables) if variables else None

    def factory() -> Controller:
        return Controller(mc, variables=vs, **kwargs)
    return factory


class ControllerServer:
    """A controller served over TCP: simulation thread + service + server.

    ``with ControllerServer(port=0) as srv: ...`` starts everything; leaving the
    block (or :meth:`close`) runs ``__HANDLER_EXIT``, says bye and closes.
    """

    def __init__(self, controller: Optional[Controller] = None, *, host: str = "127.0.0.1",
                 port: int = 0, token: Optional[str] = None,
                 controller_factory: Optional[Callable[[], Controller]] = None,
                 speed: str = "realtime", factor: float = 1.0, limits: Optional[Limits] = None,
                 image: Optional[bytes] = None, runtime_file: Optional[Path] = None,
                 **server_options):
        if controller is None:
            controller_factory = controller_factory or (lambda: Controller())
            controller = controller_factory()
        self.sim = Simulation(controller, speed, factor)
        self.service = Service(self.sim, limits=limits, controller_factory=controller_factory)
        if image is not None:
            self.service.load_image(image)          # Refused: the caller says why
        self.server = Server(self.service, host, port, token, **server_options)
        self.runtime_file = runtime_file
        self._endpoint = None
        self._closed = False

    @property
    def address(self) -> tuple[str, int]:
        return self.server.address

    @property
    def token(self) -> str:
        return self.server.token

    @property
    def controller(self) -> Controller:
        return self.sim.controller

    def start(self) -> "ControllerServer":
        self.sim.start()
        self.server.start()
        if self.runtime_file is not None:
            from plcbuilder.link import runtime
            self._endpoint = runtime.Endpoint(self.address[0], self.address[1], self.token,
                                              os.getpid())
            runtime.write(self._endpoint, self.runtime_file)
        return self

    def close(self, shutdown: bool = True) -> None:
        """Stop: __HANDLER_EXIT (with ``shutdown``), bye to the clients, close, and
        remove the runtime file."""
        if self._closed:
            return
        self._closed = True
        if self._endpoint is not None:
            from plcbuilder.link import runtime
            runtime.remove(self._endpoint, self.runtime_file)
        self.sim.stop(shutdown=shutdown)
        self.server.stop()

    def __enter__(self) -> "ControllerServer":
        return self.start()

    def __exit__(self, *exc) -> None:
        self.close()
