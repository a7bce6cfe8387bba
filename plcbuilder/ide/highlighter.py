"""Syntax highlighting and folding for the editor, driven by the project's
pygments lexer (:class:`plcbuilder.lang.highlight.PlcLexer`).

Scintilla runs as a *container lexer*: it asks for styling (``styleNeeded``)
up to the end of what it is about to paint, and everything before its
``endStyled()`` position is already styled. :class:`Highlighter` restyles
from the start of the line holding ``endStyled()`` to the end of the line
that was asked for — only the lines that changed or came into view — so
typing in a long file stays fast.

The state carried from one line to the next is kept in Scintilla's per-line
state: bit 0 says the line ends inside a ``/* */`` comment (the only lexer
state that spans lines), the other bits hold the brace depth at the line's
end, from which the fold levels are computed (a line that opens a ``{`` it
does not close is a fold header).

:func:`lex_styles` is the pure part (text -> style bytes and line states),
tested without a widget.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Iterable

from pygments.token import (Comment, Error, Keyword, Name, Number, Operator, Punctuation,
                            String)

from plcbuilder.ide.offsets import utf8_len
from plcbuilder.lang.highlight import PlcLexer

# ------------------------------------------------------------------ styles
S_DEFAULT = 0
S_COMMENT = 1
S_PREPROC = 2
S_PREPROC_FILE = 3
S_CONSTANT = 4        # built-in names (PLCCMD_…, GVAR_…)
S_KEYWORD = 5
S_BUILTIN = 6         # built-in functions
S_MAGIC = 7           # predefined variables
S_FUNCTION = 8        # a procedure definition's name
S_IDENT = 9
S_NUMBER = 10
S_OPERATOR = 11
S_PUNCT = 12
S_ERROR = 13
S_DEFINE = 14         # a name #defined in the project (pins.h, headers, the file)
S_STRING = 15         # strings (settings and XML files)
S_TAG = 16            # XML tags, TOML tables
S_ATTRIBUTE = 17      # XML attributes, TOML keys

STYLE_NAMES = {
    S_DEFAULT: "default", S_COMMENT: "comment", S_PREPROC: "preprocessor",
    S_PREPROC_FILE: "include file", S_CONSTANT: "built-in name", S_KEYWORD: "keyword",
    S_BUILTIN: "built-in function", S_MAGIC: "predefined variable", S_FUNCTION: "procedure",
    S_IDENT: "identifier", S_NUMBER: "number", S_OPERATOR: "operator", S_PUNCT: "punctuation",
    S_ERROR: "error", S_DEFINE: "define", S_STRING: "string", S_TAG: "tag",
    S_ATTRIBUTE: "attribute",
}

#: Scintilla's predefined style numbers.
STYLE_DEFAULT = 32
STYLE_LINENUMBER = 33
STYLE_BRACELIGHT = 34
STYLE_BRACEBAD = 35
STYLE_INDENTGUIDE = 37
STYLE_CALLTIP = 38

FOLD_BASE = 0x400
FOLD_HEADER = 0x2000
FOLD_WHITE = 0x1000

_TOKEN_STYLES = (
    # most specific first: the first ancestor that matches wins
    (Comment.PreprocFile, S_PREPROC_FILE),
    (Comment.Preproc, S_PREPROC),
    (Comment, S_COMMENT),
    (Keyword, S_KEYWORD),
    (Name.Builtin, S_BUILTIN),
    (Name.Variable.Magic, S_MAGIC),
    (Name.Constant, S_CONSTANT),
    (Name.Function, S_FUNCTION),
    (Name.Tag, S_TAG),
    (Name.Attribute, S_ATTRIBUTE),
    (Name, S_IDENT),
    (Number, S_NUMBER),
    (String, S_STRING),
    (Operator, S_OPERATOR),
    (Punctuation, S_PUNCT),
    (Error, S_ERROR),
)
_style_cache: dict = {}


def lexer_for(path: str):
    """None (the PLC lexer) for sources and headers, a pygments lexer for the
    project's other text files, or False for plain text."""
    suffix = path.rsplit(".", 1)[-1].lower() if "." in path else ""
    if suffix in ("plc", "h"):
        return None
    if suffix == "toml":
        from pygments.lexers import TOMLLexer
        return TOMLLexer(stripnl=False)
    if suffix == "xml":
        from pygments.lexers import XmlLexer
        return XmlLexer(stripnl=False)
    return False


def style_of(ttype) -> int:
    """The editor style of a pygments token type."""
    s = _style_cache.get(ttype)
    if s is None:
        s = S_DEFAULT
        for t, style in _TOKEN_STYLES:
            if ttype in t:
                s = style
                break
        _style_cache[ttype] = s
    return s


# ------------------------------------------------------------------ themes
@dataclass(frozen=True)
class Theme:
    name: str
    paper: str
    text: str
    styles: dict            # style -> (fore, bold, italic)
    margin_back: str
    margin_fore: str
    caret_line: str
    caret: str
    selection: str
    brace_back: str
    brace_fore: str
    brace_bad: str
    fold_fore: str
    fold_back: str
    error: str
    warning: str
    find: str
    occurrence: str
    calltip_back: str
    calltip_fore: str
    indent_guide: str


LIGHT = Theme(
    name="light", paper="#ffffff", text="#1f1f1f",
    styles={
        S_DEFAULT: ("#1f1f1f", False, False), S_COMMENT: ("#6a737d", False, True),
        S_PREPROC: ("#8250df", False, False), S_PREPROC_FILE: ("#0a7e3e", False, False),
        S_CONSTANT: ("#b35900", False, False), S_KEYWORD: ("#0033b3", True, False),
        S_BUILTIN: ("#7a3e9d", True, False), S_MAGIC: ("#00627a", False, False),
        S_FUNCTION: ("#00627a", True, False), S_IDENT: ("#1f1f1f", False, False),
        S_NUMBER: ("#1750eb", False, False), S_OPERATOR: ("#3d3d3d", False, False),
        S_PUNCT: ("#3d3d3d", False, False), S_ERROR: ("#d00000", False, False),
        S_DEFINE: ("#9e5f00", False, False), S_STRING: ("#0a7e3e", False, False),
        S_TAG: ("#0033b3", False, False), S_ATTRIBUTE: ("#7a3e9d", False, False),
    },
    margin_back="#f5f5f5", margin_fore="#8c8c8c", caret_line="#f3f6fb", caret="#000000",
    selection="#cfe0fb", brace_back="#d8ecd8", brace_fore="#005a00", brace_bad="#d00000",
    fold_fore="#ffffff", fold_back="#9a9a9a", error="#e51400", warning="#c08000",
    find="#f5b82e", occurrence="#c8c8c8", calltip_back="#fffbe6", calltip_fore="#202020",
    indent_guide="#e0e0e0",
)

DARK = Theme(
    name="dark", paper="#1e1f22", text="#d4d4d4",
    styles={
        S_DEFAULT: ("#d4d4d4", False, False), S_COMMENT: ("#7a8a7a", False, True),
        S_PREPROC: ("#c586c0", False, False), S_PREPROC_FILE: ("#ce9178", False, False),
        S_CONSTANT: ("#4fc1ff", False, False), S_KEYWORD: ("#569cd6", True, False),
        S_BUILTIN: ("#dcdcaa", True, False), S_MAGIC: ("#9cdcfe", False, False),
        S_FUNCTION: ("#dcdcaa", True, False), S_IDENT: ("#d4d4d4", False, False),
        S_NUMBER: ("#b5cea8", False, False), S_OPERATOR: ("#c8c8c8", False, False),
        S_PUNCT: ("#c8c8c8", False, False), S_ERROR: ("#f14c4c", False, False),
        S_DEFINE: ("#4ec9b0", False, False), S_STRING: ("#ce9178", False, False),
        S_TAG: ("#569cd6", False, False), S_ATTRIBUTE: ("#9cdcfe", False, False),
    },
    margin_back="#1e1f22", margin_fore="#6e7681", caret_line="#2a2d32", caret="#aeafad",
    selection="#264f78", brace_back="#3b514d", brace_fore="#ffffff", brace_bad="#f14c4c",
    fold_fore="#1e1f22", fold_back="#8b8b8b", error="#f14c4c", warning="#cca700",
    find="#7a5c00", occurrence="#4a4a4a", calltip_back="#252526", calltip_fore="#d4d4d4",
    indent_guide="#3a3a3a",
)

THEMES = {LIGHT.name: LIGHT, DARK.name: DARK}


def colour(hex_colour: str) -> int:
    """'#rrggbb' -> Scintilla's 0xBBGGRR."""
    h = hex_colour.lstrip("#")
    r, g, b = int(h[0:2], 16), int(h[2:4], 16), int(h[4:6], 16)
    return r | (g << 8) | (b << 16)


# ------------------------------------------------------------------ lexing
IN_COMMENT = 1
#: lines styled past the one asked for (a definition's ``{`` may be below it)
LOOKAHEAD_LINES = 2


def pack_state(depth: int, in_comment: bool) -> int:
    return (max(depth, 0) << 1) | (1 if in_comment else 0)


def unpack_state(state: int) -> tuple[int, bool]:
    return state >> 1, bool(state & IN_COMMENT)


_lexer = PlcLexer()


def lex_styles(text: str, state: int = 0, defines: Iterable[str] = frozenset()
               ) -> tuple[bytearray, list[tuple[int, int]]]:
    """Style ``text`` (whole lines) starting in ``state``.

    Returns one style byte per UTF-8 byte of text, and one entry per line of
    text — ``(fold_level, end_state)`` — where the fold level carries
    FOLD_HEADER for a line that opens a block it does not close, and a line's
    level is the lowest brace depth on it (so ``} else {`` heads a block and
    a lone ``}`` stays visible when its block is folded). A final line without
    a line end gets an entry too."""
    depth, in_comment = unpack_state(state)
    stack = ("root", "comment") if in_comment else ("root",)
    styles = bytearray()
    lines: list[tuple[int, int]] = []
    if not isinstance(defines, (set, frozenset, dict)):
        defines = set(defines)
    line_min = depth
    for _pos, ttype, value in _lexer.get_tokens_unprocessed(text, stack=stack):
        st = style_of(ttype)
        if st == S_IDENT:
            if value in defines:
                st = S_DEFINE
        elif st == S_PUNCT:
            if value == "{":
                depth += 1
            elif value == "}":
                depth = max(depth - 1, 0)
                if depth < line_min:
                    line_min = depth
        if value.isascii():
            styles += bytes((st,)) * len(value)
        else:
            styles += bytes((st,)) * utf8_len(value)
        newlines = value.count("\n")
        if newlines:
            # a token may span lines (whitespace runs, block comments); braces
            # are tokens of their own, so the depth is the same on all of them
            comment = st == S_COMMENT and ttype in Comment.Multiline
            end_state = pack_state(depth, comment)
            for _ in range(newlines):
                lvl = FOLD_BASE + line_min
                if depth > line_min:
                    lvl |= FOLD_HEADER
                lines.append((lvl, end_state))
                line_min = depth
    if not text.endswith("\n"):
        lvl = FOLD_BASE + line_min
        if depth > line_min:
            lvl |= FOLD_HEADER
        lines.append((lvl, pack_state(depth, False)))
    return styles, lines


# ------------------------------------------------------------------ widget
class Highlighter:
    """Styles a :class:`ScintillaEdit` incrementally with :func:`lex_styles`.

    Connects to the editor's ``styleNeeded``; :meth:`style_to` can also be
    called directly (tests, or to style a document before it is shown)."""

    def __init__(self, editor, lexer=None):
        self.editor = editor
        self.defines: frozenset[str] = frozenset()
        #: None: the PLC lexer, incrementally; else any pygments lexer for a small
        #: file (settings, XML), restyled whole
        self.lexer = lexer
        editor.styleNeeded.connect(self.style_to)

    def set_lexer(self, lexer) -> None:
        self.lexer = lexer
        self.restyle()

    # ---------------------------------------------------------------- public
    def set_defines(self, names: Iterable[str]) -> None:
        """Names #defined for this file (shown in the define style); restyles
        the document when the set changed."""
        names = frozenset(names)
        if names != self.defines:
            self.defines = names
            self.restyle()

    def restyle(self) -> None:
        """Forget all styling; Scintilla asks again for what it paints."""
        ed = self.editor
        ed.startStyling(0, 0)
        if ed.isVisible():
            last = ed.lineFromPosition(ed.length())
            vis_end = min(last, ed.firstVisibleLine() + ed.linesOnScreen() + 1)
            self.style_to(ed.lineEndPosition(vis_end))
        ed.viewport().update()

    def style_to(self, pos: int) -> None:
        """Style from the line of ``endStyled()`` to the end of pos's line."""
        ed = self.editor
        if self.lexer is not None:
            self._style_whole()
            return
        # one line back and two ahead: ``main()`` is a definition only when a
        # ``{`` follows on a later line, so the line above an edit may change
        # style, and a range must not stop between the two
        start_line = max(0, ed.lineFromPosition(ed.endStyled()) - 1)
        start = ed.positionFromLine(start_line)
        line_count = ed.lineCount()
        end_line = min(ed.lineFromPosition(max(pos, start)) + LOOKAHEAD_LINES, line_count - 1)
        end = ed.positionFromLine(end_line + 1) if end_line + 1 < line_count else ed.length()
        state = ed.lineState(start_line - 1) if start_line > 0 else 0
        data = bytes(ed.textRange(start, end)) if end > start else b""
        text = data.decode("utf-8", "replace")
        styles, lines = lex_styles(text, state, self.defines)
        if len(styles) != len(data):      # invalid UTF-8 in the document: never misalign
            styles = (styles + bytes(len(data)))[:len(data)]
        ed.startStyling(start, 0)
        if styles:
            ed.setStylingEx(len(styles), styles.decode("latin-1"))
        for i, (level, end_state) in enumerate(lines):
            line = start_line + i
            if line >= line_count:
                break
            if ed.foldLevel(line) & 0x3FFF != level:
                ed.setFoldLevel(line, level)
            if ed.lineState(line) != end_state:
                ed.setLineState(line, end_state)

    def _style_whole(self) -> None:
        ed = self.editor
        data = bytes(ed.textRange(0, ed.length())) if ed.length() else b""
        styles = bytearray()
        for _pos, ttype, value in self.lexer.get_tokens_unprocessed(
                data.decode("utf-8", "replace")):
            styles += bytes((style_of(ttype),)) * utf8_len(value)
        styles = (styles + bytes(len(data)))[:len(data)]
        ed.startStyling(0, 0)
        if styles:
            ed.setStylingEx(len(styles), styles.decode("latin-1"))
