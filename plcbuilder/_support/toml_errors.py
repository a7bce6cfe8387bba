"""TOML for messages: parsing that never overflows the stack (``loads``), and
line numbers for messages: where a parse error is, and where a key is
(``tomllib`` gives values, not their places)."""

from __future__ import annotations

import re

from .lazy import Pattern

TYPE_CHECKING = False               # (typing is not imported at run time: start-up)
if TYPE_CHECKING:
    from typing import Optional

if TYPE_CHECKING:
    import tomllib

#: (patterns compiled when first used: not at every start)
_AT = Pattern(r"\s*\(at line (\d+), column \d+\)")
_END = " (at end of document)"
_HEADER = Pattern(r"^\s*(\[\[?)\s*([^\]]+?)\s*\]\]?\s*(#.*)?$")


def loads(text: str) -> dict:
    """``tomllib.loads``, with nesting too deep for the parser (it recurses:
    ``a = [[[[…`` 50,000 deep) raised as a ``TOMLDecodeError`` like any other
    syntax error, never a ``RecursionError``."""
    import tomllib                      # (not loaded until a settings file is read)
    try:
        return tomllib.loads(text)
    except RecursionError:
        raise tomllib.TOMLDecodeError("arrays or tables are nested too deeply") from None


def decode_error(exc: tomllib.TOMLDecodeError, text: str) -> tuple[str, Optional[int]]:
    """(the message without its position, the line) of a TOML parse error; an
    error at the end of the document is on its last line."""
    msg = str(exc)
    m = _AT.search(msg)
    if m:
        return _AT.sub("", msg), int(m.group(1))
    if _END in msg:
        return msg.replace(_END, ""), max(1, len(text.splitlines()))
    return msg, None


def split_key(text: str) -> tuple[str, ...]:
    """A dotted TOML key's parts, quotes removed."""
    parts = []
    for p in re.findall(r'"[^"]*"|\'[^\']*\'|[^.]+', text):
        p = p.strip()
        if len(p) >= 2 and p[0] == p[-1] and p[0] in "\"'":
            p = p[1:-1]
        parts.append(p)
    return tuple(parts)


class TomlLocator:
    """Finds the line of a key in TOML text (best effort: plain tables, arrays of
    tables and ``key = value`` lines; None when not found). A path is a tuple of
    table names and keys, with the index of an array-of-tables entry after its
    name: ``("axes", "Z", "accel")``, ``("inputs", 2, "pin")``."""

    def __init__(self, text: str):
        self.lines = text.splitlines()
        # one entry per header: (line number, table path with array indexes)
        self.headers: list[tuple[int, tuple]] = [(0, ())]
        counts: dict[tuple, int] = {}
        for n, line in enumerate(self.lines, 1):
            m = _HEADER.match(line)
            if not m:
                continue
            path = split_key(m.group(2))
            if m.group(1) == "[[":
                k = counts.get(path, 0)
                counts[path] = k + 1
                self.headers.append((n, path + (k,)))
            else:
                self.headers.append((n, path))

    def line_of(self, path: tuple) -> Optional[int]:
        """The line of the key at ``path``, else the header of its table."""
        best: Optional[int] = None
        for i, (hline, hpath) in enumerate(self.headers):
            if hpath and hpath == path:
                return hline
            if path[:len(hpath)] == hpath and len(path) > len(hpath):
                rest = [p for p in path[len(hpath):] if not isinstance(p, int)]
                end = self.headers[i + 1][0] if i + 1 < len(self.headers) else len(self.lines) + 1
                found = self._key_line(rest, hline + 1, end)
                if found is not None:
                    return found
                if hpath:
                    best = hline
        return best

    def _key_line(self, rest: list, start: int, end: int) -> Optional[int]:
        if not rest:
            return None
        dotted = r"\s*\.\s*".join(
            r"(?:%s|\"%s\"|'%s')" % ((re.escape(str(p)),) * 3) for p in rest)
        pat = re.compile(r"^\s*(?:%s)\s*=" % dotted)
        first = re.compile(r"^\s*(?:%s|\"%s\"|'%s')\s*=" % ((re.escape(str(rest[0])),) * 3))
        fallback = None
        for n in range(start, end):
            line = self.lines[n - 1]
            if pat.match(line):
                return n
            if fallback is None and first.match(line):
                fallback = n
        return fallback
