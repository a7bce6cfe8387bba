"""The Debug Adapter Protocol's wire: ``Content-Length`` frames of JSON on a
byte stream (:mod:`plcbuilder._support.framing`), messages numbered by
``seq``, writes from several threads (requests answered on the session's
threads, events from the controller's reader thread) kept whole by a lock.

Order (docs/editors.md, "Debugging from an editor"): while a request that may
cause events is being handled the wire is *held* (:meth:`Wire.hold`): events
wait and go out after its response, so a response comes before the events it
causes. After ``terminated`` no event is sent but ``exited``, until the
session starts again (:meth:`Wire.reopen`, a new launch or attach).

A frame that is not a DAP message cannot be answered (it has no ``seq`` to
answer): it is reported as an ``output`` event on stderr, and reading goes on.
A failed request's ``body.error`` asks the client to show it to the user
(``showUser``) only when told to: for a launch or attach that did not start the
session, not for every request the adapter does not carry out.
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
        self._held = 0
        self._waiting: list[dict] = []
        self.ended = False              # "terminated" was sent

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
            if msg.get("type") == "event" and self._held:
                self._waiting.append(msg)
                return
            self._send(msg)

    def _send(self, msg: dict) -> None:
        """Write one message (the lock held)."""
        if self.closed:
            return
        if msg.get("type") == "event":
            if self.ended and msg.get("event") != "exited":
                return                      # nothing follows terminated but exited
            if msg.get("event") == "terminated":
                self.ended = True
        self._seq += 1
        msg = {"seq": self._seq, **msg}
        try:
            self._write(encode_frame(json.dumps(msg).encode("utf-8")))
        except (OSError, ValueError):
            self.closed = True

    def hold(self) -> None:
        """Keep events back (they queue) until :meth:`release`; responses go on."""
        with self._lock:
            self._held += 1

    def release(self) -> None:
        """The events kept back, sent in the order they came."""
        with self._lock:
            self._held = max(0, self._held - 1)
            if self._held:
                return
            waiting, self._waiting = self._waiting, []
            for msg in waiting:
                self._send(msg)

    def reopen(self) -> None:
        """A new launch or attach: events flow again after a terminated."""
        with self._lock:
            self.ended = False

    def respond(self, request: dict, body: Optional[dict] = None, error: Optional[str] = None,
                show_user: bool = False):
        msg = {"type": "response", "request_seq": request.get("seq", 0),
               "command": request.get("command", ""), "success": error is None}
        if error is not None:
            msg["message"] = error
            msg["body"] = {"error": {"id": 1, "format": error.replace("{", "(").replace("}", ")"),
                                     "showUser": show_user}}
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
    seq = seq if isinstance(seq, int) and not isinstance(seq, bool) and seq >= 1 else None
    command = msg.get("command") if isinstance(msg.get("command"), str) else ""
    if msg.get("type") != "request" or not command:
        if msg.get("type") == "response":
            return msg                              # answers to our requests: none are sent
        return BadMessage('a request has "type": "request" and a "command"', seq, command)
    if seq is None:
        return BadMessage("a request has a whole-number seq from 1", None, command)
    args = msg.get("arguments", {})
    if args is None:
        msg["arguments"] = {}
    elif not isinstance(args, dict):
        return BadMessage("arguments must be an object", seq, command)
    return msg
