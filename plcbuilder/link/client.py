"""A client of the simulated controller (``plcbuilder controller``).

::

    from plcbuilder.link.client import Client
    with Client.connect() as c:             # address and token from the runtime file
        c.upload(open("build/eeprom.rom", "rb").read())
        c.start("M03", eparam=12000)
        print(c.state().running)
        c.subscribe(lambda batch: print(batch.t_ms, len(batch.samples)))

The API is blocking and thread-safe: any thread may call the request methods
(each waits for its own answer). One reader thread per client reads every
message and dispatches it by type to ``on_<type>``: answers wake the waiting
request, telemetry goes to the subscribe callback (called on the reader thread:
keep it short, or hand the batch to another thread) or, without a callback, to a
bounded queue read by :meth:`Client.telemetry`.

Errors: :class:`LinkError` for anything about the connection,
:class:`NotRunningError` when no controller is there, :class:`RefusedError`
(with ``reason`` and ``code``) when the controller refuses a request.
"""

from __future__ import annotations

import base64
import itertools
import socket
import sys
import threading
import time
import traceback
from collections import deque
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Iterator, Optional

from plcbuilder.controller.events import ControllerStatus
from plcbuilder.link import protocol, runtime
from plcbuilder.link.protocol import MAX_FRAME, PROTOCOL_VERSION, REPLIES, ProtocolError

DEFAULT_TIMEOUT = 30.0


class LinkError(Exception):
    """The controller cannot be reached, or the connection broke."""


class NotRunningError(LinkError):
    """No controller is running where the client looked."""


class ConnectionLost(LinkError):
    """The connection closed (the controller stopped, or closed it)."""


class RefusedError(LinkError):
    """The controller refused a request. ``reason`` says why, ``code`` is the
    protocol's error code (``refused``, ``bad_request``, ``unauthorized``, ...)."""

    def __init__(self, reason: str, code: str = "refused"):
        super().__init__(reason)
        self.reason = reason
        self.code = code


class AuthError(RefusedError):
    """Wrong or missing token, or another protocol version."""


@dataclass
class Telemetry:
    """One telemetry batch: the sample changes and events since the previous one.

    ``samples`` holds a whole :class:`~plcbuilder.controller.events.Sample` for
    each tick where something changed; each holds until the next one, and the
    last one until ``t_ms`` (the tick the controller runs next)."""
    t_ms: int
    samples: list = field(default_factory=list)     # controller.events.Sample, changes only
    events: list = field(default_factory=list)      # controller.events Event objects
    missed: int = 0             # changes dropped because this client was slow
    missed_events: int = 0


@dataclass
class _Pending:
    done: threading.Event = field(default_factory=threading.Event)
    reply: Optional[dict] = None
    #: called on the reader thread with the result, before the waiter wakes
    on_reply: Optional[Callable[[dict], None]] = None


def _result_of(reply: dict) -> dict:
    """A ``result`` reply's result object (one that is not an object: empty)."""
    result = reply.get("result")
    return result if isinstance(result, dict) else {}


def parse_address(text: str) -> tuple[str, int]:
    """``HOST:PORT`` (``[::1]:PORT`` for IPv6) -> (host, port). Raises ValueError."""
    text = text.strip()
    if text.startswith("["):
        host, _, rest = text[1:].partition("]")
        port_text = rest[1:] if rest.startswith(":") else ""
    else:
        host, _, port_text = text.rpartition(":")
    if not host or not port_text.isdigit() or not 0 < int(port_text) < 65536:
        raise ValueError(f"expected HOST:PORT, got {text!r}")
    return host, int(port_text)


class Client:
    """A connection to a controller. Make one with :meth:`connect`."""

    def __init__(self, sock: socket.socket, *, timeout: float = DEFAULT_TIMEOUT,
                 max_frame: int = MAX_FRAME):
        self._sock = sock
        self.timeout = timeout
        self.max_frame = max_frame
        self._send_lock = threading.Lock()
        self._lock = threading.Lock()
        self._ids = itertools.count(1)
        self._pending: dict[int, _Pending] = {}
        self._closed = False
        self.close_reason: Optional[str] = None
        self._callback: Optional[Callable[[Telemetry], None]] = None
        self._batches: deque = deque(maxlen=1000)
        self._batch_ready = threading.Condition(self._lock)
        self.welcome: dict = {}
        self.sample_fields: tuple[str, ...] = protocol.SAMPLE_FIELDS
        self._changes = protocol.ChangeDecoder()
        self._reader: Optional[threading.Thread] = None
        self.address: tuple = ("", 0)
        #: called on the reader thread with each ``halted``/``resumed`` notification
        #: (the message as a dict); without one they queue for :meth:`next_notification`
        self.notification_callback: Optional[Callable[[dict], None]] = None
        self._notes: deque = deque(maxlen=1000)

    # ------------------------------------------------------------ connecting
    @classmethod
    def connect(cls, host: Optional[str] = None, port: Optional[int] = None,
                token: Optional[str] = None, *, timeout: float = DEFAULT_TIMEOUT,
                connect_timeout: float = 5.0, runtime_file: Optional[Path] = None) -> "Client":
        """Connect and say hello. What is not given comes from the runtime file
        (:mod:`plcbuilder.link.runtime`). Raises NotRunningError, AuthError or LinkError."""
        endpoint = None
        if host is None or port is None or token is None:
            path = Path(runtime_file) if runtime_file is not None else runtime.default_path()
            try:
                endpoint = runtime.read(path)
            except runtime.RuntimeFileError as exc:
                if host is None or port is None:
                    raise NotRunningError(
                        f"no controller is running ({exc}); start one with "
                        "'plcbuilder controller', or give its address") from None
                raise NotRunningError(f"no token given and {exc}") from None
            if host is None and port is None and not runtime.pid_alive(endpoint.pid):
                raise NotRunningError(
                    f"no controller is running (the runtime file {path} is left over from "
                    f"process {endpoint.pid}, which has ended)")
            host = endpoint.host if host is None else host
            port = endpoint.port if port is None else port
            token = endpoint.token if token is None else token
        try:
            sock = socket.create_connection((host, port), timeout=connect_timeout)
        except ConnectionRefusedError:
            raise NotRunningError(f"no controller answers at {host}:{port} "
                                  "(connection refused)") from None
        except socket.timeout:
            raise LinkError(f"no answer from {host}:{port} within {connect_timeout:g} s") from None
        except OSError as exc:
            raise LinkError(f"cannot connect to {host}:{port}: {exc.strerror or exc}") from None
        try:
            sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        except OSError:
            pass
        client = cls(sock, timeout=timeout)
        client.address = (host, port)
        try:
            client._hello(token, connect_timeout)
        except BaseException:
            client._closed = True
            sock.close()
            raise
        client._reader = threading.Thread(target=client._read_loop, name="plcbuilder-link-reader",
                                          daemon=True)
        client._reader.start()
        return client

    def _hello(self, token: str, timeout: float) -> None:
        self._sock.settimeout(timeout)
        try:
            protocol.send_msg(self._sock, {"type": "hello", "id": 0, "version": PROTOCOL_VERSION,
                                           "token": token})
            reply = protocol.recv_msg(self._sock, self.max_frame, REPLIES)
        except socket.timeout:
            raise LinkError(f"the controller did not answer hello within {timeout:g} s") from None
        except ProtocolError as exc:
            raise LinkError(f"not a PLC Builder controller: {exc}") from None
        except OSError as exc:
            raise ConnectionLost(f"the controller closed the connection during hello "
                                 f"({exc})") from None
        if reply["type"] == "error":
            reason = str(reply.get("reason", "refused"))
            raise AuthError(reason, str(reply.get("code", "unauthorized")))
        if reply["type"] != "welcome":
            raise LinkError(f"expected welcome, got {reply['type']}")
        self.welcome = reply
        self._sock.settimeout(None)

    # ------------------------------------------------------------ lifecycle
    @property
    def closed(self) -> bool:
        return self._closed

    def close(self) -> None:
        """Close the connection; waiting requests raise ConnectionLost."""
        with self._lock:
            if self._closed:
                return
            self._closed = True
            self.close_reason = self.close_reason or "closed by the client"
        try:
            self._sock.shutdown(socket.SHUT_RDWR)
        except OSError:
            pass
        try:
            self._sock.close()
        except OSError:
            pass
        r = self._reader
        if r is not None and r is not threading.current_thread():
            r.join(2.0)
        self._fail_pending()

    def __enter__(self) -> "Client":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    # ------------------------------------------------------------ requests
    def request(self, mtype: str, timeout: Optional[float] = None, *,
                on_reply: Optional[Callable[[dict], None]] = None, **fields) -> dict:
        """Send one request and wait for its answer; returns the result object.
        Raises RefusedError when refused, ConnectionLost/LinkError otherwise.
        ``on_reply(result)``, when given, is called on the reader thread as the
        result is read: in the order of the stream, before any notification
        that came after it (the caller's own thread may wake after those)."""
        if self._closed:
            raise ConnectionLost(f"the connection is closed ({self.close_reason})")
        with self._lock:
            mid = next(self._ids)
            slot = self._pending[mid] = _Pending(on_reply=on_reply)
        msg = {"type": mtype, "id": mid, **fields}
        try:
            frame = protocol.encode_frame(msg, self.max_frame)
        except ProtocolError as exc:
            with self._lock:
                self._pending.pop(mid, None)
            raise LinkError(str(exc)) from None
        try:
            with self._send_lock:
                self._sock.sendall(frame, protocol.NOSIGNAL)
        except OSError as exc:
            with self._lock:
                self._pending.pop(mid, None)
            raise ConnectionLost(f"the connection broke: {exc}") from None
        wait = self.timeout if timeout is None else timeout
        if not slot.done.wait(wait):
            with self._lock:
                self._pending.pop(mid, None)
            raise LinkError(f"no answer to {mtype} within {wait:g} s")
        reply = slot.reply
        if reply is None:
            raise ConnectionLost(f"the connection closed ({self.close_reason})")
        if reply["type"] == "error":
            code = str(reply.get("code", "refused"))
            cls = AuthError if code in ("unauthorized", "version") else RefusedError
            raise cls(str(reply.get("reason", "refused")), code)
        return _result_of(reply)

    def upload(self, image: bytes, timeout: Optional[float] = None,
               target: Optional[dict] = None) -> dict:
        """Upload an eeprom.rom image; RefusedError with the reason when it is not
        whole and valid (the previous image keeps running). ``target``: the
        project's target profile (docs/targets.md; None: myCNC)."""
        fields = {"target": target} if target is not None else {}
        return self.request("upload", timeout, image=protocol.encode_image(image), **fields)

    def start(self, name: Optional[str] = None, eparam: int = 0, *,
              mcode: Optional[int] = None) -> dict:
        """Start a procedure by name, or the one of an M-code (``mcode=3`` starts M03)."""
        if (name is None) == (mcode is None):
            raise ValueError("give a procedure name or an M-code")
        if name is not None:
            return self.request("start", name=name, eparam=eparam)
        return self.request("start", mcode=mcode, eparam=eparam)

    def stop(self) -> dict:
        """Press Stop (first M02, then OFF); result ``started`` names what started."""
        return self.request("stop")

    def set_input(self, pin: int, value: int) -> dict:
        return self.request("input", pin=pin, value=1 if value else 0)

    input = set_input

    def set_adc(self, channel: int, value: int) -> dict:
        return self.request("adc", channel=channel, value=value)

    adc = set_adc

    def state(self) -> ControllerStatus:
        return ControllerStatus.from_dict(self.request("state"))

    def variables(self) -> dict[str, dict[str, int]]:
        return self.request("variables").get("variables", {})

    def variables_and_target(self) -> tuple[dict, dict]:
        """(variables, the target's report: registers, calls, budget ({} on myCNC))."""
        answer = self.request("variables")
        return answer.get("variables", {}), answer.get("target", {})

    def watch(self, variables) -> list[str]:
        """Have the controller record these variables (``PROC.var``) every tick,
        as ``watch`` events in the telemetry; [] stops. Returns what it watches."""
        return list(self.request("watch", variables=[str(v) for v in variables])
                    .get("variables", []))

    def registers(self, addresses) -> dict[int, int]:
        """The values of global registers now, ``{address: value}``."""
        r = self.request("registers", addresses=[int(a) for a in addresses])
        return dict(zip(r.get("addresses", []), r.get("values", [])))

    def speed(self, mode: str, factor: Optional[float] = None) -> dict:
        """realtime, factor (with ``factor``), max or pause."""
        fields = {"mode": mode}
        if factor is not None:
            fields["factor"] = factor
        return self.request("speed", **fields)

    def step(self, ms: int = 1) -> dict:
        return self.request("step", ms=ms)

    def reset(self) -> dict:
        return self.request("reset")

    def event(self, handler: str) -> dict:
        """``__HANDLER_GCODE_START`` or ``__HANDLER_GCODE_STOP``."""
        return self.request("event", handler=handler)

    def issue_code(self, letter: str, value: int) -> dict:
        """The CNC issues code ``letter`` ``value`` (M3, S1200): ``{code, started, t_ms}``."""
        return self.request("code", letter=letter, value=int(value))

    def job(self, verb: str, text: Optional[str] = None, file: Optional[str] = None,
            play: bool = False) -> dict:
        """The G-code job: ``open`` (``text``, ``file``; ``play`` starts it too),
        ``play``, ``pause``, ``stop`` or ``reset``."""
        fields: dict = {"verb": verb}
        if verb == "open":
            fields.update(text=text or "", file=file or "job.nc", play=bool(play))
        return self.request("job", **fields)

    def ping(self) -> dict:
        return self.request("ping")

    def recording(self) -> dict:
        """The session's recording: ``{text, t_ms, actions}`` (a scenario file
        that replays the session: docs/traces.md)."""
        return self.request("recording")

    # ------------------------------------------------------------ debugger
    def set_breakpoints(self, file: str, breakpoints: list[dict]) -> list[dict]:
        """Replace the breakpoints of ``file``: dicts {line, enabled?, condition?,
        hit?, log?}; a condition is ``{text, code}`` with ``code`` the compiled
        condition's bytes (:func:`plcbuilder.api.compile_condition`) or base64.
        Returns each one's {id, file, line, verified, reason}."""
        out = []
        for b in breakpoints:
            b = dict(b)
            cond = b.get("condition")
            if isinstance(cond, dict) and isinstance(cond.get("code"), (bytes, bytearray)):
                b["condition"] = {"text": cond.get("text", ""),
                                  "code": base64.b64encode(bytes(cond["code"])).decode("ascii")}
            out.append(b)
        return self.request("set_breakpoints", file=file, breakpoints=out)["breakpoints"]

    def debug_continue(self) -> dict:
        return self.request("debug_continue")

    def debug_pause(self) -> dict:
        return self.request("debug_pause")

    def debug_step(self, kind: str, procedure: Optional[str] = None) -> dict:
        """kind: tick, into, over or out."""
        fields = {"kind": kind}
        if procedure is not None:
            fields["procedure"] = procedure
        return self.request("debug_step", **fields)

    def debug_run_to(self, file: str, line: int) -> dict:
        return self.request("debug_run_to", file=file, line=line)

    def debug_step_back(self, kind: str = "tick") -> dict:
        """kind: tick or statement; the controller halts there (SPEC §7)."""
        return self.request("debug_step_back", kind=kind)

    def debug_run_back(self) -> dict:
        """Back to the previous breakpoint hit (SPEC §7)."""
        return self.request("debug_run_back")

    def debug_evaluate(self, code: bytes, procedure: Optional[str] = None) -> int:
        """The value of an expression compiled as a condition
        (``compile_condition``) over a running procedure's variables."""
        fields = {"code": base64.b64encode(bytes(code)).decode("ascii")}
        if procedure is not None:
            fields["procedure"] = procedure
        return self.request("debug_evaluate", **fields)["value"]

    def debug_state(self) -> Optional[dict]:
        """The halted state, or None while running."""
        return self.request("debug_state")["halted"]

    def next_notification(self, timeout: Optional[float] = None) -> Optional[dict]:
        """The next ``halted``/``resumed`` notification (without a callback), or None."""
        return self._next(self._notes, timeout)

    # write and force (SPEC §6): targets as PROC.var, in N, out N, adc N, pwm N, dac N, gvar N
    def write(self, target: str, value: int) -> dict:
        """Set a target once; the answer has the canonical ``target``, ``t_ms``, ``forces``."""
        return self.request("write", target=target, value=value)

    def force(self, target: str, value: int) -> dict:
        """Hold a target at ``value`` until released."""
        return self.request("force", target=target, value=value)

    def release(self, target: str, mode: str = "restore") -> dict:
        """Release a target: ``keep`` its value or ``restore`` the program's."""
        return self.request("release", target=target, mode=mode)

    def release_all(self, mode: str = "restore") -> dict:
        return self.request("release_all", mode=mode)

    def forces(self) -> list[dict]:
        """Everything forced: ``{target, value, since_ms}`` each."""
        return self.request("forces").get("forces", [])

    # ------------------------------------------------------------ telemetry
    def subscribe(self, callback: Optional[Callable[[Telemetry], None]] = None, *,
                  samples: bool = True, events: bool = True, queue: int = 1000,
                  lossless: bool = False) -> dict:
        """Receive telemetry batches (at most one every 20 ms): through
        ``callback(batch)`` on the reader thread, or without one from
        :meth:`telemetry`. ``queue``: changes the controller keeps for this
        client between two batches (16 to 20,000); beyond it the oldest are
        dropped and counted in ``missed``, except that with ``lossless`` a
        controller at Max speed waits for this client (at most a second)."""
        self._callback = callback
        result = self.request("subscribe", samples=samples, events=events, queue=queue,
                              lossless=lossless)
        fields = result.get("sample_fields")
        if isinstance(fields, list):
            self.sample_fields = tuple(fields)
            self._changes.set_fields(self.sample_fields)
        return result

    def unsubscribe(self) -> dict:
        result = self.request("unsubscribe")
        self._callback = None
        return result

    def next_telemetry(self, timeout: Optional[float] = None) -> Optional[Telemetry]:
        """The next queued batch, waiting up to ``timeout`` (None: until one comes
        or the connection closes). None on timeout or when closed."""
        return self._next(self._batches, timeout)

    def _next(self, queue, timeout: Optional[float]):
        """The oldest item of one of the reader's queues (notifications or
        batches), waiting up to ``timeout``; None on timeout or when closed."""
        deadline = None if timeout is None else time.monotonic() + timeout
        with self._batch_ready:
            while not queue:
                if self._closed:
                    return None
                left = None if deadline is None else deadline - time.monotonic()
                if left is not None and left <= 0:
                    return None
                self._batch_ready.wait(left if left is not None else 0.5)
            return queue.popleft()

    def telemetry(self, timeout: Optional[float] = None) -> Iterator[Telemetry]:
        """Iterate over telemetry batches until the connection closes (or no batch
        comes within ``timeout``)."""
        while True:
            batch = self.next_telemetry(timeout)
            if batch is None:
                return
            yield batch

    # ------------------------------------------------------------ the reader
    def _read_loop(self) -> None:
        reason = "the controller closed the connection"
        try:
            while not self._closed:
                msg = protocol.recv_msg(self._sock, self.max_frame)
                mtype = msg["type"]
                if mtype not in REPLIES:
                    continue                       # a newer server's message: ignore it
                getattr(self, f"on_{mtype}")(msg)
        except ProtocolError as exc:
            reason = f"bad frame from the controller: {exc}"
        except (OSError, ConnectionError) as exc:
            if not self._closed:
                reason = f"the connection broke: {exc}" if str(exc) != \
                    "the connection was closed" else reason
        finally:
            with self._lock:
                if self.close_reason is None:
                    self.close_reason = reason
                self._closed = True
                self._batch_ready.notify_all()
            try:
                self._sock.close()
            except OSError:
                pass
            self._fail_pending()

    def _fail_pending(self) -> None:
        with self._lock:
            pending, self._pending = self._pending, {}
        for slot in pending.values():
            slot.done.set()

    def _answer(self, msg: dict) -> None:
        mid = msg.get("id")
        with self._lock:
            slot = self._pending.pop(mid, None) if isinstance(mid, int) else None
        if slot is not None:
            slot.reply = msg
            if slot.on_reply is not None and msg.get("type") == "result":
                try:
                    slot.on_reply(_result_of(msg))
                except Exception:  # noqa: BLE001 - a callback bug must not stop the reader
                    traceback.print_exc(file=sys.stderr)
            slot.done.set()

    def on_result(self, msg: dict) -> None:
        self._answer(msg)

    def on_welcome(self, msg: dict) -> None:
        self._answer(msg)

    def on_error(self, msg: dict) -> None:
        if msg.get("id") is None:                  # not about a request: about the connection
            self.close_reason = f"{msg.get('code')}: {msg.get('reason')}"
            return
        self._answer(msg)

    def on_bye(self, msg: dict) -> None:
        self.close_reason = str(msg.get("reason", "the controller said bye"))

    def _notify(self, msg: dict) -> None:
        self._deliver(self.notification_callback, msg, self._notes)

    def _deliver(self, cb, item, waiting: deque) -> None:
        """``item`` to the callback when there is one (a bug in it is printed,
        not raised), else onto ``waiting`` for next_notification()/next_telemetry()."""
        if cb is not None:
            try:
                cb(item)
            except Exception:  # noqa: BLE001 - a callback bug must not stop the reader
                traceback.print_exc(file=sys.stderr)
            return
        with self._batch_ready:
            waiting.append(item)
            self._batch_ready.notify_all()

    def on_halted(self, msg: dict) -> None:
        self._notify(msg)

    def on_resumed(self, msg: dict) -> None:
        self._notify(msg)

    def on_telemetry(self, msg: dict) -> None:
        dec = self._changes
        missed = msg.get("missed", 0)
        missed = missed if type(missed) is int else 0
        if missed:
            dec.reset()                            # the next change holds every field
        try:
            samples = [dec.decode(c) for c in msg.get("changes", ()) if isinstance(c, dict)]
        except (TypeError, ValueError):
            samples = []
        events = [protocol.event_from_dict(e) for e in msg.get("events", ())
                  if isinstance(e, dict)]
        missed_events = msg.get("missed_events", 0)
        t_ms = msg.get("t_ms", 0)
        batch = Telemetry(t_ms=t_ms if type(t_ms) is int else 0, samples=samples, events=events,
                          missed=missed,
                          missed_events=missed_events if type(missed_events) is int else 0)
        self._deliver(self._callback, batch, self._batches)
