"""The one opcode enum, its operand shapes, and the decoder.

A procedure is stack code. Values are 32-bit two's complement. Operands follow
the opcode byte, little-endian:

- ``I8``/``I16``/``I32``: a signed immediate (PUSH8/16/32);
- ``SLOT``: one unsigned byte, a variable slot (see ``abi.SLOT_*``);
- ``REL8``/``REL16``: a signed jump offset, relative to the end of the instruction;
- ``ABS16``: an absolute code offset (CALL).

The compiler, both VM backends and the disassembler all use the tables below
(operand shapes, sets by role, stack effects), so adding an opcode here is the
only place its shape is stated. What the operators compute is in
:mod:`plcbuilder.bytecode.semantics`.
"""

from __future__ import annotations

import enum
import struct

from plcbuilder._support.records import dataclass

TYPE_CHECKING = False               # (typing is not imported at run time: start-up)
if TYPE_CHECKING:
    from typing import Iterator, Optional


class Op(enum.IntEnum):
    NOP = 0x00
    # constants
    PUSH0 = 0x01
    PUSH1 = 0x02
    PUSH8 = 0x03
    PUSH16 = 0x04
    PUSH32 = 0x05
    # variables
    LOAD = 0x08
    STORE = 0x09
    INC = 0x0A
    DEC = 0x0B
    POP = 0x0C
    # binary operators: pop b, pop a, push a OP b
    ADD = 0x10
    SUB = 0x11
    MUL = 0x12
    DIV = 0x13
    MOD = 0x14
    SHL = 0x15
    SHR = 0x16
    AND = 0x17
    OR = 0x18
    XOR = 0x19
    EQ = 0x1A
    NE = 0x1B
    LT = 0x1C
    LE = 0x1D
    GT = 0x1E
    GE = 0x1F
    # unary operators
    NEG = 0x20
    NOT = 0x21
    BNOT = 0x22
    BOOL = 0x23          # a != 0 -> 1, else 0 (for && and ||)
    # control flow
    JMP8 = 0x30
    JMP16 = 0x31
    JZ8 = 0x32           # pop; jump if zero
    JZ16 = 0x33
    JNZ8 = 0x34          # pop; jump if not zero
    JNZ16 = 0x35
    LOOP8 = 0x36         # pop; END THE TICK; then jump if not zero (a loop's condition)
    LOOP16 = 0x37
    YIELD = 0x38         # end the tick (a loop whose condition is a constant)
    CALL = 0x39
    RET = 0x3A
    EXIT = 0x3B          # pop the exit code; the procedure ends
    # built-in functions (arguments on the stack, first pushed first)
    PORTSET = 0x40       # (pin)
    PORTCLR = 0x41       # (pin)
    PORTGET = 0x42       # (pin) -> 0/1
    GVARGET = 0x43       # (addr) -> value
    GVARSET = 0x44       # (addr, value)
    G0MOVE = 0x45        # (flags, axis_mask, distance)


class Operand(enum.Enum):
    NONE = 0
    I8 = 1
    I16 = 2
    I32 = 3
    SLOT = 4
    REL8 = 5
    REL16 = 6
    ABS16 = 7


OPERAND_SIZE = {Operand.NONE: 0, Operand.I8: 1, Operand.I16: 2, Operand.I32: 4,
                Operand.SLOT: 1, Operand.REL8: 1, Operand.REL16: 2, Operand.ABS16: 2}
_STRUCT = {Operand.I8: struct.Struct("<b"), Operand.I16: struct.Struct("<h"),
           Operand.I32: struct.Struct("<i"), Operand.SLOT: struct.Struct("<B"),
           Operand.REL8: struct.Struct("<b"), Operand.REL16: struct.Struct("<h"),
           Operand.ABS16: struct.Struct("<H")}

OPERAND: dict[Op, Operand] = {op: Operand.NONE for op in Op}
OPERAND.update({
    Op.PUSH8: Operand.I8, Op.PUSH16: Operand.I16, Op.PUSH32: Operand.I32,
    Op.LOAD: Operand.SLOT, Op.STORE: Operand.SLOT, Op.INC: Operand.SLOT, Op.DEC: Operand.SLOT,
    Op.JMP8: Operand.REL8, Op.JZ8: Operand.REL8, Op.JNZ8: Operand.REL8, Op.LOOP8: Operand.REL8,
    Op.JMP16: Operand.REL16, Op.JZ16: Operand.REL16, Op.JNZ16: Operand.REL16,
    Op.LOOP16: Operand.REL16,
    Op.CALL: Operand.ABS16,
})

#: Opcodes by shape and role (like dis.hasjrel / dis.hasconst).
HAS_CONST = frozenset({Op.PUSH8, Op.PUSH16, Op.PUSH32})
HAS_SLOT = frozenset({Op.LOAD, Op.STORE, Op.INC, Op.DEC})
WRITES_SLOT = frozenset({Op.STORE, Op.INC, Op.DEC})      # (of HAS_SLOT, those that write it)
HAS_JREL = frozenset(op for op, shape in OPERAND.items() if shape in (Operand.REL8, Operand.REL16))
HAS_JABS = frozenset({Op.CALL})
BINARY = frozenset({Op.ADD, Op.SUB, Op.MUL, Op.DIV, Op.MOD, Op.SHL, Op.SHR, Op.AND, Op.OR,
                    Op.XOR, Op.EQ, Op.NE, Op.LT, Op.LE, Op.GT, Op.GE})
UNARY = frozenset({Op.NEG, Op.NOT, Op.BNOT, Op.BOOL})
ENDS_TICK = frozenset({Op.LOOP8, Op.LOOP16, Op.YIELD})


@dataclass(frozen=True)
class BuiltinCall:
    """What a built-in call opcode does: it pops ``args`` values (the first
    argument was pushed first), calls the controller's function ``host`` (an
    attribute of controller/vm.py ``Host``, a method of the machine of the same
    name unless controller/plc.py says otherwise) with them, and pushes what
    it returns when ``value``. ``writes``: it changes the machine (a breakpoint
    condition or an evaluate may not call it)."""
    host: str
    args: int
    value: bool
    writes: bool


#: The built-in calls: a new built-in function is a row here (and its opcode
#: above), its row in lang/builtins.py (name, parameters, doc), and its
#: semantics, the machine's method; both VMs, the Host, the debugger's
#: expressions and the stack effects are made from this table.
BUILTINS: dict[Op, BuiltinCall] = {
    Op.PORTSET: BuiltinCall("portset", 1, False, True),
    Op.PORTCLR: BuiltinCall("portclr", 1, False, True),
    Op.PORTGET: BuiltinCall("portget", 1, True, False),
    Op.GVARGET: BuiltinCall("gvarget", 1, True, False),
    Op.GVARSET: BuiltinCall("gvarset", 2, False, True),
    Op.G0MOVE: BuiltinCall("g0move", 3, False, True),
}
BUILTIN_CALLS = frozenset(BUILTINS)
#: Constant pushes without an operand, and the value each pushes.
IMPLICIT_CONST = {Op.PUSH0: 0, Op.PUSH1: 1}
#: Conditional jumps: they pop the condition (LOOP also ends the tick); JZ jumps
#: when it is 0, JNZ and LOOP when it is not.
JUMPS_IF_ZERO = frozenset({Op.JZ8, Op.JZ16})
JUMPS_IF_NOT_ZERO = frozenset({Op.JNZ8, Op.JNZ16, Op.LOOP8, Op.LOOP16})
COND_JUMPS = JUMPS_IF_ZERO | JUMPS_IF_NOT_ZERO

#: (values popped, values pushed) by each opcode. CALL and RET move no values
#: (procedures share variables, not the stack).
STACK_EFFECT: dict[Op, tuple[int, int]] = {op: (0, 0) for op in Op}
STACK_EFFECT.update({op: (0, 1) for op in HAS_CONST | set(IMPLICIT_CONST) | {Op.LOAD}})
STACK_EFFECT.update({op: (1, 0) for op in COND_JUMPS | {Op.STORE, Op.POP, Op.EXIT}})
STACK_EFFECT.update({op: (2, 1) for op in BINARY})
STACK_EFFECT.update({op: (1, 1) for op in UNARY})
STACK_EFFECT.update({op: (c.args, int(c.value)) for op, c in BUILTINS.items()})
#: Opcodes after which execution does not fall through to the next instruction.
NO_FALLTHROUGH = frozenset({Op.JMP8, Op.JMP16, Op.RET, Op.EXIT})
#: Short form -> long form of each jump, for the compiler's relaxation pass.
LONG_FORM = {Op.JMP8: Op.JMP16, Op.JZ8: Op.JZ16, Op.JNZ8: Op.JNZ16, Op.LOOP8: Op.LOOP16}
SHORT_FORM = {v: k for k, v in LONG_FORM.items()}

_VALID = frozenset(int(op) for op in Op)


def size_of(op: Op) -> int:
    return 1 + OPERAND_SIZE[OPERAND[op]]


def encode(op: Op, arg: Optional[int] = None) -> bytes:
    shape = OPERAND[op]
    if shape is Operand.NONE:
        return bytes((op,))
    return bytes((op,)) + _STRUCT[shape].pack(arg)


_RANGE = {Operand.I8: (-128, 127), Operand.REL8: (-128, 127),
          Operand.I16: (-32768, 32767), Operand.REL16: (-32768, 32767),
          Operand.I32: (-2**31, 2**31 - 1), Operand.SLOT: (0, 255),
          Operand.ABS16: (0, 65535)}


def fits(shape: Operand, value: int) -> bool:
    lo, hi = _RANGE[shape]
    return lo <= value <= hi


class DecodeError(ValueError):
    def __init__(self, offset: int, reason: str):
        super().__init__(f"at code offset {offset}: {reason}")
        self.offset = offset
        self.reason = reason


@dataclass(frozen=True)
class Instruction:
    offset: int
    op: Op
    arg: Optional[int]
    size: int

    @property
    def end(self) -> int:
        return self.offset + self.size

    @property
    def target(self) -> Optional[int]:
        """The code offset a jump or call goes to, or None."""
        if self.op in HAS_JREL:
            return self.end + self.arg
        if self.op in HAS_JABS:
            return self.arg
        return None


def decode_one(code: bytes, offset: int) -> Instruction:
    byte = code[offset]
    if byte not in _VALID:
        raise DecodeError(offset, f"unknown opcode 0x{byte:02x}")
    op = Op(byte)
    shape = OPERAND[op]
    n = OPERAND_SIZE[shape]
    if offset + 1 + n > len(code):
        raise DecodeError(offset, f"{op.name} operand runs past the end of the code")
    arg = _STRUCT[shape].unpack_from(code, offset + 1)[0] if n else None
    return Instruction(offset, op, arg, 1 + n)


def decode(code: bytes) -> Iterator[Instruction]:
    """Decode every instruction in order; raises DecodeError on bad code."""
    offset = 0
    while offset < len(code):
        ins = decode_one(code, offset)
        yield ins
        offset = ins.end


def validate(code: bytes, entry: int = 0) -> list[Instruction]:
    """Decode all of ``code`` and check that every jump and call lands on an
    instruction boundary inside the code. Returns the instructions."""
    instructions = list(decode(code))
    starts = {i.offset for i in instructions}
    if code and entry not in starts:
        raise DecodeError(entry, "entry point is not an instruction boundary")
    for ins in instructions:
        t = ins.target
        if t is not None and t not in starts:
            raise DecodeError(ins.offset, f"{ins.op.name} goes to {t}, not an instruction")
    return instructions
