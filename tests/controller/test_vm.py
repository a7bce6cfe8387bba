"""The bytecode's meaning, on hand-assembled code, for both VM backends.

Every test runs on the reference interpreter and on the fast backend: the
expected values are the contract, and equal results on both are part of it.
"""

from __future__ import annotations

import re

import pytest

from plcbuilder.bytecode import abi, semantics
from plcbuilder.bytecode.opcodes import Op
from plcbuilder.bytecode.program import Kind
from plcbuilder.controller import fastvm
from plcbuilder.controller.controller import Controller
from plcbuilder.controller.events import Ended, Fault, Message

from tests.controller._asm import L, assemble

INT_MIN, INT_MAX = -2**31, 2**31 - 1
R = abi.FIRST_USER_SLOT          # the first user variable


@pytest.fixture(params=["fast", "reference"])
def backend(request):
    return request.param


class RecordingMachine:
    """A machine that records what the PLC does (for argument order)."""

    input_count = output_count = 64
    _sample = None          # Machine's cached sample (None: changed since), which the PLC reads
    quiet = False

    def __init__(self, plain=True):
        self.calls = []
        self.t = 0
        self.regs = {}
        self.plain = plain

    def portset(self, pin): self.calls.append(("portset", pin))
    def portclear(self, pin): self.calls.append(("portclear", pin))
    def portget(self, pin):
        self.calls.append(("portget", pin))
        return 1 if pin == 3 else 0
    def gvarget(self, addr):
        self.calls.append(("gvarget", addr, self.t))
        return self.regs.get(addr, self.t)
    def gvarset(self, addr, value):
        self.calls.append(("gvarset", addr, value))
        self.regs[addr] = value
    def g0move(self, flags, mask, dist): self.calls.append(("g0move", flags, mask, dist))
    def on_message(self, code): self.calls.append(("message", code))
    def is_plain_register(self, addr): return self.plain and addr != abi.MOTION_CODE
    def soft_jog(self, axis, speed): self.calls.append(("soft_jog", axis, speed))
    def set_input(self, pin, v): pass
    def set_adc(self, ch, v): pass
    def advance(self):
        self.t += 1
        return []
    def sample_fields(self):
        z = (0,) * 8
        return {"inputs": z, "outputs": z, "pwm": z, "dac": z, "adc": z, "axes": (0,) * 9,
                "velocities": (0,) * 9}
    def outputs_on(self): return []
    def axis_positions(self): return {}


def run(items, backend, *, ms=1000, eparam=0, variables=None, machine=None, nvars=4,
        kind=Kind.HARDWARE, latency=0, entry="main"):
    """Assemble, load, start at 0, run until it ends. Returns (events, vars, controller)."""
    prog = assemble(items, name="P", kind=kind, entry=entry,
                    var_names=[f"r{i}" for i in range(nvars)])
    c = Controller(backend=backend, variables=variables, machine=machine,
                   gvarget_latency_ms=latency)
    c.load([prog], autostart=False)
    c.start("P", eparam)
    c.run_until_idle(ms)
    return c.drain_events(), c.variables()["P"], c


def ends(events):
    e = [x for x in events if isinstance(x, Ended)]
    assert len(e) == 1, events
    return e[0]


# ------------------------------------------------------------ arithmetic

BINARY_CASES = [
    (Op.ADD, INT_MAX, 1, INT_MIN), (Op.ADD, -5, 3, -2), (Op.SUB, INT_MIN, 1, INT_MAX),
    (Op.SUB, 3, 10, -7), (Op.MUL, 0x10000, 0x10000, 0), (Op.MUL, -3, 7, -21),
    (Op.MUL, INT_MAX, 2, -2), (Op.MUL, INT_MIN, -1, INT_MIN),
    (Op.DIV, 7, 2, 3), (Op.DIV, -7, 2, -3), (Op.DIV, 7, -2, -3), (Op.DIV, -7, -2, 3),
    (Op.DIV, INT_MIN, -1, INT_MIN), (Op.DIV, 0, 5, 0), (Op.DIV, INT_MIN, 2, -2**30),
    (Op.MOD, 7, 2, 1), (Op.MOD, -7, 2, -1), (Op.MOD, 7, -2, 1), (Op.MOD, -7, -2, -1),
    (Op.MOD, INT_MIN, -1, 0), (Op.MOD, INT_MIN, 3, -2),
    (Op.SHL, 1, 31, INT_MIN), (Op.SHL, 1, 32, 1), (Op.SHL, 3, 33, 6), (Op.SHL, -1, 4, -16),
    (Op.SHL, 5, -1, INT_MIN), (Op.SHR, -16, 2, -4), (Op.SHR, INT_MIN, 31, -1),
    (Op.SHR, 16, -1, 0), (Op.SHR, 8, 35, 1), (Op.SHR, -1, 31, -1),
    (Op.AND, -1, 0xFF, 0xFF), (Op.OR, INT_MIN, 1, INT_MIN + 1), (Op.XOR, -1, 5, -6),
    (Op.EQ, -1, -1, 1), (Op.EQ, 0, 1, 0), (Op.NE, 3, 3, 0), (Op.NE, 3, 4, 1),
    (Op.LT, -1, 0, 1), (Op.LT, 0, -1, 0), (Op.LE, 5, 5, 1), (Op.GT, INT_MIN, INT_MAX, 0),
    (Op.GE, INT_MAX, INT_MIN, 1), (Op.GE, 2, 3, 0),
]


@pytest.mark.parametrize("op,a,b,want", BINARY_CASES,
                         ids=[f"{c[0].name}({c[1]},{c[2]})" for c in BINARY_CASES])
def test_binary_operators_wrap_and_truncate_like_c(op, a, b, want, backend):
    """Values are 32-bit two's complement, every result wraps; / and % truncate
    toward zero; INT_MIN/-1 wraps, INT_MIN%-1 is 0; shift count is b & 31;
    >> is arithmetic; comparisons give 0/1. Pop order: b then a, push a OP b."""
    # operands come from eparam and var00, so nothing is folded at translation time
    items = [L("main"), (Op.LOAD, abi.SLOT_EPARAM), (Op.LOAD, abi.SLOT_VAR00), op, (Op.STORE, R),
             (Op.PUSH8, 99), Op.EXIT]
    _, v, _ = run(items, backend, eparam=a, variables=[b])
    assert v["r0"] == want
    assert semantics.binary(op, a, b) == want


@pytest.mark.parametrize("op,a,b,want", BINARY_CASES[::3],
                         ids=[f"{c[0].name}({c[1]},{c[2]})" for c in BINARY_CASES[::3]])
def test_constant_operands_give_the_same_results(op, a, b, want, backend):
    items = [L("main"), (Op.PUSH32, a), (Op.PUSH32, b), op, (Op.STORE, R), (Op.PUSH8, 99), Op.EXIT]
    _, v, _ = run(items, backend)
    assert v["r0"] == want


@pytest.mark.parametrize("op,a,want", [(Op.NEG, INT_MIN, INT_MIN), (Op.NEG, 5, -5),
                                       (Op.NOT, 0, 1), (Op.NOT, -7, 0), (Op.BNOT, 0, -1),
                                       (Op.BNOT, INT_MIN, INT_MAX), (Op.BOOL, -5, 1),
                                       (Op.BOOL, 0, 0)])
def test_unary_operators(op, a, want, backend):
    """NEG wraps; NOT and BOOL give 0/1; BNOT is ~."""
    items = [L("main"), (Op.LOAD, abi.SLOT_EPARAM), op, (Op.STORE, R), (Op.PUSH8, 99), Op.EXIT]
    _, v, _ = run(items, backend, eparam=a)
    assert v["r0"] == want


def test_inc_and_dec_wrap(backend):
    items = [L("main"), (Op.PUSH32, INT_MAX), (Op.STORE, R), (Op.INC, R),
             (Op.PUSH32, INT_MIN), (Op.STORE, R + 1), (Op.DEC, R + 1), (Op.PUSH8, 99), Op.EXIT]
    _, v, _ = run(items, backend)
    assert (v["r0"], v["r1"]) == (INT_MIN, INT_MAX)


def test_comparison_results_are_plain_numbers_when_printed(backend):
    """A comparison's 0/1 is a number everywhere: in prints, exits and variables."""
    items = [L("main"), (Op.PUSH16, 20000), (Op.LOAD, abi.SLOT_EPARAM), Op.PUSH0, Op.GT,
             Op.GVARSET, (Op.LOAD, abi.SLOT_EPARAM), Op.PUSH0, Op.GT, Op.EXIT]
    ev, _, _ = run(items, backend, eparam=5)
    prints = [e for e in ev if e.type == "print"]
    assert [(p.value, type(p.value)) for p in prints] == [(1, int)]
    assert ends(ev).exit_code == 1 and type(ends(ev).exit_code) is int


# ---------------------------------------------------------- control flow

def test_jumps_are_relative_to_the_end_of_the_instruction(backend):
    """JMP8 +2 skips exactly the 2-byte instruction after it."""
    items = [L("main"), (Op.JMP8, 2), (Op.PUSH8, 1), (Op.PUSH8, 7), Op.EXIT]
    ev, _, _ = run(items, backend)
    assert ends(ev).exit_code == 7


def test_loop_ends_the_tick_then_goes_to_its_target_if_the_condition_was_not_zero(backend):
    """LOOP pops cond, ends the tick; resumes at target if cond != 0 else falls through."""
    items = [L("main"), (Op.PUSH8, 5), (Op.STORE, R), L(".top"), (Op.DEC, R), (Op.LOAD, R),
             (Op.LOOP8, ".top"), (Op.PUSH8, 99), Op.EXIT]
    ev, v, _ = run(items, backend)
    assert ends(ev).t_ms == 5 and v["r0"] == 0


def test_yield_ends_the_tick(backend):
    items = [L("main"), Op.YIELD, Op.YIELD, Op.YIELD, (Op.PUSH8, 99), Op.EXIT]
    ev, _, _ = run(items, backend)
    assert ends(ev).t_ms == 3


def test_ret_in_main_ends_the_procedure_with_exit_code_0(backend):
    """Falling off main (RET at depth 0) ends it with exit code 0."""
    items = [L("main"), (Op.PUSH8, 4), (Op.STORE, abi.SLOT_VEXIT), Op.RET]
    ev, _, _ = run(items, backend)
    e = ends(ev)
    assert (e.exit_code, e.exit_name, e.vexit, e.t_ms) == (0, None, 4, 0)


def test_exit_pops_its_code_and_reports_vexit(backend):
    items = [L("main"), (Op.PUSH8, 42), (Op.STORE, abi.SLOT_VEXIT), (Op.PUSH8, 99), Op.EXIT]
    e = ends(run(items, backend)[0])
    assert (e.exit_code, e.exit_name, e.vexit) == (99, "plc_exit_normal", 42)


def _nest(depth: int) -> list:
    """main calls f1, f1 calls f2, … f<depth> returns; then main exits 99."""
    items = [L("main"), (Op.CALL, "f1"), (Op.PUSH8, 99), Op.EXIT]
    for i in range(1, depth + 1):
        items += [L(f"f{i}")] + ([(Op.CALL, f"f{i + 1}")] if i < depth else []) + [Op.RET]
    return items


def test_sixteen_nested_calls_are_allowed(backend):
    """Calls nest at most 16 deep."""
    ev, _, _ = run(_nest(16), backend)
    assert ends(ev).exit_code == 99 and not [e for e in ev if isinstance(e, Fault)]


def test_a_seventeenth_nested_call_is_a_runtime_fault(backend):
    """call depth over 16 is a runtime fault. The fault names main's statement
    (the call that led there) and lists the chain down to the 17th call."""
    items = _nest(17)
    ev, _, _ = run(items, backend)
    f = [e for e in ev if isinstance(e, Fault)]
    assert len(f) == 1 and "call depth" in f[0].text
    instrs = [x for x in items if not (isinstance(x, tuple) and x[0] == "label")]
    call17 = instrs.index((Op.CALL, "f17")) + 1          # source line of each instruction
    assert (f[0].file, f[0].line) == ("t.plc", 1)         # main's CALL f1
    assert len(f[0].calls) == 17
    assert f[0].calls[0] == ("t.plc", 1, "main") and f[0].calls[-1] == ("t.plc", call17, "f16")
    assert f"(in f16() at t.plc:{call17})" in f[0].text
    assert ends(ev).exit_code == -1


def test_recursion_faults_at_depth_seventeen(backend):
    items = [L("main"), (Op.CALL, "f"), (Op.PUSH8, 99), Op.EXIT,
             L("f"), (Op.INC, R), (Op.CALL, "f"), Op.RET]
    ev, v, _ = run(items, backend)
    assert "call depth" in [e for e in ev if isinstance(e, Fault)][0].text
    assert v["r0"] == 16


def test_more_than_100000_instructions_in_one_tick_is_a_fault_at_the_exact_instruction(backend):
    """The 100 001st instruction of a tick faults (here the second NOP of the loop body)."""
    items = [L("main"), L(".top"), Op.NOP, Op.NOP, (Op.JMP8, ".top")]
    ev, _, _ = run(items, backend)
    f = [e for e in ev if isinstance(e, Fault)]
    # instructions cycle NOP, NOP, JMP: number 100001 = 3 * 33333 + 2 is the second NOP (line 2)
    assert len(f) == 1 and "100000 instructions" in f[0].text and f[0].line == 2
    assert f[0].t_ms == 0


def test_the_budget_counts_one_tick_only(backend):
    """60 000 instructions in each of several ticks is fine."""
    items = [L("main"), (Op.PUSH8, 3), (Op.STORE, R + 1), L(".outer"),
             (Op.PUSH16, 20000), (Op.STORE, R), L(".inner"), (Op.DEC, R), (Op.LOAD, R),
             (Op.JNZ8, ".inner"), (Op.DEC, R + 1), (Op.LOAD, R + 1), (Op.LOOP8, ".outer"),
             (Op.PUSH8, 99), Op.EXIT]
    ev, _, _ = run(items, backend)
    assert not [e for e in ev if isinstance(e, Fault)]
    assert ends(ev).t_ms == 3


def test_division_by_zero_faults_names_the_line_and_sends_err_vm(backend):
    """A fault ends the procedure with a fault event naming the source line and a
    PLC_MESSAGE_ERR_VM (-1) message."""
    items = [L("main"), Op.YIELD, (Op.PUSH8, 5), (Op.STORE, abi.SLOT_VAR00),
             (Op.PUSH8, 1), (Op.LOAD, abi.SLOT_EPARAM), Op.DIV, (Op.STORE, R),
             (Op.PUSH8, 99), Op.EXIT]
    ev, _, _ = run(items, backend, eparam=0)
    kinds = [e.type for e in ev]
    assert kinds == ["started", "fault", "ended", "message"]
    f, e, m = ev[1:]
    assert (f.t_ms, f.source, f.file, f.line, f.text) == (1, "P", "t.plc", 6, "division by zero")
    assert (e.exit_code, e.t_ms) == (-1, 1)
    assert (m.message, m.name, m.command, m.t_ms) == (-1, "PLC_MESSAGE_ERR_VM", 5, 1)


def test_modulo_by_zero_faults(backend):
    items = [L("main"), (Op.PUSH8, 1), (Op.LOAD, abi.SLOT_EPARAM), Op.MOD, Op.EXIT]
    ev, _, _ = run(items, backend)
    assert [e.text for e in ev if isinstance(e, Fault)] == ["modulo by zero"]


def test_running_past_the_end_of_the_code_is_a_fault(backend):
    items = [L("main"), Op.PUSH1, (Op.STORE, R)]
    ev, _, _ = run(items, backend)
    assert "past the end" in [e for e in ev if isinstance(e, Fault)][0].text


def test_stack_underflow_is_a_fault_and_such_code_runs_on_the_reference(backend):
    items = [L("main"), Op.POP, (Op.PUSH8, 99), Op.EXIT]
    ev, _, _ = run(items, backend)
    assert [e.text for e in ev if isinstance(e, Fault)] == ["stack underflow"]
    assert fastvm.unsupported_reason(assemble(items, entry="main"))


def test_values_stay_on_the_stack_across_jumps(backend):
    """a + (c ? 10 : 20), with a on the stack while the branches run."""
    items = [L("main"), (Op.PUSH8, 1), (Op.LOAD, abi.SLOT_EPARAM), (Op.JZ8, ".else"),
             (Op.PUSH8, 10), (Op.JMP8, ".end"), L(".else"), (Op.PUSH8, 20), L(".end"), Op.ADD,
             Op.EXIT]
    assert ends(run(items, backend, eparam=1)[0]).exit_code == 11
    assert ends(run(items, backend, eparam=0)[0]).exit_code == 21


# --------------------------------------------------------------- builtins

def test_builtins_pop_their_arguments_first_pushed_first(backend):
    m = RecordingMachine()
    items = [L("main"), (Op.PUSH8, 5), Op.PORTSET, (Op.PUSH8, 6), Op.PORTCLR,
             (Op.PUSH16, 1234), (Op.PUSH8, 77), Op.GVARSET,
             (Op.PUSH16, 0x81), (Op.PUSH8, 4), (Op.PUSH16, -3000), Op.G0MOVE,
             (Op.PUSH8, 3), Op.PORTGET, (Op.STORE, R), (Op.PUSH16, 1234), Op.GVARGET,
             (Op.STORE, R + 1), (Op.PUSH8, 99), Op.EXIT]
    _, v, _ = run(items, backend, machine=m)
    assert m.calls[:6] == [("portset", 5), ("portclear", 6), ("gvarset", 1234, 77),
                           ("g0move", 0x81, 4, -3000), ("portget", 3), ("gvarget", 1234, 0)]
    assert (v["r0"], v["r1"]) == (1, 77)


def test_gvarget_latency_suspends_mid_expression_and_reads_when_it_resumes(backend):
    """With a host latency of L ms, gvarget of a plain register waits L ticks
    (the procedure resumes inside the expression: 7 + gvarget(…))."""
    m = RecordingMachine()
    items = [L("main"), (Op.PUSH8, 7), (Op.PUSH16, 1500), Op.GVARGET, Op.ADD, (Op.STORE, R),
             (Op.PUSH8, 99), Op.EXIT]
    ev, v, _ = run(items, backend, machine=m, latency=3)
    assert ends(ev).t_ms == 3
    assert v["r0"] == 7 + 3                    # the fake register reads the tick it is read at
    assert ("gvarget", 1500, 3) in m.calls


def test_gvarget_latency_does_not_apply_to_mapped_registers(backend):
    m = RecordingMachine()
    items = [L("main"), (Op.PUSH16, abi.MOTION_CODE), Op.GVARGET, (Op.STORE, R),
             (Op.PUSH8, 99), Op.EXIT]
    ev, _, _ = run(items, backend, machine=m, latency=5)
    assert ends(ev).t_ms == 0


def test_prints_and_register_writes_with_computed_addresses(backend):
    """gvarset to 20000..20100 prints, whether the address is a constant or computed."""
    items = [L("main"), (Op.PUSH16, 20000), (Op.PUSH8, 5), Op.GVARSET,
             (Op.PUSH16, 20000), (Op.LOAD, abi.SLOT_EPARAM), Op.ADD, (Op.PUSH8, 6), Op.GVARSET,
             (Op.PUSH16, 20101), (Op.PUSH8, 7), Op.GVARSET, (Op.PUSH8, 99), Op.EXIT]
    ev, _, _ = run(items, backend, eparam=100)
    assert [(e.register, e.value) for e in ev if e.type == "print"] == [(20000, 5), (20100, 6)]


def test_message_slot_read_after_a_tick_end_sees_it_cleared(backend):
    """message=1100; tick end (sent, cleared); reading message gives 0."""
    items = [L("main"), (Op.PUSH16, 1100), (Op.STORE, abi.SLOT_MESSAGE), Op.YIELD,
             (Op.LOAD, abi.SLOT_MESSAGE), (Op.STORE, R), (Op.PUSH8, 99), Op.EXIT]
    ev, v, _ = run(items, backend)
    assert v["r0"] == 0
    assert [(e.t_ms, e.message) for e in ev if isinstance(e, Message)] == [(0, 1100)]


# ------------------------------------------------------------ the backends

def test_fast_backend_translates_compiled_style_code_without_dispatch():
    items = [L("main"), (Op.PUSH8, 10), (Op.STORE, abi.SLOT_TIMER), L(".top"),
             (Op.DEC, abi.SLOT_TIMER), (Op.LOAD, abi.SLOT_TIMER), Op.PUSH0, Op.GT,
             (Op.LOOP8, ".top"), (Op.PUSH8, 99), Op.EXIT]
    src = fastvm.translate(assemble(items, entry="main"))
    # one tick end (with its answer to SYNC: the loop keeps timer in a local)
    # (the condition is taken before the tick ends, so each way ends it)
    assert src.count(fastvm._SYNC_ANSWER) == 2
    assert src.count(fastvm._SYNC_WAIT) == 2
    assert "n += " not in src and "rets" not in src        # no budget, no call chain
    # timer counts down from 10 and stops at 0: no wrap; after a SYNC, a timer
    # written outside that range hands over to the reference interpreter
    assert "v2 -= 1\n" in src and "< -2147483648" not in src
    assert src.count("raise Handoff(") - src.count("except Migrate:") == 2   # (and the migrations)
    compile(src, "<t>", "exec")


def test_translation_is_cached_per_program():
    prog = assemble([L("main"), (Op.PUSH8, 99), Op.EXIT], entry="main")
    assert fastvm.factory(prog) is fastvm.factory(prog)


def test_unknown_backend_is_refused():
    from plcbuilder.controller.controller import ControllerError
    with pytest.raises(ControllerError, match="backend"):
        Controller(backend="jit")


def test_a_slot_beyond_the_programs_variables_reads_0_and_keeps_writes(backend):
    """A hand-made binary may name any slot (a byte): it is there, and starts at 0."""
    items = [L("main"), (Op.LOAD, 250), (Op.STORE, R), (Op.PUSH8, 9), (Op.STORE, 251),
             (Op.LOAD, 251), (Op.STORE, R + 1), (Op.PUSH8, 99), Op.EXIT]
    _, v, _ = run(items, backend)
    assert (v["r0"], v["r1"]) == (0, 9)
