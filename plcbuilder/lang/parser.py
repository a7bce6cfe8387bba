"""The parser: LALR(1) over the preprocessor's tokens, building the AST inline.

- The tables are lark's, built once from ``grammar.lark`` and read from a file
  (:mod:`plcbuilder.lang.lalr`); the loop that runs them is here, over the
  preprocessor's token list: no lark at run time, no token objects made.
- The AST is built during parsing (the tree builder's methods are called as
  rules reduce), so no parse tree is made and nothing recurses: nesting is
  limited to MAX_DEPTH levels by a diagnostic. Brackets nested deeper than
  that are found by a scan of the tokens before parsing (one error, and no
  parse); other nesting deeper than the parser's stack allows (a long run of
  ``-`` or ``if (x)``) stops the parse with the same error.
- Syntax errors resynchronise on ``;``, ``{`` and ``}`` (panic mode): the
  parser is brought to a state that accepts the synchronising token by feeding
  it made-up tokens, so one mistake gives one error, and the count is capped.
  The tokens are tried on a view of the state stack (:class:`lalr.Trial`),
  never a copy of it, so recovery costs no more with a deep stack or a long
  file. :mod:`plcbuilder.lang.syntax_errors` words each error.
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

from _thread import allocate_lock

from plcbuilder._support.records import dataclass, field, replace
from plcbuilder.diagnostics import Diagnostic, Span, error
from plcbuilder.lang import ast as A
from plcbuilder.lang.lalr import Tables, Trial, accepts, tables
from plcbuilder.lang.tokens import Tok

TYPE_CHECKING = False               # (typing is not imported at run time: start-up)
if TYPE_CHECKING:
    from typing import Optional

_new_span = tuple.__new__

MAX_DEPTH = 256
MAX_SYNTAX_ERRORS = 25
#: the deepest the parser's state stack may grow: the grammar's deepest
#: nesting costs 6 states a level (``if (c) s else if (c) s else …``), so a
#: stack this deep holds more than MAX_DEPTH levels of nesting
STACK_LIMIT = 6 * MAX_DEPTH + 64
SYNC = ("SEMI", "RBRACE", "LBRACE")
#: tokens fed to reach a state that accepts the synchronising token, in order of preference
FIXUPS = ("NUMBER", "RPAR", "SEMI", "RBRACE")
OPENING = frozenset(("LPAR", "LBRACK", "LBRACE"))
CLOSING = frozenset(("RPAR", "RBRACK", "RBRACE"))


def grammar_text() -> str:
    from plcbuilder.lang.lark_adapter import grammar_text as text
    return text()


def bracket_too_deep(toks: list[Tok]) -> int:
    """The index of the first bracket (``(``, ``[`` or ``{``) nested more than
    MAX_DEPTH deep, or -1. A closing bracket closes whichever is open."""
    depth = 0
    i = -1
    for t in toks:
        i += 1
        k = t.kind
        if k in OPENING:
            depth += 1
            if depth > MAX_DEPTH:
                return i
        elif depth and k in CLOSING:
            depth -= 1
    return -1


def _too_deep(span: Span, what: str = "nested") -> Diagnostic:
    return error("nesting-too-deep", f"{what} more than {MAX_DEPTH} levels deep", span,
                 "split the expression or statement into simpler parts")


class AstBuilder:
    """Builds AST nodes as the parser reduces (a method per rule, named as in
    the grammar, given the rule's children: AST nodes and the :class:`Tok` of
    each terminal); tracks nesting depth without recursion."""

    def __init__(self):
        self.toks: list[Tok] = []
        #: each node's nesting depth, keyed by the node itself: the key keeps it
        #: alive for the parse, so a node made after one was dropped (a subtree
        #: cut off too deep, values popped by error recovery) never takes over
        #: its address and with it its depth (keyed by id(), a name after a cut
        #: expression could inherit 250 levels and turn its statement Empty)
        self.depth: dict = {}
        self.diags: list[Diagnostic] = []
        self.too_deep = False
        self.items: list = []     # the top-level items (procedures, None for a stray ';')

    # ---------------------------------------------------------- helpers
    def _d(self, node) -> int:
        return self.depth.get(node, 0)

    def _nest(self, node, *kids):
        depth = self.depth
        d = 0
        for k in kids:
            kd = depth.get(k, 0)
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
        depth[node] = d
        return node

    # ---------------------------------------------------------- module
    def start(self, items):
        self.items = items
        return A.Module([i for i in items if isinstance(i, A.ProcDef)])

    def stray_semi(self, _):
        return None

    def proc_def(self, c):
        name, _lp, _rp, body = c
        ns = name.span
        return A.ProcDef(name.value, ns, body, ns.cover(body.span))

    def block(self, c):
        lb, *stmts, rb = c
        end = rb.span
        node = A.Block(stmts, lb.span.cover(end), end)
        return self._nest(node, *stmts)

    # ---------------------------------------------------------- statements
    def assign(self, c):
        name, _eq, value, semi = c
        target = A.Name(name.value, name.span)
        return self._nest(A.Assign(target, value, target.span.cover(semi.span)), value)

    def compound(self, c):
        name, op, value, semi = c
        target = A.Name(name.value, name.span)
        return self._nest(A.Assign(target, value, target.span.cover(semi.span), op[0],
                                   op[1]), value)

    def index_assign(self, c):
        target, eq, value, semi = c
        return self._nest(A.Assign(target, value, target.span.cover(semi.span), "=",
                                   eq.span), target, value)

    def index_compound(self, c):
        target, op, value, semi = c
        return self._nest(A.Assign(target, value, target.span.cover(semi.span), op[0],
                                   op[1]), target, value)

    def compound_op(self, c):
        tok = c[0]
        return (tok.value, tok.span)

    def index(self, c):
        name, _lb, expr, rb = c
        ns = name.span
        return self._nest(A.Index(name.value, ns, expr, ns.cover(rb.span)), expr)

    def inc(self, c):
        name, _op, semi = c
        target = A.Name(name.value, name.span)
        return A.IncDec(target, "++", target.span.cover(semi.span))

    def dec(self, c):
        name, _op, semi = c
        target = A.Name(name.value, name.span)
        return A.IncDec(target, "--", target.span.cover(semi.span))

    def call_stmt(self, c):
        call, semi = c
        return self._nest(A.CallStmt(call, call.span.cover(semi.span)), call)

    def if_stmt(self, c):
        kw, _lp, cond, _rp, then = c
        return self._nest(A.If(cond, then, None, kw.span.cover(then.span)), cond, then)

    def if_else(self, c):
        kw, _lp, cond, _rp, then, el, orelse = c
        return self._nest(A.If(cond, then, orelse, kw.span.cover(orelse.span), el.span),
                          cond, then, orelse)

    def do_while(self, c):
        kw, body, wh, _lp, cond, _rp, semi = c
        return self._nest(A.DoWhile(body, cond, kw.span.cover(semi.span), wh.span),
                          body, cond)

    def while_stmt(self, c):
        kw, _lp, cond, _rp, body = c
        ws = kw.span
        return self._nest(A.While(cond, body, ws.cover(body.span), ws), cond, body)

    def empty(self, c):
        return A.Empty(c[0].span)

    # ---------------------------------------------------------- expressions
    def call(self, c):
        name, lp, *rest = c
        args = rest[0] if len(rest) == 2 else []
        ns = name.span
        node = A.Call(name.value, ns, args, ns.cover(rest[-1].span))
        return self._nest(node, *args)

    def args(self, c):
        return [x for x in c if not isinstance(x, Tok)]

    def binary(self, c):
        left, op, right = c
        ls, rs = left.span, right.span
        if ls[0] == rs[0] and (ls[1], ls[2]) <= (rs[1], rs[2]) and (ls[3], ls[4]) <= (rs[3], rs[4]):
            span = _new_span(Span, (ls[0], ls[1], ls[2], rs[3], rs[4]))   # ls.cover(rs), inlined
        else:
            span = ls.cover(rs)
        node = A.Binary(op.value, left, right, span, op.span)
        depth = self.depth                  # _nest, unrolled: the commonest node
        d = depth.get(left, 0)
        r = depth.get(right, 0)
        if r > d:
            d = r
        if d >= MAX_DEPTH:
            return self._nest(node, left, right)
        depth[node] = d + 1
        return node

    def unary(self, c):
        op, operand = c
        node = A.Unary(op.value, operand, op.span.cover(operand.span))
        return self._nest(node, operand)

    def number(self, c):
        tok = c[0]
        if tok.synthetic:
            return A.Num(0, tok.span, "0", synthetic=True)
        return A.Num(tok.number, tok.span, tok.value)

    def name(self, c):
        tok = c[0]
        return A.Name(tok.value, tok.span)

    def paren(self, c):
        lp, expr, rp = c
        return self._nest(A.Paren(expr, lp.span.cover(rp.span)), expr)


def _callbacks(t: Tables, builder: "AstBuilder") -> list:
    """Per rule: None when its value is its only child's (a ``?rule`` of one
    symbol), else the function making its value from the popped children."""
    out = []
    for _origin, size, method, expand1, children in t.rules:
        if method is None:
            if children == APPEND_CHILDREN:
                out.append(_APPEND)     # ``x* x``: the list, extended in place
                continue
            fn = None if children is None else _splicer(children, None)
            out.append(fn if fn is not None else list)
            continue
        if children is None and expand1 and size == 1:
            out.append(None)
            continue
        m = getattr(builder, method)
        if children is None:
            # (a ?rule of one symbol is None above: its children, all kept,
            # are never one, so its method is called as is)
            out.append(m)
        else:
            out.append(_splicer(children, m, expand1))
    return out


#: the children of a helper list's ``x* x`` rule: the list (spliced), then the item
APPEND_CHILDREN = ((0, True), (1, False))


def _APPEND(kids: list) -> list:
    """A helper list's ``x* x``: the list with the item appended (in place, as
    lark does for left recursion). The parser's loop does this inline."""
    kept = kids[0]
    kept.append(kids[1])
    return kept


def _splicer(children: tuple, make, expand1: bool = False):
    """The children a rule keeps, helper lists spliced in (the first one
    extended in place, as lark does for left recursion), then ``make`` on them
    (None: the list itself)."""
    def value(kids):
        kept: list = []
        for i, splice in children:
            if splice:
                if kept:
                    kept += kids[i]
                else:
                    kept = kids[i]
            else:
                kept.append(kids[i])
        if make is None:
            return kept
        if expand1 and len(kept) == 1:
            return kept[0]
        return make(kept)
    return value


_lock = allocate_lock()
_builder: Optional["AstBuilder"] = None
_calls: list = []


def _parser() -> tuple[Tables, "AstBuilder", list]:
    global _builder, _calls
    if _builder is None:
        b = AstBuilder()
        _calls = _callbacks(tables(), b)
        _builder = b
    return tables(), _builder, _calls


@dataclass(slots=True, eq=False)
class _Mark:
    """The parse just before top-level item ``idx``: everything needed to go on from there."""
    idx: int                   # the token the item starts with
    stack: tuple               # the parser's state stack (the start state, then the item list's)
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


def parse_tokens(toks: list[Tok]) -> tuple[A.Module, list[Diagnostic]]:
    """Parse preprocessed tokens into a Module; syntax errors become diagnostics."""
    p = parse_incremental(toks)
    return p.module, p.diagnostics


def parse_incremental(toks: list[Tok], previous: Optional[Parsed] = None,
                      main_file: Optional[str] = None) -> Parsed:
    """Parse preprocessed tokens, reusing ``previous`` (the parse of an earlier
    version of the same file, whose lines moved only in ``main_file``) where
    the tokens did not change. The result is the one :func:`parse_tokens` gives."""
    deep = bracket_too_deep(toks)
    if deep >= 0:
        d = _too_deep(toks[deep].span, "brackets nested")
        return Parsed(toks, A.Module([]), [d], rec_diags=[d], count=1, reparsed=(0, len(toks)))
    t, builder, calls = _parser()
    with _lock:
        try:
            return _Run(t, builder, calls, toks, previous, main_file).run()
        finally:
            builder.toks, builder.depth, builder.items = [], {}, []


# what one run of the parsing loop ended with
_DONE, _ERROR, _SYNCED, _DEEP = range(4)


class _Run:
    """One parse (see :func:`parse_incremental`)."""

    def __init__(self, t: Tables, builder: AstBuilder, calls: list, toks: list[Tok],
                 previous: Optional[Parsed], main_file: Optional[str]):
        self.t, self.builder, self.calls, self.toks = t, builder, calls, toks
        #: per rule: (the nonterminal it makes, how many values it pops, its callback)
        self.reduce = [(r[0], r[1], fn) for r, fn in zip(t.rules, calls)]
        self.prev = previous if previous is not None and previous.marks else None
        self.main_file = main_file
        self.list_state = t.list_state
        self.marks: list[_Mark] = []
        self.sync_from = len(toks) + 1      # no syncing unless reusing
        self.prev_marks: dict[int, _Mark] = {}
        self.ss: list[int] = [t.start]      # the state stack
        self.vs: list = []                  # the value stack
        self.pos = 0                        # the next token to read
        self.last = 0                       # the last token read since the parse (re)started
        self.synced: Optional[tuple] = None

    # ---------------------------------------------------------- driver
    def run(self) -> Parsed:
        toks, builder = self.toks, self.builder
        builder.toks, builder.depth, builder.items = toks, {}, []
        builder.diags, builder.too_deep = [], False
        rec = self.rec = _Recovery(toks, self)
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
                self.ss = list(mark.stack)
                self.marks = [m for m in prev.marks if m.idx < mark.idx]
                if len(mark.stack) > 1:
                    # the item list goes on in a copy: the marks taken in it
                    # so far refer to the copy too (one list, one object:
                    # what :meth:`_splice` tells lists apart by)
                    ref, live = mark.items_ref, mark.items_ref[:mark.nitems]
                    self.vs = [live]
                    self.marks = [m if m.items_ref is not ref else replace(m, items_ref=live)
                                  for m in self.marks]
                rec.diags = prev.rec_diags[:mark.nrec]
                rec.errors = [x for x in prev.errors if x.idx <= mark.idx]
                rec.count, rec.quiet_until, rec.last_error_idx = mark.count, mark.quiet_until, \
                    mark.last_error
                rec.hi = mark.hi
                builder.diags = prev.build_diags[:mark.nbuild]
                builder.too_deep = mark.too_deep
        self.start = self.pos = pos
        end, result = self._parse(rec)
        if end == _SYNCED:
            return self._splice(*self.synced)
        if end == _DONE:
            return self._done(result if result is not None else A.Module([]), usable=True)
        if end == _DEEP:
            if not builder.too_deep:
                builder.too_deep = True
                from plcbuilder.lang.syntax_errors import token_span
                builder.diags.append(_too_deep(token_span(toks, result)))
        else:
            rec.give_up(result)
        return self._done(A.Module([]), usable=False)

    def _parse(self, rec: "_Recovery") -> tuple[int, object]:
        """Run the parser to the end, recovering from errors; (_DONE, the
        module), (_SYNCED, None), (_DEEP, the token) or (_ERROR, the token
        where it gave up)."""
        end, at = self._drive()
        ends = 0
        while end == _ERROR:
            kind = "$END" if at >= len(self.toks) else self.toks[at].kind
            if kind == "$END":
                ends += 1
            if ends > 1 or not rec.on_error(kind, at):      # (no progress at the end)
                return _ERROR, (self.last if kind == "$END" else at)
            self.last = 0
            end, at = self._drive()
        return end, at

    def _drive(self) -> tuple[int, object]:
        """Feed the tokens from ``self.pos`` (and then the end of the input) to
        the parser: lark's ``parse_from_state``, with the loop unrolled.

        A reduction replaces the values it pops in place (one fewer list
        operation each); a helper list's ``x* x`` appends to the list; a run
        of ``;`` where an item or a statement may start is taken at once
        (:func:`_semi_runs`): the most tokens a file of a given size can
        hold, each a stray item or an empty statement."""
        toks, n = self.toks, len(self.toks)
        states, reduce = self.t.states, self.reduce
        chains = _CHAINS
        runs = _semi_runs(self.t)
        empty = A.Empty
        ss, vs = self.ss, self.vs
        limit = STACK_LIMIT
        pos = self.pos
        last = self.last
        prev = None
        while pos < n:
            t = toks[pos]
            kind = t.kind
            if kind == "BAD":
                pos += 1
                continue
            act = states[ss[-1]].get(kind)
            while act is not None and act < 0:     # reduce (as often as it takes)
                origin, size, fn = reduce[~act]
                if fn is None:
                    # a ?rule's only child is its value: only the top state
                    # changes, and a run of them (an operand climbing the
                    # precedence levels, a dozen) is looked up at once
                    key = (ss[-2], ss[-1], kind)
                    hit = chains.get(key)
                    if hit is None:
                        hit = chains[key] = _chain(states, reduce, ss[-2], origin, kind)
                    ss[-1], act = hit
                    continue
                if size == 1:
                    vs[-1] = fn([vs[-1]])
                elif fn is _APPEND:
                    x = vs.pop()
                    vs[-1].append(x)
                    del ss[-1]
                elif size:
                    kids = vs[-size:]
                    del vs[1 - size:]
                    vs[-1] = fn(kids)
                    del ss[1 - size:]
                else:
                    vs.append(fn([]))
                    ss.append(0)
                top = ss[-1] = states[ss[-2]][origin]
                act = states[top].get(kind)
            if act is None:
                self.pos = pos + 1
                self.last = last
                return _ERROR, pos
            ss.append(act)                          # shift
            vs.append(t)
            last = pos
            pos += 1
            if len(ss) > limit:
                self.pos = pos
                self.last = last
                return _DEEP, pos - 1
            # a mark where an item may start (not inside a run of ';': a
            # parse restarts from the run's first, and marks cost time)
            if kind == "SEMI":
                if prev != "SEMI" and len(ss) <= 3:
                    self.pos = pos
                    if self._at_item(pos - 1):
                        self.last = last
                        return _SYNCED, None
                run = runs.get((ss[-2], act)) if pos < n and toks[pos].kind == "SEMI" else None
                if run is not None:
                    # each ';' up to the run's last reduces the one before
                    # (to a stray item, None, or an empty statement) and is
                    # shifted: the one before the run's last stays shifted
                    j = pos + 1
                    while j < n and toks[j].kind == "SEMI":
                        j += 1
                    if run == "stray_semi":
                        vs[-2].extend([None] * (j - pos))
                    else:
                        vs[-2].extend([empty(x.span) for x in toks[pos - 1:j - 1]])
                    vs[-1] = toks[j - 1]
                    last = j - 1
                    pos = j
            elif kind == "NAME" and len(ss) <= 3:
                self.pos = pos
                if self._at_item(pos - 1):
                    self.last = last
                    return _SYNCED, None
            prev = kind
        self.pos = n
        self.last = last
        value = self.feed("$END", None)
        if value is _FAILED:
            return _ERROR, n
        return _DONE, value

    def feed(self, kind: str, tok: Optional[Tok]):
        """Feed one token (its reductions, then its shift; for the end of the
        input, the reductions up to the accepting state: then the module);
        _FAILED, with the reductions done, when it is not accepted here."""
        states, rules, calls = self.t.states, self.t.rules, self.calls
        ss, vs = self.ss, self.vs
        end = self.t.end
        is_end = kind == "$END"
        while True:
            act = states[ss[-1]].get(kind)
            if act is None:
                return _FAILED
            if act >= 0:
                if is_end:
                    return _FAILED
                ss.append(act)
                vs.append(tok)
                return None
            act = -1 - act
            origin, size = rules[act][:2]
            fn = calls[act]
            if fn is None:
                ss.pop()
            else:
                if size:
                    kids = vs[-size:]
                    del vs[-size:]
                    del ss[-size:]
                else:
                    kids = []
                vs.append(fn(kids))
            ss.append(states[ss[-1]][origin])
            if is_end and ss[-1] == end:
                return vs[-1]

    def _at_item(self, i: int) -> bool:
        """Token ``i``, just taken, may start a top-level item: note the parse
        here; True when the parse is back where the previous one was."""
        ss = self.ss
        if len(ss) == 3 and ss[1] != self.list_state:
            return False
        rec, vs = self.rec, self.vs
        items = vs[0] if len(vs) == 2 else None
        mark = _Mark(i, tuple(ss[:-1]), len(items) if items is not None else 0, len(rec.diags),
                     len(self.builder.diags), rec.count, rec.quiet_until, rec.last_error_idx,
                     self.builder.too_deep, rec.hi, items)
        self.marks.append(mark)
        if i >= self.sync_from and i > self.start:
            old = self.prev_marks.get(i - self.f_new + self.f_old)
            if old is not None and self._can_sync(mark, old):
                self.synced = (mark, old)
                return True
        return False

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
        # the item list itself, not a copy: the marks of its items refer to it
        # (``items_ref``), and :meth:`_splice` tells them from the marks of an
        # earlier item list by it (nothing changes it once the parse is done)
        return Parsed(self.toks, module, rec.diags + builder.diags, builder.items,
                      self.marks if usable else [], rec.errors, rec.diags, builder.diags, rec.count,
                      (self.start, len(self.toks)))

    def _splice(self, new: _Mark, old: _Mark) -> Parsed:
        """This parse up to item ``new``, then the previous parse from ``old`` on."""
        prev, rec, builder = self.prev, self.rec, self.builder
        vs = self.vs
        shift = new.idx - old.idx
        file, lines = self.main_file, self.lines

        def move(d: Diagnostic) -> Diagnostic:
            return _moved_diag(d, file, lines)
        reused = prev.items[old.nitems:]
        moved: dict = {}
        if lines:
            olds, reused = reused, A.moved(reused, file, lines)
            moved = {id(n): (o, file, lines) for o, n in zip(olds, reused) if n is not None}
        items = (list(vs[0]) if len(vs) == 2 else []) + reused
        rec_diags = rec.diags + [move(d) for d in prev.rec_diags[old.nrec:]]
        build_diags = builder.diags + [move(d) for d in prev.build_diags[old.nbuild:]]
        errors = rec.errors + [_Error(x.idx + shift, x.lo + shift, x.hi + shift, x.min_stack)
                               for x in prev.errors if x.idx > old.idx]
        live = vs[0] if len(vs) == 2 else None
        marks = [m if live is None or m.items_ref is not live else replace(m, items_ref=items)
                 for m in self.marks]
        # A mark refers to the item list it was taken in. The previous parse's
        # last list is the one spliced here (``items``); a list error recovery
        # started again after ``old`` and later dropped (it unwound the parser
        # below the item list: syncing allows that only when ``old`` had no
        # list) is all after ``old``: its marks keep it, moved as the lines
        # moved, and count from its start as before.
        earlier: dict = {}
        for m in prev.marks:
            if m.idx > old.idx:
                ref, nitems = m.items_ref, m.nitems
                if ref is prev.items:
                    ref, nitems = items, nitems - old.nitems + new.nitems
                elif lines:
                    got = earlier.get(id(ref))
                    if got is None:
                        got = earlier[id(ref)] = A.moved(ref, file, lines)
                    ref = got
                marks.append(_Mark(
                    m.idx + shift, m.stack, nitems,
                    m.nrec - old.nrec + new.nrec, m.nbuild - old.nbuild + new.nbuild,
                    m.count - old.count + new.count,
                    m.quiet_until + shift if m.quiet_until > old.idx else new.quiet_until,
                    m.last_error + shift if m.last_error > old.idx else new.last_error,
                    m.too_deep, max(new.hi, m.hi + shift) if m.hi >= 0 else new.hi, ref))
        module = A.Module([i for i in items if isinstance(i, A.ProcDef)])
        return Parsed(self.toks, module, rec_diags + build_diags, items, marks, errors, rec_diags,
                      build_diags, prev.count - old.count + new.count, (self.start, new.idx), moved)


_FAILED = object()
#: (the state below, the top state, the next token's kind) -> (the top state
#: after the run of one-child reductions the token causes, the action then)
_CHAINS: dict = {}


def _chain(states: list, reduce: list, below: int, origin: str, kind: str) -> tuple:
    top = states[below][origin]
    act = states[top].get(kind)
    while act is not None and act < 0 and reduce[~act][2] is None:
        top = states[below][reduce[~act][0]]
        act = states[top].get(kind)
    return top, act

#: Tables -> {(a helper list's state, the state after ';' in it): the
#: method ';' reduces by there ("stray_semi" or "empty")}
_RUNS: dict = {}


def _semi_runs(t: Tables) -> dict:
    """Where a run of ``;`` can be taken at once: states L of a helper list
    (``item*``, ``stmt*``) whose ``;`` goes to a state S that, on a next
    ``;``, reduces that ``;`` alone to an item or statement (``stray_semi``,
    None; ``empty``, an Empty) and appends it to the list, back in L. On
    (L, S) with a ``;`` next, the parser appends the value and shifts the next
    ``;``: the stacks stay as they are but for the list and the top token.
    Read from the tables, so a grammar that no longer has this shape has no
    runs (each ``;`` is then parsed one by one)."""
    runs = _RUNS.get(id(t))
    if runs is not None and runs[0] is t:
        return runs[1]
    states, rules = t.states, t.rules
    out = {}
    for row in states:
        for sym, lst in row.items():
            if not (sym.startswith("__") and lst >= 0):
                continue
            semi = states[lst].get("SEMI")
            if semi is None or semi < 0:
                continue
            r1 = states[semi].get("SEMI")
            if r1 is None or r1 >= 0:
                continue
            origin1, size1, method1 = rules[~r1][:3]
            if size1 != 1 or method1 not in ("stray_semi", "empty"):
                continue
            item_state = states[lst].get(origin1)
            r2 = states[item_state].get("SEMI") if item_state is not None else None
            if r2 is None or r2 >= 0:
                continue
            origin2, size2, method2, _e, children2 = rules[~r2]
            if origin2 == sym and size2 == 2 and method2 is None \
                    and children2 == APPEND_CHILDREN:
                out[(lst, semi)] = method1
    _RUNS[id(t)] = (t, out)
    return out


def _moved_diag(d: Diagnostic, file: Optional[str], lines: int) -> Diagnostic:
    if not lines:
        return d

    def mv(s):
        return Span(s[0], s[1] + lines, s[2], s[3] + lines, s[4]) if s is not None and s[0] == file else s
    return replace(d, span=mv(d.span), related=tuple(replace(r, span=mv(r.span)) for r in d.related))


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
    # the common end: new token b is old token a, moved ``lines`` lines if it
    # is in ``file`` (a loop, no call a token: after an Enter it is every
    # token below it, each a copy of the old one moved a line)
    k = 0
    limit = n - e
    i, j = n_old - 1, n_new - 1
    while k < limit:
        a, b = old[i - k], new[j - k]
        if a is not b:
            if a.kind != b.kind or a.value != b.value or a.number != b.number \
                    or a.macro != b.macro or a.synthetic != b.synthetic:
                break
            sa, sb = a.span, b.span
            if lines and sa[0] == file:
                if sb[1] != sa[1] + lines or sb[3] != sa[3] + lines or sb[2] != sa[2] \
                        or sb[4] != sa[4] or sb[0] != file:
                    break
            elif sa != sb:
                break
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
    def __init__(self, toks: list[Tok], run: _Run):
        self.run = run
        self.t = run.t
        self.list_state = run.list_state
        self.toks = _Reads(toks)
        self.diags: list[Diagnostic] = []
        self.last_error_idx = -1
        self.quiet_until = -1     # errors at or before this index are cascades
        self.count = 0
        self.errors: list[_Error] = []
        self.hi = -1              # the highest index any error read
        self.min_stack = 0

    # ---------------------------------------------------------- recovery
    def on_error(self, kind: str, idx: int) -> bool:
        """The parser does not take token ``idx`` (of kind ``kind``; the end of
        the input is index len(toks)): report it unless it is a cascade, and
        bring the parser and the position to where the parse can go on; False
        when it cannot."""
        reads = self.toks
        reads.lo = reads.hi = idx
        self.min_stack = len(self.run.ss)
        try:
            return self._on_error(kind, idx)
        finally:
            self.errors.append(_Error(idx, reads.lo, reads.hi, self.min_stack))
            if reads.hi > self.hi:
                self.hi = reads.hi

    def _on_error(self, kind: str, idx: int) -> bool:
        from plcbuilder.lang.syntax_errors import c_statement_header, syntax_error, token_span
        run = self.run
        if idx <= self.last_error_idx and kind != "$END":
            # no progress at this token: drop it
            run.pos = idx + 1
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
            self.diags.append(syntax_error(self.toks, idx, accepts(run.ss, self.t)))
        self.last_error_idx = idx
        if kind not in ("LBRACE", "$END") and self._between_procedures():
            return self._skip_to_procedure(idx)
        header_end = c_statement_header(self.toks, idx)
        # find a synchronising token at or after the error (a kind that could
        # not be reached once the stack is unwound to its start cannot later)
        j = idx
        toks = self.toks
        n = len(toks)
        hopeless: set = set()
        while True:
            while j < n and (toks[j].kind not in SYNC or toks[j].kind in hopeless):
                j += 1
            target = "$END" if j >= n else toks[j].kind
            if self._fixup(target, j):
                run.pos = j
                self.quiet_until = max(self.quiet_until, j, header_end)
                return True
            if j >= n:
                return False
            if len(run.ss) <= 1:
                hopeless.add(target)
            j += 1

    def _between_procedures(self) -> bool:
        """The error is outside every procedure's body (a stray token before a
        procedure, a statement outside one, a bad header)."""
        ss = self.run.ss
        return len(ss) <= TOP_LEVEL_DEPTH and accepts(ss, self.t) <= TOP_LEVEL

    def _skip_to_procedure(self, idx: int) -> bool:
        """Recover outside procedures: drop the partial item and go on at the
        next ``NAME (`` outside braces (a procedure's start), or at the end;
        what lies between is not checked (one error, not one per line)."""
        ss, vs = self.run.ss, self.run.vs
        while len(ss) > 1 and ss[-1] != self.list_state:
            ss.pop()
            vs.pop()
        self.min_stack = min(self.min_stack, len(ss))
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
        self.run.pos = k
        self.quiet_until = max(self.quiet_until, k - 1)
        return True

    def _fixup(self, target: str, at: int) -> bool:
        """Bring the parser to a state that accepts ``target``: feed made-up tokens
        (closing an expression, a parenthesis, a statement), and where that cannot
        work, discard the partial construct from the parser's stacks (yacc-style)."""
        from plcbuilder.lang.syntax_errors import token_span
        run = self.run
        ss, vs = run.ss, run.vs
        while True:
            plan = self._plan(target)
            if plan is not None:
                s = token_span(self.toks, at)
                for kind in plan:
                    run.feed(kind, Tok(kind, "", s, synthetic=True))
                return True
            if len(ss) <= 1:
                return False
            ss.pop()
            vs.pop()
            self.min_stack = min(self.min_stack, len(ss))

    def _plan(self, target: str) -> Optional[list[str]]:
        """The made-up tokens (at most 8) after which the parser takes
        ``target``, tried on the states alone, or None."""
        t = self.t
        trial = Trial(self.run.ss, t)
        plan: list[str] = []
        order = ("RBRACE", "NUMBER", "RPAR", "SEMI") if target in ("RBRACE", "$END") else FIXUPS
        for _ in range(8):
            if _takes(trial, target, t):
                return plan
            for kind in order:
                if not (kind in ("SEMI", "NUMBER") and plan and plan[-1] == kind) \
                        and _takes(trial, kind, t):
                    trial.feed(kind)
                    plan.append(kind)
                    break
            else:
                return None
        return None

    def give_up(self, idx: int) -> None:
        from plcbuilder.lang.syntax_errors import token_span
        if not self.diags:
            self.diags.append(error("syntax", "cannot parse this", token_span(self.toks, idx)))


def _takes(trial: Trial, kind: str, t: Tables) -> bool:
    """Would the parser, as the trial has it, take a token of this kind?"""
    if kind not in t.states[trial.top()]:
        return False
    probe = Trial(trial.stack, t)
    probe.base, probe.extra = trial.base, list(trial.extra)
    return probe.feed(kind)
