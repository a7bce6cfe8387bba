"""The tokenizer: the text of one file -> tokens, each with the :class:`Span`
it came from, and its directive lines split out.

It never raises: a character the language does not have becomes a ``BAD``
token and a diagnostic, a malformed number a diagnostic and the value 0. The
preprocessor runs it over every file it reads; :mod:`plcbuilder.lang.symbols`
runs it over the editor's text (its tokens survive syntax errors).
"""

from __future__ import annotations

import re

from plcbuilder._support.records import dataclass
from plcbuilder.diagnostics import Diagnostic, Span, error
from plcbuilder.lang.builtins import KEYWORDS

TYPE_CHECKING = False               # (typing is not imported at run time: start-up)
if TYPE_CHECKING:
    from typing import Optional

PUNCT = {
    "<<": "SHL", ">>": "SHR", "<=": "LE", ">=": "GE", "==": "EQ", "!=": "NE",
    "&&": "ANDAND", "||": "OROR", "++": "INC", "--": "DEC",
    "|=": "OR_ASSIGN", "&=": "AND_ASSIGN", "^=": "XOR_ASSIGN", "+=": "ADD_ASSIGN",
    "-=": "SUB_ASSIGN", "[": "LBRACK", "]": "RBRACK",
    "(": "LPAR", ")": "RPAR", "{": "LBRACE", "}": "RBRACE", ";": "SEMI", ",": "COMMA",
    "=": "ASSIGN", "+": "PLUS", "-": "MINUS", "*": "STAR", "/": "SLASH", "%": "PERCENT",
    "<": "LT", ">": "GT", "&": "AMP", "|": "PIPE", "^": "CARET", "!": "BANG", "~": "TILDE",
}
#: terminal name -> its text, for messages ("expected ';'")
TERMINAL_TEXT = {v: k for k, v in PUNCT.items()}
TERMINAL_TEXT.update({v: k for k, v in KEYWORDS.items()})
TERMINAL_TEXT.update({"NAME": "a name", "NUMBER": "a number", "$END": "the end of the file"})

_TOKEN_RE = re.compile(r"""
    [ \t\f\v]*                  # blanks before a token are part of its match
    (?: (?P<nl>\n)
  | (?P<lc>//[^\n]*)
  | (?P<bc>/\*)
  | (?P<num>0[xX][0-9A-Fa-f]*[0-9A-Za-z_]*|[0-9][0-9A-Za-z_]*)
  | (?P<name>[A-Za-z_][A-Za-z0-9_]*)
  | (?P<punct><<|>>|<=|>=|==|!=|&&|\|\||\+\+|--|\|=|&=|\^=|\+=|-=|[(){};,=+\-*/%<>&|^!~\[\]])
  | (?P<hash>\#)
  | (?P<bad>.)
  | (?P<eof>\Z) )
""", re.VERBOSE)
_BAD_RUN_RE = re.compile(r"[^\sA-Za-z0-9_(){};,=+\-*/%<>&|^!~\[\]]+")
_new = tuple.__new__      # Span(...) without the named tuple's Python __new__
_HEX_RE = re.compile(r"0[xX][0-9A-Fa-f]+")
_DEC_RE = re.compile(r"[0-9]+")


@dataclass(slots=True)
class Tok:
    kind: str                 # a parser terminal name (NAME, NUMBER, SEMI, ...)
    value: str                # the text
    span: Span
    number: int = 0           # the value of a NUMBER
    macro: Optional[str] = None   # the define this token was expanded from
    synthetic: bool = False   # made up by error recovery


def parse_number(text: str) -> Optional[int]:
    """The value of a literal as a 32-bit two's complement int, or None if malformed/too big."""
    if _HEX_RE.fullmatch(text):
        v = int(text, 16)
    elif _DEC_RE.fullmatch(text):
        v = int(text, 10)
    else:
        return None
    if v > 0xFFFFFFFF:
        return None
    return v - (1 << 32) if v >= 1 << 31 else v


class Tokenizer:
    """Tokens of one file, with directives split out line by line."""

    def __init__(self, text: str, name: str, diags: list[Diagnostic], block_comments: list[Span],
                 max_tokens: Optional[int] = None):
        self.text, self.name, self.diags = text, name, diags
        self.block_comments = block_comments
        self.next_line: Optional[tuple[int, int]] = None
        #: stop after this many tokens (the preprocessor refuses more anyway):
        #: a huge file costs no more than its first max_tokens tokens
        self.max_tokens = max_tokens
        self.truncated = False   # it stopped at max_tokens

    def lines(self, start: int = 0, first_line: int = 1):
        """Yield (is_directive, tokens, hash_span, raw_rest) per logical line,
        from offset ``start`` (the start of a logical line, numbered
        ``first_line``). While a line is yielded, ``next_line`` is (offset,
        number) of the line after it (None after the last).

        One token costs a regex match, its Span and its Tok: the kinds are
        tested commonest first and nothing else is called per token (a long
        run of one token, 1 byte each, is the most tokens a file can hold)."""
        text, name = self.text, self.name
        line, line_start = first_line, start
        current: list[Tok] = []
        append = current.append
        directive = False
        hash_span = None
        raw_start = start
        first_on_line = True
        n = len(text)
        bad_run_end = -1
        budget = self.max_tokens
        done = 0                 # tokens of the lines yielded before this one
        #: tokens the current line may take before the budget is spent
        room = budget if budget is not None else n + 1
        punct, keywords = PUNCT, KEYWORDS
        new = _new
        pos = start
        while pos < n:
            for m in _TOKEN_RE.finditer(text, pos):
                kind = m.lastgroup
                if kind == "punct":
                    v = m.group(kind)
                    s = m.start(kind)
                    col = s - line_start + 1
                    append(Tok(punct[v], v, new(Span, (name, line, col, line, col + len(v)))))
                elif kind == "name":
                    v = m.group(kind)
                    s = m.start(kind)
                    col = s - line_start + 1
                    append(Tok(keywords.get(v, "NAME"), v,
                               new(Span, (name, line, col, line, col + len(v)))))
                elif kind == "nl":
                    e = m.end()
                    if budget is not None:
                        done += len(current)
                        if done > budget:
                            self.truncated = True
                            pos = n + 1
                            break
                        room = budget - done
                    self.next_line = (e, line + 1)
                    s = m.start(kind)
                    yield directive, current, hash_span, text[raw_start:s] if directive else ""
                    current, directive, hash_span = [], False, None
                    append = current.append
                    line, line_start, first_on_line = line + 1, e, True
                    continue
                elif kind == "num":
                    v = m.group(kind)
                    s = m.start(kind)
                    col = s - line_start + 1
                    span = new(Span, (name, line, col, line, col + len(v)))
                    num = int(v) if v.isdigit() and len(v) < 10 else parse_number(v)
                    if num is None:
                        if not directive:
                            self.diags.append(error("bad-number", f"malformed number '{v}'", span,
                                                    "numbers are decimal (123) or hex (0x7b), "
                                                    "at most 0xffffffff"))
                        num = 0
                    append(Tok("NUMBER", v, span, num))
                elif kind == "lc":
                    continue
                elif kind == "eof":
                    pos = n + 1
                    break
                elif kind == "bc":
                    s, e = m.start(kind), m.end()
                    col = s - line_start + 1
                    end = text.find("*/", e)
                    span_end = n if end < 0 else end + 2
                    start_line, start_col = line, col
                    nls = text.count("\n", s, span_end)
                    if nls:
                        line += nls
                        line_start = text.rfind("\n", s, span_end) + 1
                    sp = Span(name, start_line, start_col, line, span_end - line_start + 1)
                    self.block_comments.append(sp)
                    if end < 0:
                        self.diags.append(error("unterminated-comment", "unterminated /* comment",
                                                Span.point(name, start_line, start_col, 2),
                                                "close it with */"))
                    pos = span_end       # the tokens go on after the comment
                    break
                else:   # a '#', or a character the language does not have
                    s, e = m.start(kind), m.end()
                    col = s - line_start + 1
                    span = new(Span, (name, line, col, line, col + (e - s)))
                    if kind == "hash" and first_on_line:
                        directive, hash_span, raw_start = True, span, e
                        first_on_line = False
                        continue
                    if not directive and s > bad_run_end:
                        run = _BAD_RUN_RE.match(text, s)
                        length = len(run.group()) if run else 1
                        bad_run_end = s + length
                        ch = text[s]
                        what = "'#' (directives start a line)" if ch == "#" else repr(ch)
                        self.diags.append(error("bad-char", f"unexpected character {what}",
                                                Span(name, line, col, line, col + length)))
                    append(Tok("BAD", m.group(kind), span))
                first_on_line = False
                if len(current) > room:
                    self.truncated = True
                    pos = n + 1
                    break
            else:
                pos = n + 1
        self.next_line = None
        yield directive, current, hash_span, text[raw_start:] if directive else ""
