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


#: node type -> its mover (written for every node type when first needed)
_MOVERS: dict[type, object] = {}


def _mover(t: type):
    """A function ``(node, movers, file, lines) -> a copy of node`` with its
    spans in ``file`` moved ``lines`` lines down, written for the fields of
    node type ``t``: the copy is made without calling ``__init__``, the spans
    moved in line and the children moved through ``movers`` (one call a node:
    an Enter moves every procedure after it, thousands of nodes)."""
    body = ["def move(n, M, F, L):", "    o = new(T)"]
    for name, kind in _parts(t):
        if kind == "s":
            body += [f"    v = n.{name}",
                     f"    o.{name} = span(Span, (F, v[1] + L, v[2], v[3] + L, v[4])) "
                     "if v is not None and v[0] == F else v"]
        elif kind == "n":
            body += [f"    v = n.{name}",
                     f"    o.{name} = None if v is None else M[type(v)](v, M, F, L)"]
        elif kind == "l":
            body.append(f"    o.{name} = [M[type(x)](x, M, F, L) for x in n.{name}]")
        else:
            body.append(f"    o.{name} = n.{name}")
    body.append("    return o")
    ns: dict = {}
    exec(compile("\n".join(body) + "\n", f"<move {t.__name__}>", "exec"),  # noqa: S102 - our own source
         {"T": t, "new": object.__new__, "span": tuple.__new__, "Span": Span}, ns)
    return ns["move"]


def moved(node, file: str, lines: int):
    """A copy of ``node`` (a node, a list of nodes or None) with every span in
    ``file`` moved ``lines`` lines down: what an unchanged procedure looks like
    after lines were added (or removed) above it."""
    movers = _MOVERS
    if not movers:
        movers.update((t, _mover(t)) for t in list(globals().values())
                      if type(t) is type and "__record_types__" in t.__dict__)
    if type(node) is list:
        return [None if x is None else movers[type(x)](x, movers, file, lines) for x in node]
    return None if node is None else movers[type(node)](node, movers, file, lines)
