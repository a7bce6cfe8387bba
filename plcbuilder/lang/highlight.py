"""A pygments lexer for myCNC PLC procedures (``*.plc``).

It colours the IDE's editor and the command line's source lines, so it is
built to be fast (one regular expression for every identifier, classified by
set lookups) and total: it never raises, every character of the input comes
back in exactly one token (``get_tokens_unprocessed`` round-trips any text
exactly), and only what the compiler rejects as a token becomes ``Error``:
characters that cannot appear in a PLC procedure at all (``@``, ``$``, a ``#``
inside a line, a ``"`` outside ``#include``, non-ASCII outside comments, …) and
malformed numbers (``12ab``, ``0x``, ``0xfg``).

Token types:

=====================================  ===============================================
``Comment.Single`` / ``.Multiline``    ``// …`` and ``/* … */`` (an unclosed one runs to the end)
``Comment.Preproc``                    ``#include``, ``#define``, any other ``#word`` at a line start
``Comment.PreprocFile``                the file of an ``#include`` (``pins.h``, ``"pins.h"``, ``<pins.h>``)
``Name.Constant``                      the name after ``#define``/``#undef``/``#ifdef``/``#ifndef``;
                                       built-in names (``PLCCMD_LINE_STOP``, ``GVAR_HW_PWM0``)
``Keyword``                            ``if else do while``
``Name.Builtin``                       ``portset portclear portclr portget gvarget gvarset g0moveA exit``
``Name.Variable.Magic``                predefined variables (``eparam timer message var00 pwm01 Param`` …)
``Name.Function``                      a procedure definition's name (``name()`` followed by ``{``)
``Name``                               any other identifier (variables, calls, user defines)
``Number.Integer`` / ``Number.Hex``    ``10``, ``0xff``
``Operator`` / ``Punctuation``         ``+ - * / % << >> < <= … = ++ --`` / ``( ) { } ; ,``
=====================================  ===============================================
"""

from __future__ import annotations

from pygments.lexer import RegexLexer, default
from pygments.token import (Comment, Error, Keyword, Name, Number, Operator,
                            Punctuation, Whitespace)

from plcbuilder.lang import builtins

__all__ = ["PlcLexer", "KEYWORDS", "BUILTIN_FUNCTIONS", "PREDEFINED_VARIABLES",
           "BUILTIN_CONSTANTS"]

#: Statement keywords.
KEYWORDS = frozenset(builtins.KEYWORDS)
#: Built-in functions (``portclr`` is myCNC's own spelling of ``portclear``).
BUILTIN_FUNCTIONS = frozenset(builtins.FUNCTIONS)
#: Predefined variables: slot variables, register-mapped ones, and ``Param``.
PREDEFINED_VARIABLES = frozenset(builtins.PREDEFINED)
#: Built-in constant names (every name with a value in the manual's tables).
BUILTIN_CONSTANTS = frozenset(builtins.CONSTANTS)

_IDENT = r"[A-Za-z_][A-Za-z0-9_]*"
_WS = r"[ \t\f\v\r\n]*"
# Whitespace and comments that may stand between ``name()`` and its ``{``.
_GAP = r"(?:[ \t\f\v\r\n]|//[^\n]*|/\*[\s\S]*?\*/)*"


def _classify(text: str):
    """The token type of one identifier (set lookups: much faster than word regexes)."""
    if text in KEYWORDS:
        return Keyword
    if text in BUILTIN_FUNCTIONS:
        return Name.Builtin
    if text in PREDEFINED_VARIABLES:
        return Name.Variable.Magic
    if text in BUILTIN_CONSTANTS:
        return Name.Constant
    return Name


def _identifier(lexer, match):
    yield match.start(), _classify(match.group()), match.group()


def _definition(lexer, match):
    """``name ( )`` followed by ``{``: a procedure definition."""
    name = match.group(1)
    # ``while () {`` or a misguided ``exit() {`` keep the word's own colour
    tok = _classify(name) if name in KEYWORDS or name in BUILTIN_FUNCTIONS else Name.Function
    yield match.start(1), tok, name
    pos = match.end(1)
    for i, part in ((2, match.group(2)), (3, "("), (4, match.group(4)), (5, ")")):
        if part:
            yield pos, Whitespace if i in (2, 4) else Punctuation, part
            pos += len(part)


def _bygroups_ws(tok):
    """(leading blanks, directive) -> Whitespace, tok (no token for empty blanks)."""
    def callback(lexer, match):
        if match.group(1):
            yield match.start(1), Whitespace, match.group(1)
        yield match.start(2), tok, match.group(2)
    return callback


class PlcLexer(RegexLexer):
    """Lexer for myCNC PLC procedures (the C-like language of PLC Builder)."""

    name = "PLC"
    aliases = ["plc", "mycnc-plc"]
    filenames = ["*.plc"]
    alias_filenames: list[str] = []
    mimetypes: list[str] = []
    url = "http://docs.pv-automation.com/plc/plc"
    version_added = ""

    tokens = {
        "root": [
            # preprocessor directives: only at the start of a line
            (r"^([ \t\f\v]*)(#[ \t]*include)\b",
             _bygroups_ws(Comment.Preproc), "include"),
            (r"^([ \t\f\v]*)(#[ \t]*(?:define|undef|ifdef|ifndef))\b",
             _bygroups_ws(Comment.Preproc), "define"),
            (r"^([ \t\f\v]*)(#[ \t]*(?:" + _IDENT + ")?)",
             _bygroups_ws(Comment.Preproc)),
            (r"[ \t\f\v\r]*\n|[ \t\f\v\r]+", Whitespace),
            # comments
            (r"//[^\n]*", Comment.Single),
            (r"/\*", Comment.Multiline, "comment"),
            # procedure definitions, then every other identifier
            (r"(" + _IDENT + r")(" + _WS + r")(\()(" + _WS + r")(\))(?=" + _GAP + r"\{)", _definition),
            (_IDENT, _identifier),
            # numbers (a digit run glued to letters is malformed, as the compiler says)
            (r"0[xX][0-9A-Fa-f]+(?![0-9A-Za-z_])", Number.Hex),
            (r"[0-9]+(?![0-9A-Za-z_])", Number.Integer),
            (r"[0-9][0-9A-Za-z_]*", Error),
            # operators and punctuation (longest first)
            (r"\+\+|--|<<|>>|<=|>=|==|!=|&&|\|\||[-+&|^]=|[-+*/%&|^~!<>=]", Operator),
            (r"[(){};,\[\]]", Punctuation),
        ],
        "comment": [
            (r"[^*]+", Comment.Multiline),
            (r"\*/", Comment.Multiline, "#pop"),
            (r"\*", Comment.Multiline),
        ],
        "include": [
            (r"[ \t\f\v]+", Whitespace),
            (r'"[^"\n]*"', Comment.PreprocFile, "#pop"),
            (r"<[^>\n]*>", Comment.PreprocFile, "#pop"),
            (r"(?:[^\s/]|/(?![/*]))+", Comment.PreprocFile, "#pop"),
            default("#pop"),
        ],
        "define": [
            (r"[ \t\f\v]+", Whitespace),
            (_IDENT, Name.Constant, "#pop"),
            default("#pop"),
        ],
    }

    def __init__(self, **options):
        # Keep leading blank lines: line numbers must match the file's.
        options.setdefault("stripnl", False)
        super().__init__(**options)

