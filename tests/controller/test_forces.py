"""Write and force (SPEC §6) in the controller engine, on both backends."""

from __future__ import annotations

import random

import pytest

from plcbuilder import api
from plcbuilder.bytecode import abi
from plcbuilder.controller.controller import ControllerError
from plcbuilder.controller.events import Forces, Note, to_dict

from tests.controller._sim import BACKENDS, compile_proc, controller
from tests.controller._srcgen import random_source

#: counts up every tick; mirrors what it reads into y, o, w, p, d, a, i
COUNTER = """
main()
{
  x = 0;
  do {
    x = x + 1;
    y = x;
    portset(5); portclear(6);
    gvarset(7278, x); gvarset(7270, x + 1000); gvarset(5000, x);
    o = gvarget(0x405) + 2 * gvarget(0x406);
    w = gvarget(7184);
    p = gvarget(7278); d = gvarget(7270); g = gvarget(5000);
    a = gvarget(7197); i = portget(2); iw = gvarget(7180);
  } while (1);
};
"""


def _c(backend, src=COUNTER, name="M03"):
    c = controller(compile_proc(src, name), backend=backend)
    c.start(name)
    return c


def _v(c, name="M03"):
    return c.variables()[name]


@pytest.mark.parametrize("backend", BACKENDS)
def test_write_sets_a_variable_once(backend):
    """"**Write** sets a value once: a procedure's variable, …" """
    c = _c(backend)
    c.step(10)
    assert _v(c)["x"] == 10
    assert c.write("M03.x", 500) == "M03.x"
    assert _v(c)["x"] == 500
    c.step(1)
    assert _v(c)["x"] == 501 and _v(c)["y"] == 501      # the program goes on from it
    assert c.forces() == []


@pytest.mark.parametrize("backend", BACKENDS)
def test_write_sets_an_input_an_adc_channel_an_output_pwm_dac_and_a_register_once(backend):
    """"**Write** sets a value once: … an input, an ADC channel, an output, a
    PWM/DAC channel, a global register." """
    c = _c(backend)
    c.step(3)
    c.write("in 2", 1)
    c.write("adc 1", 77)
    c.write("out 6", 1)                   # the program clears it again in its next tick
    c.write("pwm 0", 9)
    c.write("dac 0", 8)
    c.write("gvar 5000", 7)
    st = c.state()
    assert 6 in st.outputs and st.pwm[0] == 9 and st.dac[0] == 8 and st.adc[1] == 77
    assert c.machine.gvarget(5000) == 7
    c.step(1)
    v = _v(c)
    assert v["i"] == 1 and v["a"] == 77
    st = c.state()
    assert 6 not in st.outputs and st.pwm[0] == 4 and st.dac[0] == 1004   # written once
    assert v["g"] == 4
    assert c.forces() == []


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_forced_variable_reads_the_forced_value_and_the_programs_writes_are_discarded(backend):
    """"**Force** holds it: every read returns the forced value and the
    program's writes are discarded until the force is released" """
    c = _c(backend)
    c.step(5)
    c.force("M03.x", 1000)
    c.step(4)
    v = _v(c)
    assert v["x"] == 1000 and v["y"] == 1000             # x = x + 1 is discarded, y reads it
    assert c.forces() == [{"target": "M03.x", "value": 1000, "since_ms": 5}]


@pytest.mark.parametrize("backend", BACKENDS)
def test_release_keeps_or_restores_the_value_the_program_would_have_now(backend):
    """"Release either keeps the current value or restores the value the
    program would have now." (a variable: the program's last store, x + 1 of
    the forced value)"""
    for mode, expect in (("keep", 1000), ("restore", 1001)):
        c = _c(backend)
        c.step(5)
        c.force("M03.x", 1000)
        c.step(3)
        c.release("M03.x", mode)
        assert _v(c)["x"] == expect
        c.step(1)
        assert _v(c)["x"] == expect + 1
        assert c.forces() == []


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_forced_input_or_adc_overrides_the_machines_wiring(backend):
    """"a forced input or ADC overrides the machine's wiring" (INPUT_HOME_Z is
    0 at Z 20; ADC0 follows Z); input words 7180.. show the forced input."""
    c = _c(backend)
    c.step(2)
    assert _v(c)["i"] == 0
    c.force("in 2", 1)
    c.force("adc 1", 5)
    c.set_input(2, 0)                       # a hand setting does not beat a force
    c.step(1)
    v = _v(c)
    assert v["i"] == 1 and v["iw"] & 4 and v["a"] == 5
    c.release("in 2", "restore")
    c.release("adc 1", "restore")
    c.step(1)
    v = _v(c)
    assert v["i"] == 0 and v["a"] == 2048                # the wiring again
    assert c.machine.overrides() == {}


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_hand_set_input_can_be_released(backend):
    """"an input set by hand … overrides the machine's own wiring of that pin
    from then on" — until it is released: restore gives it back to the wiring,
    keep leaves it set by hand."""
    c = _c(backend)
    c.set_input(2, 1)
    c.step(1)
    assert _v(c)["i"] == 1
    c.release("in 2", "keep")
    assert c.machine.overrides() == {2: 1}
    c.release("in 2", "restore")
    c.step(1)
    assert _v(c)["i"] == 0 and c.machine.overrides() == {}


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_forced_output_pwm_or_dac_keeps_its_value_and_gvarget_reads_it(backend):
    """"a forced output, PWM or DAC keeps its physical value whatever the
    program writes, and `gvarget` of it reads the forced value." """
    c = _c(backend)
    c.step(3)
    c.force("out 5", 0)
    c.force("out 6", 1)
    c.force("pwm 0", 123)
    c.force("gvar 7270", 456)               # DAC0 by its register
    c.step(2)
    st = c.state()
    assert 5 not in st.outputs and 6 in st.outputs
    assert st.pwm[0] == 123 and st.dac[0] == 456
    v = _v(c)
    assert v["o"] == 2 and v["w"] & (1 << 6) and not v["w"] & (1 << 5)
    assert v["p"] == 123 and v["d"] == 456
    assert [f["target"] for f in c.forces()] == ["out 5", "out 6", "pwm 0", "dac 0"]
    c.release("out 5", "restore")          # what the program set: on
    c.release("out 6", "keep")             # on until the program writes it (next tick)
    c.release("pwm 0", "restore")
    c.release("dac 0", "keep")
    st = c.state()
    assert 5 in st.outputs and 6 in st.outputs and st.pwm[0] == 5 and st.dac[0] == 456
    c.step(1)
    st = c.state()
    assert 6 not in st.outputs and st.pwm[0] == 6 and st.dac[0] == 1006


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_forced_register_reads_the_forced_value_until_released(backend):
    """"**Force** holds it" for "a global register": gvarget reads the forced
    value; restore gives the program's last write."""
    c = _c(backend)
    c.step(3)
    c.force("gvar 5000", -7)
    c.step(2)
    assert _v(c)["g"] == -7
    c.release("gvar 5000", "restore")
    assert c.machine.gvarget(5000) == 5
    assert c.machine.is_plain_register(5000)


@pytest.mark.parametrize("backend", BACKENDS)
def test_forces_survive_a_rebuild_and_are_listed_in_one_place(backend):
    """"Forces survive a rebuild and are listed in one place" — a variable
    force applies to the new image by name; one whose variable is gone is
    released with a note."""
    c = _c(backend)
    c.step(2)
    c.force("M03.y", 42)
    c.force("out 7", 1)
    c.force("M03.g", 9)
    c.drain_events()
    src2 = COUNTER.replace("g = gvarget(5000);", "z = 1;").replace("x = 0;", "q = 3; x = 0;")
    c.load([compile_proc(src2)])
    c.start("M03")
    c.step(3)
    assert _v(c)["y"] == 42 and 7 in c.state().outputs
    assert [f["target"] for f in c.forces()] == ["M03.y", "out 7"]
    ev = c.drain_events()
    notes = [e.text for e in ev if isinstance(e, Note)]
    assert any("M03.g released after the build" in t and "no variable 'g'" in t for t in notes)
    assert [e.forces for e in ev if isinstance(e, Forces)][-1][0]["since_ms"] == 2


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_procedure_started_with_a_forced_variable_holds_it_from_its_first_tick(backend):
    c = controller(compile_proc(COUNTER), backend=backend)
    c.force("M03.x", 50)
    c.start("M03")
    c.step(3)
    assert _v(c)["x"] == 50 and _v(c)["y"] == 50


def test_bad_requests_are_refused_with_a_reason_and_change_nothing():
    c = _c("fast")
    c.step(1)
    for target, value, reason in (
            ("M04.x", 1, "no procedure named M04"), ("M03.nope", 1, "has no variable 'nope'"),
            ("in 64", 1, r"no input 64 \(0..63\)"), ("out -1", 1, "no output -1"),
            ("adc 8", 1, "no ADC channel 8"), ("pwm 9", 1, "no PWM channel"),
            ("in 3", 2, "0 or 1"), ("M03.x", "1.5", "must be an integer"),
            ("M03.x", 1 << 33, "does not fit 32 bits"), ("banana", 1, "is not a target"),
            ("gvar 6060", 1, "cannot be forced"), ("gvar 7180", 1, "input word"),
            (3, 1, "is a name")):
        with pytest.raises(ControllerError, match=reason):
            c.force(target, value)
    with pytest.raises(ControllerError, match="keep or restore"):
        c.release("M03.x", "forget")
    with pytest.raises(ControllerError, match="read-only"):
        c.write("gvar 6060", 1)
    assert c.forces() == []
    c2 = controller(compile_proc(COUNTER))
    with pytest.raises(ControllerError, match="M03 is not running"):
        c2.write("M03.x", 1)


def test_aliases_name_the_same_target():
    c = _c("reference")
    c.step(1)
    assert c.force("gvar 0x405", 0) == "out 5"
    assert c.force("M03.command", 3) == "M03.var00"
    assert c.force("gvar 7279", 1) == "pwm 1"
    assert [f["target"] for f in c.release_all("keep") and c.forces()] == []


def _schedule_run(program, backend: str, seed: int):
    """Run ``program`` with random writes, forces and releases; return what
    happened (events, variables, machine state, errors) as data."""
    rng = random.Random(seed)
    names = list(program.var_names) or ["timer"]
    c = controller(program, backend=backend)
    c.start(program.name)
    log = []
    for step in range(12):
        c.step(rng.randint(0, 6))
        what = rng.choice(["force", "force", "write", "release", "pin", "all"])
        target = f"{program.name}.{rng.choice(names)}"
        value = rng.choice([0, 1, 3, -5, 0x7fffffff])
        try:
            if what == "force":
                c.force(target, value)
            elif what == "write":
                c.write(target, value)
            elif what == "release":
                c.release(target, rng.choice(["keep", "restore"]))
            elif what == "pin":
                pin = rng.choice(["in 3", "in 4", "out 2", "out 3", "pwm 0", "gvar 1000"])
                c.force(pin, value & 1) if rng.random() < 0.6 else c.release(pin, "restore")
            else:
                c.release_all(rng.choice(["keep", "restore"]))
        except ControllerError as exc:
            log.append(("error", step, str(exc)))
        st = c.state()
        log.append((c.t_ms, c.variables(), st.outputs, st.pwm, st.inputs, c.forces()))
    c.step(20)
    log.append([to_dict(e) for e in c.drain_events()])
    log.append(c.variables())
    return log


@pytest.mark.parametrize("chunk", range(2))
def test_both_backends_give_identical_results_on_generated_programs(chunk):
    """Both backends: the same writes, forces and releases at the same ticks
    give the same variables, pins and events."""
    for seed in range(chunk * 40, (chunk + 1) * 40):
        rng = random.Random(seed)
        src = random_source(rng)
        r = api.compile_source(src, "R.plc", api.CompileOptions(kind=api.Kind.HARDWARE))
        assert r.ok, (seed, src)
        fast = _schedule_run(r.program, "fast", seed)
        ref = _schedule_run(r.program, "reference", seed)
        assert fast == ref, f"seed {seed}:\n{src}"


def test_nothing_forced_keeps_the_fast_backend_running_translated_code():
    c = _c("fast")
    c.step(3)
    p = c.plc.hw
    assert p.syncing is not None or p.runner.gi_code.co_name.startswith("f_")
    c.force("out 5", 0)                      # a pin force does not change the backend
    assert c.plc.hw.runner is p.runner
    c.force("M03.x", 1)                      # a variable force does
    assert c.plc.hw.runner.gi_code.co_name == "run_reference"
    assert abi.SLOT_MESSAGE not in c.plc.hw.slots.held


#: main calls wait(), whose loop ends ticks: a force lands while it is inside the call
NESTED = """
wait()
{
  n = 0;
  do { n = n + 1; k = k + 10; } while (n < 5);
};
main()
{
  do { wait(); r = r + 1; } while (r < 3);
  exit(99);
};
"""


@pytest.mark.parametrize("at", range(1, 9))
def test_a_force_inside_a_called_procedure_goes_on_there_and_returns_to_its_caller(at):
    """The hand-over keeps the call chain: forced while wait() runs, main
    continues after the call when wait() returns (both backends the same)."""
    out = {}
    for backend in BACKENDS:
        c = _c(backend, NESTED)
        c.step(at)
        c.force("M03.k", 7)
        c.step(4)
        c.release("M03.k", "restore")
        c.run_until_idle(100)
        ev = [to_dict(e) for e in c.drain_events()]
        out[backend] = (ev, c.variables())
        assert ev[-1]["type"] == "ended" and ev[-1]["exit_code"] == 99
    assert out["fast"] == out["reference"]


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_software_procedures_variable_is_forced_the_same_way(backend):
    sw = compile_proc("main(){ do { t = t + 1; gvarset(5001, t); } while (1); };", "LUBE",
                      software=True)
    c = controller(sw, backend=backend)
    c.step(250)                                # software ticks at 0, 100, 200
    c.force("LUBE.t", 40)
    c.step(200)                                # ticks at 300, 400
    assert _v(c, "LUBE")["t"] == 40 and c.machine.gvarget(5001) == 40
    c.release("LUBE.t", "restore")
    assert _v(c, "LUBE")["t"] == 41


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_force_while_a_gvarget_waits_for_its_latency_applies_when_it_can(backend):
    """A procedure waiting for a gvarget's host latency cannot change over
    there: the force is listed at once and holds from the next step on."""
    src = "main(){ do { v = gvarget(5000); x = x + 1; } while (1); };"
    c = controller(compile_proc(src), backend=backend, gvarget_latency_ms=3)
    c.start("M03")
    c.step(2)                                  # inside the first wait
    c.force("M03.x", 9)
    assert c.forces()[0]["target"] == "M03.x"
    for _ in range(6):
        c.step(1)
    assert _v(c)["x"] == 9


#: line 5 reads, line 6 decides, line 7 counts the ticks that took the branch
BRANCHES = """main()
{
  do
  {
    x = portget(3);
    if (x == 0) {
      y = y + 1;
    };
    z = x + y;
  } while (1);
}
"""


@pytest.mark.parametrize("backend", BACKENDS)
def test_forcing_a_variable_while_halted_at_a_statement_goes_on_from_that_statement(backend):
    """A force of a variable while the debugger holds its procedure before a
    statement (mid-tick) changes where the procedure is not: it goes on from that
    statement, which runs once, and the statements before it keep being watched
    (issue 23 point 4: the tick ran again from the procedure's start, or the rest
    of the tick ran inside the force)."""
    c = controller(compile_proc(BRANCHES, "M10"), backend=backend)
    c.start("M10")
    c.debugger.set_breakpoints("M10.plc", [{"line": 7, "hit": {"mode": "eq", "n": 3}}])
    c.step(50)
    assert c.debugger.halted_state()["line"] == 7 and c.variables()["M10"]["y"] == 2
    c.force("M10.x", 4)
    assert c.debugger.halted_state()["line"] == 7 and c.variables()["M10"]["y"] == 2
    path = []
    for _ in range(6):
        c.debugger.step("into")
        while not c.debugger.halted:
            c.step(1)
        path.append((c.t_ms, c.debugger.halted_state()["line"], c.variables()["M10"]["y"]))
    # y = y + 1 ran once; then x reads 4 (forced): the branch is not taken again
    assert path == [(2, 9, 3), (2, 10, 3), (3, 5, 3), (3, 6, 3), (3, 9, 3), (3, 10, 3)]
