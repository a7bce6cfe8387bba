"""What an editor asks about a file: completion, hover, go-to-definition,
occurrences and pin names, answered from the real tokens.

:func:`index` runs the tokenizer and the preprocessor over the text (its
headers included, the built-in ``pins.h`` too), so every answer agrees with
what the compiler reads, and it works on text that does not parse: tokens
survive syntax errors. Offsets are character offsets into the text; spans are
the compiler's (file, line, column).

    idx = index(text, "M03.plc", path, include_dirs)
    idx.definition_at(offset)        # Span of the #define or procedure, or None
    idx.completions("OUT", software=False)
    idx.occurrences("speed")

:func:`header_defines` reads every header of some folders (the completion
list before a file has been compiled) and :func:`pin_names` turns
``INPUT_*``/``OUTPUT_*`` defines into pin names.
"""

from __future__ import annotations

import bisect
from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterable, Mapping, Optional, Sequence

from plcbuilder._support.files import read_bounded
from plcbuilder.diagnostics import Span
from plcbuilder.lang.builtins import (CONSTANTS, FUNCTIONS, KEYWORDS, PIN_FUNCTIONS, PREDEFINED,
                                      REGISTER_FUNCTIONS, predefined)
from plcbuilder.lang.preprocess import BUILTIN_PREFIX, Preprocessor, builtin_header
from plcbuilder.lang.source import MAX_SOURCE_BYTES, normalise
from plcbuilder.lang.tokens import Tok, Tokenizer, parse_number

# What a completion item is.
from plcbuilder.lang.kinds import (CONSTANT, DEFINE, FUNCTION, KEYWORD,  # noqa: E402,F401
                                   PREDEFINED_VARIABLE, PROCEDURE, VARIABLE)

#: The headers whose defines are always offered (the default machine's wiring).
DEFAULT_HEADERS = ("pins.h",)


@dataclass(frozen=True)
class Symbol:
    """A name the file (or one of its headers) defines."""
    name: str
    kind: str                  # DEFINE, PROCEDURE or VARIABLE
    span: Optional[Span]       # where it is defined (a variable: its first assignment)
    value: str = ""            # a define's replacement text, comments dropped


@dataclass
class SymbolIndex:
    """The symbols of one file's text."""
    name: str
    text: str
    software: bool = False
    tokens: list[Tok] = field(default_factory=list)      # the file's own tokens, directives included
    defines: dict[str, Symbol] = field(default_factory=dict)
    procedures: dict[str, Symbol] = field(default_factory=dict)
    variables: dict[str, Symbol] = field(default_factory=dict)
    includes: list[str] = field(default_factory=list)

    def __post_init__(self):
        starts = [0]
        i = self.text.find("\n")
        while i >= 0:
            starts.append(i + 1)
            i = self.text.find("\n", i + 1)
        self._line_starts = starts
        self._starts = [self.offset_of(t.span.line, t.span.col) for t in self.tokens]

    # ------------------------------------------------------------ positions
    def offset_of(self, line: int, col: int) -> int:
        """The character offset of a (1-based) line and column of this text."""
        starts = self._line_starts
        if line < 1:
            return 0
        if line > len(starts):
            return len(self.text)
        return min(starts[line - 1] + col - 1, len(self.text))

    def token_at(self, offset: int) -> Optional[Tok]:
        """The token under ``offset``, or the one that ends right there (the caret
        just after a word)."""
        i = bisect.bisect_right(self._starts, offset) - 1
        for j in (i, i - 1):
            if 0 <= j < len(self.tokens):
                t = self.tokens[j]
                start = self._starts[j]
                if start <= offset <= start + len(t.value):
                    return t
        return None

    def word_at(self, offset: int) -> Optional[tuple[int, int, str]]:
        """(start, end, text) of the name, keyword or number at ``offset``."""
        i = bisect.bisect_right(self._starts, offset) - 1
        for j in (i, i - 1):
            if 0 <= j < len(self.tokens):
                t = self.tokens[j]
                start = self._starts[j]
                if _is_word(t) and start <= offset <= start + len(t.value):
                    return start, start + len(t.value), t.value
        return None

    # ------------------------------------------------------------ questions
    def definition(self, name: str) -> Optional[Span]:
        """Where a define (in this file or a header) or a procedure is defined."""
        sym = self.defines.get(name) or self.procedures.get(name)
        return sym.span if sym is not None else None

    def definition_at(self, offset: int) -> Optional[Span]:
        w = self.word_at(offset)
        return self.definition(w[2]) if w else None

    def occurrences(self, name: str) -> list[Span]:
        """Every place this file names ``name`` (directive lines included)."""
        return [t.span for t in self.tokens if t.value == name and t.kind == "NAME"]

    def references_at(self, offset: int) -> list[Span]:
        w = self.word_at(offset)
        return self.occurrences(w[2]) if w else []

    def context_at(self, offset: int) -> str:
        """What the tokens before the word at ``offset`` make of a number there
        (see :func:`number_context`)."""
        w = self.word_at(offset)
        at = w[0] if w else offset
        i = bisect.bisect_left(self._starts, at)
        return _context(self.tokens[max(0, i - 2):i])

    def completions(self, prefix: str = "", software: Optional[bool] = None) -> list[tuple[str, str]]:
        """Every candidate as (name, kind), without duplicates: keywords, built-in
        functions, predefined variables, defines, procedures, this file's
        variables, and (once something is typed) the built-in constants. The
        editor filters by prefix."""
        sw = self.software if software is None else software
        out: list[tuple[str, str]] = [(k, KEYWORD) for k in sorted(KEYWORDS)]
        out += [(f, FUNCTION) for f in FUNCTIONS]
        out += [(v, PREDEFINED_VARIABLE) for v in predefined(sw)]
        out += [(d, DEFINE) for d in self.defines]
        out += [(p, PROCEDURE) for p in self.procedures]
        out += [(v, VARIABLE) for v in self.variables if v != prefix]
        if prefix:
            out += [(c, CONSTANT) for c in CONSTANTS]
        return unique(out)

    def pin_names(self) -> tuple[dict[int, str], dict[int, str]]:
        return pin_names(self.defines)

    def outline(self) -> list["OutlineItem"]:
        """What this file itself defines, in the order of the text: its
        procedures (with the line of their closing brace), defines and
        variables (at their first assignment). Headers' names are left out."""
        items: list[OutlineItem] = []
        for sym in self.defines.values():
            if sym.span is not None and sym.span.file == self.name:
                items.append(OutlineItem(sym.name, DEFINE, sym.span.line, sym.span.col,
                                         sym.span.line, sym.value))
        for sym in self.procedures.values():
            end = self._block_end(sym.span)
            items.append(OutlineItem(sym.name, PROCEDURE, sym.span.line, sym.span.col, end))
        for sym in self.variables.values():
            items.append(OutlineItem(sym.name, VARIABLE, sym.span.line, sym.span.col,
                                     sym.span.line))
        items.sort(key=lambda it: (it.line, it.col))
        return items

    def enclosing(self, line: int) -> Optional["OutlineItem"]:
        """The procedure whose text holds ``line`` (1-based), or None."""
        for it in self.outline():
            if it.kind == PROCEDURE and it.line <= line <= it.end_line:
                return it
        return None

    def _block_end(self, span: Span) -> int:
        """The line of the ``}`` that closes the body of the procedure named at ``span``
        (the last line of the text while it is not closed)."""
        i = bisect.bisect_left(self._starts, self.offset_of(span.line, span.col))
        depth = 0
        for t in self.tokens[i:]:
            if t.kind == "LBRACE":
                depth += 1
            elif t.kind == "RBRACE":
                depth -= 1
                if depth == 0:
                    return t.span.line
        return len(self._line_starts)


@dataclass(frozen=True)
class OutlineItem:
    """One entry of a file's outline."""
    name: str
    kind: str                  # PROCEDURE, DEFINE or VARIABLE
    line: int
    col: int
    end_line: int              # a procedure's closing brace; the same line otherwise
    detail: str = ""           # a define's value


def unique(items: Iterable[tuple[str, str]]) -> list[tuple[str, str]]:
    """The first item of each name, in order."""
    seen: set[str] = set()
    out = []
    for name, kind in items:
        if name not in seen:
            seen.add(name)
            out.append((name, kind))
    return out


def _is_word(t: Tok) -> bool:
    return t.kind in ("NAME", "NUMBER") or t.value in KEYWORDS


# ---------------------------------------------------------------- building
def _lines(text: str, name: str):
    """(the '#' of a directive line or None, tokens) of each line; never raises."""
    for is_dir, toks, hash_span, _raw in Tokenizer(normalise(text), name, [], []).lines():
        yield hash_span if is_dir else None, toks


def tokens_of(text: str, name: str = "<input>") -> list[Tok]:
    """Every token of one text, directive lines included (the ``#`` is not a
    token), comments dropped."""
    return [t for _hash, toks in _lines(text, name) for t in toks]


def _only_lines(text: str, keep) -> str:
    """The text with the lines ``keep(number, line)`` refuses made blank (so
    the others keep their line numbers)."""
    return "\n".join(t if keep(n, t) else "" for n, t in enumerate(text.split("\n"), 1))


def _defines(pp: Preprocessor) -> dict[str, Symbol]:
    out: dict[str, Symbol] = {}
    for d in pp.all_defines:
        out.setdefault(d.name, Symbol(d.name, DEFINE, d.span, d.text))
    return out


def index(text: str, name: str = "<input>", path: Optional[Path] = None,
          include_dirs: Sequence[Path] = (), *, software: bool = False) -> SymbolIndex:
    """The symbols of ``text`` (the file ``name``, at ``path`` when it is one, so
    its own folder is searched for headers)."""
    text = normalise(text)
    toks: list[Tok] = []
    code: list[Tok] = []                    # outside directives
    directive_lines: set[int] = set()
    for hash_span, line in _lines(text, name):
        toks.extend(line)
        if hash_span is None:
            code.extend(line)
        else:
            directive_lines.add(hash_span.line)
    # The preprocessor reads only the directives: the defines and headers, at little cost.
    pp = Preprocessor(include_dirs)
    pre = pp.run_text(_only_lines(text, lambda n, _t: n in directive_lines), name, path)
    procedures: dict[str, Symbol] = {}
    variables: dict[str, Symbol] = {}
    for i, t in enumerate(code):
        if t.kind != "NAME" or t.value in FUNCTIONS:
            continue
        nxt = code[i + 1].kind if i + 1 < len(code) else ""
        if nxt == "LPAR" and i + 3 < len(code) and code[i + 2].kind == "RPAR" \
                and code[i + 3].kind == "LBRACE":
            procedures.setdefault(t.value, Symbol(t.value, PROCEDURE, t.span))
        elif nxt in ("ASSIGN", "INC", "DEC") and t.value not in PREDEFINED \
                and t.value not in CONSTANTS:
            variables.setdefault(t.value, Symbol(t.value, VARIABLE, t.span))
    return SymbolIndex(name, text, software, toks, _defines(pp), procedures, variables,
                       list(pre.includes))


def own_defines(text: str, name: str = "<input>") -> dict[str, Symbol]:
    """The defines a text makes itself (not its headers'), quickly: only lines
    that start with ``#`` are read (so a ``#define`` inside a ``/* */`` comment
    counts too), for colouring define names on every edit."""
    pp = Preprocessor(())
    pp.run_text(_only_lines(normalise(text), lambda _n, t: t.lstrip().startswith("#")), name, None)
    return {n: sym for n, sym in _defines(pp).items() if sym.span.file == name}


def file_defines(text: str, name: str, path: Optional[Path] = None) -> dict[str, Symbol]:
    """The defines of one file's text (and of the headers it includes)."""
    pp = Preprocessor(())
    pp.run_text(text, name, path)
    return _defines(pp)


def header_defines(include_dirs: Iterable[Path], read=None) -> dict[str, Symbol]:
    """The defines of every header (``*.h``) in the folders, then of the
    built-in ``pins.h``; the first definition of a name wins. ``read(path)``
    returns a header's defines (a cache may stand in for :func:`read_header`)."""
    read = read or read_header
    out: dict[str, Symbol] = {}
    for folder in include_dirs:
        try:
            headers = sorted(p for p in Path(folder).glob("*.h") if p.is_file())
        except OSError:
            continue
        for h in headers:
            for n, sym in read(h).items():
                out.setdefault(n, sym)
    for header in DEFAULT_HEADERS:
        text = builtin_header(header)
        if text is not None:
            for n, sym in file_defines(text, BUILTIN_PREFIX + header).items():
                out.setdefault(n, sym)
    return out


def read_header(path: Path) -> dict[str, Symbol]:
    """The defines of a header file ({} when it cannot be read)."""
    try:
        text = read_bounded(path, MAX_SOURCE_BYTES).decode("utf-8", errors="replace")
    except OSError:
        return {}
    return file_defines(text, str(path))


class HeaderCache:
    """:func:`read_header` of a path, read again only when the file's
    modification time changed ({} while the file cannot be looked at)."""

    def __init__(self):
        self._hits: dict[str, tuple[int, dict[str, Symbol]]] = {}

    def read(self, path: Path) -> dict[str, Symbol]:
        try:
            stamp = path.stat().st_mtime_ns
        except OSError:
            return {}
        hit = self._hits.get(str(path))
        if hit is None or hit[0] != stamp:
            hit = (stamp, read_header(path))
            self._hits[str(path)] = hit
        return hit[1]


# ---------------------------------------------------------------- numbers
def _context(before: list[Tok]) -> str:
    if len(before) < 2:
        return ""
    word, mark = before[-2], before[-1]
    if word.kind != "NAME":
        return ""
    if mark.kind == "LPAR":
        if word.value in REGISTER_FUNCTIONS:
            return "register"
        if word.value == "exit":
            return "exit"
        if word.value in PIN_FUNCTIONS:
            return "pin"
    elif mark.kind == "ASSIGN" and word.value in ("message", "proc"):
        return word.value
    return ""


def number_context(before: str) -> str:
    """What the text just before a number makes of it: 'register'
    (``gvarget(``), 'exit' (``exit(``), 'message' / 'proc' (``message =``),
    'pin' (``portset(``) or ''."""
    return _context(tokens_of(before)[-2:])


def number_of(text: str) -> Optional[int]:
    """The value of a text that is one number, perhaps negated and in
    parentheses (``7``, ``0x1f``, ``(2)``, ``-1``); None otherwise."""
    toks = tokens_of(text)
    while len(toks) >= 2 and toks[0].kind == "LPAR" and toks[-1].kind == "RPAR":
        toks = toks[1:-1]
    sign = 1
    if len(toks) == 2 and toks[0].kind == "MINUS":
        sign, toks = -1, toks[1:]
    if len(toks) == 1 and toks[0].kind == "NUMBER":
        v = parse_number(toks[0].value)
        return None if v is None else sign * v
    return None


def pin_names(defines: Mapping) -> tuple[dict[int, str], dict[int, str]]:
    """Pin names from defines: ``INPUT_*`` name inputs, ``OUTPUT_*`` outputs.
    A define's value is a :class:`Symbol`, its text, ``(text, span)`` (as
    ``CompileResult.symbols.defines``) or an int. Names of one pin are joined
    with " / "."""
    inputs: dict[int, str] = {}
    outputs: dict[int, str] = {}
    for name, value in defines.items():
        if name.startswith("INPUT_"):
            target = inputs
        elif name.startswith("OUTPUT_"):
            target = outputs
        else:
            continue
        if isinstance(value, Symbol):
            value = value.value
        elif isinstance(value, (tuple, list)):
            value = value[0] if value else ""
        if isinstance(value, bool):
            continue
        pin = value if isinstance(value, int) else number_of(value) if isinstance(value, str) else None
        if pin is None or not 0 <= pin < 256:
            continue
        target[pin] = f"{target[pin]} / {name}" if pin in target else name
    return inputs, outputs
