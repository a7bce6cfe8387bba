"""One meaning of every operator: the checker's constant folding, the reference
interpreter and the fast backend agree on edge values (bytecode.semantics).

For each operator, every pair of edge values is compiled twice: once as a
constant expression (the checker folds it into one constant) and once with the
operands read from registers at run time (so the VMs compute it), also with one
operand a literal (the fast backend's special cases: constant shift counts,
positive divisors). Both programs run on both backends.
"""

from __future__ import annotations

import functools
import itertools

import pytest

from plcbuilder.api import CompileOptions, Kind, compile_source
from plcbuilder.bytecode import semantics
from plcbuilder.bytecode.opcodes import BINARY, COND_JUMPS, Op, decode
from plcbuilder.bytecode.semantics import INT_MAX, INT_MIN, wrap
from plcbuilder.controller import fastvm
from plcbuilder.controller.controller import Controller
from plcbuilder.controller.events import Fault

from tests.controller._asm import L, assemble

EDGES = [0, 1, -1, 2, -2, 3, -3, 31, 32, 33, -32, 46341, 65536, INT_MAX, INT_MIN, INT_MAX - 1,
         INT_MIN + 1, 0x7fffffff, wrap(0xffffffff), 0x55555555, wrap(0xaaaaaaaa)]
EDGES = list(dict.fromkeys(EDGES))
PAIRS = list(itertools.product(EDGES, EDGES))
OPERANDS = 9000            # register OPERANDS + i holds EDGES[i]
RESULTS = 10000            # register RESULTS + k receives the k-th result
BINARY_SYMBOLS = [o.symbol for o in semantics.BINARY.values()] + ["&&", "||"]
UNARY_SYMBOLS = list(semantics.UNARY_SYMBOL)
BACKENDS = ["fast", "reference"]


def lit(v: int) -> str:
    """v as a literal of the language (hex above 0x7fffffff wraps, as in C)."""
    return f"0x{v & 0xffffffff:x}"


def reg(v: int) -> str:
    return f"gvarget({OPERANDS + EDGES.index(v)})"


def compiled(lines: list[str], name: str = "S"):
    return _compiled(tuple(lines), name)


@functools.lru_cache(maxsize=None)
def _compiled(lines: tuple[str, ...], name: str):
    """Each program is compiled once for both backends."""
    src = "main()\n{\n" + "\n".join(f"  {ln}" for ln in lines) + "\n  exit(99);\n};\n"
    r = compile_source(src, f"{name}.plc", CompileOptions(kind=Kind.SOFTWARE))
    assert r.ok, [d.message for d in r.diagnostics]
    return r.program


def execute(program, backend: str, count: int) -> tuple[list[int], list]:
    """Run a software procedure once; the results it wrote and the events."""
    if backend == "fast":
        assert fastvm.unsupported_reason(program) is None
    c = Controller(backend=backend)
    for i, v in enumerate(EDGES):
        c.machine.gvarset(OPERANDS + i, v)
    c.load([program], autostart=False)
    c.start(program.name)
    c.run_until_idle(1000)
    events = c.drain_events()
    return [c.machine.gvarget(RESULTS + k) for k in range(count)], events


def ops_in(program) -> set[Op]:
    return {i.op for i in decode(program.code)}


def defined(symbol: str, b: int) -> bool:
    return not (symbol in ("/", "%") and b == 0)


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("symbol", BINARY_SYMBOLS)
def test_folding_equals_execution_for_every_binary_operator(symbol, backend):
    pairs = [(a, b) for a, b in PAIRS if defined(symbol, b)]
    want = [semantics.fold_binary(symbol, a, b) for a, b in pairs]
    assert None not in want
    # the checker folds each expression into one constant
    folded = compiled([f"gvarset({RESULTS + k}, {lit(a)} {symbol} {lit(b)});"
                       for k, (a, b) in enumerate(pairs)])
    assert not ops_in(folded) & (BINARY | COND_JUMPS)
    got, _ = execute(folded, backend, len(pairs))
    assert got == want
    # the VM computes it: operands from registers, and each of them a literal
    for shape in ((reg, reg), (reg, lit), (lit, reg)):
        run_time = compiled([f"gvarset({RESULTS + k}, {shape[0](a)} {symbol} {shape[1](b)});"
                             for k, (a, b) in enumerate(pairs)])
        assert ops_in(run_time) & (BINARY | COND_JUMPS)
        got, _ = execute(run_time, backend, len(pairs))
        bad = [(a, b, g, w) for (a, b), g, w in zip(pairs, got, want) if g != w]
        assert not bad, ([f.__name__ for f in shape], bad[:5])


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("symbol", UNARY_SYMBOLS)
def test_folding_equals_execution_for_every_unary_operator(symbol, backend):
    want = [semantics.fold_unary(symbol, a) for a in EDGES]
    folded = compiled([f"gvarset({RESULTS + k}, {symbol}({lit(a)}));" for k, a in enumerate(EDGES)])
    assert semantics.UNARY_SYMBOL[symbol] not in ops_in(folded)
    assert execute(folded, backend, len(EDGES))[0] == want
    run_time = compiled([f"gvarset({RESULTS + k}, {symbol}{reg(a)});" for k, a in enumerate(EDGES)])
    assert semantics.UNARY_SYMBOL[symbol] in ops_in(run_time)
    assert execute(run_time, backend, len(EDGES))[0] == want


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("op", sorted(semantics.UNARY, key=int))
def test_every_unary_opcode_runs_as_the_table_says(op, backend):
    """BOOL has no operator in the language: assembled by hand, like the others."""
    items = [L("main")]
    for k, a in enumerate(EDGES):
        items += [(Op.PUSH16, RESULTS + k), (Op.PUSH16, OPERANDS + k), Op.GVARGET, op, Op.GVARSET]
    items += [(Op.PUSH8, 99), Op.EXIT]
    prog = assemble(items, name="U", kind=Kind.SOFTWARE, entry="main")
    assert execute(prog, backend, len(EDGES))[0] == [semantics.unary(op, a) for a in EDGES]


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("symbol", ["/", "%"])
def test_a_zero_divisor_is_not_folded_and_faults_when_it_runs(symbol, backend):
    fault = "division by zero" if symbol == "/" else "modulo by zero"
    for a in EDGES:
        assert semantics.fold_binary(symbol, a, 0) is None
        for left, right in ((lit, lit), (reg, lit), (lit, reg), (reg, reg)):
            prog = compiled([f"gvarset({RESULTS}, 5);",
                             f"gvarset({RESULTS}, {left(a)} {symbol} {right(0)});"])
            assert semantics.BINARY_SYMBOL[symbol] in ops_in(prog)     # left as it is
            got, events = execute(prog, backend, 1)
            faults = [e for e in events if isinstance(e, Fault)]
            assert len(faults) == 1 and faults[0].text.startswith(fault), (a, left, right)
            assert got == [5]


def test_the_operators_are_those_of_c_on_32_bit_values():
    """The table's meaning, independently of how it is written: the C definitions."""
    def c_trunc_div(a, b):
        q = abs(a) // abs(b)
        return q if (a < 0) == (b < 0) else -q

    for a, b in PAIRS:
        f = semantics.fold_binary
        assert f("+", a, b) == wrap(a + b) and f("-", a, b) == wrap(a - b)
        assert f("*", a, b) == wrap(a * b)
        if b:
            assert f("/", a, b) == wrap(c_trunc_div(a, b))
            assert f("%", a, b) == wrap(a - c_trunc_div(a, b) * b)
        assert f("<<", a, b) == wrap(a << (b % 32)) and f(">>", a, b) == a >> (b % 32)
        assert (f("&", a, b), f("|", a, b), f("^", a, b)) == (a & b, a | b, a ^ b)
        assert [f(s, a, b) for s in ("==", "!=", "<", "<=", ">", ">=", "&&", "||")] == \
            [int(a == b), int(a != b), int(a < b), int(a <= b), int(a > b), int(a >= b),
             int(bool(a and b)), int(bool(a or b))]
    for a in EDGES:
        assert semantics.fold_unary("-", a) == wrap(-a)
        assert semantics.fold_unary("!", a) == int(a == 0)
        assert semantics.fold_unary("~", a) == -a - 1
        assert semantics.unary(Op.BOOL, a) == int(a != 0)
    for v in EDGES + [2**32, -2**33 + 5, 2**40 + 3]:
        assert wrap(v) == eval(semantics.WRAP_SOURCE.format(v=v)) and INT_MIN <= wrap(v) <= INT_MAX


def test_what_the_fast_backend_relies_on_holds():
    """Operators marked modular give the same 32-bit result on unwrapped operands
    (the fast backend defers wrapping through them); a positive divisor's source
    is the general one."""
    offsets = [0, 2**32, -2**32, 3 * 2**32]
    for o in semantics.BINARY.values():
        for a, b in PAIRS:
            if o.modular:
                for da, db in itertools.product(offsets, offsets):
                    raw = eval(o.text(f"({a + da})", f"({b + db})"))
                    assert wrap(int(raw)) == o.fn(a, b), (o.op, a, b, da, db)
            if o.divides and b > 0:
                assert eval(o.positive_divisor.format(a=f"({a})", b=b)) == o.fn(a, b)
    for o in semantics.UNARY.values():
        if o.modular:
            for a, d in itertools.product(EDGES, offsets):
                assert wrap(eval(o.text(f"({a + d})"))) == o.fn(a)


def test_the_reference_functions_are_compiled_when_first_used():
    """Issue 26.1: importing the table compiles only what it uses itself
    (c_div, c_mod): a command that uses three operators compiles three."""
    import subprocess
    import sys
    code = ("from plcbuilder.bytecode import semantics as s\n"
            "ops = [*s.BINARY.values(), *s.UNARY.values()]\n"
            "print(len(ops), sum('fn' in vars(o) for o in ops))")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert r.stdout.split() == ["20", "2"], r.stdout + r.stderr
