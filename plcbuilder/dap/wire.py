"""The Debug Adapter Protocol's wire: ``Content-Length`` frames of JSON on a
byte stream (:mod:`plcbuilder._support.framing`), messages numbered by
``seq``, writes from several threads (requests answered on the main thread,
events from the controller's reader thread) kept whole by a lock.

A frame that is not a DAP message cannot be answered (it has no ``seq`` to
answer): it is reported as an ``output`` event on stderr, and reading goes on.
"""

from __future__ import annotations

import json
import threading
from typing import Callable, Iterator, Optional, Union

from plcbuilder._support.framing import MAX_BODY, Frame, FrameReader, encode_frame


class BadMessage(Exception):
    """A frame that is not a DAP message; ``seq`` and ``command`` when it had them."""

    def __init__(self, reason: str, seq: Optional[int] = None, command: str = ""):
        super().__init__(reason)
        self.reason = reason
        self.seq = seq
        self.command = command


class Wire:
    def __init__(self, read: Callable[[int], bytes], write: Callable[[bytes], None],
                 max_body: int = MAX_BODY):
        self._read = read
        self._write = write
        self._lock = threading.Lock()
        self._seq = 0
        self._frames = FrameReader(max_body)
        self.closed = False

    # ------------------------------------------------------------ reading
    def messages(self) -> Iterator[Union[dict, BadMessage]]:
        """Each message read (a dict), or a BadMessage for a frame that is not one,
        until the input ends."""
        while True:
            try:
                data = self._read(65536)
            except (OSError, ValueError):
                data = b""
            if not data:
                return
            for ev in self._frames.feed(data):
                if isinstance(ev, Frame):
                    yield _decode(ev.body)
                else:
                    yield BadMessage(ev.reason)

    # ------------------------------------------------------------ writing
    def send(self, msg: dict) -> None:
        with self._lock:
            if self.closed:
                return
            self._seq += 1
            msg = {"seq": self._seq, **msg}
            try:
                self._write(encode_frame(json.dumps(msg).encode("utf-8")))
            except (OSError, ValueError):
                self.closed = True

    def respond(self, request: dict, body: Optional[dict] = None, error: Optional[str] = None):
        msg = {"type": "response", "request_seq": request.get("seq", 0),
               "command": request.get("command", ""), "success": error is None}
        if error is not None:
            msg["message"] = error
            msg["body"] = {"error": {"id": 1, "format": error.replace("{", "(").replace("}", ")"),
                                     "showUser": True}}
        elif body is not None:
            msg["body"] = body
        self.send(msg)

    def event(self, name: str, body: Optional[dict] = None) -> None:
        msg = {"type": "event", "event": name}
        if body is not None:
            msg["body"] = body
        self.send(msg)

    def output(self, text: str, category: str = "console") -> None:
        self.event("output", {"category": category,
                              "output": text if text.endswith("\n") else text + "\n"})


def _decode(body: bytes) -> Union[dict, BadMessage]:
    try:
        msg = json.loads(body.decode("utf-8"))
    except (UnicodeDecodeError, ValueError, RecursionError) as exc:
        return BadMessage(f"a message that is not JSON: {exc}")
    if not isinstance(msg, dict):
        return BadMessage(f"a message is a JSON object, not {type(msg).__name__}")
    seq = msg.get("seq")
    seq = seq if isinstance(seq, int) and not isinstance(seq, bool) else None
    command = msg.get("command") if isinstance(msg.get("command"), str) else ""
    if msg.get("type") != "request" or not command:
        if msg.get("type") == "response":
            return msg                              # answers to our requests: none are sent
        return BadMessage('a request has "type": "request" and a "command"', seq, command)
    if seq is None:
        return BadMessage("a request has a whole-number seq", None, command)
    args = msg.get("arguments", {})
    if args is None:
        msg["arguments"] = {}
    elif not isinstance(args, dict):
        return BadMessage("arguments must be an object", seq, command)
    return msg
