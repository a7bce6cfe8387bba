"""How the language server reads its messages: stdio or one TCP client at a
time, ``Content-Length`` frames (:mod:`plcbuilder._support.framing`), and
JSON-RPC's answers to what cannot be served.

pygls's own reader trusts its input (a body of any length is read whole; a
body that is not JSON is logged and not answered). This one bounds every
frame and answers as JSON-RPC 2.0 says, then goes on serving:

- a body that is not JSON (or not UTF-8): ``-32700`` Parse error, id null;
- JSON that is not a request object: ``-32600`` Invalid Request;
- params that do not fit the method: ``-32602`` Invalid params, with its id;
- a frame over the size limit, or a header without ``Content-Length``:
  ``-32600``, id null (the body is skipped unread);
- an unknown method: pygls answers ``-32601`` Method not found.
"""

from __future__ import annotations

import asyncio
import json
import logging
import os
import sys
import threading
from typing import Optional

from pygls.exceptions import JsonRpcInvalidParams
from pygls.io_ import StdoutWriter

from plcbuilder._support.framing import MAX_BODY, Frame, FrameReader

log = logging.getLogger(__name__)

PARSE_ERROR = -32700
INVALID_REQUEST = -32600
INVALID_PARAMS = -32602
INTERNAL_ERROR = -32603


class Transport:
    """Feeds a pygls server's protocol from a byte stream."""

    def __init__(self, server, max_body: int = MAX_BODY):
        self.server = server
        self.max_body = max_body

    # ------------------------------------------------------------ running
    def serve_stdio(self, stdin=None, stdout=None) -> None:
        stdin = stdin or sys.stdin.buffer
        stdout = stdout or sys.stdout.buffer
        self.server._stop_event = threading.Event()
        self.server.protocol.set_writer(StdoutWriter(stdout))
        try:
            asyncio.run(self._stdio(stdin))
        except BrokenPipeError:
            log.error("the client went away")
        except (KeyboardInterrupt, SystemExit):
            pass
        finally:
            self.server.shutdown()

    def serve_tcp(self, host: str, port: int, ready=None) -> None:
        """Serve clients on ``host:port``, one connection at a time (each one
        starts a new session of the same server). ``ready(address)`` is called
        once listening."""
        self.server._stop_event = threading.Event()
        try:
            asyncio.run(self._tcp(host, port, ready))
        except (KeyboardInterrupt, SystemExit):
            pass
        finally:
            self.server.shutdown()

    async def _stdio(self, stdin) -> None:
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
                loop.call_soon_threadsafe(chunks.put_nowait, data)
                if not data:
                    return
        threading.Thread(target=pump, name="lsp-stdin", daemon=True).start()
        frames = FrameReader(self.max_body)
        while not self.server._stop_event.is_set():
            data = await chunks.get()
            if not data:
                return
            self.feed(frames, data)

    async def _tcp(self, host: str, port: int, ready) -> None:
        busy = asyncio.Lock()

        async def client(reader: asyncio.StreamReader, writer: asyncio.StreamWriter):
            if busy.locked():
                writer.close()
                return
            async with busy:
                self.server.protocol.set_writer(writer)
                frames = FrameReader(self.max_body)
                try:
                    while True:
                        data = await reader.read(65536)
                        if not data:
                            break
                        self.feed(frames, data)
                finally:
                    writer.close()

        srv = await asyncio.start_server(client, host, port)
        if ready is not None:
            ready(srv.sockets[0].getsockname()[:2])
        async with srv:
            await srv.serve_forever()

    # ------------------------------------------------------------ messages
    def feed(self, frames: FrameReader, data: bytes) -> None:
        for ev in frames.feed(data):
            if isinstance(ev, Frame):
                self.message(ev.body)
            else:
                self.error(None, INVALID_REQUEST, ev.reason)

    def message(self, body: bytes) -> None:
        """One frame's body: answered with an error, or handed to pygls."""
        try:
            raw = json.loads(body.decode("utf-8"))
        except (UnicodeDecodeError, ValueError, RecursionError) as exc:
            self.error(None, PARSE_ERROR, f"the message is not JSON: {exc}")
            return
        if not isinstance(raw, dict):
            self.error(None, INVALID_REQUEST, "a JSON-RPC message is an object, not "
                                              f"{type(raw).__name__}")
            return
        mid = raw.get("id")
        if not isinstance(mid, (int, str)) or isinstance(mid, bool):
            mid = None
        if raw.get("jsonrpc") != "2.0":
            self.error(mid, INVALID_REQUEST, 'a JSON-RPC 2.0 message has "jsonrpc": "2.0"')
            return
        if "method" in raw and not isinstance(raw["method"], str):
            self.error(mid, INVALID_REQUEST, "method must be a string")
            return
        protocol = self.server.protocol
        try:
            msg = protocol.structure_message(raw)
        except JsonRpcInvalidParams:
            if "method" in raw and "id" in raw:
                self.error(mid, INVALID_PARAMS, f"invalid params for {raw['method']}")
            return
        except Exception as exc:  # noqa: BLE001 - an answer, and serve on
            if "id" in raw:
                self.error(mid, INTERNAL_ERROR, f"cannot read the message: {exc}")
            return
        if not hasattr(msg, "jsonrpc"):
            self.error(mid, INVALID_REQUEST, "neither a request, a notification nor a response")
            return
        try:
            protocol.handle_message(msg)
        except Exception as exc:  # noqa: BLE001 - pygls answers requests itself; serve on
            log.exception("cannot handle a message")
            if "id" in raw and "method" in raw:
                self.error(mid, INTERNAL_ERROR, f"internal error: {exc}")

    def error(self, mid: Optional[object], code: int, message: str) -> None:
        self.server.protocol._send_data(
            {"jsonrpc": "2.0", "id": mid, "error": {"code": code, "message": message}})
