"""What the operators mean: 32-bit two's complement arithmetic, stated once.

The checker's constant folding (:mod:`plcbuilder.lang.checker`), the reference
interpreter (:mod:`plcbuilder.controller.vm`) and the code the fast backend
generates (:mod:`plcbuilder.controller.fastvm`) all take the meaning of an
operator from the tables below, so the three cannot disagree.

Values are Python ints in ``INT_MIN..INT_MAX``. In short:

- every result wraps to 32 bits;
- ``/`` and ``%`` truncate toward zero as in C (``%`` takes the sign of the
  dividend); ``INT_MIN / -1`` wraps to ``INT_MIN`` and ``INT_MIN % -1`` is 0;
  a zero divisor has no value (the VMs fault, folding leaves it alone);
- a shift count is ``b & 31``; ``>>`` is arithmetic;
- comparisons, ``!`` (NOT) and BOOL give 0 or 1; ``~`` is bitwise not.

Each operator is written once as Python source over operands ``{a}`` and ``{b}``
that are 32-bit values (``source``), with what turns Python's value of that
source into the 32-bit result (``result``). The reference functions (``fn``) are
compiled from that source; the fast backend writes the same source into the code
it generates, filling in its own operand expressions.
"""

from __future__ import annotations

import enum
from functools import cached_property

from plcbuilder._support.records import dataclass
from plcbuilder.bytecode.opcodes import BINARY as BINARY_OPS, UNARY as UNARY_OPS, Op

TYPE_CHECKING = False               # (typing is not imported at run time: start-up)
if TYPE_CHECKING:
    from typing import Callable, Optional

INT_MIN = -0x80000000
INT_MAX = 0x7FFFFFFF
#: The mask of a shift count: ``a << b`` shifts by ``b & SHIFT_MASK``.
SHIFT_MASK = 31

#: Python source of wrap(), over ``{v}`` (which may be any int).
WRAP_SOURCE = "(({v} + 2147483648 & 4294967295) - 2147483648)"


def wrap(v: int) -> int:
    """v as a 32-bit two's complement value (the same expression as WRAP_SOURCE)."""
    return (v + 2147483648 & 4294967295) - 2147483648


class Result(enum.Enum):
    """How Python's value of an operator's source becomes the 32-bit result."""
    EXACT = "exact"    # it already is a 32-bit value
    WRAP = "wrap"      # it is right modulo 2**32: wrap it
    BOOL = "bool"      # it is a bool: 1 or 0


@dataclass(frozen=True)
class Operator:
    op: Op
    symbol: str                 # the language's operator ("+", "<<", "!"); "" for BOOL
    source: str                 # Python over 32-bit operands {a} (and {b})
    result: Result
    #: the result modulo 2**32 depends only on the operands modulo 2**32, so a
    #: value may stay unwrapped through it (the fast backend defers wrapping)
    modular: bool = False
    #: DIV and MOD: the source for a divisor known to be positive (simpler; its
    #: value always is a 32-bit value)
    positive_divisor: Optional[str] = None

    @cached_property
    def fn(self) -> Callable:
        """The reference function, compiled from the source when first used
        (a command uses few of the twenty: not at every start)."""
        return _compile(self)

    @property
    def divides(self) -> bool:
        """A zero right operand has no value."""
        return self.positive_divisor is not None

    @property
    def shifts(self) -> bool:
        return self.op in (Op.SHL, Op.SHR)

    def text(self, a: str, b: str = "") -> str:
        """The source with operand expressions filled in (each is used as it is,
        possibly more than once: pass names or parenthesised expressions)."""
        return self.source.format(a=a, b=b)


def _compile(o: Operator) -> Callable:
    """The reference function of an operator, compiled from its source."""
    params = "a, b" if o.op in BINARY_OPS else "a"
    body = f"({o.text('a', 'b')})"
    if o.result is Result.WRAP:
        body = WRAP_SOURCE.format(v=body)
    elif o.result is Result.BOOL:
        body = f"1 if {body} else 0"
    fn = eval(f"lambda {params}: {body}", {"__builtins__": {}})  # noqa: S307 - our own table
    fn.__name__ = fn.__qualname__ = o.op.name.lower()
    fn.__doc__ = f"{o.op.name}: {body}"
    return fn


_BINARY_LIST = [
    Operator(Op.ADD, "+", "{a} + {b}", Result.WRAP, modular=True),
    Operator(Op.SUB, "-", "{a} - {b}", Result.WRAP, modular=True),
    Operator(Op.MUL, "*", "{a} * {b}", Result.WRAP, modular=True),
    # truncating division: Python's // floors, so divide the magnitudes where the signs differ
    Operator(Op.DIV, "/", "{a} // {b} if ({a} >= 0) == ({b} > 0) else -(-{a} // {b})", Result.WRAP,
             positive_divisor="{a} // {b} if {a} >= 0 else -(-{a} // {b})"),
    Operator(Op.MOD, "%", "{a} % {b} if ({a} >= 0) == ({b} > 0) else -(-{a} % {b})", Result.EXACT,
             positive_divisor="{a} % {b} if {a} >= 0 else -(-{a} % {b})"),
    Operator(Op.SHL, "<<", "{a} << ({b} & %d)" % SHIFT_MASK, Result.WRAP, modular=True),
    Operator(Op.SHR, ">>", "{a} >> ({b} & %d)" % SHIFT_MASK, Result.EXACT),
    Operator(Op.AND, "&", "{a} & {b}", Result.EXACT, modular=True),
    Operator(Op.OR, "|", "{a} | {b}", Result.EXACT, modular=True),
    Operator(Op.XOR, "^", "{a} ^ {b}", Result.EXACT, modular=True),
    Operator(Op.EQ, "==", "{a} == {b}", Result.BOOL),
    Operator(Op.NE, "!=", "{a} != {b}", Result.BOOL),
    Operator(Op.LT, "<", "{a} < {b}", Result.BOOL),
    Operator(Op.LE, "<=", "{a} <= {b}", Result.BOOL),
    Operator(Op.GT, ">", "{a} > {b}", Result.BOOL),
    Operator(Op.GE, ">=", "{a} >= {b}", Result.BOOL),
]
_UNARY_LIST = [
    Operator(Op.NEG, "-", "-{a}", Result.WRAP, modular=True),
    Operator(Op.NOT, "!", "not {a}", Result.BOOL),
    Operator(Op.BNOT, "~", "~{a}", Result.EXACT, modular=True),
    Operator(Op.BOOL, "", "{a} != 0", Result.BOOL),
]

#: Opcode -> its meaning, for every binary and every unary opcode.
BINARY: dict[Op, Operator] = {o.op: o for o in _BINARY_LIST}
UNARY: dict[Op, Operator] = {o.op: o for o in _UNARY_LIST}
assert set(BINARY) == set(BINARY_OPS) and set(UNARY) == set(UNARY_OPS)

#: The language's operators -> opcodes (``&&`` and ``||`` are jumps, not opcodes).
BINARY_SYMBOL: dict[str, Op] = {o.symbol: o.op for o in _BINARY_LIST}
UNARY_SYMBOL: dict[str, Op] = {o.symbol: o.op for o in _UNARY_LIST if o.symbol}

c_div = BINARY[Op.DIV].fn          # a / b truncated toward zero, wrapped (b != 0)
c_mod = BINARY[Op.MOD].fn          # a % b with the sign of a, as in C (b != 0)


def binary(op: Op, a: int, b: int) -> int:
    """The result of a binary operator on two 32-bit values (b != 0 for DIV and MOD)."""
    return BINARY[op].fn(a, b)


def unary(op: Op, a: int) -> int:
    return UNARY[op].fn(a)


def fold_binary(symbol: str, a: int, b: int) -> Optional[int]:
    """The value of ``a symbol b`` for the language's binary operators, ``&&`` and
    ``||`` included; None where it has none (a zero divisor)."""
    if symbol == "&&":
        return 1 if a and b else 0
    if symbol == "||":
        return 1 if a or b else 0
    op = BINARY_SYMBOL.get(symbol)
    if op is None:
        raise ValueError(symbol)
    o = BINARY[op]
    if o.divides and b == 0:
        return None
    return o.fn(a, b)


def fold_unary(symbol: str, a: int) -> int:
    """The value of ``symbol a`` for the language's unary operators (- ! ~)."""
    return UNARY[UNARY_SYMBOL[symbol]].fn(a)
