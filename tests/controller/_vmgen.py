"""Random bytecode programs for comparing the two VM backends.

``random_program(rng)`` builds a structured program the way a compiler would
(statements, loops that end ticks, short-circuit expressions that leave values
on the stack across jumps, calls, recursion, busy loops without tick ends,
division by values that may be zero, builtins with constant and computed
addresses), so that it exercises every path of the fast backend's translator.
``random_soup(rng)`` is unstructured instruction soup (stack underflows,
jumps anywhere): programs the translator declines and the reference runs.
"""

from __future__ import annotations

import random

from plcbuilder.bytecode import abi
from plcbuilder.bytecode.opcodes import BINARY, UNARY, Op
from plcbuilder.bytecode.program import Kind, Program

from tests.controller._asm import L, assemble

_EDGE = [0, 1, -1, 2, 31, 32, 33, 255, 0x7FFFFFFF, -0x80000000, 0x7FFFFFFE, -0x7FFFFFFF,
         1000, -1000, 65535, 99, 100]
_READ_ADDRS = [0x400, 0x403, 7180, 7184, 7196, 7270, 7278, 6060, 5021, 5023, 17023, 17003,
               1000, 1001, 20000, 8635, 100041, 4242]
_WRITE_ADDRS = [1000, 1001, 4242, 20000, 20042, 20100, 7278, 7279, 7270, 7184, 8631, 8632,
                8634, 100040, 100041, 100020, 100022, 5521, 5539]
_MESSAGES = [0, 1100, 146, 1001, 1008, 1033, -5, 120]
_BINS = sorted(BINARY)
_UNS = sorted(UNARY)


class _Gen:
    def __init__(self, rng: random.Random, kind: Kind):
        self.r = rng
        self.kind = kind
        self.out: list = []
        self.n = 0
        self.nvars = rng.randint(1, 6)
        self.funcs = [f"f{i}" for i in range(rng.randint(0, 3))]
        self.budget = rng.randint(25, 90)     # statements left

    def label(self) -> str:
        self.n += 1
        return f".l{self.n}"

    def e(self, *items) -> None:
        self.out.extend(items)

    def user(self) -> int:
        return abi.FIRST_USER_SLOT + self.r.randrange(self.nvars)

    def wslot(self) -> int:
        r = self.r.random()
        if r < 0.65:
            return self.user()
        return self.r.choice([abi.SLOT_TIMER, abi.SLOT_PROC, abi.SLOT_VEXIT, abi.SLOT_VAR00,
                              abi.SLOT_VAR00 + 1, abi.SLOT_EPARAM])

    def rslot(self) -> int:
        if self.r.random() < 0.7:
            return self.user()
        return self.r.randrange(abi.FIRST_USER_SLOT)

    def const(self, v: int) -> None:
        if v == 0 and self.r.random() < 0.7:
            self.e(Op.PUSH0)
        elif v == 1 and self.r.random() < 0.7:
            self.e(Op.PUSH1)
        elif -128 <= v <= 127 and self.r.random() < 0.8:
            self.e((Op.PUSH8, v))
        elif -32768 <= v <= 32767 and self.r.random() < 0.8:
            self.e((Op.PUSH16, v))
        else:
            self.e((Op.PUSH32, v))

    # ---------------------------------------------------------- expressions
    def expr(self, depth: int = 0) -> None:
        r = self.r.random()
        if depth > 3 or r < 0.3:
            if self.r.random() < 0.5:
                self.const(self.r.choice(_EDGE) if self.r.random() < 0.5
                           else self.r.randint(-50, 50))
            else:
                self.e((Op.LOAD, self.rslot()))
            return
        if r < 0.6:
            op = self.r.choice(_BINS)
            self.expr(depth + 1)
            self.expr(depth + 1)
            self.e(op)
        elif r < 0.7:
            self.expr(depth + 1)
            self.e(self.r.choice(_UNS))
        elif r < 0.8:                       # a && b / a || b, value on the stack across jumps
            end, short = self.label(), self.label()
            self.expr(depth + 1)
            self.e((self.r.choice([Op.JZ16, Op.JNZ16]), short))
            self.expr(depth + 1)
            self.e(Op.BOOL, (Op.JMP16, end), L(short), self.r.choice([Op.PUSH0, Op.PUSH1]), L(end))
        elif r < 0.85:                      # c ? a : b
            other, end = self.label(), self.label()
            self.expr(depth + 1)
            self.e((Op.JZ16, other))
            self.expr(depth + 1)
            self.e((Op.JMP16, end), L(other))
            self.expr(depth + 1)
            self.e(L(end))
        elif r < 0.92:
            if self.r.random() < 0.7:
                self.const(self.r.choice(_READ_ADDRS))
            else:
                self.const(1000)
                self.e((Op.LOAD, self.rslot()), Op.PUSH1, Op.AND, Op.ADD)
            self.e(Op.GVARGET)
        else:
            self.const(self.r.choice([0, 3, 4, 5, 9, 70, -1]))
            self.e(Op.PORTGET)

    # ----------------------------------------------------------- statements
    def block(self, depth: int, ticks: bool = True) -> None:
        for _ in range(self.r.randint(1, 4)):
            if self.budget <= 0:
                return
            self.stmt(depth, ticks)

    def stmt(self, depth: int, ticks: bool) -> None:
        self.budget -= 1
        r = self.r.random()
        if r < 0.25:
            self.expr()
            self.e((Op.STORE, self.wslot()))
        elif r < 0.3:
            self.e((self.r.choice([Op.INC, Op.DEC]), self.wslot()))
        elif r < 0.4 and depth < 4:
            other, end = self.label(), self.label()
            self.expr()
            self.e((self.r.choice([Op.JZ16, Op.JNZ16]), other))
            self.block(depth + 1, ticks)
            if self.r.random() < 0.5:
                self.e((Op.JMP16, end), L(other))
                self.block(depth + 1, ticks)
                self.e(L(end))
            else:
                self.e(L(other))
        elif r < 0.5 and depth < 4 and ticks:      # do { } while (--c > 0) : one tick an iteration
            c = self.user()
            top = self.label()
            self.const(self.r.randint(1, 6))
            self.e((Op.STORE, c), L(top))
            self.block(depth + 1, ticks)
            self.e((Op.DEC, c), (Op.LOAD, c), Op.PUSH0, Op.GT, (Op.LOOP16, top))
        elif r < 0.55 and depth < 4 and ticks:     # while (e) { } with the test at the bottom
            top, cond = self.label(), self.label()
            c = self.user()
            self.const(self.r.randint(0, 4))
            self.e((Op.STORE, c), (Op.JMP16, cond), L(top))
            self.block(depth + 1, ticks)
            self.e((Op.DEC, c), L(cond), (Op.LOAD, c), Op.PUSH0, Op.GT, (Op.LOOP16, top))
        elif r < 0.58 and depth < 3:                # busy loop: no tick end (maybe too long)
            top = self.label()
            c = self.user()
            self.const(self.r.choice([1, 3, 10, 200, 40000, 70000]))
            self.e((Op.STORE, c), L(top))
            self.block(depth + 1, ticks=False)
            self.e((Op.DEC, c), (Op.LOAD, c), (Op.JNZ16, top))
        elif r < 0.63:
            if self.r.random() < 0.5:
                self.const(self.r.choice([0, 2, 3, 5, 7, 64, -1]))
            else:
                self.expr()
            self.e(self.r.choice([Op.PORTSET, Op.PORTCLR]))
        elif r < 0.72:
            if self.r.random() < 0.75:
                self.const(self.r.choice(_WRITE_ADDRS))
            else:                                   # a computed address
                self.const(self.r.choice([20000, 100040, 100020, 100040]))
                self.e((Op.LOAD, self.rslot()), Op.PUSH1, Op.AND, Op.ADD)
            self.expr()
            self.e(Op.GVARSET)
        elif r < 0.74:
            self.const(self.r.choice([0, 1, 2, 3, 0x81, 0x80]))
            self.const(self.r.choice([1, 2, 4, 7]))
            self.expr()
            self.e(Op.G0MOVE)
        elif r < 0.78:
            self.const(self.r.choice(_MESSAGES))
            self.e((Op.STORE, abi.SLOT_MESSAGE))
        elif r < 0.82 and ticks:
            self.e(Op.YIELD)
        elif r < 0.87 and self.funcs:
            self.e((Op.CALL, self.r.choice(self.funcs)))
        elif r < 0.89:
            self.expr()
            self.e((Op.EXIT if self.r.random() < 0.4 else Op.POP))
        elif r < 0.92:                              # a value below a call / builtin result
            self.expr()
            self.expr()
            self.e(self.r.choice([Op.DIV, Op.MOD]))
            self.e((Op.STORE, self.wslot()))
        elif r < 0.97:                              # statements while a value waits on the stack
            x = self.rslot() if self.r.random() < 0.5 else abi.SLOT_MESSAGE
            if x == abi.SLOT_MESSAGE:
                self.const(self.r.choice(_MESSAGES))
                self.e((Op.STORE, x))
            self.e((Op.LOAD, x))
            for _ in range(self.r.randint(1, 3)):
                k = self.r.random()
                if k < 0.3:
                    self.expr()
                    self.e((Op.STORE, x))
                elif k < 0.5:
                    self.e((self.r.choice([Op.INC, Op.DEC]), x))
                elif k < 0.7 and ticks:
                    self.e(Op.YIELD)
                elif k < 0.85:
                    self.const(20001)
                    self.e((Op.LOAD, x), Op.GVARSET)
                else:
                    self.expr()
                    self.e(Op.GVARGET, (Op.STORE, self.wslot()))
            self.expr()
            self.e(self.r.choice(_BINS))
            self.e((Op.STORE, self.wslot()))
        else:
            self.e(Op.NOP)

    def program(self, name: str) -> Program:
        self.e(L("main"))
        self.block(0)
        end = self.r.random()
        if end < 0.45:
            self.const(self.r.choice([99, 0, 7, 100, -1]))
            self.e(Op.EXIT)
        elif end < 0.9:
            self.e(Op.RET)
        else:       # runs past the end of main into the next procedure (or the end of the code)
            self.e(Op.NOP)
        for f in self.funcs:
            self.budget = self.r.randint(3, 20)
            self.e(L(f))
            self.block(1)
            self.e(Op.RET)
        names = [f"u{i}" for i in range(self.nvars)]
        return assemble(self.out, name=name, kind=self.kind, entry="main", var_names=names,
                        relax=self.r.random() < 0.5)


def random_program(rng: random.Random, kind: Kind = Kind.HARDWARE, name: str = "R") -> Program:
    return _Gen(rng, kind).program(name)


def random_soup(rng: random.Random, kind: Kind = Kind.HARDWARE, name: str = "S") -> Program:
    """Unstructured code: any instruction anywhere, jumps to random instructions."""
    ops = [op for op in Op if op is not Op.CALL]
    items: list = []
    n = rng.randint(3, 40)
    for i in range(n):
        items.append(L(f".i{i}"))
        op = rng.choice(ops)
        if op.name.startswith(("JMP", "JZ", "JNZ", "LOOP")):
            items.append((op, f".i{rng.randrange(n)}"))
        elif op in (Op.PUSH8,):
            items.append((op, rng.randint(-128, 127)))
        elif op in (Op.PUSH16,):
            items.append((op, rng.randint(-32768, 32767)))
        elif op in (Op.PUSH32,):
            items.append((op, rng.choice(_EDGE)))
        elif op in (Op.LOAD, Op.STORE, Op.INC, Op.DEC):
            items.append((op, rng.randrange(abi.FIRST_USER_SLOT + 2)))
        else:
            items.append(op)
    if rng.random() < 0.3:
        items.append((Op.CALL, f".i{rng.randrange(n)}"))
    return assemble(items, name=name, kind=kind, entry=".i0", var_names=["a", "b"],
                    relax=True)
