"""Positions between the compiler and the client.

The compiler counts 1-based lines and columns in characters (code points);
an LSP client counts 0-based lines and columns in the code units of the
position encoding agreed at ``initialize`` (UTF-16 unless the client offers
UTF-8 or UTF-32). A span becomes a range through the text of its lines.
"""

from __future__ import annotations

from typing import Callable, Optional

from lsprotocol import types as T

from plcbuilder.lang import Span

UTF8, UTF16, UTF32 = "utf-8", "utf-16", "utf-32"


def units(text: str, encoding: str) -> int:
    """How many code units ``text`` is in the encoding."""
    if encoding == UTF32 or text.isascii():
        return len(text)
    if encoding == UTF8:
        return len(text.encode("utf-8"))
    return len(text.encode("utf-16-le")) // 2


def to_client(line: str, col: int, encoding: str) -> int:
    """A 0-based character column of ``line`` -> the client's column."""
    return units(line[:max(col, 0)], encoding)


def from_client(line: str, character: int, encoding: str) -> int:
    """The client's column in ``line`` -> a 0-based character column (clamped)."""
    if encoding == UTF32 or line.isascii():
        return min(max(character, 0), len(line))
    n = 0
    for i, ch in enumerate(line):
        if n >= character:
            return i
        n += units(ch, encoding)
    return len(line)


class Lines:
    """The lines of one text, for turning positions around."""

    def __init__(self, text: str, encoding: str = UTF16):
        self.lines = text.split("\n")
        self.encoding = encoding
        starts = [0]
        for ln in self.lines[:-1]:
            starts.append(starts[-1] + len(ln) + 1)
        self.starts = starts

    def line(self, n0: int) -> str:
        return self.lines[n0] if 0 <= n0 < len(self.lines) else ""

    def position(self, line1: int, col1: int) -> T.Position:
        """A compiler (line, col) -> a client Position."""
        n0 = max(line1 - 1, 0)
        return T.Position(n0, to_client(self.line(n0), col1 - 1, self.encoding))

    def offset(self, pos: T.Position) -> int:
        """A client Position -> a character offset into the text."""
        n0 = min(max(pos.line, 0), len(self.lines) - 1)
        return self.starts[n0] + from_client(self.lines[n0], pos.character, self.encoding)

    def at_offset(self, offset: int) -> T.Position:
        import bisect
        n0 = max(bisect.bisect_right(self.starts, offset) - 1, 0)
        return T.Position(n0, to_client(self.lines[n0], offset - self.starts[n0], self.encoding))

    def span_range(self, span: Span) -> T.Range:
        return T.Range(self.position(span.line, span.col), self.position(span.end_line, span.end_col))


def span_range(span: Span, line_text: Callable[[int], Optional[str]], encoding: str) -> T.Range:
    """A span -> a range, ``line_text(line1)`` giving the text of a line (or None:
    the columns are taken as they are)."""
    def pos(line1: int, col1: int) -> T.Position:
        text = line_text(line1)
        col0 = max(col1 - 1, 0)
        return T.Position(max(line1 - 1, 0), col0 if text is None else to_client(text, col0, encoding))
    return T.Range(pos(span.line, span.col), pos(span.end_line, span.end_col))
