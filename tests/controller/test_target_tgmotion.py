"""SPEC §9 "tgmotion": TG Motion's virtual PLC schedule, one test a rule."""

from __future__ import annotations

import pytest

from plcbuilder.bytecode import targets as T
from plcbuilder.controller.events import Fault
from tests.controller._targets import controller, faults, notes, tgm



def loop(n: int) -> str:
    """A body of 4 + 5n instructions with its exit(1): i = 0 (2), n iterations
    of INC, LOAD, PUSH, LT, LOOP (5 each), exit(1) (2)."""
    return f"i = 0; do {{ i++; }} while (i < {n});"


def test_program_ini_runs_once():
    """`Program_Ini` runs once"""
    c = controller(tgm(ini="n++;"), "tgmotion")
    c.step(5)
    assert c.plc.calls["Program_Ini"] == 1 and c.variables()["plc"]["n"] == 1


def test_program_ini_returning_0_aborts_the_start():
    """each returns its status with `exit(1)` (0 from `Program_Ini` aborts the
    start with an error)."""
    src = tgm().replace("Program_Ini() {  exit(1); }", "Program_Ini() {\n  exit(0);\n}")
    c = controller(src, "tgmotion")
    c.step(3)
    events = c.drain_events()
    f = [e for e in events if isinstance(e, Fault)]
    assert len(f) == 1 and "Program_Ini returned 0" in f[0].text and f[0].line == 2
    assert any("did not start" in t for t in notes(events, "error"))
    assert c.idle() and "Program_05" not in c.plc.calls


def test_program_ini_runs_to_its_end_however_long():
    """`Program_Ini` runs once, to its end however long ("The execution length
    of this function is not limited"; the instruction limit applies to the
    cyclic programs only)"""
    # clearing all of TGM_Data: 131072 iterations, far over the 100 000 instructions of a call
    src = tgm(head="#include <tgmotion.h>\n",
              ini="i = 0; do { gvarset(TGM_DATA + i, 7); i++; } while (i < TGM_WORDS);")
    c = controller(src, "tgmotion", instruction_ns=1)
    c.step(10)
    assert faults(c) == []
    assert c.plc.calls["Program_Ini"] == 1 and c.variables()["plc"]["i"] == T.TGM_DATA_WORDS
    assert len(c.plc.data) == T.TGM_DATA_WORDS and c.plc.calls["Program_05"] > 0
    # the same loop in a cyclic program is over the limit: a fault
    cyc = controller(tgm(head="#include <tgmotion.h>\n",
                         p04="i = 0; do { i++; } while (i < TGM_WORDS);"), "tgmotion")
    cyc.step(1)
    assert "instructions in one call" in faults(cyc)[0].text


def test_program_ini_time_passes_before_the_first_cycle():
    """"After PLC is started and Program_Ini function is executed successfully,
    cyclical calling of a loop lasting 250 μs is started": its modelled time
    (instructions x instruction_ns) passes first, a tick's worth a tick."""
    # 5 instructions an iteration x 1000 ns: 200 iterations a tick; 1000 of them take 5 ticks
    c = controller(tgm(ini=loop(1000), p04="n4++;"), "tgmotion", instruction_ns=1000)
    c.step(3)
    assert "Program_04" not in c.plc.calls and not c.idle()   # Program_Ini still runs
    c.step(4)
    assert c.variables()["plc"]["i"] == 1000 and c.plc.calls["Program_04"] >= 2


def test_a_program_ini_that_never_ends_never_stops_the_controller():
    """Bad input never crashes anything: an endless Program_Ini runs on, tick by
    tick, and time still advances."""
    c = controller(tgm(ini="do { n++; } while (1);"), "tgmotion")
    c.step(50)
    assert c.t_ms == 50 and faults(c) == [] and c.state().running == "plc"
    assert "Program_05" not in c.plc.calls


def test_a_program_period_over_10000_us_is_accepted():
    """`cycle_time_program_01_us` … `_03_us` (from 100; the seed: "100 μs to 10 000 μs
    (the upper value is not limited)")"""
    c = controller(tgm(), "tgmotion", cycle_time_us=1000, program_periods_us=(20_000, 1000, 100))
    c.step(100)
    assert c.plc.calls["Program_01"] == 5 and c.plc.calls["Program_02"] == 100


@pytest.mark.parametrize("bad", [99, 0, -5])
def test_a_program_period_under_100_us_is_refused(bad):
    from plcbuilder.controller.targets import TargetConfig, TargetConfigError
    with pytest.raises(TargetConfigError, match="at least 100"):
        TargetConfig("tgmotion", program_periods_us=(bad, 1000, 1000)).check()


@pytest.mark.parametrize("cycle,slots", [(250, 5), (500, 5), (1000, 10)])
def test_cycle_split_into_slots_program_05_in_every_slot(cycle, slots):
    """each cycle is split into 5 (250 and 500 µs) or 10 (1000 µs) equal slots;
    `Program_05` runs in every slot"""
    c = controller(tgm(), "tgmotion", cycle_time_us=cycle)
    c.step(4)
    cycles = 4 * 1000 // cycle
    assert c.plc.calls["Program_05"] == cycles * slots
    assert c.plc.calls["Program_04"] == cycles
    assert c.plc.slot_us == cycle / slots


def test_program_04_in_the_fourth_slot_after_program_05_then_the_oscilloscope():
    """`Program_04` runs once per cycle in the fourth slot, after `Program_05`,
    and the oscilloscope samples right after it"""
    c = controller(tgm(p05="n5++;", p04="at = n5; portset(3);"), "tgmotion",
                   cycle_time_us=1000)
    c.step(1)
    assert c.variables()["plc"]["at"] == 4          # the fourth slot's Program_05 ran before it
    c.step(1)
    assert c.variables()["plc"]["at"] == 14         # the next cycle: 10 slots later
    scope = list(c.plc.scope)
    assert c.plc.scope_count == 2 and len(scope) == 2
    t_us, cycle, _inputs, outputs = scope[0]
    assert cycle == 0 and 300 < t_us < 400          # in the fourth slot (300..400 µs)
    assert outputs & (1 << 3)                       # sampled after Program_04's write


def test_programs_01_to_03_at_their_periods():
    """`Program_01`…`03` run at their own periods in the time left"""
    c = controller(tgm(), "tgmotion", cycle_time_us=500, program_periods_us=(1000, 500, 100))
    c.step(10)
    calls = c.plc.calls
    assert (calls["Program_01"], calls["Program_02"], calls["Program_03"]) == (10, 20, 100)


def test_programs_03_then_02_then_01():
    """lowest priority first to be interrupted (`Program_03` before `02` before `01`)"""
    c = controller(tgm(p01="order = order * 10 + 1;", p02="order = order * 10 + 2;",
                       p03="order = order * 10 + 3;"), "tgmotion",
                   program_periods_us=(10_000, 10_000, 10_000))
    c.step(1)
    assert c.variables()["plc"]["order"] == 321


def test_a_long_program_01_is_interrupted_and_03_still_runs_every_slot():
    """lowest priority first to be interrupted (`Program_03` before `02` before
    `01`). Each call runs to completion."""
    # Program_01: about 300 µs of modelled time; the slots of a 500 µs cycle are 100 µs
    c = controller(tgm(p01=loop(3000), p03="n3++;"), "tgmotion",
                   cycle_time_us=500, program_periods_us=(10_000, 10_000, 100))
    c.step(1)                                        # two cycles, ten slots
    assert c.variables()["plc"]["i"] == 3000         # its effects: the whole call at once
    assert c.plc.calls["Program_03"] == 10           # released and run in every slot
    assert c.plc.calls["Program_05"] == 10


def test_budgets_checked_and_reported():
    """Execution time is modelled by a cost per instruction (a project setting,
    default 20 ns), and the budgets of the seed are checked and reported when
    exceeded: `Program_04` ≤ 10 % of the cycle, `Program_05` ≤ 10 µs,
    `Program_01`…`03` ≤ 20 % of their period."""
    src = tgm(p05=loop(200), p04=loop(1000), p02=loop(1000))
    c = controller(src, "tgmotion", cycle_time_us=500, program_periods_us=(1000, 500, 1000))
    c.step(1)
    rep = c.target_report()
    by = {}
    for b in rep["budget"]:
        by.setdefault(b["procedure"], b)
    assert set(by) == {"Program_05", "Program_04", "Program_02"}
    # about 5 instructions an iteration at 20 ns
    assert by["Program_05"]["budget_us"] == 10 and 15 < by["Program_05"]["used_us"] < 30
    assert by["Program_04"]["budget_us"] == 50 and by["Program_04"]["used_us"] > 50
    assert by["Program_02"]["budget_us"] == 100 and by["Program_02"]["used_us"] > 100
    assert by["Program_05"]["cycle"] == 0
    warned = notes(c.drain_events())
    assert any(w.startswith("Program_05 took") and "budget of 10.000 µs" in w for w in warned)
    # the same program within its budgets at 1 ns an instruction
    fast = controller(src, "tgmotion", cycle_time_us=500, program_periods_us=(1000, 500, 1000),
                      instruction_ns=1)
    fast.step(1)
    assert fast.target_report()["budget"] == []


def test_default_instruction_cost_is_20_ns():
    """Execution time is modelled by a cost per instruction (a project setting,
    default 20 ns)"""
    c = controller(tgm(p05=loop(200)), "tgmotion")
    c.step(1)
    b = c.target_report()["budget"][0]
    assert b["procedure"] == "Program_05" and b["used_us"] == (4 + 5 * 200) * 20 / 1000


def test_tgm_data_through_gvarget_and_gvarset():
    """Shared memory (`TGM_Data`, 512 KiB) is reached with `gvarget`/`gvarset` on
    addresses documented by the project."""
    c = controller(tgm(head="#include <tgmotion.h>\n",
                       ini="gvarset(TGM_DATA + TGM_WORDS - 1, 7); "
                           "gvarset(TGM_DATA + TGM_WORDS, 9);",
                       p04="a = gvarget(TGM_DATA + 131071) + 1; gvarset(TGM_DATA + 5, a);"),
                   "tgmotion")
    c.step(1)
    assert c.plc.registers() == {"TGM_Data": {"5": 8, str(T.TGM_DATA_WORDS - 1): 7}}
    assert c.machine.gvarget(T.TGM_DATA_BASE + T.TGM_DATA_WORDS) == 9   # past its end: a plain register
    assert T.TGM_DATA_WORDS * 4 == 512 * 1024


def test_run_report_has_registers_calls_and_budget():
    """`plcbuilder run`'s JSON for these targets gains the registers and, for TG
    Motion, per-program call counts (issue 15)."""
    c = controller(tgm(p04="gvarset(2000000 + 3, 0 - 1);"), "tgmotion", cycle_time_us=1000)
    c.step(2)
    rep = c.target_report()
    assert rep["target_profile"] == "tgmotion"
    assert rep["registers"] == {"TGM_Data": {"3": -1}}
    assert rep["calls"] == {"Program_01": 2, "Program_02": 2, "Program_03": 2,
                            "Program_04": 2, "Program_05": 20, "Program_Ini": 1}
    assert rep["budget"] == [] and rep["cycles"] == 2


def test_seed_program_02_example_runs():
    """The seed's example of an empty Program_02 (``return 1;``, here exit(1)),
    with the other five likewise: the PLC starts and cycles without faults."""
    c = controller("""
        Program_Ini() { exit(1); }
        Program_01() { exit(1); }
        Program_02()
        {
            exit(1);
        }
        Program_03() { exit(1); }
        Program_04() { exit(1); }
        Program_05() { exit(1); }""", "tgmotion")
    c.step(10)
    assert faults(c) == [] and not c.idle() and c.plc.cycle == 20


def test_the_trace_is_the_oscilloscope():
    """The trace of §7 is this target's oscilloscope."""
    # Program_04 sets output 3 and Program_05 clears it again in the slots after
    # the fourth: at the end of the tick it is off, at the oscilloscope's sample on.
    c = controller(tgm(p04="portset(3); after = 1;",
                       p05="if (after) { n = n + 1; if (n > 0) portclr(3); }"), "tgmotion",
                   cycle_time_us=1000)
    c.record_samples = True
    c.step(3)
    assert 3 not in c.machine.outputs_on()
    rows = c.drain_sample_rows()
    assert len(rows) == 3 and all(r[4]["outputs"][0] & (1 << 3) for r in rows)


# ------------------------------------------------ PLC_DATA's shared memories
def test_tgm_system_header_mem_size_data_and_compatibility_id():
    """The seed: "The actual size of the shared memory is contained in the
    TGM_System.HEADER.Mem_Size_Data register", and its Program_Ini checks
    `pHeader->Compatibility_Id != ID_COMPATIBILITY` (then returns 0)."""
    src = tgm(head="#include <tgmotion.h>\n",
              ini="size = gvarget(HEADER_MEM_SIZE_DATA);"
                  "if (gvarget(HEADER_COMPATIBILITY_ID) != ID_COMPATIBILITY) exit(0);")
    c = controller(src, "tgmotion")
    c.step(2)
    assert faults(c) == [] and c.variables()["plc"]["size"] == 524_288


def test_tgm_servo_positions_statuses_and_desired_positions():
    """The seed: "register values of all desired inputs must be loaded ... the
    servo drive positions and statuses" and "sending the desired positions to the
    servo drives": TGM_Servo, one block per axis; the axis follows the desired
    position Program_04 writes every cycle."""
    src = tgm(head="#include <tgmotion.h>\n",
              p04="pos = gvarget(TGM_SERVO + SERVO_ACT_POSITION);"
                  "st = gvarget(TGM_SERVO + SERVO_STATUS);"
                  "if (want < 15000) want = want + 100;"
                  "gvarset(TGM_SERVO + SERVO_DESIRED_POSITION, want);",
              ini="want = gvarget(TGM_SERVO + SERVO_ACT_POSITION);")
    c = controller(src, "tgmotion", cycle_time_us=1000)
    c.step(10)
    v = c.variables()["plc"]
    assert 10000 < v["pos"] < 10400 and v["st"] & 0x3 == 0x3   # present, moving
    c.step(600)                     # it follows at X's rapid speed (16.7 a ms)
    v = c.variables()["plc"]
    assert c.machine.axis_positions()["X"] == 15000 and v["pos"] == 15000
    assert v["st"] == 0x5                               # present, in position
    assert faults(c) == []


def test_tgm_dio_words():
    """The seed: "the values of digital and analog inputs" loaded, "digital and
    analog output values" set "through writing the values in the respective
    registers": TGM_Dio's DI, DO, AI and AO words."""
    src = tgm(head="#include <tgmotion.h>\n",
              p04="di = gvarget(DIO_DI); ai = gvarget(DIO_AI + 1);"
                  "gvarset(DIO_DO, di << 1); gvarset(DIO_AO + 0, 77);")
    c = controller(src, "tgmotion")
    c.set_input(9, 1)
    c.step(2)
    v = c.variables()["plc"]
    assert v["di"] & (1 << 9) and v["ai"] == 2048
    assert 10 in c.machine.outputs_on() and c.machine.sample_fields()["dac"][0] == 77


def test_rtwprintf_prints_in_the_run_log():
    """The seed: "Diagnostic functions from the structure PLC_DATA are used to
    output texts to RTX Server console ... string listing, variable value
    listing (long type variable), formatted text listing": RtWprintf_String,
    RtWprintf_Long and RtWprintf_Ex print in the run log, naming their line."""
    from plcbuilder.controller.events import Log
    src = tgm(ini="RtWprintf_Long(4321);\n  RtWprintf_Ex(2, 0-7);\n  RtWprintf_String(1);")
    c = controller(src, "tgmotion")
    c.step(1)
    logs = [(e.source, e.text) for e in c.drain_events() if isinstance(e, Log)]
    assert logs == [("Program_Ini", "RtWprintf_Long(4321) (plc.plc:1)"),
                    ("Program_Ini", "RtWprintf_Ex(severity 2, -7) (plc.plc:2)"),
                    ("Program_Ini", "RtWprintf_String(1) (plc.plc:3)")]


def test_the_oscilloscope_samples_the_signals_picked():
    """The seed: the oscilloscope "is used to capture the values of desired
    registers within an exact time interval of Cycle_Time and their saving into
    the TGM_Oscilloscope shared memory. This happens after Program_04 function is
    executed." The signals are the project's choice (registers and variables)."""
    src = tgm(head="#include <tgmotion.h>\n", p04="n4++; gvarset(TGM_DATA + 1, n4 * 2);"
              "count = gvarget(TGM_OSC); last = gvarget(OSC_LAST + 1);")
    c = controller(src, "tgmotion", cycle_time_us=1000,
                   scope=("in 9", "plc.n4", "gvar 2000001"))
    c.set_input(9, 1)
    c.step(3)
    rep = c.target_report()["oscilloscope"]
    assert rep["signals"] == ["in 9", "plc.n4", "gvar 2000001"] and rep["samples"] == 3
    assert [s[2:] for s in rep["last"]] == [[1, 1, 2], [1, 2, 4], [1, 3, 6]]
    v = c.variables()["plc"]
    assert (v["count"], v["last"]) == (2, 2)        # what the sample before this one held


def test_an_oscilloscope_signal_that_does_not_exist_is_refused():
    from plcbuilder.controller.controller import ControllerError
    with pytest.raises(ControllerError, match="has no variable nope"):
        controller(tgm(), "tgmotion", scope=("plc.nope",))
    from plcbuilder.controller.targets import TargetConfig, TargetConfigError
    with pytest.raises(TargetConfigError, match="not a signal"):
        TargetConfig("tgmotion", scope=("output 3",)).check()
