"""How the language server reads its messages: stdio, or TCP with one session
per connection; ``Content-Length`` frames (:mod:`plcbuilder._support.framing`);
JSON decoded here and handed to :class:`~plcbuilder.lsp.protocol.PlcProtocol`,
which answers what JSON-RPC and LSP say for what cannot be served.

pygls's own reader trusts its input (a body of any length is read whole; a
body that is not JSON is logged and not answered). This one bounds every
frame and answers, then goes on serving:

- a body that is not JSON (or not UTF-8; ``NaN`` and ``Infinity`` are not
  JSON): ``-32700`` Parse error, id null;
- a frame over the size limit, a header without ``Content-Length``, or two
  ``Content-Length`` headers that differ: ``-32600``, id null (the body is
  skipped, and the next frame is read as it comes; the rest of a body whose
  ``Content-Length`` was too short does not swallow the next message's header);
- everything about the message itself: :mod:`plcbuilder.lsp.protocol`.

Over TCP each connection is a session of its own (its own documents and
checks), so one client never blocks or resets another. A connection that has
not sent ``initialize`` within :data:`INIT_TIMEOUT` seconds is closed.
"""

from __future__ import annotations

import asyncio
import json
import logging
import os
import sys
import threading
from typing import Callable, Optional

from pygls.io_ import StdoutWriter

from plcbuilder._support.framing import MAX_BODY, Frame, FrameReader
from plcbuilder.lsp.protocol import INTERNAL_ERROR, INVALID_REQUEST, PARSE_ERROR, PlcProtocol

log = logging.getLogger(__name__)

#: Seconds a TCP connection has to send ``initialize`` before it is closed.
INIT_TIMEOUT = 5.0
#: TCP sessions at once; when full, the oldest connection that has not
#: initialized is closed to make room (none: the newcomer is closed).
MAX_SESSIONS = 32
#: How often the interpreter hands the GIL between threads while the check
#: worker compiles: at Python's default (5 ms) every step of a request waited
#: up to that long for the compiling thread.
GIL_SWITCH_S = 0.001


def _not_json(constant: str):
    raise ValueError(f"{constant} is not a JSON value")


class Session:
    """One client's session: a server, the frames it is sent, and its end."""

    def __init__(self, server, writer, max_body: int = MAX_BODY):
        self.server = server
        self.protocol: PlcProtocol = server.protocol
        self.protocol.set_writer(writer)
        self.protocol.on_exit = self._exit
        self.frames = FrameReader(max_body)
        self.exit_code: Optional[int] = None
        self.started = 0.0                  # (TCP) when it connected, who, its writer
        self.peer = None
        self.transport_writer = None

    @property
    def initialized(self) -> bool:
        return self.protocol.initialize_received

    def feed(self, data: bytes) -> None:
        for ev in self.frames.feed(data):
            if self.exit_code is not None:
                return                       # nothing is read after exit
            if isinstance(ev, Frame):
                self.message(ev.body)
            else:
                self.protocol.reply_error(None, INVALID_REQUEST, ev.reason)

    def message(self, body: bytes) -> None:
        """One frame's body: answered with a parse error, or handed to the protocol."""
        try:
            raw = json.loads(body.decode("utf-8"), parse_constant=_not_json)
        except (UnicodeDecodeError, ValueError, RecursionError) as exc:
            self.protocol.reply_error(None, PARSE_ERROR, f"the message is not JSON: {exc}")
            return
        try:
            self.protocol.receive(raw)
        except Exception as exc:  # noqa: BLE001 - a bug: logged, answered, and serve on
            log.exception("cannot handle a message")
            if isinstance(raw, dict) and "method" in raw and "id" in raw:
                from plcbuilder.lsp.protocol import valid_id
                self.protocol.reply_error(raw["id"] if valid_id(raw["id"]) else None,
                                          INTERNAL_ERROR, f"internal error: {exc}")

    def _exit(self, code: int) -> None:
        self.exit_code = code

    def close(self) -> None:
        self.server.stop()
        self.server.shutdown()


# ---------------------------------------------------------------- stdio
def serve_stdio(make_server: Callable, stdin=None, stdout=None,
                max_body: int = MAX_BODY) -> int:
    """Serve one session on stdin/stdout until ``exit`` (its status: 0 after
    shutdown, 1 without) or the end of stdin (0)."""
    stdin = stdin or sys.stdin.buffer
    stdout = stdout or sys.stdout.buffer
    if sys.getswitchinterval() > GIL_SWITCH_S:
        sys.setswitchinterval(GIL_SWITCH_S)
    session = Session(make_server(), StdoutWriter(stdout), max_body)
    try:
        asyncio.run(_stdio(session, stdin))
    except BrokenPipeError:
        log.error("the client went away")
    except KeyboardInterrupt:
        pass
    finally:
        session.close()
    return session.exit_code or 0


async def _stdio(session: Session, stdin) -> None:
    loop = asyncio.get_running_loop()
    chunks: asyncio.Queue = asyncio.Queue()

    # A daemon thread, so that a blocked read never holds the exit; it reads
    # the file descriptor itself: a read through the buffered stdin holds
    # that object's lock, and an interpreter that exits meanwhile aborts
    # ("could not acquire lock for <stdin> at interpreter shutdown").
    try:
        fd = stdin.fileno()
    except (AttributeError, OSError, ValueError):
        fd = None

    def read() -> bytes:
        if fd is not None:
            return os.read(fd, 65536)
        return stdin.read1(65536) if hasattr(stdin, "read1") else stdin.read(65536)

    def pump():
        while True:
            try:
                data = read()
            except (OSError, ValueError):
                data = b""
            try:
                loop.call_soon_threadsafe(chunks.put_nowait, data)
            except RuntimeError:              # the loop is gone
                return
            if not data:
                return
    threading.Thread(target=pump, name="lsp-stdin", daemon=True).start()
    while session.exit_code is None:
        data = await chunks.get()
        if not data:
            return
        session.feed(data)


# ---------------------------------------------------------------- TCP
def serve_tcp(make_server: Callable, host: str, port: int, ready=None,
              init_timeout: float = INIT_TIMEOUT, max_sessions: int = MAX_SESSIONS,
              max_body: int = MAX_BODY) -> None:
    """Serve sessions on ``host:port``, each connection its own
    (``make_server()`` makes each one's server). ``ready(address)`` is called
    once listening."""
    if sys.getswitchinterval() > GIL_SWITCH_S:
        sys.setswitchinterval(GIL_SWITCH_S)
    try:
        asyncio.run(_tcp(make_server, host, port, ready, init_timeout, max_sessions, max_body))
    except KeyboardInterrupt:
        pass


async def _tcp(make_server, host, port, ready, init_timeout, max_sessions, max_body) -> None:
    sessions: set[Session] = set()
    loop = asyncio.get_running_loop()

    async def client(reader: asyncio.StreamReader, writer: asyncio.StreamWriter):
        peer = writer.get_extra_info("peername")
        if len(sessions) >= max_sessions:
            # full: the oldest connection that has not initialized makes room; when
            # every one is an editor's session, the newcomer is turned away
            idle = [x for x in sessions if not x.initialized]
            if not idle:
                log.warning("connection from %s closed: %d sessions already", peer, len(sessions))
                writer.close()
                return
            oldest = min(idle, key=lambda x: x.started)
            log.warning("connection from %s closed to make room: it had not initialized",
                        oldest.peer)
            sessions.discard(oldest)
            oldest.transport_writer.close()
        session = Session(make_server(), writer, max_body)
        session.started, session.peer, session.transport_writer = loop.time(), peer, writer
        sessions.add(session)
        deadline = loop.time() + init_timeout
        try:
            while session.exit_code is None:
                if session.initialized:
                    data = await reader.read(65536)
                else:
                    left = deadline - loop.time()
                    if left <= 0:
                        raise TimeoutError
                    data = await asyncio.wait_for(reader.read(65536), left)
                if not data:
                    break
                session.feed(data)
                await writer.drain()     # a client that does not read is not buffered for
        except TimeoutError:
            log.warning("connection from %s closed: no initialize within %g s", peer, init_timeout)
        except (ConnectionError, OSError):
            pass
        finally:
            sessions.discard(session)
            session.close()
            writer.close()

    srv = await asyncio.start_server(client, host, port)
    if ready is not None:
        ready(srv.sockets[0].getsockname()[:2])
    async with srv:
        await srv.serve_forever()
