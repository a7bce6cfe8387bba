"""The debugger's rules (SPEC §6): breakpoints, conditions, hit counts,
logpoints, the halted state, continue/pause/steps/run to line, faults.
Every test runs on both backends."""

from __future__ import annotations

import pytest

from plcbuilder import api
from plcbuilder.controller.controller import Controller
from plcbuilder.controller.debugger import DebugError
from plcbuilder.controller.events import Fault, Halted, Log, Resumed

from tests.controller._sim import BACKENDS, COUNT, EXAMPLE, compile_proc

SOFT = "main(){ do { k++; } while(1); }"


def _c(backend: str, *programs, **kw) -> Controller:
    c = Controller(backend=backend, **kw)
    c.load(programs or [compile_proc(COUNT, "M10")])
    return c


def _where(c: Controller) -> tuple:
    st = c.debugger.halted_state()
    return st["reason"], st["procedure"], st["line"], st["t_ms"]


def _vars(c: Controller, name: str = "M10") -> dict:
    st = c.debugger.halted_state()
    return next(p for p in st["procedures"] if p["name"] == name)["vars"]


@pytest.fixture(params=BACKENDS)
def backend(request):
    return request.param


def test_a_breakpoint_on_a_line_without_code_moves_to_the_next_line_with_code(backend):
    """"A breakpoint on a line with no code moves to the next line that has code." """
    c = _c(backend)
    answer = c.debugger.set_breakpoints("M10.plc", [{"line": 4}, {"line": 11}])
    assert [(a["line"], a["verified"]) for a in answer] == [(7, True), (15, True)]


def test_it_halts_before_the_line_runs_mid_tick(backend):
    """"Execution halts *before* the first instruction of that line runs, in
    whichever procedure reaches it (hardware or software), at that exact
    instruction — mid-tick." """
    c = _c(backend)
    c.debugger.set_breakpoints("M10.plc", [{"line": 8}])
    c.start("M10")
    c.step(100)
    assert _where(c) == ("breakpoint", "M10", 8, 0)
    assert _vars(c)["n"] == 1 and _vars(c)["total"] == 0     # n++ ran, bump() did not
    assert c.plc.mid_tick
    c.debugger.resume()
    c.step(100)
    assert _where(c) == ("breakpoint", "M10", 8, 1)
    assert _vars(c)["n"] == 2 and _vars(c)["total"] == 1


def test_a_software_procedure_halts_too_and_time_stands_still(backend):
    """"halting stops the whole controller (every procedure, the machine,
    motion, timers), so nothing moves while the user looks." """
    soft = compile_proc(SOFT, "S1", software=True)
    c = _c(backend, compile_proc(COUNT, "M10"), soft)
    c.debugger.set_breakpoints("S1.plc", [{"line": 1, "hit": {"mode": "eq", "n": 3}}])
    c.start("M10")
    c.step(1000)
    assert _where(c) == ("breakpoint", "S1", 1, 200)        # software ticks: 0, 100, 200
    n = _vars(c)["n"]
    c.step(500)                                              # halted: nothing runs
    assert c.t_ms == 200 and _vars(c)["n"] == n
    st = c.debugger.halted_state()
    m10 = next(p for p in st["procedures"] if p["name"] == "M10")
    assert m10["line"] == 9 and m10["at_loop_end"]          # at its loop's condition line


def test_a_breakpoint_in_a_header_halts_where_the_procedure_calls_it(backend, tmp_path):
    """"Breakpoints are set on a source line of a procedure (in its `.plc` or in
    a header it includes)." """
    (tmp_path / "helpers.h").write_text("twice()\n{\n  v = v * 2;\n};\n")
    (tmp_path / "M20.plc").write_text("#include helpers.h\nmain()\n{\n  v = 3;\n  twice();\n"
                                      "  exit(v);\n}\n")
    r = api.compile_file(tmp_path / "M20.plc")
    c = _c(backend, r.program)
    c.debugger.set_breakpoints("helpers.h", [{"line": 3}])
    c.start("M20")
    c.step(10)
    st = c.debugger.halted_state()
    assert (st["file"], st["line"]) == ("helpers.h", 3)
    assert [(f["procedure"], f["file"], f["line"]) for f in st["procedures"][0]["stack"]] == \
        [("twice", "helpers.h", 3), ("main", "M20.plc", 5)]


def test_conditions_are_checked_each_time_and_bound_by_name(backend):
    """"A breakpoint may have a condition (an expression in the PLC language over
    the procedure's variables and built-in names, checked each time the line is
    reached" """
    c = _c(backend)
    code = api.compile_condition("n % 10 == 0 && total > 100")
    c.debugger.set_breakpoints("M10.plc", [{"line": 8, "condition": {"text": "…",
                                                                      "code": code}}])
    c.start("M10")
    c.step(1000)
    assert _where(c)[:3] == ("breakpoint", "M10", 8) and _vars(c)["n"] == 20


def test_a_condition_that_does_not_compile_is_refused_with_its_diagnostic():
    """"a condition that does not compile is refused with its diagnostic" """
    diags = api.compile_condition("n == ")
    assert isinstance(diags, list) and diags and diags[0].is_error
    assert diags[0].span.file == "<condition>" and diags[0].span.line == 1
    too = api.compile_condition("gvarset(1, 2)")
    assert isinstance(too, list) and "returns nothing" in too[0].message


def test_a_condition_may_use_the_files_defines(tmp_path):
    (tmp_path / "M30.plc").write_text("#define LIMIT 7\nmain(){ n=1; exit(n); }\n")
    assert isinstance(api.compile_condition("n > LIMIT", tmp_path / "M30.plc"), bytes)
    assert isinstance(api.compile_condition("portget(INPUT_HOME_Z) == 0",
                                            EXAMPLE / "hardware" / "M80.plc"), bytes)


@pytest.mark.parametrize("mode, n, halts", [("eq", 3, [3]), ("ge", 3, [3, 4, 5]),
                                            ("every", 2, [2, 4, 6])])
def test_hit_counts(backend, mode, n, halts):
    """"a hit count (halt on the Nth hit, from the Nth on, or every Nth)" """
    c = _c(backend)
    c.debugger.set_breakpoints("M10.plc", [{"line": 7, "hit": {"mode": mode, "n": n}}])
    c.start("M10")
    seen = []
    for _ in range(len(halts)):
        c.step(20)
        seen.append(_vars(c)["n"] + 1)           # the hit about to run n++
        c.debugger.resume()
    assert seen == halts


def test_a_logpoint_logs_and_does_not_halt(backend):
    """"or be a logpoint (a message with `{name}` placeholders written to the log;
    no halt)." """
    c = _c(backend)
    c.debugger.set_breakpoints("M10.plc", [{"line": 8, "log": "n={n} total={total} {nope}",
                                            "hit": {"mode": "every", "n": 100}}])
    c.start("M10")
    c.run_until_idle(2000)
    assert c.debugger.halt is None
    logs = [e for e in c.drain_events() if isinstance(e, Log)]
    assert [(e.t_ms, e.text) for e in logs][:2] == [(99, "n=100 total=4950 {nope}"),
                                                     (199, "n=200 total=19900 {nope}")]


def test_breakpoints_change_while_running(backend):
    """"Breakpoints can be added, disabled and removed while running." """
    c = _c(backend)
    c.start("M10")
    c.step(50)                                   # running plain code: it goes over when watched
    c.debugger.set_breakpoints("M10.plc", [{"line": 7}])
    c.step(10)
    assert _where(c) == ("breakpoint", "M10", 7, 50)
    c.debugger.set_breakpoints("M10.plc", [{"line": 7, "enabled": False}, {"line": 15}])
    c.debugger.resume()
    c.step(10)
    assert _where(c)[2] == 15
    c.debugger.set_breakpoints("M10.plc", [])
    c.debugger.resume()
    c.run_until_idle(5000)
    assert c.debugger.halt is None and c.plc.last["M10"].exit_code == 99


def test_after_a_rebuild_breakpoints_stay_on_their_lines(backend):
    """"After a rebuild they stay on their lines." """
    c = _c(backend)
    c.debugger.set_breakpoints("M10.plc", [{"line": 8}])
    edited = COUNT.replace("  n = 0;\n", "  n = 0; // started\n  total = 5;\n")
    c.load([compile_proc(edited, "M10")])
    [bp] = c.debugger.breakpoints()
    assert (bp["line"], bp["at_line"], bp["verified"]) == (8, 8, True)
    c.start("M10")
    c.step(10)
    assert _where(c)[2] == 8 and _vars(c)["total"] == 5      # line 8 is now bump()... of 5+


def test_the_halted_state(backend):
    """"Halted state shows, for every running procedure: the line it is at ...,
    its call stack (nesting ≤ 16) and its variables; the machine state (I/O,
    PWM, DAC, ADC, axes, registers) and `t_ms`; and why it halted" """
    c = _c(backend)
    c.debugger.set_breakpoints("M10.plc", [{"line": 15, "hit": {"mode": "eq", "n": 4}}])
    c.start("M10")
    c.step(100)
    st = c.debugger.halted_state()
    assert st["reason"] == "breakpoint" and st["t_ms"] == 3
    assert st["breakpoint"]["line"] == 15 and st["fault"] is None
    [m10] = st["procedures"]
    assert m10["stack"] == [{"procedure": "bump", "file": "M10.plc", "line": 15},
                            {"procedure": "main", "file": "M10.plc", "line": 8}]
    assert set(st["machine"]) == {"inputs", "outputs", "adc", "pwm", "dac", "axes", "registers"}
    assert len(st["machine"]["pwm"]) == 8 and "X" in st["machine"]["axes"]


def test_events_announce_halts_and_resumes(backend):
    c = _c(backend)
    c.debugger.set_breakpoints("M10.plc", [{"line": 7}])
    c.start("M10")
    c.step(5)
    c.debugger.resume()
    c.step(5)
    kinds = [e.type for e in c.drain_events() if isinstance(e, (Halted, Resumed))]
    assert kinds == ["halted", "resumed", "halted"]


def test_pause_halts_at_the_end_of_the_tick_and_step_tick_runs_one(backend):
    """"pause (halts at the end of the current tick), step tick (run exactly one
    1 ms tick, then halt)" """
    c = _c(backend)
    c.start("M10")
    c.step(7)
    c.debugger.pause()
    assert _where(c) == ("pause", None, None, 7)
    c.debugger.step("tick")
    assert _where(c) == ("step", None, None, 8) and _vars(c)["n"] == 8


def test_step_into_over_out(backend):
    """"step into / over / out (statement level, in the procedure that halted:
    into enters a called procedure, over runs a call whole, out runs to the
    caller; a step that crosses a tick end runs the rest of the controller's
    tick, then halts at the next statement of that procedure)" """
    c = _c(backend)
    c.debugger.set_breakpoints("M10.plc", [{"line": 8}])
    c.start("M10")
    c.step(5)
    c.debugger.set_breakpoints("M10.plc", [])
    d = c.debugger
    d.step("into")
    assert _where(c)[2] == 15
    d.step("out")
    assert _where(c)[2] == 9                       # back in main: the loop's condition
    d.step("over")                                 # the loop ends the tick: it runs on
    assert d.halt is None
    c.step(10)
    assert _where(c) == ("step", "M10", 7, 1)      # next tick, the next statement
    d.step("over")
    d.step("over")                                 # over bump() whole
    assert _where(c)[2] == 9 and _vars(c)["total"] == 1 + 2


def test_run_to_line(backend):
    """"and **run to line**." """
    c = _c(backend)
    c.start("M10")
    c.step(3)
    c.debugger.pause()
    c.debugger.run_to("M10.plc", 15)
    c.step(10)
    assert _where(c) == ("step", "M10", 15, 3)
    with pytest.raises(DebugError, match="no code on line 40"):
        c.debugger.run_to("M10.plc", 40)


def test_a_fault_halts_at_its_line_before_the_procedure_ends(backend):
    """"A fault (division by zero, call depth, instruction limit) halts at the
    faulting line when the debugger is on, before the procedure is ended." """
    src = "main()\n{\n  d = 2;\n  do\n  {\n    d--;\n    q = 10 / d;\n  }while(1);\n}\n"
    c = _c(backend, compile_proc(src, "M40"))
    c.debugger.halt_on_fault = True
    c.start("M40")
    c.step(100)
    st = c.debugger.halted_state()
    assert (st["reason"], st["line"], st["t_ms"]) == ("fault", 7, 1)
    assert "division by zero" in st["fault"]["text"]
    assert c.plc.hw is not None                    # not ended yet
    c.debugger.resume()
    assert c.plc.hw is None and c.plc.last["M40"].exit_code == -1


def test_a_breakpoint_set_while_halted_at_a_fault_keeps_the_fault(backend):
    """Setting a breakpoint in the faulted procedure's file while it is halted
    at its fault hands nothing over: going on ends it with that fault (the fast
    backend's procedure ended as an internal error before)."""
    src = "main()\n{\n  d = 2;\n  do\n  {\n    d--;\n    q = 10 / d;\n  }while(1);\n}\n"
    c = _c(backend, compile_proc(src, "M40"))
    c.debugger.halt_on_fault = True
    c.start("M40")
    c.step(100)
    assert c.debugger.halted_state()["reason"] == "fault"
    c.debugger.set_breakpoints("M40.plc", [{"line": 6}])
    c.debugger.resume()
    faults = [(e.text, e.line) for e in c.drain_events() if isinstance(e, Fault)]
    assert faults == [("division by zero", 7)]
    assert c.plc.hw is None and c.plc.last["M40"].exit_code == -1


def test_bad_breakpoints_change_nothing(backend):
    """Bad requests (unknown file, line out of range, a condition that does not
    bind) are refused with a clear reason and change nothing."""
    c = _c(backend)
    c.debugger.set_breakpoints("M10.plc", [{"line": 7}])
    ghost = api.compile_condition("ghost > 1")
    for file, specs, why in [
            ("M99.plc", [{"line": 1}], "no loaded procedure is built from 'M99.plc'"),
            ("M10.plc", [{"line": 7}, {"line": 17}], "breakpoint 2: M10.plc has no code on "
                                                       "line 17"),
            ("M10.plc", [{"line": 7, "condition": {"text": "ghost > 1", "code": ghost}}],
             "'ghost', which is not a variable of M10"),
            ("M10.plc", [{"line": 7, "hit": {"mode": "eq", "n": 0}}], "hit count n must be")]:
        with pytest.raises(DebugError, match=why):
            c.debugger.set_breakpoints(file, specs)
    assert [b["line"] for b in c.debugger.breakpoints()] == [7]


def test_m80_halts_on_the_home_switch_read_and_steps_over_it(backend):
    """End to end on the example project's M80 (homing Z, waiting for
    INPUT_HOME_Z): break on the line that reads the home switch, halt there
    with the call stack, step over it and see the value it read."""
    project = api.Project.open(EXAMPLE)
    programs = [pb.program() for pb in api.compile_all(project)]
    c = Controller(api.load_machine(project.machine_path) if project.machine_path.is_file()
                   else None, backend=backend)
    c.load([p for p in programs if p is not None])
    answer = c.debugger.set_breakpoints("M80.plc", [{"line": 31, "hit": {"mode": "ge", "n": 2}}])
    assert answer[0]["verified"]
    c.start("M80")
    c.step(100)
    st = c.debugger.halted_state()
    assert (st["reason"], st["procedure"], st["line"], st["t_ms"]) == ("breakpoint", "M80", 31, 1)
    m80 = next(p for p in st["procedures"] if p["name"] == "M80")
    assert [(f["procedure"], f["line"]) for f in m80["stack"]] == [("find_home_z", 31),
                                                                   ("main", 75)]
    c.debugger.set_breakpoints("M80.plc", [])
    c.debugger.step("over")
    st = c.debugger.halted_state()
    assert (st["reason"], st["line"], st["t_ms"]) == ("step", 32, 1)
    m80 = next(p for p in st["procedures"] if p["name"] == "M80")
    assert m80["vars"]["sens"] == 0                      # the switch is open up there
    closed = api.compile_condition("portget(INPUT_HOME_Z) != 0", EXAMPLE / "hardware" / "M80.plc")
    c.debugger.set_breakpoints("M80.plc", [{"line": 31, "condition": {
        "text": "portget(INPUT_HOME_Z) != 0", "code": closed}}])
    c.debugger.resume()
    c.step(60_000)
    st = c.debugger.halted_state()
    assert (st["reason"], st["line"]) == ("breakpoint", 31) and st["t_ms"] > 1
    c.debugger.set_breakpoints("M80.plc", [])
    c.debugger.step("over")
    m80 = next(p for p in c.debugger.halted_state()["procedures"] if p["name"] == "M80")
    assert m80["vars"]["sens"] == 1 and m80["line"] == 32
    c.debugger.resume()
    c.run_until_idle(60_000)
    assert c.plc.last["M80"].exit_code == 99             # homed


def test_the_condition_and_log_texts_are_bounded():
    """Issue 24.2: a client of the controller that sends its own condition (not
    through compile_condition, which refuses over 1000 characters) meets the
    same bound, and so does a log text and a compiled expression to evaluate."""
    from plcbuilder.controller.debugger import MAX_TEXT
    c = _c("reference")
    code = api.compile_condition("n > 1")
    for spec, why in [
            ({"line": 7, "condition": {"text": "n" * (MAX_TEXT + 1), "code": code}},
             "breakpoint 1: a condition is at most 1000 characters"),
            ({"line": 7, "log": "x" * (MAX_TEXT + 1)}, "log must be text of at most 1000"),
            ({"line": 7, "condition": {"text": "n", "code": code + b"\0" * 70000}},
             "64 KiB compiled")]:
        with pytest.raises(DebugError, match=why):
            c.debugger.set_breakpoints("M10.plc", [spec])
    assert c.debugger.breakpoints() == []
    c.start("M10")
    c.step(5)
    with pytest.raises(DebugError, match="at most 64 KiB"):
        c.debugger.evaluate(b"\0" * 70000)
