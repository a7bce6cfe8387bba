"""``plcbuilder run PROJECT --gcode FILE`` (SPEC §10) and ``plcbuilder test`` with a
test's ``gcode = \"\"\"…\"\"\"``, through the command line."""

from __future__ import annotations

import json

from tests.cli._run import run_cli
from tests.testing._proj import make_project

PROCS = {"M03": "main(){ pwm01 = eparam; portset(0); exit(99); };",
         "M05": "main(){ pwm01 = 0; portclear(0); exit(99); };",
         "M08": "main(){ portset(3); timer=20; do{timer--;}while(timer>0); exit(99); };"}


def test_run_gcode_json_has_the_job(tmp_path, capsys):
    """SPEC §10: "`plcbuilder run PROJECT --gcode FILE` ... The JSON report gains
    `job`: the line reached, and for each M-code the procedure, start and end
    times and exit code"."""
    root = make_project(tmp_path / "p", procs=PROCS)
    (root / "job.nc").write_text("S1200 M03\nM08\nG4 P0.1\nM05\nM30\n")
    code, out, err = run_cli(capsys, "run", root, "--gcode", root / "job.nc", "--json")
    assert code == 0, err
    job = json.loads(out)["job"]
    assert (job["state"], job["line"], job["lines"]) == ("ended", 5, 5)
    assert [(m["line"], m["procedure"], m["eparam"], m["started_at_ms"], m["ended_at_ms"],
             m["exit_code"]) for m in job["mcodes"]] == [
        (1, "M03", 1200, 0, 0, 99), (2, "M08", 0, 1, 21, 99), (4, "M05", 0, 122, 122, 99)]
    code, out, _ = run_cli(capsys, "run", root, "--gcode", root / "job.nc")
    assert code == 0 and "line 2: M08 -> M08 1 -> 21 ms, exit 99 plc_exit_normal" in out
    code, out, _ = run_cli(capsys, "run", root, "--json")
    assert json.loads(out)["job"] is None


def test_run_gcode_refuses_a_bad_line_naming_it(tmp_path, capsys):
    """SPEC §10: "an unsupported word is an error naming the line" (exit 2, bad usage)."""
    root = make_project(tmp_path / "p", procs=PROCS)
    (root / "job.nc").write_text("M03\nG0 X10\nG3 X1 Y1 I1\n")
    code, _out, err = run_cli(capsys, "run", root, "--gcode", root / "job.nc")
    assert code == 2 and f"{root / 'job.nc'}:3: G3 is not supported" in err
    code, _out, err = run_cli(capsys, "run", root, "--gcode", root / "none.nc")
    assert code == 2 and "cannot read" in err


def test_a_test_with_gcode(tmp_path, capsys):
    """SPEC §10: "a test's `gcode = \"\"\"…\"\"\"`": the job runs it from 0 ms; a
    line it cannot run is an error at the test file's line."""
    test = '''[[test]]
name = "the program runs the spindle"
ms = 500
gcode = """
S800 M03
M08
M05
"""

[[test.expect]]
during_ms = [1, 20]
outputs_on = [0, 3]
pwm = { 0 = 800 }

[[test.expect]]
at_end = true
outputs_off = [0]
exit = { M03 = 99, M08 = 99, M05 = 99 }
'''
    root = make_project(tmp_path / "p", procs=PROCS, tests={"job": test})
    code, out, _ = run_cli(capsys, "test", root)
    assert code == 0 and "1 passed, 0 failed" in out
    (root / "tests" / "job.toml").write_text(test.replace("M08\n", "M08\nG2 X1\n"))
    code, _out, err = run_cli(capsys, "test", root)
    assert code == 2 and "job.toml:7: gcode: G2 is not supported" in err
