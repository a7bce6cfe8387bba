"""The simulated controller as a TCP server.

:class:`Server`
    The network side: one thread with a selector serves every connection
    (non-blocking sockets, per-connection output buffers). It checks frames and
    the hello, dispatches requests to the :class:`~plcbuilder.link.service.Service`,
    and sends telemetry at most every 20 ms. A bad frame, a wrong token, a frame
    left half sent beyond ``frame_timeout`` or a client that does not read its
    replies closes that connection only.

:class:`ControllerServer` puts the simulation thread
(:class:`~plcbuilder.link.pacing.Simulation`), the service and the server
together; ``plcbuilder controller`` runs one.
"""

from __future__ import annotations

import hmac
import os
import selectors
import socket
import threading
import time
import traceback
from pathlib import Path
from typing import Callable, Optional

from plcbuilder.controller.controller import Controller
from plcbuilder.controller.machine_config import ConfigError
from plcbuilder.image.manifest import Limits
from plcbuilder.link import protocol
from plcbuilder.link.pacing import Simulation
from plcbuilder.link.protocol import (MAX_FRAME, PROTOCOL_VERSION, REQUESTS, SAMPLE_FIELDS,
                                      ErrorCode, FrameDecoder, ProtocolError, encode_frame)
from plcbuilder.link.protocol import debug as _debug
from plcbuilder.link.service import Refused, Service, Session

__all__ = ["ConfigError", "ControllerServer", "Limits", "Server", "make_controller"]


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
