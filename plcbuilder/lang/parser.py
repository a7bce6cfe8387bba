"""The parser: lark LALR(1) over the preprocessor's tokens, building the AST inline.

- lark's own lexer is not used: a small Lexer class hands lark the tokens the
  preprocessor made; each lark Token's ``start_pos`` is its index in that list,
  which gives back the token's Span.
- The AST is built during parsing (an inline Transformer), so no parse tree is
  made and nothing recurses: nesting is limited to MAX_DEPTH by a diagnostic.
- Syntax errors resynchronise on ``;``, ``{`` and ``}`` (panic mode): the
  parser is brought to a state that accepts the synchronising token by feeding
  it made-up tokens, so one mistake gives one error, and the count is capped.
  :mod:`plcbuilder.lang.syntax_errors` words each error.
- A parse can start from the one before it (:func:`parse_incremental`): it
  keeps the parser's state at the start of every top-level item, so the next
  parse of an edited token list starts at the last item before the edit and
  stops as soon as it is back in the state the old parse was in at an item
  after the edit; the items after that are the old ones (moved down or up by
  the lines the edit added or removed). Error recovery notes which tokens it
  read, so an error whose message or recovery looked across the edit is
  never reused. The result is the one a parse from scratch gives.
"""

from __future__ import annotations

import threading
from copy import copy
from dataclasses import dataclass, field, replace
from functools import lru_cache
from importlib import resources
from typing import Optional

from lark import Lark, Token, Transformer, Tree
from lark.exceptions import UnexpectedInput, UnexpectedToken
from lark.lexer import Lexer as _LarkLexer
from lark.lexer import LexerThread
from lark.parsers.lalr_parser_state import ParseConf, ParserState

from plcbuilder.diagnostics import Diagnostic, Span, error
from plcbuilder.lang import ast as A
from plcbuilder.lang.syntax_errors import c_statement_header, syntax_error, token_span
from plcbuilder.lang.tokens import Tok

MAX_DEPTH = 256
MAX_SYNTAX_ERRORS = 25
SYNC = ("SEMI", "RBRACE", "LBRACE")
#: tokens fed to reach a state that accepts the synchronising token, in order of preference
FIXUPS = ("NUMBER", "RPAR", "SEMI", "RBRACE")


def grammar_text() -> str:
    return (resources.files("plcbuilder.lang") / "grammar.lark").read_text(encoding="utf-8")


class _Stream:
    """The token list, handed to lark one Token at a time; error recovery moves
    ``pos``. After lark has taken a token that starts a top-level item (the
    parser's stack is then the start state, the item list and that token), it
    calls ``at_item(index)``."""

    def __init__(self, toks: list[Tok], pos: int = 0, stack: Optional[list] = None, at_item=None):
        self.toks = toks
        self.pos = pos
        self.stack = stack          # the parser's state stack (lark changes it in place)
        self.at_item = at_item

    def __iter__(self):
        toks = self.toks
        n = len(toks)
        new = Token
        stack = self.stack
        at_item = self.at_item
        while self.pos < n:
            i = self.pos
            self.pos = i + 1
            t = toks[i]
            kind = t.kind
            if kind == "BAD":
                continue
            s = t.span
            yield new(kind, t.value, i, s[1], s[2], s[3], s[4], i + 1)
            if at_item is not None and (kind == "NAME" or kind == "SEMI") and len(stack) <= 3:
                at_item(i)


class _TokLexer(_LarkLexer):
    def __init__(self, lexer_conf):  # noqa: D401 - lark's interface
        pass

    def lex(self, data: _Stream, parser_state=None):
        return iter(data)


class AstBuilder(Transformer):
    """Builds AST nodes as lark reduces; tracks nesting depth without recursion."""

    def __init__(self):
        super().__init__(visit_tokens=False)
        self.toks: list[Tok] = []
        self.depth: dict[int, int] = {}
        self.diags: list[Diagnostic] = []
        self.too_deep = False
        self.items: list = []     # the top-level items (procedures, None for a stray ';')

    # ---------------------------------------------------------- helpers
    def _span(self, tok: Token) -> Span:
        i = tok.start_pos
        if i is not None and 0 <= i < len(self.toks):
            return self.toks[i].span
        last = self.toks[-1].span if self.toks else Span("<input>", 1, 1, 1, 2)
        return Span(last.file, last.end_line, last.end_col, last.end_line, last.end_col + 1)

    def _d(self, node) -> int:
        return self.depth.get(id(node), 0)

    def _nest(self, node, *kids):
        depth = self.depth
        d = 0
        for k in kids:
            kd = depth.get(id(k), 0)
            if kd > d:
                d = kd
        d += 1
        if d > MAX_DEPTH:
            if not self.too_deep:
                self.too_deep = True
                self.diags.append(error("nesting-too-deep",
                                        f"nested more than {MAX_DEPTH} levels deep", node.span,
                                        "split the expression or statement into simpler parts"))
            # cut the tree here so later passes stay shallow
            if isinstance(node, (A.Num, A.Name, A.Call, A.Unary, A.Binary, A.Paren, A.Index)):
                node = A.Num(0, node.span, "0", synthetic=True)
            else:
                node = A.Empty(node.span)
            d = 1
        depth[id(node)] = d
        return node

    # ---------------------------------------------------------- module
    def start(self, items):
        self.items = items
        return A.Module([i for i in items if isinstance(i, A.ProcDef)])

    def stray_semi(self, _):
        return None

    def proc_def(self, c):
        name, _lp, _rp, body = c
        ns = self._span(name)
        return A.ProcDef(str(name), ns, body, ns.cover(body.span))

    def block(self, c):
        lb, *stmts, rb = c
        end = self._span(rb)
        node = A.Block(stmts, self._span(lb).cover(end), end)
        return self._nest(node, *stmts)

    # ---------------------------------------------------------- statements
    def assign(self, c):
        name, _eq, value, semi = c
        target = A.Name(str(name), self._span(name))
        return self._nest(A.Assign(target, value, target.span.cover(self._span(semi))), value)

    def compound(self, c):
        name, op, value, semi = c
        target = A.Name(str(name), self._span(name))
        return self._nest(A.Assign(target, value, target.span.cover(self._span(semi)), op[0],
                                   op[1]), value)

    def index_assign(self, c):
        target, eq, value, semi = c
        return self._nest(A.Assign(target, value, target.span.cover(self._span(semi)), "=",
                                   self._span(eq)), target, value)

    def index_compound(self, c):
        target, op, value, semi = c
        return self._nest(A.Assign(target, value, target.span.cover(self._span(semi)), op[0],
                                   op[1]), target, value)

    def compound_op(self, c):
        tok = c[0]
        return (str(tok), self._span(tok))

    def index(self, c):
        name, _lb, expr, rb = c
        ns = self._span(name)
        return self._nest(A.Index(str(name), ns, expr, ns.cover(self._span(rb))), expr)

    def inc(self, c):
        name, _op, semi = c
        target = A.Name(str(name), self._span(name))
        return A.IncDec(target, "++", target.span.cover(self._span(semi)))

    def dec(self, c):
        name, _op, semi = c
        target = A.Name(str(name), self._span(name))
        return A.IncDec(target, "--", target.span.cover(self._span(semi)))

    def call_stmt(self, c):
        call, semi = c
        return self._nest(A.CallStmt(call, call.span.cover(self._span(semi))), call)

    def if_stmt(self, c):
        kw, _lp, cond, _rp, then = c
        return self._nest(A.If(cond, then, None, self._span(kw).cover(then.span)), cond, then)

    def if_else(self, c):
        kw, _lp, cond, _rp, then, el, orelse = c
        return self._nest(A.If(cond, then, orelse, self._span(kw).cover(orelse.span), self._span(el)),
                          cond, then, orelse)

    def do_while(self, c):
        kw, body, wh, _lp, cond, _rp, semi = c
        return self._nest(A.DoWhile(body, cond, self._span(kw).cover(self._span(semi)), self._span(wh)),
                          body, cond)

    def while_stmt(self, c):
        kw, _lp, cond, _rp, body = c
        ws = self._span(kw)
        return self._nest(A.While(cond, body, ws.cover(body.span), ws), cond, body)

    def empty(self, c):
        return A.Empty(self._span(c[0]))

    # ---------------------------------------------------------- expressions
    def call(self, c):
        name, lp, *rest = c
        args = rest[0] if len(rest) == 2 else []
        ns = self._span(name)
        node = A.Call(str(name), ns, args, ns.cover(self._span(rest[-1])))
        return self._nest(node, *args)

    def args(self, c):
        return [x for x in c if not isinstance(x, Token)]

    def binary(self, c):
        left, op, right = c
        node = A.Binary(str(op), left, right, left.span.cover(right.span), self._span(op))
        return self._nest(node, left, right)

    def unary(self, c):
        op, operand = c
        node = A.Unary(str(op), operand, self._span(op).cover(operand.span))
        return self._nest(node, operand)

    def number(self, c):
        tok = c[0]
        i = tok.start_pos
        if tok.value == "" or i is None or not (0 <= i < len(self.toks)):
            return A.Num(0, self._span(tok), "0", synthetic=True)
        t = self.toks[i]
        return A.Num(t.number, t.span, t.value)

    def name(self, c):
        tok = c[0]
        return A.Name(str(tok), self._span(tok))

    def paren(self, c):
        lp, expr, rp = c
        return self._nest(A.Paren(expr, self._span(lp).cover(self._span(rp))), expr)


@lru_cache(maxsize=1)
def _parser() -> tuple[Lark, AstBuilder]:
    builder = AstBuilder()
    lark = Lark(grammar_text(), parser="lalr", lexer=_TokLexer, transformer=builder,
                maybe_placeholders=False)
    return lark, builder


_lock = threading.Lock()
_LIST = "__start_star_0"        # lark's rule for ``item*``: its value is the list of items


@dataclass
class _Mark:
    """The parse just before top-level item ``idx``: everything needed to go on from there."""
    idx: int                   # the token the item starts with
    stack: tuple               # lark's state stack (the start state, then the item list's)
    nitems: int                # items before this one
    nrec: int                  # recovery's diagnostics so far
    nbuild: int                # the tree builder's diagnostics so far
    count: int                 # syntax errors counted so far
    quiet_until: int
    last_error: int
    too_deep: bool
    hi: int                    # the highest token index error recovery read so far (-1: none)
    items_ref: Optional[list] = None   # a list whose first ``nitems`` are the items before


@dataclass
class _Error:
    """One syntax error: where, which tokens its recovery and message read, and
    how far recovery unwound the parser's stack."""
    idx: int
    lo: int
    hi: int
    min_stack: int


@dataclass
class Parsed:
    """One parse: the tree and the diagnostics, and what lets the next parse of
    an edited token list reuse it (:func:`parse_incremental`)."""
    toks: list[Tok]
    module: A.Module
    diagnostics: list[Diagnostic]
    items: list = field(default_factory=list)
    marks: list[_Mark] = field(default_factory=list)    # empty: nothing can be reused
    errors: list[_Error] = field(default_factory=list)
    rec_diags: list[Diagnostic] = field(default_factory=list)
    build_diags: list[Diagnostic] = field(default_factory=list)
    count: int = 0             # syntax errors counted
    reparsed: tuple = (0, 0)   # the tokens parsed this time [start, end) (for tests and benches)
    #: procedures of the previous parse reused here moved by some lines:
    #: id(new) -> (the previous one, the file, how many lines)
    moved: dict = field(default_factory=dict)


class _Synced(Exception):
    """Raised by the stream: the parse is back in a state the previous one was in."""


def parse_tokens(toks: list[Tok]) -> tuple[A.Module, list[Diagnostic]]:
    """Parse preprocessed tokens into a Module; syntax errors become diagnostics."""
    p = parse_incremental(toks)
    return p.module, p.diagnostics


def parse_incremental(toks: list[Tok], previous: Optional[Parsed] = None,
                      main_file: Optional[str] = None) -> Parsed:
    """Parse preprocessed tokens, reusing ``previous`` (the parse of an earlier
    version of the same file, whose lines moved only in ``main_file``) where
    the tokens did not change. The result is the one :func:`parse_tokens` gives."""
    lark, builder = _parser()
    with _lock:
        try:
            return _Run(lark, builder, toks, previous, main_file).run()
        finally:
            builder.toks, builder.depth, builder.items = [], {}, []


class _Run:
    """One parse (see :func:`parse_incremental`)."""

    def __init__(self, lark: Lark, builder: AstBuilder, toks: list[Tok], previous: Optional[Parsed],
                 main_file: Optional[str]):
        self.lark, self.builder, self.toks = lark, builder, toks
        self.prev = previous if previous is not None and previous.marks else None
        self.main_file = main_file
        front = lark.parser
        self.lalr = front.parser.parser                  # lark's _Parser
        self.conf = ParseConf(self.lalr.parse_table, self.lalr.callbacks, "start")
        self.lexer = front.lexer
        start = self.conf.start_state
        self.list_state = self.conf.states[start][_LIST][1]
        self.marks: list[_Mark] = []
        self.sync_from = len(toks) + 1      # no syncing unless reusing
        self.prev_marks: dict[int, _Mark] = {}

    # ---------------------------------------------------------- driver
    def run(self) -> Parsed:
        toks, builder = self.toks, self.builder
        builder.toks, builder.depth, builder.items = toks, {}, []
        builder.diags, builder.too_deep = [], False
        rec = self.rec = _Recovery(toks, self.list_state)
        state_stack = [self.conf.start_state]
        value_stack: list = []
        pos = 0
        prev = self.prev
        if prev is not None:
            diff = _diff(prev.toks, toks, self.main_file)
            if diff is None:        # the same tokens
                return replace(prev, toks=toks, reparsed=(0, 0), moved={})
            e, self.f_old, self.f_new, self.lines = diff
            mark = None
            for m in prev.marks:
                if m.idx >= e:
                    break
                if m.hi + 1 < e:
                    mark = m
            self.sync_from = self.f_new
            self.prev_marks = {m.idx: m for m in prev.marks if m.idx >= self.f_old}
            if mark is not None:
                pos = mark.idx
                state_stack = list(mark.stack)
                if len(mark.stack) > 1:
                    value_stack = [Tree(_LIST, mark.items_ref[:mark.nitems])]
                self.marks = [m for m in prev.marks if m.idx < mark.idx]
                rec.diags = prev.rec_diags[:mark.nrec]
                rec.errors = [x for x in prev.errors if x.idx <= mark.idx]
                rec.count, rec.quiet_until, rec.last_error_idx = mark.count, mark.quiet_until, \
                    mark.last_error
                rec.hi = mark.hi
                builder.diags = prev.build_diags[:mark.nbuild]
                builder.too_deep = mark.too_deep
        self.start = pos
        stream = _Stream(toks, pos, state_stack, self._at_item)
        rec.stream = stream
        state = ParserState(self.conf, LexerThread.from_custom_input(self.lexer, stream),
                            state_stack, value_stack)
        self.state = state
        try:
            module = self._parse(state, rec)
        except _Synced as s:
            return self._splice(s.args[0], s.args[1])
        except UnexpectedInput as exc:
            rec.give_up(exc)
            return self._done(A.Module([]), usable=False)
        except RecursionError:  # pragma: no cover - the grammar is iterative
            rec.diags.append(error("nesting-too-deep", "program nests too deeply", None))
            return self._done(A.Module([]), usable=False)
        return self._done(module if module is not None else A.Module([]), usable=True)

    def _parse(self, state: ParserState, rec: "_Recovery"):
        """lark's LALR_Parser.parse with ``on_error``, from the given state."""
        try:
            return self.lalr.parse_from_state(state)
        except UnexpectedInput as e:
            while True:
                if not rec.on_error(e):
                    raise e
                try:
                    return self.lalr.parse_from_state(state)
                except UnexpectedToken as e2:
                    if (isinstance(e, UnexpectedToken) and e.token.type == e2.token.type == "$END"
                            and e.interactive_parser == e2.interactive_parser):
                        raise e2     # no progress at the end
                    e = e2

    def _at_item(self, i: int) -> None:
        ss = self.state.state_stack
        if len(ss) == 3 and ss[1] != self.list_state:
            return
        rec, vs = self.rec, self.state.value_stack
        items = vs[0].children if len(vs) == 2 else None
        mark = _Mark(i, tuple(ss[:-1]), len(items) if items is not None else 0, len(rec.diags),
                     len(self.builder.diags), rec.count, rec.quiet_until, rec.last_error_idx,
                     self.builder.too_deep, rec.hi, items)
        self.marks.append(mark)
        if i >= self.sync_from and i > self.start:
            old = self.prev_marks.get(i - self.f_new + self.f_old)
            if old is not None and self._can_sync(mark, old):
                raise _Synced(mark, old)

    def _can_sync(self, new: _Mark, old: _Mark) -> bool:
        """Would the previous parse, from ``old`` on, do what this one does from ``new`` on?"""
        if new.stack != old.stack or new.too_deep != old.too_deep \
                or new.quiet_until > new.idx or old.quiet_until > old.idx:
            return False
        if new.count != old.count and new.count + self.prev.count - old.count > MAX_SYNTAX_ERRORS:
            return False            # the errors after would be counted past the cap
        for x in self.prev.errors:
            if x.idx > old.idx and (x.lo < self.f_old or x.min_stack < len(old.stack)):
                return False
        return True

    # ---------------------------------------------------------- results
    def _done(self, module: A.Module, usable: bool) -> Parsed:
        rec, builder = self.rec, self.builder
        return Parsed(self.toks, module, rec.diags + builder.diags, list(builder.items),
                      self.marks if usable else [], rec.errors, rec.diags, builder.diags, rec.count,
                      (self.start, len(self.toks)))

    def _splice(self, new: _Mark, old: _Mark) -> Parsed:
        """This parse up to item ``new``, then the previous parse from ``old`` on."""
        prev, rec, builder = self.prev, self.rec, self.builder
        vs = self.state.value_stack
        shift = new.idx - old.idx
        file, lines = self.main_file, self.lines

        def move(d: Diagnostic) -> Diagnostic:
            return _moved_diag(d, file, lines)
        reused = prev.items[old.nitems:]
        moved: dict = {}
        if lines:
            olds, reused = reused, A.moved(reused, file, lines)
            moved = {id(n): (o, file, lines) for o, n in zip(olds, reused) if n is not None}
        items = (list(vs[0].children) if len(vs) == 2 else []) + reused
        rec_diags = rec.diags + [move(d) for d in prev.rec_diags[old.nrec:]]
        build_diags = builder.diags + [move(d) for d in prev.build_diags[old.nbuild:]]
        errors = rec.errors + [_Error(x.idx + shift, x.lo + shift, x.hi + shift, x.min_stack)
                               for x in prev.errors if x.idx > old.idx]
        marks = self.marks
        for m in prev.marks:
            if m.idx > old.idx:
                marks.append(_Mark(
                    m.idx + shift, m.stack, m.nitems - old.nitems + new.nitems,
                    m.nrec - old.nrec + new.nrec, m.nbuild - old.nbuild + new.nbuild,
                    m.count - old.count + new.count,
                    m.quiet_until + shift if m.quiet_until > old.idx else new.quiet_until,
                    m.last_error + shift if m.last_error > old.idx else new.last_error,
                    m.too_deep, max(new.hi, m.hi + shift) if m.hi >= 0 else new.hi, items))
        module = A.Module([i for i in items if isinstance(i, A.ProcDef)])
        return Parsed(self.toks, module, rec_diags + build_diags, items, marks, errors, rec_diags,
                      build_diags, prev.count - old.count + new.count, (self.start, new.idx), moved)


def _moved_diag(d: Diagnostic, file: Optional[str], lines: int) -> Diagnostic:
    if not lines:
        return d

    def mv(s):
        return Span(s[0], s[1] + lines, s[2], s[3] + lines, s[4]) if s is not None and s[0] == file else s
    return replace(d, span=mv(d.span), related=tuple(replace(r, span=mv(r.span)) for r in d.related))


def _same_moved(a: Tok, b: Tok, file: Optional[str], lines: int) -> bool:
    """Is new token ``b`` old token ``a``, moved ``lines`` lines if it is in ``file``?"""
    if a is b:
        return True
    if a.kind != b.kind or a.value != b.value or a.number != b.number or a.macro != b.macro \
            or a.synthetic != b.synthetic:
        return False
    sa, sb = a.span, b.span
    if lines and sa[0] == file:
        return sb[0] == file and sa[1] + lines == sb[1] and sa[3] + lines == sb[3] \
            and sa[2] == sb[2] and sa[4] == sb[4]
    return sa == sb


def _diff(old: list[Tok], new: list[Tok], file: Optional[str]):
    """Where two token lists differ: (the first token that differs, where the
    common end starts in old and in new, how many lines it moved in ``file``),
    or None when they are the same."""
    n_old, n_new = len(old), len(new)
    n = min(n_old, n_new)
    e = 0
    while e < n and (old[e] is new[e] or old[e] == new[e]):
        e += 1
    if e == n_old == n_new:
        return None
    lines = 0
    for k in range(1, n - e + 1):             # the last token of the file moved by as many lines
        a, b = old[-k], new[-k]
        if a.span[0] == file and b.span[0] == file:
            lines = b.span[1] - a.span[1]
            break
        if a.span[0] != b.span[0]:
            break
    k = 0
    while k < n - e and _same_moved(old[n_old - 1 - k], new[n_new - 1 - k], file, lines):
        k += 1
    return e, n_old - k, n_new - k, lines


class _Reads:
    """The token list as error recovery and its messages see it: notes the
    lowest and highest index they read, so a later parse knows whether an edit
    there could change what they did."""

    __slots__ = ("toks", "lo", "hi")

    def __init__(self, toks: list[Tok]):
        self.toks = toks
        self.lo = self.hi = -1

    def __len__(self) -> int:
        return len(self.toks)

    def __getitem__(self, i: int) -> Tok:
        j = i + len(self.toks) if i < 0 else i
        if j < self.lo:
            self.lo = j
        if j > self.hi:
            self.hi = j
        return self.toks[i]


#: what the parser accepts between procedures and in a procedure's header
TOP_LEVEL = frozenset(("NAME", "SEMI", "$END", "LPAR", "RPAR", "LBRACE"))
#: the deepest parser stack there is outside every procedure's body (start, the
#: item list, NAME LPAR RPAR)
TOP_LEVEL_DEPTH = 5


class _Recovery:
    def __init__(self, toks: list[Tok], list_state: Optional[int] = None):
        self.list_state = list_state
        self.toks = _Reads(toks)
        self.diags: list[Diagnostic] = []
        self.stream: Optional[_Stream] = None
        self.last_error_idx = -1
        self.quiet_until = -1     # errors at or before this index are cascades
        self.count = 0
        self.errors: list[_Error] = []
        self.hi = -1              # the highest index any error read
        self.min_stack = 0

    # ---------------------------------------------------------- recovery
    def on_error(self, e) -> bool:
        if not isinstance(e, UnexpectedToken):
            return False
        tok = e.token
        idx = len(self.toks) if tok.type == "$END" else tok.start_pos
        reads = self.toks
        reads.lo = reads.hi = idx
        self.min_stack = len(e.interactive_parser.parser_state.state_stack)
        try:
            return self._on_error(e)
        finally:
            self.errors.append(_Error(idx, reads.lo, reads.hi, self.min_stack))
            if reads.hi > self.hi:
                self.hi = reads.hi

    def _on_error(self, e) -> bool:
        tok = e.token
        idx = len(self.toks) if tok.type == "$END" else tok.start_pos
        ip = e.interactive_parser
        if idx <= self.last_error_idx and tok.type != "$END":
            # no progress at this token: drop it
            self.stream.pos = idx + 1
            self.last_error_idx = idx
            return True
        after_bad = 0 < idx <= len(self.toks) and self.toks[idx - 1].kind == "BAD"
        if idx > self.quiet_until and not after_bad:
            self.count += 1
            if self.count > MAX_SYNTAX_ERRORS:
                self.diags.append(error("too-many-errors",
                                        f"too many syntax errors; stopped after {MAX_SYNTAX_ERRORS}",
                                        token_span(self.toks, idx)))
                return False
            self.diags.append(syntax_error(self.toks, idx, set(ip.accepts())))
        self.last_error_idx = idx
        if tok.type not in ("LBRACE", "$END") and self._between_procedures(ip):
            return self._skip_to_procedure(ip, idx)
        header_end = c_statement_header(self.toks, idx)
        # find a synchronising token at or after the error
        j = idx
        toks = self.toks
        for _attempt in range(len(toks) - idx + 2):
            while j < len(toks) and toks[j].kind not in SYNC:
                j += 1
            target = "$END" if j >= len(toks) else toks[j].kind
            if self._fixup(ip, target, j):
                self.stream.pos = j
                self.quiet_until = max(self.quiet_until, j, header_end)
                return True
            if j >= len(toks):
                return False
            j += 1
        return False

    def _between_procedures(self, ip) -> bool:
        """The error is outside every procedure's body (a stray token before a
        procedure, a statement outside one, a bad header)."""
        return (len(ip.parser_state.state_stack) <= TOP_LEVEL_DEPTH
                and set(ip.accepts()) <= TOP_LEVEL)

    def _skip_to_procedure(self, ip, idx: int) -> bool:
        """Recover outside procedures: drop the partial item and go on at the
        next ``NAME (`` outside braces (a procedure's start), or at the end;
        what lies between is not checked (one error, not one per line)."""
        state = ip.parser_state
        while len(state.state_stack) > 1 and state.state_stack[-1] != self.list_state:
            state.state_stack.pop()
            state.value_stack.pop()
        self.min_stack = min(self.min_stack, len(state.state_stack))
        toks = self.toks
        n = len(toks)
        depth = 0
        k = idx
        while k < n:
            kind = toks[k].kind
            if kind == "LBRACE":
                depth += 1
            elif kind == "RBRACE":
                depth = max(0, depth - 1)
            elif depth == 0 and kind == "NAME" and k + 1 < n and toks[k + 1].kind == "LPAR":
                break
            k += 1
        self.stream.pos = k
        self.quiet_until = max(self.quiet_until, k - 1)
        return True

    def _fixup(self, ip, target: str, at: int) -> bool:
        """Bring the parser to a state that accepts ``target``: feed made-up tokens
        (closing an expression, a parenthesis, a statement), and where that cannot
        work, discard the partial construct from the parser's stacks (yacc-style)."""
        state = ip.parser_state
        while True:
            plan = self._plan(ip, target)
            if plan is not None:
                s = token_span(self.toks, at)
                for kind in plan:
                    ip.feed_token(Token(kind, "", at, s.line, s.col, s.end_line, s.end_col, at))
                return True
            if len(state.state_stack) <= 1:
                return False
            state.state_stack.pop()
            state.value_stack.pop()
            self.min_stack = min(self.min_stack, len(state.state_stack))

    @staticmethod
    def _plan(ip, target: str) -> Optional[list[str]]:
        # a trial on the states alone: no values copied, no tree built
        trial = ip.copy(deepcopy_values=False)
        conf = copy(trial.parser_state.parse_conf)
        conf.callbacks = {}
        trial.parser_state.parse_conf = conf
        plan: list[str] = []
        order = ("RBRACE", "NUMBER", "RPAR", "SEMI") if target in ("RBRACE", "$END") else FIXUPS
        for _ in range(8):
            acc = trial.accepts()
            if target in acc:
                return plan
            for kind in order:
                if kind in acc and not (kind in ("SEMI", "NUMBER") and plan and plan[-1] == kind):
                    trial.feed_token(Token(kind, "", 0))
                    plan.append(kind)
                    break
            else:
                return None
        return None

    def give_up(self, exc) -> None:
        if not any(d.code == "too-many-errors" for d in self.diags) and not self.diags:
            idx = getattr(getattr(exc, "token", None), "start_pos", len(self.toks))
            if not isinstance(idx, int):
                idx = len(self.toks)
            self.diags.append(error("syntax", "cannot parse this", token_span(self.toks, idx)))
