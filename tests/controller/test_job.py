"""The G-code job runner (SPEC §10, docs/controller.md "G-code jobs"), one test
a sentence, each quoting it; every test runs on both VM backends."""

from __future__ import annotations

import pytest

from plcbuilder.bytecode import abi
from plcbuilder.controller.controller import ControllerError
from plcbuilder.controller.events import Ended, JobEvent, Note, Print, Started
from plcbuilder.controller.scenario import Scenario, drive

from tests.controller._sim import compile_proc, controller, of


@pytest.fixture(params=["fast", "reference"])
def backend(request):
    return request.param


def proc(name: str, body: str, software: bool = False):
    return compile_proc(f"main(){{ {body} }};", name, software)


def wait(n: int) -> str:
    return f"timer={n}; do {{ timer--; }} while (timer > 0);"


def started(events) -> list[tuple[str, int, int]]:
    return [(e.name, e.t_ms, e.eparam) for e in of(events, Started)]


def ends(events) -> dict[str, tuple[int, int]]:
    return {e.name: (e.t_ms, e.exit_code) for e in of(events, Ended)}


def run_job(c, text: str, ms: int = 10_000):
    c.job_open(text, "job.nc", play=True)
    c.run_until_idle(ms)
    return c.drain_events()


# ----------------------------------------------------------------- M-codes
def test_an_m_code_starts_its_procedure_and_the_next_block_waits_for_its_exit(backend):
    """SPEC §10: "`Mnn` (stop motion, start procedure `Mnn`, and read the next
    block when it exits"; the seed: "if within a running program the next code
    is a PLC M-code, then the movement will be stopped and the controller will
    run the PLC program"."""
    c = controller(proc("M10", wait(5) + " exit(99);"), proc("M11", "exit(42);"),
                   backend=backend)
    ev = run_job(c, "M10\nM11\n")
    assert started(ev) == [("M10", 0, 0), ("M11", 6, 0)]      # M10 ends in tick 5
    rep = c.job_report()
    assert rep["state"] == "ended" and rep["line"] == 2
    assert [(m["code"], m["procedure"], m["started_at_ms"], m["ended_at_ms"], m["exit_code"])
            for m in rep["mcodes"]] == [("M10", "M10", 0, 5, 99), ("M11", "M11", 6, 6, 42)]


def test_motion_continue_runs_the_procedure_and_the_next_motion_side_by_side(backend):
    """SPEC §10: "or when it sends `PLCCMD_MOTION_CONTINUE`, after which the
    procedure and the next motion run at the same time"; the seed: "After this
    code, the PLC procedure continues running through its code while at the same
    time the next motion code is launched"."""
    body = "message=PLCCMD_MOTION_CONTINUE; " + wait(300) + " x = gvarget(5021); exit(99);"
    c = controller(proc("M12", body), backend=backend)
    ev = run_job(c, "M12\nG0 X150\n")
    rep = c.job_report()
    m = rep["mcodes"][0]
    assert m["continued_at_ms"] == 0 and m["ended_at_ms"] == 300
    x = c.variables()["M12"]["x"]
    assert 10000 < x < 15000                         # X was moving while M12 ran
    assert c.machine.axis_positions()["X"] == 15000 and rep["state"] == "ended"


def test_motion_skip_cancels_the_motion_and_reads_the_next_block(backend):
    """SPEC §10: "`PLCCMD_MOTION_SKIP` cancels the current motion and reads the
    next block"; the seed: "the motion controller will cancel current motion (it
    will stop moving) and will read the next code from the buffer"."""
    body = ("message=PLCCMD_MOTION_CONTINUE; " + wait(200) +
            " message=PLCCMD_MOTION_SKIP; " + wait(2) + " exit(99);")
    c = controller(proc("M13", body), proc("M14", "x = gvarget(5021); exit(99);"),
                   backend=backend)
    ev = run_job(c, "M13\nG1 X900 F6000\nM14\n")
    x = c.variables()["M14"]["x"]
    assert 10000 < x < 40000                         # far from X 900: the move was cut
    m14 = [t for n, t, _e in started(ev) if n == "M14"][0]
    assert 200 < m14 < 320           # read once the move had stopped (100 ms to decelerate)
    assert c.job_report()["state"] == "ended"


def test_s_is_the_next_m03_or_m04_eparam(backend):
    """SPEC §10: "`S` (the next `M03`/`M04`'s eparam)"."""
    c = controller(proc("M03", "exit(99);"), proc("M04", "exit(99);"), proc("M05", "exit(99);"),
                   backend=backend)
    ev = run_job(c, "S12000 M03\nM05\nM04\nS500\nM03\n")
    assert [(n, e) for n, _t, e in started(ev)] == [("M03", 12000), ("M05", 0), ("M04", 12000),
                                                     ("M03", 500)]


def test_an_error_exit_stops_the_job_naming_the_line(backend):
    """The seed's exit codes: "PLC aborted, No Arc sensor signal Timeout" (3)
    ... "MyCNC software will catch exit code and report about Error": an M-code
    procedure that exits with one (or faults) stops the job, naming the line."""
    c = controller(proc("M71", "exit(plc_exit_plasma_timeout);"), proc("M08", "exit(99);"),
                   backend=backend)
    ev = run_job(c, "G0 X110\nM71\nM08\n")
    rep = c.job_report()
    assert rep["state"] == "error" and rep["line"] == 2
    assert rep["error"] == "job.nc:2: M71 ended with 3 (plc_exit_plasma_timeout): the job stops"
    assert "M08" not in [n for n, _t, _e in started(ev)]
    assert any(isinstance(e, Note) and e.level == "error" for e in ev)


def test_a_missing_procedure_is_a_warning_and_the_job_goes_on(backend):
    c = controller(proc("M05", "exit(99);"), backend=backend)
    ev = run_job(c, "M07\nM05\n")
    assert any("M07: no procedure M07 is loaded" in e.text for e in of(ev, Note))
    assert [m["procedure"] for m in c.job_report()["mcodes"]] == [None, "M05"]


# ------------------------------------------------------------------ motion
def test_g0_g1_g90_g91_and_6060(backend):
    """SPEC §10: "`G0`/`G1` (X Y Z A, F) on the machine model ... `G90`/`G91`";
    6060 reads the motion's code: 1 while a G1 runs, 0 for a G0, 0x4d when idle."""
    c = controller(proc("M20", "g = gvarget(6060); exit(99);"), backend=backend)
    c.job_open("G91\nG0 X10\nX10\nG90 G1 Y50 F6000\n", "job.nc", play=True)
    seen = {}
    for _ in range(3000):
        seen.setdefault(c.job_report()["line"], set()).add(c.machine.gvarget(abi.MOTION_CODE))
        c.step(1)
        if c.job.state == "ended":
            break
    assert c.machine.axis_positions()["X"] == 12000 and c.machine.axis_positions()["Y"] == 5000
    assert 0 in seen[2] and 1 in seen[4]
    assert c.machine.gvarget(abi.MOTION_CODE) == abi.MOTION_CODE_IDLE


def test_g4_dwells_p_seconds(backend):
    """SPEC §10: "`G4 P` (dwell)": P in seconds."""
    c = controller(proc("M10", "exit(99);"), proc("M11", "exit(99);"), backend=backend)
    ev = run_job(c, "M10\nG4 P0.25\nM11\n")
    assert started(ev) == [("M10", 0, 0), ("M11", 251, 0)]


def test_m30_ends_the_job_and_comments_are_skipped(backend):
    """SPEC §10: "`M30`/`M2` (end), `(…)` and `;` comments"; procedure M30 (or
    M02) runs first where the project has one; nothing after the end is read."""
    c = controller(proc("M02", "gvarset(20000, 2); exit(99);"), proc("M10", "exit(99);"),
                   backend=backend)
    ev = run_job(c, "(start) M10 ; the first\n%\nM2\nM10\n")
    assert [n for n, _t, _e in started(ev)] == ["M10", "M02"]
    rep = c.job_report()
    assert rep["state"] == "ended" and rep["line"] == 3 and rep["lines"] == 4


def test_an_unsupported_word_is_an_error_naming_the_line(backend):
    """SPEC §10: "an unsupported word is an error naming the line"; the job
    loaded before stays."""
    c = controller(proc("M10", "exit(99);"), backend=backend)
    with pytest.raises(ControllerError, match=r"^job\.nc:3: G2 is not supported"):
        c.job_open("M10\nG0 X1\nG2 X5 Y5\n", "job.nc")
    with pytest.raises(ControllerError, match=r"^job\.nc:1: A1: the machine has no A axis"):
        c.job_open("G0 A1\n", "job.nc")
    assert c.job is None


# --------------------------------------------------------------- handlers
def test_gcode_start_runs_before_the_job_and_gcode_stop_after(backend):
    """SPEC §10: "The software procedures `__HANDLER_GCODE_START` and
    `__HANDLER_GCODE_STOP` run before the job starts and after it ends or is
    stopped, as the seed's handler table says" ("just before the myCNC software
    run g-code (after pressing PLAY button)", "just after the myCNC software
    finished g-code running")."""
    c = controller(proc("__HANDLER_GCODE_START", wait(3) + " gvarset(20001, 1); exit(99);", True),
                   proc("__HANDLER_GCODE_STOP", "gvarset(20002, 1); exit(99);", True),
                   proc("M10", "gvarset(20003, 1); exit(99);"), backend=backend)
    c.step(50)
    ev = run_job(c, "M10\n", 1000)
    prints = [(p.register, p.t_ms) for p in of(ev, Print)]
    # the software tick at 100 starts GCODE_START; its loop takes three more (100 ms) ticks
    assert prints == [(20001, 400), (20003, 401), (20002, 500)]


def test_stop_stops_the_job(backend):
    """SPEC §2: "Stop: pressing Stop once starts `M02`"; a job running then is
    stopped (motion stopped) and `__HANDLER_GCODE_STOP` runs ("after pressing
    STOP/PAUSE button")."""
    c = controller(proc("M02", "exit(99);"),
                   proc("__HANDLER_GCODE_STOP", "gvarset(20002, 1); exit(99);", True),
                   backend=backend)
    sc = Scenario.parse("stop @ 300\n")
    c.job_open("G1 X900 F3000\nG0 X0\n", "job.nc", play=True)
    drive(c, sc, 2000)
    ev = c.drain_events()
    rep = c.job_report()
    assert rep["state"] == "stopped" and rep["ended_at_ms"] == 300 and rep["line"] == 1
    assert 10000 < c.machine.axis_positions()["X"] < 30000
    assert ("M02", 300, 0) in started(ev) and any(p.register == 20002 for p in of(ev, Print))


def test_pause_and_play_go_on_with_the_move(backend):
    """The Server API's ProgramPause and ProgramPlay (docs/controller.md): a
    pause decelerates the move; play goes on to the same line's target."""
    c = controller(proc("M10", "exit(99);"), backend=backend)
    c.job_open("G1 X300 F6000\nM10\n", "job.nc", play=True)
    c.step(500)
    c.job_control("pause")
    c.step(1000)
    x = c.machine.axis_positions()["X"]
    assert 10000 < x < 30000 and c.job.state == "paused"
    c.step(500)
    assert c.machine.axis_positions()["X"] == x     # still
    c.job_control("play")
    c.run_until_idle(10_000)
    assert c.machine.axis_positions()["X"] == 30000 and c.job.state == "ended"
    assert [m["code"] for m in c.job_report()["mcodes"]] == ["M10"]


def test_reset_rewinds(backend):
    c = controller(proc("M10", "exit(99);"), backend=backend)
    run_job(c, "M10\nM10\n")
    c.job_control("reset")
    assert c.job.state == "ready" and c.job_report()["line"] == 0
    c.job_control("play")
    c.run_until_idle(100)
    assert c.job_report()["state"] == "ended" and len(c.job_report()["mcodes"]) == 2


# ------------------------------------------------------- scenario and replay
def test_scenario_lines_and_the_recording(tmp_path, backend):
    """SPEC §10: "a scenario line `gcode FILE @ MS`" (FILE relative to the
    scenario's folder); the recording holds it, so a replay runs the job again
    tick for tick (SPEC §7)."""
    (tmp_path / "job.nc").write_text("M10\nG0 X50\nM10\n")
    sc_file = tmp_path / "s.txt"
    sc_file.write_text("gcode job.nc @ 20\njob pause @ 200\njob play @ 400\n")
    c = controller(proc("M10", "exit(99);"), backend=backend)
    drive(c, Scenario.load(sc_file), 5000)
    first = [(type(e).__name__, e.t_ms) for e in c.drain_events()]
    rec = c.recorder.text(c.t_ms)
    assert f"gcode {tmp_path / 'job.nc'} @ 20" in rec and "job pause @ 200" in rec
    again = controller(proc("M10", "exit(99);"), backend=backend)
    drive(again, Scenario.parse(rec), 5000)
    assert [(type(e).__name__, e.t_ms) for e in again.drain_events()] == first
    assert any(n == "JobEvent" for n, _t in first)


def test_job_events_name_the_line_and_the_procedure(backend):
    """The run panels show "the job's line and the procedures it called": JobEvent."""
    c = controller(proc("M10", "exit(99);"), backend=backend)
    ev = run_job(c, "G0 X110\nM10\n")
    jobs = [(e.state, e.line, e.procedure) for e in of(ev, JobEvent)]
    assert ("running", 1, None) in jobs and ("running", 2, "M10") in jobs
    assert jobs[-1][0] == "ended"


def test_the_server_apis_job_runner(backend):
    """The Server API's program commands drive the job through
    ``Controller.job_runner`` (open, play, pause, stop, reset, status, and the
    handwheel's move, recorded as ``move X=…``)."""
    c = controller(proc("M10", wait(50) + " exit(99);"), backend=backend)
    r = c.job_runner
    assert r.status().state == "idle" and r.status().name is None
    r.open("job.nc", "M10\nG0 X120\n", "/p/job.nc")
    st = r.status()
    assert (st.state, st.name, st.path, st.lines, st.size) == ("idle", "job.nc", "/p/job.nc", 2, 12)
    r.play()
    c.step(10)
    assert r.status().state == "running" and r.status().line == 1
    r.pause()
    assert r.status().state == "paused" and r.status().paused_line == 1
    r.play()
    c.run_until_idle(5000)
    assert r.status().state == "done" and c.machine.axis_positions()["X"] == 12000
    r.reset()
    assert r.status().state == "idle" and r.status().line == 0
    r.move("x", -2.5)
    c.step(500)
    assert c.machine.axis_positions()["X"] == 11750
    assert "move X=-2.5 @" in c.recorder.text(c.t_ms)
    with pytest.raises(ControllerError, match="no axis 'Q'"):
        r.move("Q", 1)


def test_the_run_panels_get_each_called_procedures_exit(backend):
    """Issue 27.11: "reporting the job's line, the procedures it called and their
    exit codes in the JSON report and the run panels": a JobEvent with the exit
    code when each procedure the job called ends (one it went on from after its
    PLCCMD_MOTION_CONTINUE too), and the state's job names the last call."""
    c = controller(proc("M10", wait(30) + " exit(99);"),
                   proc("M11", "message=PLCCMD_MOTION_CONTINUE; " + wait(300) + " exit(7);"),
                   backend=backend)
    ev = run_job(c, "M10\nM11\nG4 P0.1\nM30\n")
    exits = [(e.line, e.procedure, e.exit_code, e.text) for e in of(ev, JobEvent)
             if e.exit_code is not None]
    assert exits == [(1, "M10", 99, "M10 exit 99 plc_exit_normal"),
                     (2, "M11", 7, f"M11 exit 7 {abi.exit_name(7)}")]
    end = {e.name: e.t_ms for e in of(ev, Ended)}
    assert [e.t_ms for e in of(ev, JobEvent) if e.exit_code is not None] == \
        [end["M10"], end["M11"]]                         # in the tick each one ends
    st = c.state().job
    assert st["last_call"] == {"line": 2, "code": "M11", "procedure": "M11", "exit_code": 7}
    assert st["mcode_count"] == 2


def test_the_estimate_of_the_time_left(backend):
    """GetEstimateTime (the Server API): the moves at their feed or the rapid
    speeds, accelerating as the axes do, and the dwells, from where the job is."""
    c = controller(backend=backend)
    r = c.job_runner
    r.open("job.nc", "G0 X150\nG1 X160 F600\nG4 P0.5\nG91 G0 Y-20\nM30\n")
    first = r.status().estimate_s
    r.play()
    c.step(400)
    mid = r.status().estimate_s
    c.run_until_idle(10_000)
    took = (c.job.ended_at - c.job.started_at) / 1000
    assert first == pytest.approx(took, abs=0.01) and mid == pytest.approx(took - 0.4, abs=0.01)
    assert r.status().estimate_s == 0.0
