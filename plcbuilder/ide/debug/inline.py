"""Inline values and hover values: which variables a line uses, and the text
shown at its end while the controller is halted (``statez = 0 · sens = 1``).

Pure functions of text and values (tested without widgets); the editor marks
(:mod:`.markers`) show the result.
"""

from __future__ import annotations

import re
from typing import Mapping, Optional

from plcbuilder.lang.builtins import KEYWORDS

_IDENT = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
_STRING_OR_COMMENT = re.compile(r'"(?:[^"\\]|\\.)*"|//.*')
#: at most this many values at the end of one line
MAX_PER_LINE = 6


def code_part(line: str, in_comment: bool = False) -> tuple[str, bool]:
    """The line without comments (and strings); ``in_comment``: a ``/*`` comment
    is open at its start. Returns (code, a block comment still open at its end)."""
    out = []
    i = 0
    while i < len(line):
        if in_comment:
            end = line.find("*/", i)
            if end < 0:
                return "".join(out), True
            i, in_comment = end + 2, False
            out.append(" ")
            continue
        start = line.find("/*", i)
        chunk = line[i:] if start < 0 else line[i:start]
        out.append(_STRING_OR_COMMENT.sub(" ", chunk))
        if start < 0 or "//" in chunk:
            break
        i, in_comment = start + 2, True
    return "".join(out), in_comment


def names_on_lines(text: str) -> dict[int, list[str]]:
    """Every identifier used on each line (1-based), in order, once each;
    comments and preprocessor lines left out."""
    out: dict[int, list[str]] = {}
    in_comment = False
    for n, line in enumerate(text.split("\n"), 1):
        code, in_comment = code_part(line, in_comment)
        if code.lstrip().startswith("#"):
            continue
        seen: list[str] = []
        for m in _IDENT.finditer(code):
            w = m.group()
            if w not in seen and w not in KEYWORDS:
                seen.append(w)
        if seen:
            out[n] = seen
    return out


def inline_values(text: str, values: Mapping[str, int], *, forced: frozenset = frozenset(),
                  lines: Optional[range] = None) -> dict[int, str]:
    """``{line: "a = 1 · b = 2"}`` for the lines (1-based, all or ``lines``) that
    use one of ``values``' names; a forced name is marked ``(forced)``."""
    out = {}
    for n, names in names_on_lines(text).items():
        if lines is not None and n not in lines:
            continue
        parts = []
        for name in names:
            if name in values:
                mark = " (forced)" if name in forced else ""
                parts.append(f"{name} = {values[name]}{mark}")
        if parts:
            more = len(parts) - MAX_PER_LINE
            text_ = " · ".join(parts[:MAX_PER_LINE]) + (f" · +{more}" if more > 0 else "")
            out[n] = text_
    return out


def hover_value(name: str, values: Mapping[str, int], procedure: str, *,
                halted: bool, forced: bool = False) -> Optional[str]:
    """The hover line of a variable's live value (None when unknown)."""
    if name not in values:
        return None
    v = int(values[name])
    when = "halted" if halted else "live"
    text = f"{procedure}.{name} = {v} (0x{v & 0xFFFFFFFF:x}) — {when}"
    if forced:
        text += ", forced"
    return text
