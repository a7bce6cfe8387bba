"""Autocompletion: what may be typed at the caret.

The list holds the keywords, the built-in functions (with call tips giving
their signatures), the predefined variables, the built-in names of the
myCNC tables, the project's defines and pins (from the last compile of the
file, or — before there is one — from the project's headers and the
built-in ``pins.h``), and the file's own variables and procedures.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Iterable, Optional

from plcbuilder.api import abi
from plcbuilder.api import Kind
from plcbuilder.ide.editor import (KIND_CONSTANT, KIND_DEFINE, KIND_FUNCTION, KIND_KEYWORD,
                                   KIND_PREDEFINED, KIND_PROCEDURE, KIND_VARIABLE)
from plcbuilder.lang.checker import BUILTINS
from plcbuilder.lang.highlight import KEYWORDS
from plcbuilder.lang.preprocess import builtin_header
from plcbuilder.lang.source import MAX_SOURCE_BYTES
from plcbuilder._support.files import read_bounded

_DEFINE_RE = re.compile(r"^[ \t]*#[ \t]*define[ \t]+([A-Za-z_][A-Za-z0-9_]*)[ \t]*([^\n]*)$",
                        re.MULTILINE)
_ASSIGN_RE = re.compile(r"(?<![A-Za-z0-9_])([A-Za-z_][A-Za-z0-9_]*)\s*(?:=(?!=)|\+\+|--)")
_PROC_RE = re.compile(r"^[ \t]*([A-Za-z_][A-Za-z0-9_]*)[ \t]*\([ \t]*\)[ \t]*(?:\{|$)",
                      re.MULTILINE)
_COMMENT_RE = re.compile(r"//[^\n]*|/\*[\s\S]*?(?:\*/|$)")


def scan_defines(text: str) -> dict[str, str]:
    """{name: replacement text} of every #define in text (comments dropped)."""
    out = {}
    for m in _DEFINE_RE.finditer(text):
        value = _COMMENT_RE.sub("", m.group(2)).strip()
        out.setdefault(m.group(1), value)
    return out


def scan_variables(text: str) -> list[str]:
    """Names the text assigns (``x = …``, ``x++``): its own variables, found
    even while the file does not compile."""
    code = _COMMENT_RE.sub(" ", text)
    names = []
    seen = set()
    for m in _ASSIGN_RE.finditer(code):
        n = m.group(1)
        if n not in seen and n not in KEYWORDS and n not in BUILTINS:
            seen.add(n)
            names.append(n)
    return names


def scan_procedures(text: str) -> list[str]:
    code = _COMMENT_RE.sub(" ", text)
    return [m.group(1) for m in _PROC_RE.finditer(code)
            if m.group(1) not in KEYWORDS and m.group(1) not in BUILTINS]


class HeaderDefines:
    """The defines of a project's include folder plus the built-in pins.h,
    re-read only when a header changed."""

    def __init__(self):
        self._cache: dict[str, tuple[float, dict[str, tuple[str, str, int]]]] = {}

    def defines(self, include_dirs: Iterable[Path]) -> dict[str, tuple[str, str, int]]:
        """{name: (value text, file, line)}."""
        out: dict[str, tuple[str, str, int]] = {}
        for folder in include_dirs:
            try:
                headers = sorted(p for p in Path(folder).glob("*.h") if p.is_file())
            except OSError:
                continue
            for h in headers:
                for name, v in self._file(h).items():
                    out.setdefault(name, v)
        pins = builtin_header("pins.h")
        if pins:
            for name, v in self._text("<builtin>/pins.h", pins).items():
                out.setdefault(name, v)
        return out

    def _file(self, path: Path) -> dict:
        try:
            mtime = path.stat().st_mtime
        except OSError:
            return {}
        key = str(path)
        hit = self._cache.get(key)
        if hit and hit[0] == mtime:
            return hit[1]
        try:
            text = read_bounded(path, MAX_SOURCE_BYTES).decode("utf-8", errors="replace")
        except OSError:
            return {}
        found = self._text(key, text)
        self._cache[key] = (mtime, found)
        return found

    @staticmethod
    def _text(name: str, text: str) -> dict:
        out = {}
        for m in _DEFINE_RE.finditer(text):
            value = _COMMENT_RE.sub("", m.group(2)).strip()
            line = text.count("\n", 0, m.start()) + 1
            out.setdefault(m.group(1), (value, name, line))
        return out


def predefined_variables(kind: Kind) -> list[str]:
    names = list(abi.SLOT_NAMES) + list(abi.MAPPED_VARIABLES)
    if kind is Kind.SOFTWARE:
        names += list(abi.SOFTWARE_SLOT_NAMES)
    return names


def completions(prefix: str, *, kind: Kind = Kind.HARDWARE, text: str = "",
                symbols=None, defines: Optional[dict] = None) -> list[tuple[str, int]]:
    """Every candidate as (name, kind-of-item); the editor filters by prefix.

    ``symbols`` is the last compile's CompileResult.symbols (or None);
    ``defines`` the project's header defines (name -> anything)."""
    out: list[tuple[str, int]] = []
    out += [(k, KIND_KEYWORD) for k in sorted(KEYWORDS)]
    out += [(b, KIND_FUNCTION) for b in BUILTINS]
    out += [(v, KIND_PREDEFINED) for v in predefined_variables(kind)]
    if symbols is not None:
        out += [(n, KIND_DEFINE) for n in getattr(symbols, "defines", {}) or {}]
        out += [(n, KIND_PROCEDURE) for n in getattr(symbols, "procedures", {}) or {}]
        out += [(n, KIND_VARIABLE) for n in getattr(symbols, "variables", []) or []]
    if defines:
        out += [(n, KIND_DEFINE) for n in defines]
    if text:
        out += [(n, KIND_DEFINE) for n in scan_defines(text)]
        out += [(n, KIND_PROCEDURE) for n in scan_procedures(text)]
        out += [(n, KIND_VARIABLE) for n in scan_variables(text) if n != prefix]
    if len(prefix) >= 1:
        out += [(n, KIND_CONSTANT) for n in abi.BUILTIN_NAMES]
    seen: set[str] = set()
    unique = []
    for name, k in out:
        if name not in seen:
            seen.add(name)
            unique.append((name, k))
    return unique


def signature(name: str) -> Optional[str]:
    """The call tip of a built-in function: its signature and what it does."""
    b = BUILTINS.get(name)
    if b is None:
        return None
    ret = "returns a value" if b.returns else "returns nothing"
    return f"{b.name}({', '.join(b.params)})  — {ret}\n{b.doc}"
