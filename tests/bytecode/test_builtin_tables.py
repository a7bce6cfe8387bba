"""A built-in function is stated once (issue 28.1): its opcode's row of
opcodes.BUILTINS (the Host function it calls, its arguments, whether it
gives a value, whether it writes), its row of the language's FUNCTIONS (name,
parameters, doc) and its semantics, the machine's method. Everything else is
made from those: the stack effects, the reference interpreter's one path for
built-in calls, the fast backend's generic call, the Host's functions, the
PLC's host over the machine, the debugger's expression host. These tests
fail when the tables disagree."""

from __future__ import annotations

import inspect

import pytest

from plcbuilder.bytecode import abi
from plcbuilder.bytecode.opcodes import BUILTIN_CALLS, BUILTINS, STACK_EFFECT, Op
from plcbuilder.controller import fastvm, plc, vm
from plcbuilder.controller.machine import Machine
from plcbuilder.lang.builtins import FUNCTIONS
from tests.controller._sim import compile_proc


def test_each_builtin_pops_its_arguments_and_pushes_its_value():
    for b in FUNCTIONS.values():
        if b.op is None:
            continue
        assert STACK_EFFECT[b.op] == (b.arity, 1 if b.returns else 0), b.name
        if b.op in BUILTINS:
            c = BUILTINS[b.op]
            assert (c.args, c.value) == (b.arity, b.returns), b.name


def test_every_builtin_call_opcode_is_a_function_and_back():
    ops = {b.op for b in FUNCTIONS.values() if b.op is not None}
    assert BUILTIN_CALLS == set(BUILTINS)
    assert BUILTIN_CALLS <= ops, BUILTIN_CALLS - ops
    assert ops - BUILTIN_CALLS <= {Op.EXIT}, ops - BUILTIN_CALLS


def test_the_host_has_a_function_for_each_builtin_call_and_the_machine_a_method():
    assert set(vm.CALLS) == {c.host for c in BUILTINS.values()}
    assert set(vm.CALLS) <= set(vm.Host.__slots__)
    assert set(vm.CALLS) <= set(fastvm._HOST_NAMES)
    with pytest.raises(TypeError, match="missing"):
        vm.Host(**{name: None for name in vm.CALLS[1:]})
    for c in BUILTINS.values():
        method = getattr(Machine, plc._MACHINE_NAME.get(c.host, c.host))
        assert len(inspect.signature(method).parameters) == 1 + c.args, c.host


def test_an_expression_host_refuses_exactly_the_writes():
    host = vm.Host(**{name: name for name in vm.CALLS})
    refused = host.for_expression(write="refused")
    for c in BUILTINS.values():
        assert getattr(refused, c.host) == ("refused" if c.writes else c.host), c.host
        assert getattr(host.for_expression(), c.host) == c.host


CALLS_EACH = """
main()
{
  a = portget(3);
  portset(2);
  portclear(2);
  portclr(a + 4);
  v = gvarget(5000 + a);
  gvarset(5001, v + 1);
  g0moveA(1, 7, a - 250);
  exit(99);
};
"""


@pytest.mark.parametrize("make", [vm.run_reference, fastvm.make_runner],
                         ids=["reference", "fast"])
def test_both_vms_call_each_builtin_through_the_table(make):
    """Every built-in call reaches the Host function its row names, with its
    arguments in order, and what it returns is the call's value."""
    seen = []

    def recorder(name, value):
        def fn(*argv):
            seen.append((name, *argv))
            return value
        return fn

    host = vm.Host(**{c.host: recorder(c.host, 1 if c.host == "portget" else 40)
                      for c in BUILTINS.values()})
    gen = make(compile_proc(CALLS_EACH, "M10"), [0] * 256, host)
    with pytest.raises(vm.ProcExit) as ended:
        next(gen)
    assert ended.value.code == 99
    assert seen == [("portget", 3), ("portset", 2), ("portclr", 2), ("portclr", 5),
                    ("gvarget", 5001), ("gvarset", 5001, 41), ("g0move", 1, 7, -249)]


def test_vm_limits_live_in_the_abi():
    assert vm.MAX_CALL_DEPTH is abi.MAX_CALL_DEPTH == 16
    assert vm.TICK_BUDGET is abi.TICK_BUDGET
    assert vm.STACK_LIMIT is abi.STACK_LIMIT
