"""Autocompletion: what may be typed at the caret.

The candidates come from :mod:`plcbuilder.lang.symbols` (the real tokens of
the editor's text, so they are there while the file does not compile): the
keywords, the built-in functions (with call tips giving their signatures), the
predefined variables, the built-in names of the myCNC tables, the file's
defines, variables and procedures, plus the last compile's symbols and the
project's header defines (and the built-in ``pins.h``).
"""

from __future__ import annotations

from pathlib import Path
from typing import Iterable, Optional

from plcbuilder.api import Kind
from plcbuilder.ide.editor import (KIND_CONSTANT, KIND_DEFINE, KIND_FUNCTION, KIND_KEYWORD,
                                   KIND_PREDEFINED, KIND_PROCEDURE, KIND_VARIABLE)
from plcbuilder.lang import symbols as lang_symbols
from plcbuilder.lang.hover import signature_text

#: the language's kinds of item -> the editor's
KINDS = {
    lang_symbols.KEYWORD: KIND_KEYWORD, lang_symbols.FUNCTION: KIND_FUNCTION,
    lang_symbols.PREDEFINED_VARIABLE: KIND_PREDEFINED, lang_symbols.DEFINE: KIND_DEFINE,
    lang_symbols.PROCEDURE: KIND_PROCEDURE, lang_symbols.VARIABLE: KIND_VARIABLE,
    lang_symbols.CONSTANT: KIND_CONSTANT,
}

_last: Optional[tuple[str, lang_symbols.SymbolIndex]] = None


def index(text: str) -> lang_symbols.SymbolIndex:
    """The symbols of an editor's text (the last one is kept: hover and
    completion ask again and again about text that did not change)."""
    global _last
    if _last is None or _last[0] != text:
        _last = (text, lang_symbols.index(text, "<editor>"))
    return _last[1]


def scan_defines(text: str) -> dict[str, str]:
    """{name: replacement text} of every #define of the text (not its headers')."""
    return {n: s.value for n, s in lang_symbols.own_defines(text, "<editor>").items()}


def scan_variables(text: str) -> list[str]:
    """Names the text assigns (``x = …``, ``x++``): its own variables, found
    even while the file does not compile."""
    return list(index(text).variables)


def scan_procedures(text: str) -> list[str]:
    return list(index(text).procedures)


class HeaderDefines:
    """The defines of a project's include folders plus the built-in pins.h,
    a header re-read only when it changed."""

    def __init__(self):
        self._cache = lang_symbols.HeaderCache()

    def defines(self, include_dirs: Iterable[Path]) -> dict[str, tuple[str, str, int]]:
        """{name: (value text, file, line)}."""
        found = lang_symbols.header_defines(include_dirs, read=self._cache.read)
        return {n: (s.value, s.span.file, s.span.line) for n, s in found.items()}


def completions(prefix: str, *, kind: Kind = Kind.HARDWARE, text: str = "",
                symbols=None, defines: Optional[dict] = None) -> list[tuple[str, int]]:
    """Every candidate as (name, kind-of-item); the editor filters by prefix.

    ``symbols`` is the last compile's CompileResult.symbols (or None);
    ``defines`` the project's header defines (name -> anything)."""
    items = index(text).completions(prefix, software=kind is Kind.SOFTWARE)
    if symbols is not None:
        items += [(n, lang_symbols.DEFINE) for n in getattr(symbols, "defines", {}) or {}]
        items += [(n, lang_symbols.PROCEDURE) for n in getattr(symbols, "procedures", {}) or {}]
        items += [(n, lang_symbols.VARIABLE) for n in getattr(symbols, "variables", []) or []]
    items += [(n, lang_symbols.DEFINE) for n in defines or {}]
    return [(n, KINDS[k]) for n, k in lang_symbols.unique(items)]


def signature(name: str) -> Optional[str]:
    """The call tip of a built-in function: its signature and what it does."""
    return signature_text(name)


def definition(word: str, text: str, path: Optional[str], include_dirs: Iterable[Path] = (),
               header_defines: Optional[dict] = None) -> Optional[tuple[str, int, int]]:
    """(file, line, column) where ``word`` is defined: a define of the file or
    of a header it includes (the built-in pins.h too), a procedure of the file,
    else a define of the project's other headers (``header_defines``, as
    :meth:`HeaderDefines.defines` gives them). None for built-in names."""
    file_path = Path(path) if path and not path.startswith("<") else None
    span = lang_symbols.index(text, path or "<editor>", file_path, tuple(include_dirs)).definition(word)
    if span is not None:
        return span.file, span.line, span.col
    hd = (header_defines or {}).get(word)
    return (hd[1], hd[2], 1) if hd is not None else None
