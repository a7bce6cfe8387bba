"""The abstract syntax tree: records (dataclasses) with spans, built by parser.AstBuilder."""

from __future__ import annotations

from plcbuilder._support.records import dataclass, field
from plcbuilder.diagnostics import Span

TYPE_CHECKING = False               # (typing is not imported at run time: start-up)
if TYPE_CHECKING:
    from typing import Optional, Union


# ------------------------------------------------------------- expressions
@dataclass(slots=True, eq=False)
class Num:
    value: int
    span: Span
    text: str = ""
    synthetic: bool = False


@dataclass(slots=True, eq=False)
class Name:
    id: str
    span: Span


@dataclass(slots=True, eq=False)
class Call:
    name: str
    name_span: Span
    args: list["Expr"]
    span: Span


@dataclass(slots=True, eq=False)
class Unary:
    op: str                    # "-", "!", "~"
    operand: "Expr"
    span: Span


@dataclass(slots=True, eq=False)
class Binary:
    op: str                    # "+", "<<", "&&", ...
    left: "Expr"
    right: "Expr"
    span: Span
    op_span: Span


@dataclass(slots=True, eq=False)
class Paren:
    expr: "Expr"
    span: Span


@dataclass(slots=True, eq=False)
class Index:
    """A register bank element, ``X[n]`` (a target's syntax: docs/targets.md)."""
    bank: str
    bank_span: Span
    index: "Expr"
    span: Span


if TYPE_CHECKING:
    Expr = Union[Num, Name, Call, Unary, Binary, Paren, Index]


# -------------------------------------------------------------- statements
@dataclass(slots=True, eq=False)
class Assign:
    target: Union[Name, Index]
    value: Expr
    span: Span
    op: str = "="              # or a compound assignment: "|=", "&=", "^=", "+=", "-="
    op_span: Optional[Span] = None


@dataclass(slots=True, eq=False)
class IncDec:
    target: Name
    op: str                    # "++" | "--"
    span: Span


@dataclass(slots=True, eq=False)
class CallStmt:
    call: Call
    span: Span


@dataclass(slots=True, eq=False)
class If:
    cond: Expr
    then: "Stmt"
    orelse: Optional["Stmt"]
    span: Span
    else_span: Optional[Span] = None


@dataclass(slots=True, eq=False)
class DoWhile:
    body: "Stmt"
    cond: Expr
    span: Span
    while_span: Span


@dataclass(slots=True, eq=False)
class While:
    cond: Expr
    body: "Stmt"
    span: Span
    while_span: Span


@dataclass(slots=True, eq=False)
class Block:
    stmts: list["Stmt"]
    span: Span
    end_span: Span             # the closing brace


@dataclass(slots=True, eq=False)
class Empty:
    span: Span


if TYPE_CHECKING:
    Stmt = Union[Assign, IncDec, CallStmt, If, DoWhile, While, Block, Empty]


@dataclass(slots=True, eq=False)
class ProcDef:
    name: str
    name_span: Span
    body: Block
    span: Span


@dataclass(slots=True, eq=False)
class Module:
    procs: list[ProcDef] = field(default_factory=list)


# -------------------------------------------------------------- moving lines
_PARTS: dict[type, tuple] = {}


def _parts(t: type) -> tuple:
    """(field name, what it holds) of a node type: 's' a span, 'n' a node or
    None, 'l' a list of nodes, '' anything else."""
    parts = _PARTS.get(t)
    if parts is None:
        parts = []
        for name, h in t.__record_types__.items():     # the annotations, as written
            h = h.strip()
            kind = ("" if h in ("int", "str", "bool") else "s" if "Span" in h else
                    "l" if h.startswith("list") else "n")
            parts.append((name, kind))
        parts = _PARTS[t] = tuple(parts)
    return parts


_MOVERS: dict[type, object] = {}


def _mover(t: type):
    """A function ``(node, span_mover, node_mover) -> a copy of node`` for node
    type ``t``, written for its fields (one call a node: an Enter moves every
    procedure after it, thousands of nodes)."""
    args = []
    for name, kind in _parts(t):
        args.append(f"s(n.{name})" if kind == "s" else f"m(n.{name})" if kind == "n" else
                    f"[m(x) for x in n.{name}]" if kind == "l" else f"n.{name}")
    src = f"def move(n, s, m):\n    return T({', '.join(args)})\n"
    ns: dict = {}
    exec(compile(src, f"<move {t.__name__}>", "exec"), {"T": t}, ns)  # noqa: S102 - our own source
    return ns["move"]


def moved(node, file: str, lines: int):
    """A copy of ``node`` (a node, a list of nodes or None) with every span in
    ``file`` moved ``lines`` lines down: what an unchanged procedure looks like
    after lines were added (or removed) above it."""
    new = tuple.__new__
    movers = _MOVERS

    def s(v):
        if v is not None and v[0] == file:
            return new(Span, (file, v[1] + lines, v[2], v[3] + lines, v[4]))
        return v

    def m(x):
        if x is None:
            return None
        f = movers.get(type(x))
        if f is None:
            f = movers[type(x)] = _mover(type(x))
        return f(x, s, m)

    if type(node) is list:
        return [m(x) for x in node]
    return m(node)
