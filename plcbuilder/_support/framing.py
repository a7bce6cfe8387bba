"""``Content-Length`` framing, as the Language Server Protocol and the Debug
Adapter Protocol frame their JSON messages::

    Content-Length: 52\\r\\n
    \\r\\n
    {"jsonrpc": "2.0", "id": 1, "method": "initialize", ...}

:class:`FrameReader` is a parser without I/O: :meth:`FrameReader.feed` takes
whatever bytes arrived and returns what they completed, in order: a
:class:`Frame` (a whole body) or a :class:`FrameError` (a header it cannot
use, a body over the limit). Nothing it is fed can make it raise or hold more
than ``max_header`` + ``max_body`` bytes: a body over the limit is skipped as
it arrives, and after a header it cannot read it looks for the next
``Content-Length:`` and goes on from there, so one bad frame costs one error
and the connection keeps serving.

:func:`encode_frame` frames one body.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Union

#: Largest body accepted by default (a document of a megabyte is 1-2 MB as JSON).
MAX_BODY = 16 << 20
#: Largest header block (every header line together).
MAX_HEADER = 8 << 10

_LENGTH = re.compile(rb"content-length[ \t]*:[ \t]*(\S*)[ \t]*$", re.IGNORECASE)
_RESYNC = re.compile(rb"content-length[ \t]*:", re.IGNORECASE)


@dataclass(frozen=True)
class Frame:
    body: bytes


@dataclass(frozen=True)
class FrameError:
    """A frame that could not be used; ``reason`` says why. ``skipped`` is the
    number of body bytes thrown away (a body over the limit)."""
    reason: str
    skipped: int = 0


Event = Union[Frame, FrameError]


def encode_frame(body: bytes) -> bytes:
    """One framed message (the length counts the body's bytes)."""
    return b"Content-Length: %d\r\n\r\n" % len(body) + body


class FrameReader:
    """Turns a byte stream into frames; see the module's docstring."""

    def __init__(self, max_body: int = MAX_BODY, max_header: int = MAX_HEADER):
        self.max_body = max_body
        self.max_header = max_header
        self._buf = bytearray()
        self._need = -1          # body bytes still to read (-1: reading a header)
        self._skip = 0           # body bytes still to throw away
        self._resync = False     # after a bad header: looking for the next Content-Length
        self.frames = 0
        self.errors = 0

    @property
    def pending(self) -> int:
        """Bytes held (an unfinished header or body)."""
        return len(self._buf)

    def feed(self, data: bytes) -> list[Event]:
        out: list[Event] = []
        self._buf += data
        while True:
            if self._skip:
                n = min(self._skip, len(self._buf))
                del self._buf[:n]
                self._skip -= n
                if self._skip:
                    return out
                continue
            if self._need >= 0:
                if len(self._buf) < self._need:
                    return out
                body = bytes(self._buf[:self._need])
                del self._buf[:self._need]
                self._need = -1
                self.frames += 1
                out.append(Frame(body))
                continue
            if self._resync:
                m = _RESYNC.search(self._buf)
                if m is None:
                    # keep a tail that may be the start of the next header name
                    keep = len(b"content-length:") - 1
                    if len(self._buf) > keep:
                        del self._buf[:len(self._buf) - keep]
                    return out
                del self._buf[:m.start()]
                self._resync = False
            end, sep = self._header_end()
            if end < 0:
                if len(self._buf) > self.max_header:
                    self._error(out, f"a header of more than {self.max_header} bytes "
                                     "without the blank line that ends it")
                    del self._buf[:]
                    self._resync = True
                return out
            header = bytes(self._buf[:end])
            del self._buf[:end + sep]
            if not header.strip():
                continue                          # blank lines between messages
            self._header(header, out)

    # ------------------------------------------------------------ private
    def _header_end(self) -> tuple[int, int]:
        """(where the header ends, the length of the blank line) or (-1, 0)."""
        crlf = self._buf.find(b"\r\n\r\n")
        lf = self._buf.find(b"\n\n")
        if crlf >= 0 and (lf < 0 or crlf < lf):
            return crlf, 4
        if lf >= 0:
            return lf, 2
        return -1, 0

    def _header(self, header: bytes, out: list[Event]) -> None:
        values = [m.group(1) for m in (_LENGTH.match(line.strip(b"\r"))
                                       for line in header.split(b"\n")) if m is not None]
        if not values:
            # Bytes before the header are what is left of a body whose
            # Content-Length was too short (that frame was used and refused): the
            # header after them is the next message's, not lost with them.
            m = _RESYNC.search(header)
            if m is not None:
                line = header[m.start():].split(b"\n", 1)[0]
                got = _LENGTH.match(line.strip(b"\r"))
                values = [got.group(1)] if got is not None else []
        if not values:
            shown = header[:60].decode("utf-8", "replace").replace("\r", "").replace("\n", " | ")
            self._error(out, f"a frame without a Content-Length header ({shown!r})")
            self._resync = True
            return
        if len(set(values)) > 1:
            # which one is the body's length cannot be known: the frame is refused
            # and the next one is looked for (as HTTP treats differing lengths)
            shown = " and ".join(v[:20].decode("utf-8", "replace") for v in dict.fromkeys(values))
            self._error(out, f"a frame with different Content-Length headers ({shown}); it is "
                             "skipped")
            self._resync = True
            return
        length = values[0]
        if not length.isdigit() or len(length) > 12:
            self._error(out, f"Content-Length {length[:20].decode('utf-8', 'replace')!r} "
                             "is not a number of bytes")
            self._resync = True
            return
        n = int(length)
        if n > self.max_body:
            self._error(out, f"a message of {n} bytes is over the limit of {self.max_body} "
                             "bytes; it is skipped", n)
            self._skip = n
            return
        self._need = n

    def _error(self, out: list[Event], reason: str, skipped: int = 0) -> None:
        self.errors += 1
        out.append(FrameError(reason, skipped))
