"""The abstract syntax tree: dataclasses with spans, built by parser.AstBuilder."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Optional, Union

from plcbuilder.diagnostics import Span


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


Expr = Union[Num, Name, Call, Unary, Binary, Paren]


# -------------------------------------------------------------- statements
@dataclass(slots=True, eq=False)
class Assign:
    target: Name
    value: Expr
    span: Span


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
