"""The timing rules of the hardware PLC and the software PLC (docs/controller.md,
"Timing rules"), one test per sentence, each quoting its sentence; every test
runs on both VM backends."""

from __future__ import annotations

import pytest

from plcbuilder.controller.controller import Controller
from plcbuilder.controller.events import Ended, Fault, Message, Note, Print, Started

from tests.controller._sim import compile_proc, controller, ended, of, run_hw


@pytest.fixture(params=["fast", "reference"])
def backend(request):
    return request.param


def prints(events):
    return [(e.t_ms, e.register, e.value) for e in events if isinstance(e, Print)]


# ====================================================== hardware PLC timing

def test_time_advances_in_ticks_of_1_ms(backend):
    """Time advances in ticks of 1 ms."""
    c = controller(compile_proc("main(){ do { n++; } while (1); };"), backend=backend)
    c.start("M03")
    c.step(25)
    assert c.t_ms == 25
    assert [s.t_ms for s in c.drain_samples()] == list(range(25))
    assert c.variables()["M03"]["n"] == 25


def test_one_hardware_procedure_runs_at_a_time(backend):
    """One hardware procedure runs at a time."""
    a = compile_proc("main(){ do { } while (1); };", "M10")
    b = compile_proc("main(){ do { } while (1); };", "M11")
    c = controller(a, b, backend=backend)
    c.start("M10")
    c.step(3)
    c.start("M11")
    c.step(3)
    assert c.state().running == "M11"
    assert [e.name for e in c.drain_events() if isinstance(e, Ended)] == ["M10"]


def test_a_procedure_started_at_tick_t_begins_executing_in_tick_t(backend):
    """A procedure started at tick t begins executing in tick t."""
    c = controller(compile_proc("main(){ gvarset(20000, 1); exit(99); };"), backend=backend)
    c.step(7)
    c.start("M03")
    c.step(1)
    ev = c.drain_events()
    assert prints(ev) == [(7, 20000, 1)]
    assert [e.t_ms for e in ev if isinstance(e, (Started, Ended))] == [7, 7]


def test_it_runs_until_the_end_of_a_loop_iteration_or_until_it_ends(backend):
    """It runs until it reaches the end of a loop iteration (the point where a
    do…while or while condition is evaluated) or ends."""
    src = """main(){
        gvarset(20000, 1); gvarset(20001, 2);
        n = 0; do { gvarset(20002, n); n++; } while (n < 3);
        gvarset(20003, 4); exit(99);
    };"""
    _, ev = run_hw(src, backend=backend)
    assert prints(ev) == [(0, 20000, 1), (0, 20001, 2), (0, 20002, 0), (1, 20002, 1),
                          (2, 20002, 2), (3, 20003, 4)]


def test_reaching_the_end_of_an_iteration_ends_the_tick_even_when_the_loop_stops(backend):
    """Reaching the end of an iteration ends the tick, whether the loop goes on or
    not; the next statement runs in the next tick."""
    src = "main(){ do { } while (0); gvarset(20000, 9); exit(99); };"
    _, ev = run_hw(src, backend=backend)
    assert prints(ev) == [(1, 20000, 9)]
    assert ended(ev).t_ms == 1


def test_while_loop_condition_ends_each_iteration(backend):
    """A loop that runs N iterations takes exactly N ms (while as well)."""
    src = "main(){ n = 0; while (n < 4) { n++; }; exit(99); };"
    _, ev = run_hw(src, backend=backend)
    assert ended(ev).t_ms == 4


def test_a_loop_of_n_iterations_takes_n_ms_the_delay_example_ends_at_10(backend):
    """So a loop that runs N iterations takes exactly N ms: a procedure started at
    t = 0 with timer=10; do{timer--;}while(timer>0); exit(99); ends at t = 10 ms."""
    _, ev = run_hw("main(){ timer=10; do{timer--;}while(timer>0); exit(99); };",
                   backend=backend)
    e = ended(ev)
    assert (e.t_ms, e.exit_code, e.exit_name) == (10, 99, "plc_exit_normal")


def test_writes_to_outputs_pwm_and_dac_take_effect_at_once(backend):
    """Writes to outputs, PWM and DAC take effect at once (portset(3);
    a=gvarget(0x403); reads 1)."""
    src = """main(){ portset(3); a=gvarget(0x403);
        pwm01=1234; p=gvarget(7278); dac02=77; d=gvarget(7271); exit(99); };"""
    c, ev = run_hw(src, backend=backend)
    v = c.variables()["M03"]
    assert (v["a"], v["p"], v["d"]) == (1, 1234, 77)
    assert ended(ev).t_ms == 0


def test_message_is_sent_at_the_end_of_the_tick_with_command_and_parameter(backend):
    """At the end of every tick: if message is not 0, one message event {t,
    message, command=var00, parameter=var01} is sent to the host and message
    becomes 0."""
    src = """main(){
        command=120; parameter=5; message=PLCCMD_REPLY_TO_MYCNC;
        command=121;                       // the values at the end of the tick count
        timer=2; do { timer--; } while (timer > 0);
        m = message;
        exit(99);
    };"""
    c, ev = run_hw(src, backend=backend)
    msgs = of(ev, Message)
    assert [(m.t_ms, m.message, m.name, m.command, m.parameter, m.source) for m in msgs] == \
        [(0, 1100, "PLCCMD_REPLY_TO_MYCNC", 121, 5, "M03")]
    assert c.variables()["M03"]["m"] == 0 and c.variables()["M03"]["message"] == 0


def test_the_state_is_sampled_at_the_end_of_every_tick(backend):
    """the state is sampled for telemetry and the trace (after the message)."""
    src = "main(){ portset(2); proc=70; message=146; do { } while (0); exit(99); };"
    c = controller(compile_proc(src), backend=backend)
    c.start("M03")
    c.step(3)
    s = c.drain_samples()
    assert [(x.t_ms, x.running, x.proc, x.message) for x in s] == \
        [(0, "M03", 70, 146), (1, None, 70, 0), (2, None, 70, 0)]
    assert s[0].outputs[0] == 0b100


def test_the_motion_controller_advances_1_ms_each_tick(backend):
    """the motion controller advances 1 ms."""
    src = """main(){ g0moveA(0x3, 1, 10100);
        do { c = gvarget(6060); } while (c != 0);
        do { c = gvarget(6060); } while (c != 0x4d); exit(99); };"""
    c, ev = run_hw(src, ms=20_000, backend=backend)
    assert c.state().axes["X"] == 10100
    assert c.machine.t_ms == c.t_ms


def test_an_input_change_scheduled_for_t_is_seen_from_tick_t_on(backend):
    """An input change scheduled for t is seen from tick t on."""
    src = "main(){ do { s = portget(9); n++; } while (s == 0); exit(99); };"
    c = controller(compile_proc(src), backend=backend)
    c.start("M03")
    c.step(40)
    c.set_input(9, 1)          # before tick 40 runs
    c.run_until_idle(100)
    # the iteration of tick 40 (the 41st) sees it; exit() runs in the next tick
    assert c.variables()["M03"]["n"] == 41
    assert ended(c.drain_events()).t_ms == 41


def test_an_input_set_by_hand_overrides_the_wiring_from_then_on(backend):
    """an input set by hand (a scenario, the IDE, the server) overrides the
    machine's own wiring of that pin from then on."""
    # INPUT_HOME_X (0) is wired to X <= 0; X starts at 100 mm, so it reads 0
    src = "main(){ a = portget(0); do { } while (0); b = portget(0); exit(99); };"
    c = controller(compile_proc(src), backend=backend)
    c.start("M03")
    c.step(1)
    c.set_input(0, 1)
    c.run_until_idle(10)
    v = c.variables()["M03"]
    assert (v["a"], v["b"]) == (0, 1)


def test_exit_ends_the_procedure_in_that_tick_and_the_event_carries_vexit(backend):
    """exit(code) ends the procedure in that tick with that exit code; the event
    carries vexit too."""
    _, ev = run_hw("main(){ vexit=42; exit(7); gvarset(20000,1); };", backend=backend)
    e = ended(ev)
    assert (e.t_ms, e.exit_code, e.vexit) == (0, 7, 42)
    assert not prints(ev)


def test_exit_codes_are_named_from_the_seed_table(backend):
    """Codes are named from the seed's exit-code table (99 plc_exit_normal)."""
    for code, name in [(99, "plc_exit_normal"), (7, "plc_exit_probe_error"),
                       (3, "plc_exit_plasma_timeout"), (55, None)]:
        _, ev = run_hw(f"main(){{ exit({code}); }};", backend=backend)
        assert ended(ev).exit_name == name


def test_falling_off_the_end_of_main_ends_it_with_code_0(backend):
    """Falling off the end of main ends it with code 0."""
    _, ev = run_hw("main(){ a = 1; };", backend=backend)
    assert (ended(ev).exit_code, ended(ev).t_ms) == (0, 0)


def test_starting_a_procedure_while_another_runs_breaks_it_and_starts_in_the_same_tick(backend):
    """Starting a procedure while another runs ends the running one at once with
    code 100 (plc_exit_extern_break), and the new one begins in the same tick."""
    a = compile_proc("main(){ do { gvarset(20000, 1); } while (1); };", "M10")
    b = compile_proc("main(){ gvarset(20001, 2); exit(99); };", "M11")
    c = controller(a, b, backend=backend)
    c.start("M10")
    c.step(5)
    c.start("M11", eparam=3)
    c.step(1)
    ev = c.drain_events()
    tail = [e for e in ev if e.t_ms == 5]
    assert [(type(e).__name__, getattr(e, "name", None)) for e in tail] == \
        [("Ended", "M10"), ("Started", "M11"), ("Print", None), ("Ended", "M11")]
    br = tail[0]
    assert (br.exit_code, br.exit_name) == (100, "plc_exit_extern_break")
    assert prints(ev)[-1] == (5, 20001, 2)


@pytest.mark.parametrize("src,line,text", [
    ("main(){\n a=eparam;\n b=10/a;\n exit(99);\n};", 3, "division by zero"),
    ("main(){\n a=eparam;\n b=10%a;\n exit(99);\n};", 3, "modulo by zero"),
    ("f(){ n++; f(); };\nmain(){\n f();\n exit(99);\n};", 3, "call depth over 16"),
])
def test_a_runtime_fault_ends_the_procedure_names_the_line_and_sends_err_vm(src, line, text,
                                                                         backend):
    """A runtime fault (division by zero, call depth over 16, more than 100 000
    instructions in one tick) ends the procedure with a fault event that names
    the source line, and a PLC_MESSAGE_ERR_VM (-1) message."""
    c, ev = run_hw(src, backend=backend)
    f = of(ev, Fault)
    assert len(f) == 1 and f[0].line == line and f[0].file == "M03.plc"
    assert f[0].text.startswith(text)
    assert ended(ev).exit_code == -1
    m = of(ev, Message)
    assert [(x.message, x.name) for x in m] == [(-1, "PLC_MESSAGE_ERR_VM")]
    assert c.state().running is None


def test_too_many_instructions_in_one_tick_is_a_fault(backend):
    """more than 100 000 instructions in one tick (here: 10^6 calls in a tick)."""
    src = """l4(){ n++; };
    l3(){ l4(); l4(); l4(); l4(); l4(); l4(); l4(); l4(); l4(); l4(); };
    l2(){ l3(); l3(); l3(); l3(); l3(); l3(); l3(); l3(); l3(); l3(); };
    l1(){ l2(); l2(); l2(); l2(); l2(); l2(); l2(); l2(); l2(); l2(); };
    l0(){ l1(); l1(); l1(); l1(); l1(); l1(); l1(); l1(); l1(); l1(); };
    main(){
      l0(); l0(); l0(); l0(); l0(); l0(); l0(); l0(); l0(); l0(); l0(); l0(); l0();
      l0(); l0(); l0(); l0(); l0(); l0(); l0(); l0(); l0(); l0(); l0(); l0(); l0();
      exit(99);
    };"""
    c, ev = run_hw(src, backend=backend)
    f = of(ev, Fault)
    assert len(f) == 1 and "100000 instructions" in f[0].text and f[0].line == 7
    chain = [c[2] for c in f[0].calls]
    assert chain[:4] == ["main", "l0", "l1", "l2"] and chain[-1] in ("l3", "l4")
    n = c.variables()["M03"]["n"]
    assert 20_000 < n < 100_000


# ==================================================================== stop

def _stop_project(backend, with_off=True):
    progs = [compile_proc("main(){ portset(4); do { } while (1); };", "M03"),
             compile_proc("main(){ gvarset(20000, 2); do { } while (1); };", "M02")]
    if with_off:
        progs.append(compile_proc("main(){ gvarset(20000, 3); exit(99); };", "OFF"))
    c = controller(*progs, backend=backend)
    c.start("M03")
    c.step(5)
    return c


def test_stop_once_starts_m02_twice_starts_off_and_leaves_outputs(backend):
    """Stop: pressing Stop once starts M02, twice starts OFF (where the project
    has them); a stop leaves outputs as the procedures left them."""
    c = _stop_project(backend)
    assert c.stop() == "M02"
    c.step(5)
    assert c.stop() == "OFF"
    c.step(5)
    ev = c.drain_events()
    assert [p[2] for p in prints(ev)] == [2, 3]
    assert [e.name for e in of(ev, Started)] == ["M03", "M02", "OFF"]
    assert 4 in c.state().outputs


def test_stop_without_off_ends_the_running_procedure(backend):
    c = _stop_project(backend, with_off=False)
    assert c.stop() == "M02"
    c.step(2)
    assert c.stop() is None
    c.step(1)
    assert c.state().running is None
    assert ended(c.drain_events(), "M02").exit_code == 100


# ==================================================================== starts

def test_an_m_code_starts_its_procedure_with_eparam(backend):
    """Ways to start a procedure: an M-code (M03 starts M03.plc, with eparam)."""
    c = controller(compile_proc("main(){ v = eparam; exit(99); };", "M03"), backend=backend)
    assert c.start_mcode(3, eparam=1500) == "M03"
    c.step(1)
    assert c.variables()["M03"]["v"] == 1500


def test_an_input_pin_edge_bound_to_a_procedure_starts_it(backend):
    """Ways to start a procedure: … an input pin edge bound to it."""
    c = controller(compile_proc("main(){ v = eparam; do { } while (1); };", "M88"),
                   backend=backend)
    c.bind_input(9, "M88", eparam=5)
    c.step(20)
    c.set_input(9, 1)                 # 0 -> 1 before tick 20: M88 starts in tick 20
    c.step(10)
    c.set_input(9, 1)                 # no edge
    c.step(10)
    c.set_input(9, 0)
    c.step(10)
    c.set_input(9, 1)                 # a second edge restarts it
    c.step(1)
    ev = c.drain_events()
    assert [(e.t_ms, e.name, e.eparam) for e in of(ev, Started)] == [(20, "M88", 5),
                                                                    (50, "M88", 5)]
    assert c.variables()["M88"]["v"] == 5
    c.unbind_input(9)
    c.set_input(9, 0)
    c.step(1)
    c.set_input(9, 1)
    c.step(1)
    assert not of(c.drain_events(), Started)


def test_a_software_procedure_starts_a_hardware_one_with_100041_and_100040(backend):
    """… and a software procedure writing gvarset(100041, eparam);
    gvarset(100040, N); (starts M<N>)."""
    sw = compile_proc("main(){ gvarset(100041, 333); gvarset(100040, 602); exit(99); };",
                      "launcher", software=True)
    hw = compile_proc("main(){ v = eparam; exit(99); };", "M602")
    c = controller(sw, hw, backend=backend)
    c.run_until_idle(1000)
    ev = c.drain_events()
    st = [e for e in of(ev, Started) if e.name == "M602"]
    # the software PLC runs after the hardware PLC in tick 0: M602 starts in tick 1
    assert [(e.t_ms, e.eparam, e.kind) for e in st] == [(1, 333, "hardware")]
    assert c.variables()["M602"]["v"] == 333


def test_a_software_start_of_a_missing_procedure_is_a_warning(backend):
    sw = compile_proc("main(){ gvarset(100040, 77); exit(99); };", "launcher", software=True)
    c = controller(sw, backend=backend)
    c.step(1)
    notes = [e for e in c.drain_events() if isinstance(e, Note)]
    assert notes and "M77" in notes[0].text and notes[0].level == "warning"


def test_prints_from_every_procedure(backend):
    """20000..20100: writing prints the value in the host's message log (a print
    event {t, register, value}). The software procedure prints first: "in a tick
    where software procedures run, they run before the hardware procedure"."""
    hw = compile_proc("main(){ gvarset(20000, 5); gvarset(20100, 0-1); gvarset(20101, 9); "
                      "exit(99); };", "M03")
    sw = compile_proc("main(){ gvarset(20050, Param + 1); exit(99); };", "S", software=True)
    c = controller(hw, sw, backend=backend)
    c.start("M03")
    c.step(1)
    ev = c.drain_events()
    assert [(e.t_ms, e.register, e.value, e.source) for e in of(ev, Print)] == \
        [(0, 20050, 1, "S"), (0, 20000, 5, "M03"), (0, 20100, -1, "M03")]


def test_gvarget_latency_defaults_to_0_and_can_be_set(backend):
    """A host round-trip latency for gvarget of plain registers can be set; the
    default is 0."""
    src = "main(){ gvarset(4000, 5); a = 1 + gvarget(4000); b = gvarget(7180); exit(99); };"
    c, ev = run_hw(src, backend=backend)
    assert ended(ev).t_ms == 0 and c.variables()["M03"]["a"] == 6
    c, ev = run_hw(src, backend=backend, gvarget_latency_ms=50)
    assert ended(ev).t_ms == 50 and c.variables()["M03"]["a"] == 6


def test_software_procedures_jog_with_100020_plus_axis(backend):
    """Software procedures jog with gvarset(100020 + axis, speed) (negative speed
    via 0-X)."""
    sw = compile_proc("main(){ gvarset(100020, 0-1000); do { } while (1); };", "J",
                      software=True)
    c = controller(sw, backend=backend)
    c.step(1000)
    assert c.state().axes["X"] < 10000 - 500


def test_variables_start_at_0_except_eparam_var00_15_and_param(backend):
    """Every variable is 0 when a procedure starts, except the predefined ones
    (eparam, var00..var15 from plc-variables.xml, Param in software)."""
    hw = compile_proc("main(){ a = x; b = eparam; c = var00; d = var15; e = command; "
                      "exit(99); };", "M03")
    sw = compile_proc("main(){ p = Param; q = var01; exit(99); };", "__S", software=True)
    c = Controller(backend=backend, variables=list(range(100, 116)))
    c.load([hw, sw])
    c.start("M03", eparam=-9)
    c.start("__S", eparam=12)
    c.step(1)
    v = c.variables()
    assert [v["M03"][k] for k in "abcde"] == [0, -9, 100, 115, 100]
    assert (v["__S"]["p"], v["__S"]["q"]) == (12, 101)


# ========================================================= software PLC

def test_software_ticks_are_100_ms(backend):
    """Ticks of 100 ms."""
    sw = compile_proc("main(){ do { gvarset(20000, n); n++; } while (1); };", "S",
                      software=True)
    c = controller(sw, backend=backend)
    c.step(350)
    assert [p[0] for p in prints(c.drain_events())] == [0, 100, 200, 300]


def test_software_procedures_start_with_the_controller_and_after_build_all(backend):
    """Every software procedure whose name does not start with __ is started when
    the controller starts and after Build All, and all run side by side."""
    a = compile_proc("main(){ do { n++; } while (1); };", "A", software=True)
    b = compile_proc("main(){ do { n++; } while (1); };", "B", software=True)
    sys_ = compile_proc("main(){ do { n++; } while (1); };", "__SYS", software=True)
    c = controller(a, b, sys_, backend=backend)
    c.step(250)
    assert c.state().software == ("A", "B")
    c.load([a, b, sys_])               # Build All again: they restart
    c.step(100)
    ev = c.drain_events()
    assert [(e.t_ms, e.name) for e in of(ev, Started)] == [(0, "A"), (0, "B"), (300, "A"),
                                                          (300, "B")]
    assert [(e.name, e.exit_code) for e in of(ev, Ended)] == [("A", 100), ("B", 100)]


def test_software_procedures_end_ticks_at_loop_iterations_like_hardware(backend):
    """each ends its tick at the end of a loop iteration, exactly as on the
    hardware PLC but with 100 ms ticks."""
    sw = compile_proc("main(){ timer=3; do { timer--; } while (timer > 0); exit(99); };", "S",
                      software=True)
    c = controller(sw, backend=backend)
    c.run_until_idle(10_000)
    assert ended(c.drain_events()).t_ms == 300


def test_software_order_within_a_tick_is_by_name_and_runs_repeat_exactly(backend):
    """Their order within a tick is deterministic (by name), so a run can be
    repeated exactly."""
    progs = [compile_proc(f"main(){{ do {{ gvarset(20000, {i}); }} while (1); }};", name,
                          software=True) for i, name in enumerate(["zeta", "Alpha", "mid"])]

    def once():
        c = controller(*progs, backend=backend)
        c.step(201)
        return c.drain_events(), c.drain_samples()

    first = once()
    assert [e.source for e in of(first[0], Print)][:3] == ["Alpha", "mid", "zeta"]
    assert once() == first


def test_software_procedures_reach_the_hardware_through_the_host(backend):
    """They reach the hardware through the host (portget, portset, gvarget, gvarset
    all work)."""
    sw = compile_proc("main(){ portset(5); a = portget(6); b = gvarget(0x405); "
                      "gvarset(7278, 99); c = gvarget(7278); exit(99); };", "S", software=True)
    c = controller(sw, backend=backend)
    c.step(1)
    v = c.variables()["S"]
    assert (v["a"], v["b"], v["c"]) == (1, 1, 99)      # input 6 (air pressure) reads 1
    assert 5 in c.state().outputs and c.state().pwm[0] == 99


def test_system_procedures_start_on_their_events(backend):
    """__HANDLER_INIT when the controller has started and received its
    configuration, __HANDLER_EXIT before it shuts down, __HANDLER_GCODE_START and
    __HANDLER_GCODE_STOP when a program is started and stopped; any other __ name
    only by hand."""
    names = ["__HANDLER_INIT", "__HANDLER_EXIT", "__HANDLER_GCODE_START",
             "__HANDLER_GCODE_STOP", "__BV17"]
    progs = [compile_proc(f"main(){{ gvarset(20000, {i}); exit(99); }};", n, software=True)
             for i, n in enumerate(names)]
    c = controller(*progs, backend=backend)
    c.step(150)
    assert c.event("GCODE_START") and c.event("__HANDLER_GCODE_STOP")
    assert not c.event("NO_SUCH_EVENT")
    c.step(100)
    c.load(progs)                       # a second load does not run INIT again
    c.step(100)
    c.shutdown()
    ev = c.drain_events()
    assert [(e.t_ms, e.name) for e in of(ev, Started)] == [
        (0, "__HANDLER_INIT"), (200, "__HANDLER_GCODE_START"), (200, "__HANDLER_GCODE_STOP"),
        (400, "__HANDLER_EXIT")]
    c2 = controller(*progs, backend=backend)
    c2.start("__BV17")
    c2.step(1)
    assert [e.name for e in of(c2.drain_events(), Started)] == ["__HANDLER_INIT", "__BV17"]


def test_a_software_procedure_started_by_hand_starts_at_the_next_software_tick(backend):
    sw = compile_proc("main(){ gvarset(20000, Param); exit(99); };", "__S", software=True)
    c = controller(sw, backend=backend)
    c.step(130)
    c.start("__S", eparam=4)
    c.step(100)
    assert prints(c.drain_events()) == [(200, 20000, 4)]


# ============================================================ one tick, fast paths

def test_the_fast_paths_run_exactly_as_the_tick_function(backend):
    """Where only a hardware procedure runs, or nothing does, PLC.run takes a
    fast path; an input bound to a procedure sends every tick through the tick
    function instead. Both give the same events and samples, tick for tick:
    messages, prints, motion, a procedure started by a software one, a fault."""
    m10 = compile_proc("""main(){
        timer=30; do { timer--; if (timer==20) { message=PLCCMD_LINE_STOP; };
                       if (timer==10) { gvarset(20000, timer); }; } while (timer>0);
        g0moveA(0, 1, 500);
        do { s=gvarget(6060); } while (s==0);
        portset(3);
        timer=40; do { timer--; } while (timer>0);
        a=5/eparam;
        exit(99); };""", "M10")
    m11 = compile_proc("""main(){ timer=5; do { timer--; } while (timer>0);
        message=PLCCMD_MOTION_PAUSE; exit(99); };""", "M11")
    s1 = compile_proc("""main(){ n=0; do { n++;
        if (n==3) { message=PLC_MESSAGE_PRESSED_ALARM_KEY; };
        if (n==12) { gvarset(100040, 11); }; } while (n<15); exit(99); };""", "S1",
                      software=True)

    def session(bound: bool):
        c = controller(m10, m11, s1, backend=backend)
        plc = c.plc
        fast = []
        hardware_alone, machine_alone = plc._hardware_alone, plc._machine_alone
        plc._hardware_alone = lambda *a: fast.append("hw") or hardware_alone(*a)
        plc._machine_alone = lambda *a: fast.append("idle") or machine_alone(*a)
        if bound:
            c.set_input(40, 0)
            c.bind_input(40, "M11")          # never rises: every tick is the general one
        c.start("M10")
        for ms in (1, 37, 250, 99, 100, 3):
            c.step(ms)
        c.run_until_idle(3000)
        c.start("M11")
        c.run_until_idle(3000)
        return c.drain_events(), c.drain_samples(), c.t_ms, fast

    events, samples, t_end, fast = session(bound=False)
    events2, samples2, t_end2, fast2 = session(bound=True)
    assert "hw" in fast and "idle" in fast and fast2 == []
    assert of(events, Fault) and of(events, Message) and of(events, Print)
    # S1, started by the load, "begins in the tick of the first load, before any
    # procedure started at that same tick"
    assert [e.name for e in of(events, Started)] == ["S1", "M10", "M11", "M11"]
    assert events == events2 and samples == samples2 and t_end == t_end2


@pytest.mark.parametrize("clock", [0, 7])
def test_the_plain_hardware_path_runs_exactly_as_the_tick_function(backend, clock):
    """Without samples, a hardware procedure that never writes its ``message``
    runs through the plainest fast path (the machine's clock set from the tick,
    no message asked): the same events, machine clock and positions as the
    tick function gives, with a message written from outside between steps,
    motion (the machine not quiet), prints, a start due and a fault; also with
    a machine whose clock ran before the PLC (``clock`` ms)."""
    m10 = compile_proc("""main(){
        timer=300; do { timer--; if (timer==10) { gvarset(20000, timer); }; } while (timer>0);
        g0moveA(0, 1, 500);
        do { s=gvarget(6060); n++; } while (s==0);
        timer=700; do { timer--; } while (timer>0);
        a=5/eparam;
        exit(99); };""", "M10")
    s1 = compile_proc("""main(){ n=0; do { n++; if (n==30) { gvarset(100040, 11); }; }
        while (n<35); exit(99); };""", "S1", software=True)
    m11 = compile_proc("main(){ timer=5; do { timer--; } while (timer>0); exit(98); };", "M11")

    def session(bound: bool):
        c = Controller(backend=backend, record_samples=False)
        c.machine.t_ms = clock
        c.load([m10, m11, s1])
        plc = c.plc
        fast = []
        hardware_alone = plc._hardware_alone
        plc._hardware_alone = lambda *a: fast.append("hw") or hardware_alone(*a)
        if bound:
            c.set_input(40, 0)
            c.bind_input(40, "M11")          # never rises: every tick is the general one
        c.start("M10")
        seen = []
        for ms in (1, 37, 250, 99, 100, 3, 1200, 98):
            c.step(ms)
            if ms == 99:
                c.write("M10.message", 23)   # sent at the end of the next tick (387)
            seen.append((c.t_ms, c.machine.t_ms, tuple(c.machine.motion.ipos)))
        c.run_until_idle(3000)
        seen.append((c.t_ms, c.machine.t_ms))
        return c.drain_events(), seen, fast

    events, seen, fast = session(bound=False)
    events2, seen2, fast2 = session(bound=True)
    assert "hw" in fast and fast2 == []
    assert of(events, Fault) and of(events, Print)
    assert [(e.t_ms, e.message, e.source) for e in of(events, Message)][0] == (387, 23, "M10")
    assert [e.name for e in of(events, Started)] == ["S1", "M10", "M11"]
    assert events == events2 and seen == seen2
    assert all(s[1] == s[0] + clock for s in seen)


# ------------------------------------------------- the software grid and order
def test_the_software_grid_starts_at_the_first_load(backend):
    """"The software grid starts at the tick of the controller's first load (so
    software ticks fall at load + k·100 ms)"; later loads keep it."""
    sw = compile_proc("main(){ do { gvarset(20001, 1); } while(1); };", "S", software=True)
    c = Controller(backend=backend)
    c.step(37)
    c.load([sw])
    c.step(250)
    assert [e.t_ms for e in of(c.drain_events(), Print)] == [37, 137, 237]
    c.load([sw])                        # Build All again at 287: the grid stays
    c.step(100)
    assert [e.t_ms for e in of(c.drain_events(), Print)] == [337]


def test_software_runs_before_hardware_in_a_shared_tick(backend):
    """"in a tick where software procedures run, they run before the hardware
    procedure": a software write is seen by the hardware procedure in that tick,
    and the hardware procedure's write only by the next software tick."""
    sw = compile_proc("main(){ do { gvarset(9000, gvarget(9000) + 1); "
                      "gvarset(20002, gvarget(9001)); } while(1); };", "S", software=True)
    hw = compile_proc("main(){ do { gvarset(9001, gvarget(9000)); } while(1); };", "M03")
    c = controller(hw, sw, backend=backend)
    c.start("M03")
    c.step(201)
    assert c.machine.gvarget(9001) == 3
    assert [(e.t_ms, e.value) for e in of(c.drain_events(), Print)] == [(0, 0), (100, 1),
                                                                        (200, 2)]


def test_handler_init_runs_before_a_hardware_start_in_the_load_tick(backend):
    """__HANDLER_INIT "begins in the tick of the first load, before any procedure
    started at that same tick, so 'upload, then start M03 at once' leaves the
    spindle on"."""
    init = compile_proc("main(){ portclear(0); exit(99); };", "__HANDLER_INIT", software=True)
    m03 = compile_proc("main(){ portset(0); exit(99); };", "M03")
    c = Controller(backend=backend)
    c.step(5)
    c.load([init, m03])
    c.start("M03")
    c.step(1)
    started = [(e.t_ms, e.name) for e in of(c.drain_events(), Started)]
    assert started == [(5, "__HANDLER_INIT"), (5, "M03")]
    assert c.machine.outputs_on() == [0]
