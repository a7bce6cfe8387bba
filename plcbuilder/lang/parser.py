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
"""

from __future__ import annotations

import threading
from functools import lru_cache
from importlib import resources
from typing import Optional

from lark import Lark, Token, Transformer
from lark.exceptions import UnexpectedInput, UnexpectedToken
from lark.lexer import Lexer as _LarkLexer

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
    """The token list, handed to lark one Token at a time; error recovery moves ``pos``."""

    def __init__(self, toks: list[Tok]):
        self.toks = toks
        self.pos = 0

    def __iter__(self):
        toks = self.toks
        n = len(toks)
        new = Token
        while self.pos < n:
            i = self.pos
            self.pos = i + 1
            t = toks[i]
            kind = t.kind
            if kind == "BAD":
                continue
            s = t.span
            yield new(kind, t.value, i, s[1], s[2], s[3], s[4], i + 1)


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
            if isinstance(node, (A.Num, A.Name, A.Call, A.Unary, A.Binary, A.Paren)):
                node = A.Num(0, node.span, "0", synthetic=True)
            else:
                node = A.Empty(node.span)
            d = 1
        depth[id(node)] = d
        return node

    # ---------------------------------------------------------- module
    def start(self, items):
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


def parse_tokens(toks: list[Tok]) -> tuple[A.Module, list[Diagnostic]]:
    """Parse preprocessed tokens into a Module; syntax errors become diagnostics."""
    lark, builder = _parser()
    with _lock:
        builder.toks = toks
        builder.depth = {}
        builder.diags = []
        builder.too_deep = False
        recovery = _Recovery(toks)
        stream = _Stream(toks)
        recovery.stream = stream
        try:
            module = lark.parse(stream, on_error=recovery.on_error)
        except UnexpectedInput as exc:
            recovery.give_up(exc)
            module = A.Module([])
        except RecursionError:  # pragma: no cover - the grammar is iterative
            module = A.Module([])
            recovery.diags.append(error("nesting-too-deep", "program nests too deeply", None))
        diags = recovery.diags + builder.diags
        builder.toks, builder.depth = [], {}
        if module is None:
            module = A.Module([])
        return module, diags


class _Recovery:
    def __init__(self, toks: list[Tok]):
        self.toks = toks
        self.diags: list[Diagnostic] = []
        self.stream: Optional[_Stream] = None
        self.last_error_idx = -1
        self.quiet_until = -1     # errors at or before this index are cascades
        self.count = 0

    # ---------------------------------------------------------- recovery
    def on_error(self, e) -> bool:
        if not isinstance(e, UnexpectedToken):
            return False
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

    def _fixup(self, ip, target: str, at: int) -> bool:
        """Bring the parser to a state that accepts ``target``: feed made-up tokens
        (closing an expression, a parenthesis, a statement), and where that cannot
        work, discard the partial construct from the parser's stacks (yacc-style)."""
        state = ip.parser_state
        while True:
            plan = self._plan(ip.copy(), target)
            if plan is not None:
                s = token_span(self.toks, at)
                for kind in plan:
                    ip.feed_token(Token(kind, "", at, s.line, s.col, s.end_line, s.end_col, at))
                return True
            if len(state.state_stack) <= 1:
                return False
            state.state_stack.pop()
            state.value_stack.pop()

    @staticmethod
    def _plan(trial, target: str) -> Optional[list[str]]:
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
