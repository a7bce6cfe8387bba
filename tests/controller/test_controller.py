"""The Controller facade that the server, the IDE and ``plcbuilder run`` build on."""

from __future__ import annotations

import json

import pytest

from plcbuilder.bytecode.opcodes import Op
from plcbuilder.bytecode.program import Kind, Program
from plcbuilder.controller.events import ControllerStatus
from plcbuilder.controller.controller import Controller, ControllerError
from plcbuilder.controller.events import Started, to_dict
from plcbuilder.controller.scenario import (Scenario, ScenarioError, drive, parse_adc,
                                            parse_input, parse_start)

from tests.controller._asm import L, assemble
from tests.controller._sim import compile_proc, controller


def test_load_refuses_what_is_not_a_valid_program_and_keeps_the_previous_set():
    good = compile_proc("main(){ exit(99); };", "M03")
    c = controller(good)
    bad = Program("BAD", Kind.HARDWARE, bytes([Op.JMP8, 50]))
    with pytest.raises(ControllerError, match="BAD: invalid code"):
        c.load([bad])
    with pytest.raises(ControllerError, match="two procedures named M03"):
        c.load([good, good])
    with pytest.raises(ControllerError, match="not a compiled procedure"):
        c.load(["M03"])
    assert list(c.programs) == ["M03"]


def test_start_of_an_unknown_procedure_says_what_is_loaded():
    c = controller(compile_proc("main(){ exit(99); };", "M03"))
    with pytest.raises(ControllerError, match=r"no procedure named 'M04' is loaded \(loaded: M03\)"):
        c.start("M04")
    with pytest.raises(ControllerError, match="M05"):
        c.start_mcode(5)
    with pytest.raises(ControllerError, match="nothing is loaded"):
        Controller().start("M03")
    with pytest.raises(ControllerError, match="eparam must be an integer"):
        c.start("M03", eparam="x")


def test_start_mcode_finds_two_digit_and_long_names():
    c = controller(compile_proc("main(){ exit(99); };", "M03"),
                   compile_proc("main(){ exit(98); };", "M602"))
    assert c.start_mcode(3) == "M03"
    assert c.start_mcode(602) == "M602"


def test_state_reports_what_the_server_needs():
    hw = compile_proc("main(){ portset(1); pwm02 = 5; proc = 70; do { } while (1); };", "M03")
    sw = compile_proc("main(){ do { } while (1); };", "lube", software=True)
    c = controller(hw, sw)
    c.start("M03")
    c.step(3)
    st = c.state()
    assert st.t_ms == 3 and st.running == "M03" and st.software == ("lube",)
    assert st.proc == 70 and st.proc_name == "plc_proc_spindle"
    assert st.outputs == (1,) and st.pwm[1] == 5 and len(st.dac) == 8
    assert st.axes == {"X": 10000, "Y": 10000, "Z": 2000}
    assert [(i["name"], i["kind"], i["size"]) for i in st.image] == \
        [("M03", "hardware", hw.code_size), ("lube", "software", sw.code_size)]
    assert st.image[0]["crc32"] == hw.crc32
    json.dumps(st.to_dict())


def test_proc_is_kept_after_the_procedure_ends():
    c = controller(compile_proc("main(){ proc = 33; exit(99); };", "M03"))
    c.start("M03")
    c.step(5)
    assert c.state().proc == 33 and c.state().running is None


def test_variables_by_procedure_and_name():
    c = controller(compile_proc("main(){ speed = 5; exit(99); };", "M03"))
    c.start("M03")
    c.step(1)
    v = c.variables()["M03"]
    assert v["speed"] == 5 and v["eparam"] == 0 and "var15" in v and "Param" not in v


def test_events_and_samples_drain_and_serialise():
    c = controller(compile_proc("main(){ message = 146; do { } while (0); exit(99); };"))
    c.start("M03")
    c.step(3)
    ev = c.drain_events()
    assert [e.type for e in ev] == ["started", "message", "ended"]
    assert c.drain_events() == []
    assert len(c.drain_samples()) == 3 and c.drain_samples() == []
    json.dumps([to_dict(e) for e in ev])


def test_samples_are_not_kept_when_nobody_listens():
    c = Controller(record_samples=False)
    c.step(50)
    assert c.drain_samples() == []
    c.record_samples = True
    c.step(2)
    assert [s.t_ms for s in c.drain_samples()] == [50, 51]


def test_idle_and_run_until_idle():
    c = controller(compile_proc("main(){ timer=5; do { timer--; } while (timer > 0); exit(99); };"))
    assert c.idle()
    c.start("M03")
    assert not c.idle()
    assert c.run_until_idle(1000) == 6          # ticks 0..5; it ends in tick 5
    assert c.idle() and c.t_ms == 6


def test_step_refuses_negative_time():
    with pytest.raises(ControllerError):
        Controller().step(-1)


def test_inputs_out_of_range_are_refused_with_the_reason():
    c = Controller()
    with pytest.raises(ControllerError, match="no input 500"):
        c.set_input(500, 1)
    with pytest.raises(ControllerError, match="ADC"):
        c.set_adc(9, 1)


def test_runs_are_deterministic():
    src = "main(){ do { g0moveA(0, 1, 500); t = gvarget(5021); gvarset(20000, t); } while (1); };"

    def once():
        c = controller(compile_proc(src))
        c.start("M03")
        c.step(300)
        return c.drain_events(), c.drain_samples()

    assert once() == once()


def test_the_translation_is_done_at_load_time():
    from plcbuilder.controller import fastvm
    prog = compile_proc("main(){ n = 17; exit(n); };", "M17")
    fastvm._CACHE.clear()
    controller(prog)
    assert fastvm._CACHE


def test_a_procedure_the_translator_declines_still_runs():
    prog = assemble([L("main"), (Op.PUSH8, 4), Op.POP, Op.POP, Op.RET], name="M04",
                    entry="main")
    c = controller(prog)
    c.start("M04")
    c.step(1)
    assert [e.type for e in c.drain_events()] == ["started", "fault", "ended", "message"]


# ------------------------------------------------------------------ scenario

def test_scenario_lines_and_options():
    sc = Scenario.parse("""# comment
        start M03:12000 @ 5
        input 4=0@150   # trailing comment
        adc 0=0x800 @ 200
        stop @ 500
        event GCODE_START @ 100
        --start M88@7
    """)
    assert [a.describe() for a in sc.ordered()] == [
        "start M03:12000 @ 5", "start M88:0 @ 7", "event GCODE_START @ 100",
        "input 4=0 @ 150", "adc 0=2048 @ 200", "stop @ 500"]
    assert parse_start("M03").t_ms == 0 and parse_start("M03:-5@9").a == -5
    assert parse_input("3=1@0x10").t_ms == 16 and parse_adc("1=-4@2").b == -4


def test_bind_lines_and_errors():
    c = controller(compile_proc("main(){ exit(99); };", "M88"))
    sc = Scenario.parse("bind 9=M88:3 @ 0\ninput 9=1 @ 40")
    assert sc.ordered()[0].describe() == "bind 9=M88:3 @ 0"
    assert drive(c, sc, 1000) == 40
    assert [(e.t_ms, e.eparam) for e in c.drain_events() if e.type == "started"] == [(40, 3)]
    with pytest.raises(ControllerError, match="no procedure named 'M99'"):
        c.bind_input(3, "M99")
    with pytest.raises(ControllerError, match="no input 300"):
        c.bind_input(300, "M88")


def test_fault_events_survive_a_json_round_trip():
    from plcbuilder.controller.events import Fault, from_dict
    f = Fault(1, "M", "a.plc", 3, "x", calls=(("a.plc", 3, "main"), ("a.plc", 9, "f")))
    assert from_dict(json.loads(json.dumps(to_dict(f)))) == f


@pytest.mark.parametrize("text,msg", [
    ("jump M03 @ 5", "unknown action"), ("start 3x @ 1", "not a procedure name"),
    ("input 3=2 @ 1", "0 or 1"), ("input 3 @ 1", "PIN=0|1@MS"), ("adc x=1", "whole number"),
    ("start M03 @ -1", "must not be negative"), ("stop now @ 3", "only a time"),
])
def test_bad_scenario_lines_name_the_line(text, msg):
    with pytest.raises(ScenarioError, match=msg) as exc:
        Scenario.parse("\n" + text, "s.txt")
    assert str(exc.value).startswith("s.txt:2: ")


def test_drive_applies_actions_before_their_tick_and_stops_when_idle():
    hw = compile_proc("main(){ do { s = portget(9); } while (s == 0); exit(99); };", "M88")
    c = controller(hw)
    sc = Scenario.parse("start M88 @ 10\ninput 9=1 @ 30")
    ended = drive(c, sc, 10_000)
    ev = c.drain_events()
    assert [(e.type, e.t_ms) for e in ev] == [("started", 10), ("ended", 31)]
    assert ended == 31 and c.t_ms == 32


def test_drive_stops_at_the_limit_and_waits_for_future_starts():
    hw = compile_proc("main(){ exit(99); };", "M03")
    c = controller(hw)
    assert drive(c, Scenario.parse("start M03 @ 500"), 10_000) == 500
    c2 = controller(compile_proc("main(){ do { } while (1); };", "M03"))
    assert drive(c2, Scenario.parse("start M03 @ 0"), 1234) == 1234
    assert drive(Controller(), Scenario(), 1000) == 0


def test_started_events_carry_the_kind():
    c = controller(compile_proc("main(){ do { } while (1); };", "S", software=True))
    c.step(1)
    assert c.drain_events() == [Started(0, "S", "software", 0)]


def test_the_status_goes_over_the_wire_and_back():
    """ControllerStatus is a JSON object on the link; from_dict ignores keys it
    does not know and gives missing ones their defaults (either side may be newer)."""
    c = controller(compile_proc("main(){ portset(2); do { } while (1); };", "M03"))
    c.start("M03")
    c.step(2)
    st = c.state()
    wire = json.loads(json.dumps(st.to_dict()))
    assert wire["outputs"] == [2] and wire["running"] == "M03"
    assert ControllerStatus.from_dict(wire) == st
    newer = ControllerStatus.from_dict({**wire, "something_new": 1})
    assert newer == st
    older = ControllerStatus.from_dict({"t_ms": 5})
    assert older.t_ms == 5 and older.running is None and older.software == ()
