"""softMC virtual I/O (SPEC §9, "softMC I/O"): 32 virtual inputs and outputs as
bits and as 32-bit words, on both VM backends, from hardware and software
procedures, with constant and computed addresses."""

from __future__ import annotations

import pytest

from plcbuilder.bytecode import abi, softmc
from plcbuilder.controller.machine import Machine
from plcbuilder.controller.session import ReportCollector

from tests.controller._sim import BACKENDS, Note, Print, compile_proc, controller, of, run_hw



def _vars(c, name="M03"):
    return c.variables()[name]


@pytest.mark.parametrize("backend", BACKENDS)
def test_bits_and_words_are_one_state(backend):
    """SPEC §9: "32 virtual inputs and 32 virtual outputs (VIN.1…32, VOUT.1…32)
    readable and writable as bits and as whole 32-bit words (registers documented
    by the project)". A bit written shows in the word, a word written shows in
    every bit; VOUT.32 is the word's sign bit."""
    src = """
main()
{
  gvarset(VOUT_1, 1);
  gvarset(VOUT_3, 7);          // any non-zero value sets the bit
  gvarset(VOUT_32, 1);
  var00 = gvarget(VOUT_WORD);
  gvarset(VIN_WORD, 0x12);
  var01 = gvarget(VIN_2);
  var02 = gvarget(VIN_5);
  var03 = gvarget(VIN_1);
  gvarset(VOUT_1, 0);
  var04 = gvarget(VOUT_WORD);
  exit(99);
}
"""
    c, _ = run_hw(src, backend=backend)
    v = _vars(c)
    assert v["var00"] == -(1 << 31) | 0b101          # bits 0, 2 and 31
    assert (v["var01"], v["var02"], v["var03"]) == (1, 1, 0)
    assert v["var04"] == -(1 << 31) | 0b100
    assert c.machine.vio.vouts_on() == [3, 32]
    assert c.machine.vio.vins_on() == [2, 5]


@pytest.mark.parametrize("backend", BACKENDS)
def test_the_seeds_word_copy(backend):
    """SPEC §9 (softMC I/O): "readable and writable as bits and as whole 32-bit
    words". The seed's ``System.VOut=System.VIn`` copies all 32 bits at once."""
    src = """
main()
{
  gvarset(VIN_WORD, 0-1);
  gvarset(VOUT_WORD, gvarget(VIN_WORD));
  exit(99);
}
"""
    c, _ = run_hw(src, backend=backend)
    assert c.machine.vio.vouts_on() == list(range(1, 33))
    assert c.machine.gvarget(softmc.VOUT_WORD) == -1


@pytest.mark.parametrize("backend", BACKENDS)
def test_computed_addresses_take_the_same_path(backend):
    """SPEC §9: "readable and writable as bits and as whole 32-bit words". An
    address computed at run time (not a constant the fast backend could
    specialise) reaches the same registers."""
    src = """
main()
{
  a = VOUT_1;
  i = 0;
  do { gvarset(a + i, 1); i = i + 2; } while (i < 32);
  var00 = gvarget(VOUT_WORD);
  b = VIN_1;
  gvarset(VIN_WORD, 0x80000000);
  var01 = gvarget(b + 31);
  exit(99);
}
"""
    c, _ = run_hw(src, 200, backend=backend)
    assert _vars(c)["var00"] == 0x55555555
    assert _vars(c)["var01"] == 1


@pytest.mark.parametrize("backend", BACKENDS)
def test_software_procedures_reach_virtual_io(backend):
    """SPEC §9: "readable and writable as bits and as whole 32-bit words" — from
    software procedures too (they reach the hardware through the host)."""
    sw = compile_proc("main()\n{\n  gvarset(VOUT_7, gvarget(VIN_7) + 1);\n}\n", "vio",
                      software=True)
    c = controller(sw, backend=backend)
    c.run_until_idle(300)
    assert c.machine.vio.vouts_on() == [7]


@pytest.mark.parametrize("backend", BACKENDS)
def test_virtual_registers_have_no_host_latency(backend):
    """SPEC §2: "A host round-trip latency for `gvarget` of plain registers can be
    set"; the virtual I/O registers are not plain registers, so a read is at once."""
    src = "main()\n{\n  gvarset(VOUT_2, 1);\n  var00 = gvarget(VOUT_WORD);\n  exit(99);\n}\n"
    c, events = run_hw(src, backend=backend, gvarget_latency_ms=50)
    assert _vars(c)["var00"] == 2
    assert of(events, Print) == []
    assert [e for e in events if getattr(e, "name", None) == "M03"][-1].t_ms == 0


def test_dip_is_read_only_and_comes_from_io_dat():
    """SPEC §9: "physical inputs preset from an `IO.DAT` file in the project
    (`INP=0xXX`, `DIP=0xXX` lines, as the seed shows)". DIP reads at IO_DAT_DIP;
    writing it is ignored with a warning."""
    import dataclasses

    from plcbuilder.controller.machine_config import default_machine
    m = Machine(dataclasses.replace(default_machine(), dip=0x5A))
    assert m.gvarget(softmc.IO_DAT_DIP) == 0x5A
    m.gvarset(softmc.IO_DAT_DIP, 1)
    assert m.gvarget(softmc.IO_DAT_DIP) == 0x5A
    notes = m.advance()
    assert notes and "IO_DAT_DIP" in notes[0][1] and "read-only" in notes[0][1]


def test_reset_clears_virtual_io():
    """SPEC §9: softMC I/O is "available on every target as part of the machine";
    a reset (power-on) clears the virtual inputs and outputs."""
    m = Machine()
    m.gvarset(softmc.VOUT_WORD, 0xF0)
    m.gvarset(softmc.VIN_BIT_BASE + 4, 1)
    m.reset()
    assert (m.gvarget(softmc.VOUT_WORD), m.gvarget(softmc.VIN_WORD)) == (0, 0)


def test_names_are_built_in_and_described():
    """SPEC §9: "(registers documented by the project)" — every name is a
    built-in constant, and hover/disassembly describe the addresses."""
    assert abi.BUILTIN_NAMES["VIN_1"] == 30101
    assert abi.BUILTIN_NAMES["VOUT_32"] == 30232
    assert abi.BUILTIN_NAMES["VOUT_WORD"] == 30001
    assert abi.BUILTIN_KIND["VIN_WORD"] == "softMC register"
    assert abi.describe_register(30205) == "VOUT_5: virtual output 5"
    assert "virtual inputs" in abi.describe_register(softmc.VIN_WORD)
    # nothing in the softMC block collides with a myCNC register
    for name, addr in softmc.REGISTERS.items():
        assert name not in abi.GVAR and addr not in abi.GVAR.values()
        assert not abi.PRINT_FIRST <= addr <= abi.PRINT_LAST


@pytest.mark.parametrize("backend", BACKENDS)
def test_run_report_lists_virtual_outputs(backend):
    """SPEC §9: softMC I/O is "available on every target as part of the machine":
    the run report lists the virtual outputs on (``vouts``) and the virtual
    inputs on (``vins``), numbered 1..32."""
    c, events = run_hw("main()\n{\n  gvarset(VOUT_4, 1);\n  gvarset(VIN_9, 1);\n"
                       "  exit(99);\n}\n", backend=backend)
    rc = ReportCollector(c)
    rc.take(events)
    rep = rc.report(c.t_ms, "M03.plc")
    assert rep["vouts"] == [4] and rep["vins"] == [9]
    assert rep["pls"] == []
    assert not of(events, Note)


# ------------------------------------------------ software I/O starts events
def _events_controller(backend, *extra, machine_config=None):
    from plcbuilder.controller.controller import Controller
    from plcbuilder.controller.machine_config import parse_machine
    cfg = machine_config or parse_machine(
        '[axes.X]\nrapid = 60000.0\naccel = 20000.0\nstart = 0.0\n'
        '[[pls]]\naxis = "X"\noutput = 5\npositions = [10.0]\npolarity = 1\nenabled = true\n',
        "machine.toml")
    c = Controller(cfg, backend=backend)
    c.load([compile_proc("main(){ gvarset(20000, eparam); exit(99); };", "M20"),
            compile_proc("main(){ gvarset(VIN_1, 1); exit(99); };", "M21"),
            compile_proc("main(){ g0moveA(3, 1, 2000); exit(99); };", "M22"),
            *extra])
    return c


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_virtual_input_starts_an_event(backend):
    """The seed: "You can use software I/O to start events just as with standard
    I/O" — ``OnEvent SoftwareInputEvent System.VIn.1 = ON``: ``bind vin 1=M20``
    starts M20 when VIN.1 goes 0 -> 1 (seen at the beginning of the next tick,
    as an input edge is)."""
    from plcbuilder.controller.scenario import Scenario, drive
    c = _events_controller(backend)
    sc = Scenario.parse("bind vin 1=M20:7 @ 0\nstart M21 @ 10\n")
    drive(c, sc, 100)
    started = [(e.name, e.t_ms) for e in c.drain_events() if type(e).__name__ == "Started"]
    assert started == [("M21", 10), ("M20", 11)]
    assert c.variables()["M20"]["eparam"] == 7


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_virtual_output_and_a_pls_output_start_events(backend):
    """The seed: "Programmable limit switches can use software outputs just as
    with standard outputs" and a PLS "drives events: EventOn MyEvent
    MyPLS.PlsOutput = ON". ``bind pls 1=M20`` starts M20 when PLS1's output
    turns on (X crossing 10 mm); ``bind vout 3=M20`` when VOUT.3 does."""
    from plcbuilder.controller.scenario import Scenario, drive
    c = _events_controller(backend, compile_proc("main(){ gvarset(VOUT_3, 1); exit(99); };",
                                                 "M23"))
    sc = Scenario.parse("bind pls 1=M20:1 @ 0\nstart M22 @ 0\n"
                        "bind vout 3=M20:3 @ 0\nstart M23 @ 500\n")
    drive(c, sc, 600)
    events = c.drain_events()
    prints = [(p.t_ms, p.value) for p in of(events, Print)]
    assert [v for _t, v in prints] == [1, 3]
    crossed = prints[0][0]
    assert 0 < crossed < 100 and c.machine.outputs_on() == [5]
    assert prints[1][0] == 501


def test_bind_sources_are_checked_and_recorded():
    """``bind vin 33=…`` is refused naming the range; a binding is recorded as
    the scenario line that replays it."""
    from plcbuilder.controller.controller import ControllerError
    from plcbuilder.controller.scenario import ScenarioError, Scenario
    with pytest.raises(ScenarioError, match="1 to 32"):
        Scenario.parse("bind vin 33=M20 @ 0")
    with pytest.raises(ScenarioError, match="in N, vin N"):
        Scenario.parse("bind led 3=M20 @ 0")
    c = _events_controller("fast")
    with pytest.raises(ControllerError, match="virtual inputs and outputs are 1..32"):
        c.bind_input(0, "M20", source="vout")
    c.bind_input(2, "M20", 5, source="pls")
    assert "bind pls 2=M20:5 @ 0" in c.recorder.text(0)
    assert Scenario.parse("bind pls 2=M20:5 @ 0").actions[0].source == "pls"
