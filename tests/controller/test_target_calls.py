"""controller/targets/calls.py: a call runs to its end and counts its instructions."""

from __future__ import annotations

from plcbuilder.controller import vm
from plcbuilder.controller.targets.calls import CALL_LIMIT, Entries, call
from tests.controller._targets import compiled


def _host(faulting: bool = False) -> vm.Host:
    def gvarset(addr, value):
        if faulting:
            raise vm.VMFault(-1, "refused by the host")
    return vm.Host(portset=lambda p: None, portclr=lambda p: None, portget=lambda p: 0,
                   gvarget=lambda a: 0, gvarset=gvarset, g0move=None)


PROGRAM = """
init() { a = 1; b = 2; }
plc1() { i = 0; do { i++; } while (i < 10); exit(7); }
plc2() {
    gvarset(5, 1);
}
"""


def test_counts_are_exact_across_loop_ends():
    e = Entries(compiled(PROGRAM, "huazhong"))
    slots = [0] * 256
    r = call(e.get("init"), slots, _host())
    assert (r.code, r.instructions) == (0, 5)        # PUSH1 STORE PUSH8 STORE RET
    r = call(e.get("plc1"), slots, _host())
    assert (r.code, r.instructions) == (7, 4 + 5 * 10)


def test_a_host_fault_gets_the_calling_instruction():
    e = Entries(compiled(PROGRAM, "huazhong"))
    r = call(e.get("plc2"), [0] * 256, _host(faulting=True))
    assert r.code is None and r.fault.text == "refused by the host"
    assert e.program.location(r.fault.pc)[1] == 5          # gvarset(5, 1);


def test_the_instruction_limit_spans_loop_ends():
    e = Entries(compiled("init() { do { n++; } while (1); }\nplc1() { }\nplc2() { }", "huazhong"))
    r = call(e.get("init"), [0] * 256, _host())
    assert r.code is None and "instructions in one call" in r.fault.text
    assert CALL_LIMIT < r.instructions <= CALL_LIMIT + 10
