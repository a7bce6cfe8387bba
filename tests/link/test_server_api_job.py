"""myCNC's Server API program commands on the simulated controller's own G-code
job runner (SPEC §10, docs/editors.md "The Server API", docs/controller.md
"G-code jobs"): a real socket, and ``nc`` as the manual shows it. The
commands' answers with a stand-in runner are in test_server_api.py."""

import re
import shutil
import subprocess
import sys
import time

import pytest

from plcbuilder.bytecode.program import Kind
from tests.link.linkkit import compile_programs, image_of
# the served controller (its Server API on) and a line to it, over this file's image
from tests.link.test_server_api import (Line, line, run_manual_example, served,  # noqa: F401
                                        served_controller)

WAIT_S = 30.0


@pytest.fixture(scope="module")
def api_image():
    return image_of(compile_programs(["M03", "M05", "M08"], {
        "M03": (Kind.HARDWARE,
                "main(){ portset(3); gvarset(5000, eparam); timer=300; "
                "do{ timer--; }while(timer>0); exit(99); }"),
        "M08": (Kind.HARDWARE, "main(){ portset(8); exit(99); }")}))


def _on_sim(served, fn):
    return served.sim.call(lambda: fn(served.controller))


def _until(ask, command: str, want, timeout: float = WAIT_S) -> str:
    """Ask ``command`` until its reply is ``want`` (or matches it, a callable)."""
    end = time.monotonic() + timeout
    while True:
        got = ask(command)
        if (want(got) if callable(want) else got == want) or time.monotonic() > end:
            return got
        time.sleep(0.02)


def test_programfileopen_and_play_run_a_job_that_calls_m03(served, line, tmp_path):
    """SPEC §10: the job runs "the Server API's program commands" too; "`S` (the
    next `M03`/`M04`'s eparam), `Mnn` (stop motion, start procedure `Mnn` ...)"."""
    g = tmp_path / "part.nc"
    g.write_text("S1500 M03\nG0 X101\nM08\nM30\n")
    ask = line.ask
    assert ask(f"ProgramFileOpen {g}") == f"OK {g}"
    assert ask("GetWorkState") == "OK idle"                     # open is not play
    assert ask("GetJobName") == f"OK {g.resolve()}"
    assert ask("GetSVariable8020") == f"OK {g.resolve()}"
    assert ask("GetSVariable8107") == "OK part.nc"
    assert ask("GetSVariable8108") == f"OK {g.resolve().parent}"
    assert ask("GetSVariable8109") == "OK 0.000"
    estimate = ask("GetEstimateTime")
    assert re.fullmatch(r"OK \d+\.\d{3}", estimate) and float(estimate[3:]) > 0
    assert ask("GetPausedLine") == "OK 0"
    assert ask("ProgramPlay") == "OK"
    assert _until(ask, "GetIVariable 5000", "OK 1500") == "OK 1500"       # M03's eparam is S
    assert _until(ask, "GetHWOutputBit 8", "OK 1") == "OK 1"
    assert _until(ask, "GetWorkState", "OK idle") == "OK idle"
    assert ask("GetHWOutputBit 3") == "OK 1"
    assert ask("GetMachinePosition").startswith("OK X 101.00 ")
    assert ask("GetEstimateTime") == "OK 0.000"
    job = _on_sim(served, lambda c: c.job_report())
    assert job["state"] == "ended" and job["line"] == 4
    assert [(m["line"], m["procedure"], m["eparam"], m["exit_code"]) for m in job["mcodes"]] == [
        (1, "M03", 1500, 99), (3, "M08", 0, 99)]
    # the job's commands are in the session's recording, so a replay runs it again
    rec = _on_sim(served, lambda c: c.recorder.text(c.t_ms))
    assert f"gcode {g}" in rec and "job play @" in rec


def test_pause_the_handwheel_continue_stop_and_reset(served, line, tmp_path):
    """ProgramPause holds the job (GetPausedLine names its line); SetPendant moves an
    axis through the runner while it is paused, not while it runs; ProgramStop
    and ProgramReset end and rewind it."""
    g = tmp_path / "long.nc"
    g.write_text("G1 X110 F120\nM30\n")                  # 10 mm at 120 mm/min: 5 s
    ask = line.ask
    assert ask(f"ProgramFileOpen {g}") == f"OK {g}"
    assert ask("ProgramPlay") == "OK"
    assert _until(ask, "GetWorkState", "OK job running") == "OK job running"
    assert _until(ask, "GetMachinePosition",
                  lambda r: float(r.split()[2]) > 100.05).startswith("OK X 100.")
    assert ask("SetPendant 10;0x0201") == "OK X 0.000"          # X, 0.1 mm a click
    assert ask("SetPendant 12;0x0201") == ("ERROR the handwheel moves an axis while no G-code "
                                           "job runs (ProgramPause or ProgramStop first)")
    assert ask("ProgramPause") == "OK"
    assert ask("GetWorkState") == "OK job paused" and ask("GetPausedLine") == "OK 1"
    assert _until(ask, "GetMCC", "OK 77") == "OK 77"             # the move has decelerated
    x0 = float(ask("GetMachinePosition").split()[2])
    assert ask("SetPendant 15;0x0201") == "OK X 0.500"
    assert _until(ask, "GetMachinePosition",
                  lambda r: abs(float(r.split()[2]) - (x0 + 0.5)) < 0.006) \
        .startswith(f"OK X {x0 + 0.5:.2f}")
    assert "move X=0.5 @" in _on_sim(served, lambda c: c.recorder.text(c.t_ms))
    assert ask("ProgramPlay") == "OK" and ask("GetWorkState") == "OK job running"
    assert ask("ProgramStop") == "OK"
    assert ask("GetPausedLine") == "OK 0"
    assert _on_sim(served, lambda c: c.job.state) == "stopped"
    assert ask("ProgramReset") == "OK"
    assert _on_sim(served, lambda c: (c.job.state, c.job.line)) == ("ready", 0)


def test_a_program_sent_line_by_line_and_one_that_cannot_run(served, line, tmp_path):
    ask = line.ask
    assert ask("ProgramPlay") == "ERROR no G-code program is open (open one first)"
    assert ask("ProgramBegin") == "OK"
    assert ask("ProgramAppend S800 M3") == "OK 1"
    assert ask("ProgramAppend M30") == "OK 2"
    assert ask("ProgramEnd") == "OK 2"
    assert ask("GetJobName") == "OK (server api)"
    assert ask("ProgramPlay") == "OK"
    assert _until(ask, "GetIVariable 5000", "OK 800") == "OK 800"
    bad = tmp_path / "bad.nc"
    bad.write_text("M03\nG2 X1 Y1\n")
    assert ask(f"ProgramFileOpen {bad}").startswith(
        f"ERROR {bad.resolve()}:2: G2 is not supported")
    assert ask("GetJobName") == "OK (server api)"               # the job before stays


# ---------------------------------------------------------------- the manual's example

@pytest.mark.skipif(shutil.which("nc") is None, reason="nc is not installed")
def test_the_manuals_job_example_gives_the_replies_it_shows(tmp_path):
    """ProgramFileOpen job.nc + ProgramPlay on a controller started as the manual
    starts it, in a project made by plcbuilder new: M03 runs with S12000."""
    printed, shown = run_manual_example(tmp_path, "server-api-job", timeout=60)
    assert printed == shown


def _cli(*args, cwd):
    return subprocess.run([sys.executable, "-m", "plcbuilder", *map(str, args)],
                          capture_output=True, text=True, timeout=120, cwd=cwd)


def _served_controller(tmp_path, cwd, *extra):
    """``plcbuilder controller --server-api 0 ...`` as a user starts it; the
    process, its Server API port and its runtime file."""
    rt = tmp_path / "rt.json"
    proc, port = served_controller(cwd, "--port", "0", "--server-api", "0", "--runtime-file", rt,
                                   *extra)
    return proc, port, rt


def _ask(port: int, command: str) -> str:
    c = Line(("127.0.0.1", port))
    try:
        return c.ask(command)
    finally:
        c.close()


@pytest.mark.parametrize("how", ["controller --image", "upload"])
def test_a_huazhong_project_served_from_the_command_line_runs_as_huazhong(tmp_path, how):
    """Issue 27 "Done when": item 11 "works from the command line" on every target:
    `plcbuilder controller --image build/eeprom.rom` (or `plcbuilder upload`) of a
    Huazhong project runs its program as Huazhong (the seed's init() "该函数一般设置系统
    MSBT功能的响应函数", the M/S handlers), so ProgramFileOpen + ProgramPlay of the
    example's job.nc homes X (lamp Y0.5) and its M03 reaches on_m. Before, the
    image ran as myCNC procedures: no handler, no lamp."""
    proj = tmp_path / "mill"
    assert _cli("new", "--target", "huazhong", proj, cwd=tmp_path).returncode == 0
    assert _cli("build", proj, cwd=tmp_path).returncode == 0
    image = proj / "build" / "eeprom.rom"
    if how == "upload":
        proc, port, rt = _served_controller(tmp_path, tmp_path)
    else:
        proc, port, rt = _served_controller(tmp_path, proj, "--image", "build/eeprom.rom")
    try:
        if how == "upload":
            up = _cli("upload", image, "--runtime-file", rt, cwd=tmp_path)
            assert up.returncode == 0, up.stderr
            assert "target huazhong" in up.stdout
        g = proj / "job.nc"
        g.write_text("G28 X0\nS1500 M03\nM30\n", encoding="utf-8")
        assert _ask(port, f"ProgramFileOpen {g}") == f"OK {g}"
        assert _ask(port, "ProgramPlay") == "OK"
        end = time.monotonic() + WAIT_S
        while _ask(port, "GetWorkState") != "OK idle" and time.monotonic() < end:
            time.sleep(0.1)
        assert _ask(port, "GetHWOutputBit 5") == "OK 1"      # X homed: AX_HOME_FIN's lamp
        assert _ask(port, "GetHWOutputBit 0") == "OK 1"      # M03 went to on_m: spindle on
        assert _ask(port, "GetIVariable 1013001") == "OK 1500"   # S went to on_s: G[1]
    finally:
        proc.terminate()
        proc.wait(20)
