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
import queue
import selectors
import socket
import threading
import time
import traceback
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Callable, Optional

from plcbuilder.controller.controller import Controller
from plcbuilder.controller.machine_config import ConfigError
from plcbuilder.image.manifest import Limits
from plcbuilder.link import protocol
from plcbuilder.link.pacing import Simulation
from plcbuilder.link.protocol import (MAX_FRAME, PROTOCOL_VERSION, REQUESTS,
                                      ErrorCode, FrameDecoder, ProtocolError, encode_frame)
from plcbuilder.link.protocol import (NOSIGNAL, accept_all, listening_socket, refuse,
                                      send_pending)
from plcbuilder.link.protocol import debug as _debug
from plcbuilder.link.service import Refused, Service, Session

__all__ = ["ConfigError", "ControllerServer", "Limits", "Server", "make_controller"]


# ===================================================================== the network


class _Conn:
    __slots__ = ("sock", "peer", "decoder", "out", "authed", "opened", "last_rx",
                 "frame_started", "close_at", "session", "closed", "mask", "inflight")

    def __init__(self, sock: socket.socket, peer: str, now: float, max_frame: int,
                 notify: Optional[Callable[[], None]] = None):
        self.sock = sock
        self.peer = peer
        self.decoder = FrameDecoder(max_frame)
        self.out = bytearray()
        self.authed = False
        self.opened = now
        self.last_rx = now
        self.frame_started: Optional[float] = None
        self.close_at: Optional[float] = None      # set: closing once out is sent
        self.session = Session(peer=peer, notify=notify)
        self.closed = False
        self.mask = 0
        self.inflight = False                      # a slow request runs on a worker

    @property
    def held(self) -> int:
        """Bytes this connection holds in the server (unsent output, unread input)."""
        return len(self.out) + self.decoder.pending


class _Watch:
    """A socket another part of the controller serves through this loop."""
    __slots__ = ("callback",)

    def __init__(self, callback: Callable):
        self.callback = callback


class Server:
    """Serves a :class:`Service` over TCP (one selector thread, many clients).

    Budgets (issue 17): connections without a hello have their own small budget
    (``max_unauthed``; the oldest is closed to make room) and a short
    ``hello_timeout``, and may send one frame of at most ``hello_frame`` bytes,
    the hello, which is the only thing parsed before the token is checked. An
    authenticated client gets one of ``max_clients`` places. Each pass of the
    loop handles at most ``frames_per_turn`` requests or ``turn_budget`` seconds
    of one client before the next (the rest stay buffered, and its socket is
    not read meanwhile); slow requests (``SLOW_REQUESTS``: upload, step, reset)
    run on a worker thread, one at a time per client, so the loop keeps
    answering everybody else. A client stops being read while more than
    ``read_pause`` bytes of its answers wait; one that holds more than
    ``max_outbuf`` bytes, or the largest one when all together hold more than
    ``max_total_held``, is closed with the reason.
    """

    #: Seconds the telemetry of a subscriber is batched.
    telemetry_interval = 0.02
    #: Output waiting for a client above which no telemetry is added (it is counted missed).
    telemetry_high_water = 1 << 20
    #: Output waiting for a client above which its requests are not read (back-pressure).
    read_pause = 256 << 10
    #: Output waiting for one client above which the connection is closed.
    max_outbuf = 8 << 20
    #: Bytes all connections together may hold (output and input); above it the largest goes.
    max_total_held = 96 << 20
    #: Largest frame accepted before the hello (the hello itself).
    hello_frame = protocol.MAX_HELLO_FRAME
    #: Requests of one client handled per pass of the loop, and seconds spent on them.
    frames_per_turn = 16
    turn_budget = 0.005
    #: Requests that run on a worker thread (their answer comes back to the loop).
    SLOW_REQUESTS = frozenset({"upload", "step", "reset"})
    #: Seconds a closing connection gets to take its last message.
    close_grace = 1.0

    def __init__(self, service: Service, host: str = "127.0.0.1", port: int = 0,
                 token: Optional[str] = None, *, max_frame: int = MAX_FRAME,
                 frame_timeout: float = 10.0, hello_timeout: float = 3.0, max_clients: int = 64,
                 max_unauthed: int = 16, workers: int = 2):
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
        self.max_unauthed = max(1, max_unauthed)
        self._sel = selectors.DefaultSelector()
        lsock = self._lsock = listening_socket(host, port, 64)
        self.address: tuple[str, int] = lsock.getsockname()[:2]
        self._wake_r, self._wake_w = socket.socketpair()
        self._wake_r.setblocking(False)
        self._wake_w.setblocking(False)
        self._sel.register(lsock, selectors.EVENT_READ, "listen")
        self._sel.register(self._wake_r, selectors.EVENT_READ, "wake")
        self._conns: dict[int, _Conn] = {}
        self._unauthed: dict[int, _Conn] = {}     # insertion order: oldest first
        self._backlog: set[_Conn] = set()         # whole requests buffered, not handled yet
        self._done: "queue.SimpleQueue[tuple[_Conn, Optional[dict]]]" = queue.SimpleQueue()
        self._pool = ThreadPoolExecutor(max_workers=max(1, workers),
                                        thread_name_prefix="plcbuilder-request")
        self._thread: Optional[threading.Thread] = None
        self._stopping = False
        self._next_flush = time.monotonic()
        self._wake_at = float("inf")             # when the loop's select returns at the latest
        self._flushing: list[_Conn] = []          # subscribers still to serve this round
        self._parts: list = []                    # other protocols this loop serves (attach)
        self.stats = {"accepted": 0, "closed": 0, "bad_frames": 0, "unauthorized": 0,
                      "timeouts": 0, "requests": 0, "telemetry_frames": 0, "evicted": 0,
                      "busy": 0, "overflow": 0, "passes": 0}

    # ---------------------------------------------------------------- lifecycle
    @property
    def host(self) -> str:
        return self.address[0]

    @property
    def port(self) -> int:
        return self.address[1]

    @property
    def clients(self) -> int:
        """Authenticated connections."""
        return len(self._conns) - len(self._unauthed)

    @property
    def connections(self) -> int:
        """Every open connection, with or without a hello."""
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

    # ---------------------------------------------------------------- other parts
    def attach(self, part) -> None:
        """Serve another protocol on this loop (the Server API,
        :mod:`plcbuilder.link.server_api`), before :meth:`start`:
        ``part.attach_to(self)`` registers its sockets with :meth:`watch`;
        after every pass of the loop ``part.on_pass()`` runs, and the loop
        does not sleep while ``part.pending``; ``part.close()`` when the loop ends."""
        part.attach_to(self)
        self._parts.append(part)

    def watch(self, sock, events: int, callback: Callable) -> None:
        """Call ``callback(sock, mask)`` from the loop when sock is ready."""
        self._sel.register(sock, events, _Watch(callback))

    def rewatch(self, sock, events: int, callback: Callable) -> None:
        self._sel.modify(sock, events, _Watch(callback))

    def unwatch(self, sock) -> None:
        self._sel.unregister(sock)

    def _poke(self) -> None:
        """A subscriber's telemetry has something new (the simulation thread):
        wake the loop unless it wakes soon anyway."""
        if self._wake_at > time.monotonic() + self.telemetry_interval:
            self._wake()

    def _wake(self) -> None:
        try:
            self._wake_w.send(b"x", NOSIGNAL)
        except OSError:
            pass

    # ---------------------------------------------------------------- the loop
    def _loop(self) -> None:
        try:
            while not self._stopping:
                busy = self._backlog or self._flushing or any(p.pending for p in self._parts)
                self._wake_at = float("inf")     # a poke from now on wakes the select
                timeout = 0.0 if busy else self._timeout()
                self._wake_at = time.monotonic() + timeout
                self.stats["passes"] += 1
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
                    elif isinstance(tag, _Watch):
                        self._part_call(tag.callback, key.fileobj, mask)
                    else:
                        conn: _Conn = tag
                        self._guard(conn, self._on_ready, conn, mask)
                self._finish_slow()
                for part in self._parts:
                    self._part_call(part.on_pass)
                for conn in list(self._backlog):
                    self._guard(conn, self._serve, conn)
                try:
                    now = time.monotonic()
                    self._timers(now)
                    self._check_memory()
                except Exception:  # noqa: BLE001 - keep serving
                    traceback.print_exc()
        except Exception:  # noqa: BLE001 - log it; the finally closes everything
            traceback.print_exc()
        finally:
            self._flush_telemetry(time.monotonic(), everything=True)
            self._close_all(self._stopping if isinstance(self._stopping, str) else "stopped")
            self._pool.shutdown(wait=False, cancel_futures=True)

    @staticmethod
    def _part_call(fn, *args) -> None:
        try:
            fn(*args)
        except Exception:  # noqa: BLE001 - a bug in another part costs nothing here
            traceback.print_exc()

    def _guard(self, conn: _Conn, fn, *args) -> None:
        try:
            if not conn.closed:
                fn(*args)
            if not conn.closed:
                self._update(conn)
        except Exception:  # noqa: BLE001 - a bug here costs one connection
            traceback.print_exc()
            self._drop(conn)

    def _on_ready(self, conn: _Conn, mask: int) -> None:
        if mask & selectors.EVENT_READ and not conn.closed:
            self._read(conn)
        if mask & selectors.EVENT_WRITE and not conn.closed:
            self._write(conn)

    def _timeout(self) -> float:
        now = time.monotonic()
        t = 0.5
        for c in self._conns.values():
            q = c.session.telemetry
            if q is not None:                  # asleep until it has something (or a poke)
                ready = q.ready_at()
                if ready is not None:
                    t = min(t, max(0.0, max(ready, self._next_flush) - now))
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
            waiting = not c.mask & selectors.EVENT_READ     # we are not reading it: not its fault
            if not waiting and c.decoder.mid_frame and (
                    now - c.last_rx > self.frame_timeout or
                    c.frame_started is not None and now - c.frame_started > 6 * self.frame_timeout):
                self.stats["timeouts"] += 1
                self._fatal(c, ErrorCode.BAD_FRAME,
                            f"frame left unfinished for more than {self.frame_timeout:g} s")
            elif not c.authed and now - c.opened > self.hello_timeout:
                self.stats["timeouts"] += 1
                self._fatal(c, ErrorCode.UNAUTHORIZED,
                            f"no hello within {self.hello_timeout:g} s")
        if self._flushing:
            self._flush_telemetry(now)
        elif now >= self._next_flush:
            # a round at most every telemetry_interval, of the subscribers that have
            # something to take (a controller where nothing changes wakes nobody)
            ready = []
            for c in self._conns.values():
                q = c.session.telemetry
                if q is not None:
                    at = q.ready_at()
                    if at is not None and at <= now:
                        ready.append(c)
            if ready:
                self._flushing = ready
                self._next_flush = now + self.telemetry_interval
                self._flush_telemetry(now)

    # ---------------------------------------------------------------- connections
    def _accept(self) -> None:
        for sock, peer in accept_all(self._lsock):
            self.stats["accepted"] += 1
            try:
                sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            except OSError:
                pass
            if self.clients >= self.max_clients or self._stopping:
                self.stats["busy"] += 1
                refuse(sock, encode_frame({"type": "error", "id": None, "code": ErrorCode.BUSY,
                                           "reason": f"too many clients ({self.max_clients})"}))
                continue
            while len(self._unauthed) >= self.max_unauthed:
                # Make room: the oldest connection without a hello goes, so that a
                # client that has the token (and says hello at once) always gets in.
                oldest = next(iter(self._unauthed.values()))
                self.stats["evicted"] += 1
                self._refuse_now(oldest, ErrorCode.UNAUTHORIZED,
                                 f"no hello yet, and {self.max_unauthed} connections without "
                                 "one are the most allowed")
            now = time.monotonic()
            conn = _Conn(sock, peer, now, min(self.hello_frame, self.max_frame), self._poke)
            self._conns[sock.fileno()] = conn
            self._unauthed[sock.fileno()] = conn
            conn.mask = selectors.EVENT_READ
            self._sel.register(sock, conn.mask, conn)
            self.service.clients = self.clients

    def _update(self, conn: _Conn) -> None:
        if conn.close_at is not None and not conn.out:
            self._drop(conn)
            return
        mask = 0
        if conn.close_at is None and not conn.inflight and conn not in self._backlog \
                and len(conn.out) < self.read_pause:
            mask = selectors.EVENT_READ
        if conn.out:
            mask |= selectors.EVENT_WRITE
        if mask != conn.mask:
            if mask & selectors.EVENT_READ and not conn.mask & selectors.EVENT_READ:
                # reading again: the time it was not read is not the client's delay
                conn.last_rx = time.monotonic()
                if conn.frame_started is not None:
                    conn.frame_started = conn.last_rx
            if mask == 0:
                self._sel.unregister(conn.sock)
            elif conn.mask == 0:
                self._sel.register(conn.sock, mask, conn)
            else:
                self._sel.modify(conn.sock, mask, conn)
            conn.mask = mask

    def _drop(self, conn: _Conn) -> None:
        if conn.closed:
            return
        conn.closed = True
        self.stats["closed"] += 1
        fd = conn.sock.fileno()
        self._conns.pop(fd, None)
        self._unauthed.pop(fd, None)
        self._backlog.discard(conn)
        if conn.mask:
            try:
                self._sel.unregister(conn.sock)
            except (KeyError, ValueError, OSError):
                pass
        try:
            conn.sock.close()
        except OSError:
            pass
        conn.out = bytearray()
        try:
            self.service.end_session(conn.session)
        except Exception:  # noqa: BLE001
            _debug(traceback.format_exc())
        self.service.clients = self.clients

    def _refuse_now(self, conn: _Conn, code: ErrorCode, reason: str) -> None:
        """Tell the connection why in one non-blocking send (when its socket has
        room), and close it at once."""
        _debug(f"closing {conn.peer}: {reason}")
        try:
            conn.sock.send(encode_frame({"type": "error", "id": None, "code": code,
                                         "reason": reason}), NOSIGNAL)
        except OSError:
            pass
        self._drop(conn)

    def _check_memory(self) -> None:
        """Close whoever holds the most while everybody together holds too much."""
        total = sum(c.held for c in self._conns.values())
        while total > self.max_total_held and self._conns:
            worst = max(self._conns.values(), key=lambda c: c.held)
            held = worst.held
            self.stats["overflow"] += 1
            self._refuse_now(worst, ErrorCode.BUSY,
                             f"closed: this connection held {held} bytes while all together "
                             f"held more than {self.max_total_held} (it does not read its "
                             "answers, or sends faster than they are handled)")
            total -= held

    def _close_all(self, reason: str) -> None:
        for part in self._parts:
            self._part_call(part.close)
        for c in list(self._conns.values()):
            if not c.closed:
                try:
                    c.sock.setblocking(True)
                    c.sock.settimeout(0.2)
                    if c.out:
                        c.sock.sendall(bytes(c.out), NOSIGNAL)
                    if c.authed:
                        c.sock.sendall(encode_frame({"type": "bye", "reason": reason}),
                                       NOSIGNAL)
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
        if conn.close_at is not None or conn.inflight or conn in self._backlog:
            return
        try:
            # before the hello only a small frame is allowed: never read much more
            data = conn.sock.recv(256 * 1024 if conn.authed else 2 * self.hello_frame)
        except (BlockingIOError, InterruptedError):
            return
        except OSError:
            self._drop(conn)
            return
        if not data:
            self._drop(conn)
            return
        now = time.monotonic()
        conn.last_rx = now
        conn.decoder.push(data)
        had = conn.frame_started is not None
        self._serve(conn)
        if conn.closed:
            return
        if not conn.decoder.mid_frame:
            conn.frame_started = None
        elif not had or conn.frame_started is None:
            conn.frame_started = now

    def _serve(self, conn: _Conn) -> None:
        """Handle the whole requests buffered, a turn's worth at most."""
        self._backlog.discard(conn)
        t0 = time.perf_counter()
        n = 0
        while not conn.closed and conn.close_at is None and not conn.inflight:
            if n >= self.frames_per_turn or time.perf_counter() - t0 > self.turn_budget \
                    or len(conn.out) >= self.read_pause:
                if conn.decoder.ready:
                    self._backlog.add(conn)     # the rest waits for the next pass
                return
            try:
                payload = conn.decoder.next_frame()
            except ProtocolError as exc:
                self.stats["bad_frames"] += 1
                if not conn.authed:
                    exc = ProtocolError(f"{exc.reason}; before the hello only a hello of at "
                                        f"most {conn.decoder.max_frame} bytes is accepted",
                                        exc.code)
                self._fatal(conn, exc.code, exc.reason)
                return
            if payload is None:
                return
            n += 1
            conn.frame_started = None
            self._on_payload(conn, payload)

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
        if mtype in self.SLOW_REQUESTS:
            conn.inflight = True
            self._pool.submit(self._slow, conn, msg)
            return
        self._answer(conn, self._handle(conn, msg))

    def _handle(self, conn: _Conn, msg: dict) -> Optional[dict]:
        """Run one request; the message to send back (None: nothing)."""
        mtype, mid = msg["type"], msg.get("id")
        handler = getattr(self, f"handle_{mtype}", None)
        try:
            if handler is not None:
                result = handler(conn, msg)
            else:
                result = self.service.dispatch(msg, conn.session)
        except ProtocolError as exc:
            return {"type": "error", "id": mid, "code": exc.code, "reason": exc.reason}
        except Refused as exc:
            return {"type": "error", "id": mid, "code": ErrorCode.REFUSED, "reason": exc.reason}
        except Exception as exc:  # noqa: BLE001 - the client gets a reason, the server lives
            _debug(traceback.format_exc())
            return {"type": "error", "id": mid, "code": ErrorCode.INTERNAL,
                    "reason": f"internal error: {type(exc).__name__}: {exc}"}
        if result is None:
            return None
        return {"type": "result", "id": mid, "result": result}

    def _answer(self, conn: _Conn, reply: Optional[dict]) -> None:
        if reply is None or conn.closed:
            return
        if reply["type"] == "error" and reply["code"] in protocol.FATAL_CODES:
            self._fatal(conn, reply["code"], reply["reason"], reply["id"])
        else:
            self._send(conn, reply)

    def _slow(self, conn: _Conn, msg: dict) -> None:
        """On a worker thread: one slow request; its answer goes back to the loop."""
        try:
            reply = self._handle(conn, msg)
        except BaseException as exc:  # noqa: BLE001 - _handle catches; this is a last resort
            reply = {"type": "error", "id": msg.get("id"), "code": ErrorCode.INTERNAL,
                     "reason": f"internal error: {type(exc).__name__}"}
        self._done.put((conn, reply))
        self._wake()

    def _finish_slow(self) -> None:
        while True:
            try:
                conn, reply = self._done.get_nowait()
            except queue.Empty:
                return
            conn.inflight = False
            if conn.closed:
                continue
            self._guard(conn, self._after_slow, conn, reply)

    def _after_slow(self, conn: _Conn, reply: Optional[dict]) -> None:
        self._answer(conn, reply)
        if not conn.closed and conn.close_at is None and conn.decoder.ready:
            self._backlog.add(conn)             # what it sent meanwhile

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
        if self.clients >= self.max_clients:
            self.stats["busy"] += 1
            self._fatal(conn, ErrorCode.BUSY, f"too many clients ({self.max_clients})", mid)
            return
        conn.authed = True
        self._unauthed.pop(conn.sock.fileno(), None)
        conn.decoder.max_frame = self.max_frame
        self.service.clients = self.clients
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
        self._send_frame(conn, frame)

    def _send_frame(self, conn: _Conn, frame: bytes) -> None:
        conn.out += frame
        if len(conn.out) > self.max_outbuf:
            held = len(conn.out)
            conn.out = bytearray()
            self.stats["overflow"] += 1
            self._refuse_now(conn, ErrorCode.BUSY,
                             f"closed: {held} bytes of answers waited for this client, more "
                             f"than the {self.max_outbuf}-byte limit (it does not read them)")
            return
        self._write(conn)
        if not conn.closed:
            self._update(conn)

    def _write(self, conn: _Conn) -> None:
        if not send_pending(conn.sock, conn.out, 1 << 20):
            self._drop(conn)

    def _error(self, conn: _Conn, code: ErrorCode, reason: str, mid=None) -> None:
        self._send(conn, {"type": "error", "id": mid, "code": code, "reason": reason})

    def _fatal(self, conn: _Conn, code: ErrorCode, reason: str, mid=None) -> None:
        """Answer with an error, then close the connection once that is sent."""
        if conn.close_at is None:
            conn.close_at = time.monotonic() + self.close_grace
            self._backlog.discard(conn)
            self._send(conn, {"type": "error", "id": mid, "code": code, "reason": reason})
            if not conn.closed:
                self._update(conn)

    #: Changes (and events) taken from one subscriber's queue per round at most.
    telemetry_batch = protocol.TELEMETRY_PER_FRAME
    #: Seconds of telemetry work per pass of the loop (the rest of the round waits).
    flush_budget = 0.005

    def _flush_telemetry(self, now: float, everything: bool = False) -> None:
        """Send the subscribers of this round their telemetry, within
        ``flush_budget`` (``everything``: all of it, when stopping)."""
        t0 = time.perf_counter()
        if everything:
            self._flushing = [c for c in self._conns.values() if c.session.telemetry is not None]
        while self._flushing:
            if not everything and time.perf_counter() - t0 > self.flush_budget:
                return
            conn = self._flushing.pop()
            q = conn.session.telemetry
            if q is None or conn.closed or conn.close_at is not None:
                continue
            if len(conn.out) > self.telemetry_high_water:
                continue                       # it is not reading: the queue drops and counts
            got = q.take(None if everything else self.telemetry_batch)
            if got is None:
                continue
            rows, events, missed, missed_events, t_ms = got
            notes = [e for e in events if getattr(e, "type", None) in protocol.NOTIFICATIONS]
            if notes:
                events = [e for e in events if getattr(e, "type", None) not in
                          protocol.NOTIFICATIONS]
            enc = conn.session.changes
            if missed:
                enc.reset()                    # the chain is broken: start from a whole sample
            changes = [enc.encode(r) for r in rows]
            n = protocol.TELEMETRY_PER_FRAME
            parts = max(1, -(-len(changes) // n), -(-len(events) // n))
            for i in range(parts):
                msg = {"type": "telemetry", "t_ms": t_ms, "changes": changes[i * n:(i + 1) * n],
                       "events": [protocol.event_dict(e) for e in events[i * n:(i + 1) * n]],
                       "missed": missed if i == 0 else 0,
                       "missed_events": missed_events if i == 0 else 0}
                self.stats["telemetry_frames"] += 1
                try:
                    frame = protocol.encode_binary_frame(msg, self.max_frame)
                except (ProtocolError, TypeError, ValueError) as exc:
                    _debug(f"telemetry not sent: {exc}")
                    enc.reset()
                    continue
                self._send_frame(conn, frame)
                if conn.closed:
                    break
            for e in notes:                    # after the telemetry that led to them
                if conn.closed:
                    break
                note = protocol.event_dict(e)
                self._send(conn, {"type": note.pop("type"), **note})
            if not conn.closed:
                self._update(conn)


# ===================================================================== together

def make_controller(machine=None, variables=None, io_dat=None,
                    **kwargs) -> Callable[[], Controller]:
    """A factory of controllers for a machine file, a plc-variables.xml and an
    IO.DAT (paths or None for the defaults). Raises ConfigError on a bad file."""
    from plcbuilder.controller import io_dat as io_dat_file
    from plcbuilder.controller import machine_config, variables_xml
    mc = machine_config.load_machine(machine) if machine else machine_config.default_machine()
    if io_dat:
        mc = io_dat_file.with_io_dat(mc, io_dat_file.load_io_dat(io_dat))
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
                 server_api: Optional[tuple[str, int]] = None,
                 image_target: Optional[dict] = None, **server_options):
        if controller is None:
            controller_factory = controller_factory or (lambda: Controller())
            controller = controller_factory()
        self.sim = Simulation(controller, speed, factor)
        self.service = Service(self.sim, limits=limits, controller_factory=controller_factory)
        if image is not None:
            self.service.load_image(image, image_target)   # Refused: the caller says why
        self.server = Server(self.service, host, port, token, **server_options)
        #: myCNC's text Server API on (host, port), when asked for (no token: loopback by default)
        self.server_api = None
        if server_api is not None:
            from plcbuilder.link.server_api import ServerApi
            try:
                self.server_api = ServerApi(self.sim, *server_api)
            except OSError:
                self.server.stop()
                raise
            self.server.attach(self.server_api)
        self.runtime_file = runtime_file
        self._endpoint = None
        self._previous = None
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
            try:
                old = runtime.read(self.runtime_file)
            except runtime.RuntimeFileError:
                old = None
            # another controller that still runs: its file is put back when this one ends
            self._previous = old if old is not None and runtime.pid_alive(old.pid) else None
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
            runtime.remove(self._endpoint, self.runtime_file, self._previous)
        self.sim.stop(shutdown=shutdown)
        self.server.stop()
        try:
            self.service.save_state()           # Huazhong's B, for the next start
        except OSError as exc:
            from plcbuilder.link.protocol import debug
            debug(f"cannot write the controller state: {exc}")

    def __enter__(self) -> "ControllerServer":
        return self.start()

    def __exit__(self, *exc) -> None:
        self.close()
