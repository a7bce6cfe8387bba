"""The built-in functions are stated in three tables that must agree (issue 28.1):
the language's FUNCTIONS (name, parameters, whether it gives a value, its
opcode), the opcode table's BUILTIN_CALLS and STACK_EFFECT, and the reference
interpreter's kind of each opcode (controller/vm.py _KIND_OF)."""

from plcbuilder.bytecode import abi
from plcbuilder.bytecode.opcodes import BUILTIN_CALLS, STACK_EFFECT, Op
from plcbuilder.controller import vm
from plcbuilder.lang.builtins import FUNCTIONS


def test_each_builtin_pops_its_arguments_and_pushes_its_value():
    for b in FUNCTIONS.values():
        if b.op is None:
            continue
        assert STACK_EFFECT[b.op] == (b.arity, 1 if b.returns else 0), b.name


def test_every_builtin_call_opcode_is_a_function_and_back():
    ops = {b.op for b in FUNCTIONS.values() if b.op is not None}
    assert BUILTIN_CALLS <= ops, BUILTIN_CALLS - ops
    assert ops - BUILTIN_CALLS <= {Op.EXIT}, ops - BUILTIN_CALLS


def test_the_reference_interpreter_has_a_kind_of_its_own_for_each_builtin_call():
    kinds = [vm._KIND_OF[op] for op in BUILTIN_CALLS]
    assert len(set(kinds)) == len(kinds)
    assert set(vm._KIND_OF) == set(Op)


def test_vm_limits_live_in_the_abi():
    assert vm.MAX_CALL_DEPTH is abi.MAX_CALL_DEPTH == 16
    assert vm.TICK_BUDGET is abi.TICK_BUDGET
    assert vm.STACK_LIMIT is abi.STACK_LIMIT
