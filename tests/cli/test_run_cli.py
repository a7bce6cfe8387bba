"""``plcbuilder run``: SPEC §5's options, JSON object and exit statuses."""

from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path

import pytest

from tests.cli._run import run_cli

DELAY = "main(){ timer=10; do{timer--;}while(timer>0); exit(99); };\n"


def write(path: Path, text: str) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text, encoding="utf-8")
    return path


def test_json_output_is_one_object_with_the_spec_fields(tmp_path, capsys):
    f = write(tmp_path / "M05.plc", DELAY)
    code, out, err = run_cli(capsys, "run", f, "--json")
    assert code == 0, err
    rep = json.loads(out)
    assert rep["ended_at_ms"] == 10
    p = rep["procedures"][0]
    assert (p["name"], p["kind"], p["started_at_ms"], p["ended_at_ms"], p["exit_code"],
            p["exit_name"], p["vexit"]) == ("M05", "hardware", 0, 10, 99, "plc_exit_normal", 0)
    assert set(rep) >= {"vars", "outputs", "pwm", "dac", "messages", "prints", "faults", "axes",
                        "proc"}


def test_options_start_input_adc_eparam_ms(tmp_path, capsys):
    proj = tmp_path / "p"
    write(proj / "hardware" / "M88.plc",
          "main(){ v = eparam; do { s = portget(9); a = adc01; } while (s == 0); exit(99); };")
    write(proj / "software" / "tick.plc", "main(){ do { n++; } while (1); };")
    code, out, err = run_cli(capsys, "run", proj, "--start", "M88:0x10@20", "--input",
                             "9=1@50", "--adc", "0=777@30", "--ms", "400", "--json")
    assert code == 0, err
    rep = json.loads(out)
    m88 = [p for p in rep["procedures"] if p["name"] == "M88"][0]
    assert (m88["started_at_ms"], m88["ended_at_ms"]) == (20, 51)
    assert rep["vars"]["M88"]["v"] == 16 and rep["vars"]["M88"]["a"] == 777
    assert rep["ended_at_ms"] == 400                     # the software procedure runs on


def test_software_single_file_and_trace(tmp_path, capsys):
    f = write(tmp_path / "S.plc", "main(){ do { n++; } while (n < 2); exit(99); };")
    trace = tmp_path / "trace.csv"
    code, out, _ = run_cli(capsys, "run", f, "--software", "--trace", trace, "--json")
    assert code == 0
    assert json.loads(out)["procedures"][0]["kind"] == "software"
    assert len(trace.read_text().splitlines()) == 1 + 201


def test_summary_without_json(tmp_path, capsys):
    f = write(tmp_path / "M03.plc", "main(){ portset(2); message=146; do { } while (0); "
                                    "gvarset(20000, 5); exit(99); };")
    code, out, _ = run_cli(capsys, "run", f, "--color=never")
    assert code == 0
    assert "M03 (hardware): 0 -> 1 ms, exit 99 plc_exit_normal" in out
    assert "146 PLC_MESSAGE_USER" in out and "[20000] 5" in out
    assert "outputs on: 2" in out and "run ended at 1 ms" in out


def test_compile_errors_exit_1_with_diagnostics(tmp_path, capsys):
    f = write(tmp_path / "M03.plc", "main(){\n  a = ;\n};\n")
    code, out, err = run_cli(capsys, "run", f, "--color=never")
    assert code == 1
    assert "M03.plc:2:" in err and "error:" in err and "did not compile" in err


def test_strict_applies(tmp_path, capsys):
    f = write(tmp_path / "M03.plc", "main(){ a = 1; if (a) { a = 2; } else { a = 3; }; };")
    assert run_cli(capsys, "run", f)[0] == 0
    assert run_cli(capsys, "run", f, "--strict")[0] == 1


@pytest.mark.parametrize("args,msg", [
    (["--start", "M99@0"], "no procedure named M99"),
    (["--input", "3=7@0"], "0 or 1"),
    (["--ms", "-1"], "must not be negative"),
    (["--ms", "lots"], "not a whole number"),
    (["--machine", "/nonexistent/m.toml"], "m.toml"),
    (["--bogus"], "unrecognized arguments"),
])
def test_bad_usage_exits_2_without_a_traceback(tmp_path, capsys, args, msg):
    f = write(tmp_path / "M05.plc", DELAY)
    code, out, err = run_cli(capsys, "run", f, *args)
    assert code == 2
    assert msg in err and "Traceback" not in err


def test_missing_target_exits_2(tmp_path, capsys):
    code, _, err = run_cli(capsys, "run", tmp_path / "nope.plc")
    assert code == 2 and "no such file or folder" in err


def test_the_installed_command_runs(tmp_path):
    f = write(tmp_path / "M05.plc", DELAY)
    r = subprocess.run([sys.executable, "-m", "plcbuilder", "run", str(f), "--json"],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    assert json.loads(r.stdout)["ended_at_ms"] == 10


@pytest.mark.parametrize("key", ["accel", "rapid"])
def test_a_machine_value_too_small_to_move_is_refused_not_a_crash(tmp_path, capsys, key):
    # issue 17 item 7: ZeroDivisionError in motion.trapezoid ("internal error")
    src = write(tmp_path / "M03.plc", "main(){ g0moveA(0, 4, 1000); exit(99); };\n")
    mach = write(tmp_path / "m.toml", f"[axes.Z]\n{key} = 5e-324\n")
    rc, out, err = run_cli(capsys, "run", str(src), "--machine", str(mach), "--json")
    assert rc == 2 and out == ""
    assert f"m.toml:2: axes.Z.{key}: 5e-324 is out of range (allowed: 0.01 to" in err
    assert "internal error" not in err


@pytest.mark.parametrize("args,msg", [
    # issue 17 item 10: `run --eparam 4294967297` ran with eparam 1; --adc took any size
    (["--eparam", "4294967297"], "argument --eparam: must be from -2147483648 to 4294967295, "
                                 "not 4294967297"),
    (["--eparam", "-2147483649"], "must be from -2147483648 to 4294967295"),
    (["--adc", "0=99999999999"], "the value of --adc must be from -2147483648 to 2147483647, "
                                 "not 99999999999"),
    (["--adc", "8=1"], "the channel of --adc must be from 0 to 7, not 8"),
    (["--input", "256=1"], "the pin of --input must be from 0 to 255, not 256"),
    (["--start", "M05:4294967296@0"], "the eparam of --start must be from -2147483648 to "
                                      "4294967295, not 4294967296"),
    (["--start", "M05@99999999999999"], "the time of --start must be from 0 to 604800000 ms"),
    (["--gvarget-latency", "99999999999"], "must be from 0 to 60000 ms"),
    (["--ms", "99999999999999"], "--ms must be from 0 to 604800000"),
])
def test_numbers_out_of_range_exit_2_naming_option_and_range(tmp_path, capsys, args, msg):
    f = write(tmp_path / "M05.plc", DELAY)
    code, out, err = run_cli(capsys, "run", f, *args)
    assert code == 2 and out == ""
    assert msg in err and "Traceback" not in err


def test_an_eparam_written_unsigned_is_the_signed_32_bit_value(tmp_path, capsys):
    f = write(tmp_path / "M05.plc", "main(){ v = eparam; exit(99); };\n")
    code, out, _ = run_cli(capsys, "run", f, "--eparam", "0xFFFFFFFF", "--json")
    assert code == 0 and json.loads(out)["vars"]["M05"]["v"] == -1
    code, out, _ = run_cli(capsys, "run", f, "--eparam", "-2147483648", "--json")
    assert code == 0 and json.loads(out)["vars"]["M05"]["v"] == -(1 << 31)


def test_the_controller_api_refuses_what_does_not_fit(tmp_path):
    from plcbuilder import api
    c = api.Controller(api.default_machine())
    with pytest.raises(api.ControllerError, match="ADC value must be from -2147483648"):
        c.set_adc(0, 1 << 40)
    c.load([api.compile_source("main(){ exit(99); };", "M05.plc").program])
    with pytest.raises(api.ControllerError, match="eparam must be from"):
        c.start("M05", 1 << 32)
    c.start("M05", 0xFFFFFFFF)


# ------------------------------------------------------------------ --break (SPEC §6)

EXAMPLE = Path(__file__).resolve().parents[2] / "plcbuilder" / "resources" / "example_project"


def test_break_halts_the_run_and_the_json_says_where(capsys):
    """"When a run halts at a breakpoint, it ends there: the JSON gains
    `halted: {reason, t_ms, procedure, file, line, stack: [{procedure, line}],
    vars}` and the exit status is 0." — M80 halts on the line that reads the
    home switch."""
    code, out, err = run_cli(capsys, "run", EXAMPLE, "--start", "M80@5", "--break",
                             "M80.plc:31", "--json")
    assert code == 0, err
    rep = json.loads(out)
    h = rep["halted"]
    assert (h["reason"], h["t_ms"], h["procedure"], h["file"], h["line"]) == \
        ("breakpoint", 5, "M80", "M80.plc", 31)
    assert [(f["procedure"], f["line"]) for f in h["stack"]] == [("find_home_z", 31),
                                                                  ("main", 75)]
    assert h["vars"]["statez"] == 0 and h["vars"]["speed"] == 500
    assert rep["ended_at_ms"] == 5
    m80 = [p for p in rep["procedures"] if p["name"] == "M80"][0]
    assert m80["ended_at_ms"] is None


def test_break_with_a_condition_and_on_a_line_without_code(capsys):
    """"--break FILE:LINE[:CONDITION] (repeatable; FILE is a procedure's file
    name, e.g. `M80.plc:12`)" — a condition, and a line without code (30) that
    moves to the next one with code (31)."""
    code, out, err = run_cli(capsys, "run", EXAMPLE, "--start", "M80@5", "--break",
                             "M80.plc:41:sens==1 && timer>0", "--break", "M80.plc:30:statez==2",
                             "--json")
    assert code == 0, err
    h = json.loads(out)["halted"]
    assert (h["line"], h["vars"]["sens"], h["vars"]["statez"]) == (41, 1, 1)


def test_without_break_halted_is_null(tmp_path, capsys):
    """"Without `--break`, `halted` is null." """
    f = write(tmp_path / "M05.plc", DELAY)
    code, out, err = run_cli(capsys, "run", f, "--json")
    assert code == 0 and json.loads(out)["halted"] is None


def test_a_break_never_reached_leaves_halted_null_and_the_summary_says_halted(capsys, tmp_path):
    f = write(tmp_path / "M05.plc", DELAY)
    code, out, err = run_cli(capsys, "run", f, "--break", "M05.plc:1:timer==99", "--json")
    assert code == 0 and json.loads(out)["halted"] is None
    code, out, err = run_cli(capsys, "run", EXAMPLE, "--start", "M80@5", "--break",
                             "M80.plc:31")
    assert code == 0 and "halted (breakpoint) at 5 ms in M80: M80.plc:31" in out
    assert "run ended at 5 ms (halted)" in out


@pytest.mark.parametrize("spec, msg", [
    ("M80.plc", "give FILE:LINE[:CONDITION]"),
    ("M80.plc:x", "give FILE:LINE[:CONDITION]"),
    ("M80.plc:31:sens==", "the condition does not compile"),
    ("M80.plc:31:ghost==1", "'ghost', which is not a variable of M80"),
    ("M80.plc:500", "M80.plc has no code on line 500"),
    ("NOPE.plc:3", "no loaded procedure is built from 'NOPE.plc'"),
])
def test_bad_breaks_exit_2_with_the_reason(capsys, spec, msg):
    code, out, err = run_cli(capsys, "run", EXAMPLE, "--start", "M80@5", "--break", spec)
    assert code == 2 and msg in err and "Traceback" not in err


# ------------------------------------------------------------ --write and --force (SPEC §6)

COUNT = ("main(){ x = 0; do { x = x + 1; y = portget(2); if (x > 5) { portset(1); } }"
         " while (x < 20); exit(99); };\n")


def test_force_and_write_options_act_at_their_ms_and_the_json_lists_what_is_forced(
        tmp_path, capsys):
    """"`--force NAME=VALUE@MS` and `--write NAME=VALUE@MS` (repeatable; NAME is
    `PROC.var`, `in N`, `out N`, `adc N`, `pwm N`, `dac N` or `gvar N`)" """
    f = write(tmp_path / "C.plc", COUNT)
    code, out, err = run_cli(capsys, "run", f, "--json", "--ms", "30", "--force", "C.x=3@2",
                             "--force", "in 2=1@0", "--write", "out 7=1@1",
                             "--write", "pwm 1=250@4", "--force", "gvar 0x401=0@0")
    assert code == 0, err
    rep = json.loads(out)
    assert rep["vars"]["C"]["x"] == 3 and rep["vars"]["C"]["y"] == 1
    assert rep["procedures"][0]["ended_at_ms"] is None          # x never reaches 20
    assert rep["outputs"] == [7] and rep["pwm"][1] == 250       # output 1 held off
    assert list(rep)[-1] == "forces"
    assert rep["forces"] == [{"target": "in 2", "value": 1, "since_ms": 0},
                             {"target": "out 1", "value": 0, "since_ms": 0},
                             {"target": "C.x", "value": 3, "since_ms": 2}]
    code, out, err = run_cli(capsys, "run", f, "--ms", "30", "--force", "C.x=3@2")
    assert code == 0 and "forced: C.x=3 (from 2 ms)" in out


def test_without_forces_the_json_has_an_empty_list(tmp_path, capsys):
    f = write(tmp_path / "C.plc", COUNT)
    code, out, err = run_cli(capsys, "run", f, "--json")
    assert code == 0 and json.loads(out)["forces"] == []


@pytest.mark.parametrize("opt, value, reason", [
    ("--force", "C.zz=3@2", "C has no variable 'zz'"),
    ("--force", "D.x=3@2", "no procedure named D"),
    ("--force", "in 99=1@2", r"no input 99 \(0..63\)"),
    ("--write", "adc 8=1", "no ADC channel 8"),
    ("--force", "in 2=x@2", "the value of --force in 2 must be a whole number"),
    ("--force", "in 2=2@2", "0 or 1"),
    ("--write", "bogus 2=1", "'bogus 2' is not a target"),
    ("--write", "in 2", "--write needs NAME=VALUE@MS"),
    ("--force", "gvar 6060=1", "cannot be forced"),
])
def test_bad_force_and_write_options_are_usage_errors(tmp_path, capsys, opt, value, reason):
    f = write(tmp_path / "C.plc", COUNT)
    code, out, err = run_cli(capsys, "run", f, opt, value)
    assert code == 2 and out == ""
    assert re.search(reason, err), err


def test_scenario_file_lines_write_force_and_release(tmp_path, capsys):
    f = write(tmp_path / "C.plc", COUNT)
    sc = write(tmp_path / "s.txt", "force C.x=3 @ 2\nforce in 2=1 @ 0\n"
                                   "release C.x restore @ 10\nrelease in 2 keep @ 12\n"
                                   "write C.x=18 @ 12\n")
    code, out, err = run_cli(capsys, "run", f, "--json", "--scenario", sc)
    assert code == 0, err
    rep = json.loads(out)
    # released at 10 with the program's x (4): 5, 6; written 18 at 12: 19, 20 (tick 13);
    # exit(99) runs in the next tick
    assert rep["procedures"][0]["ended_at_ms"] == 14 and rep["vars"]["C"]["x"] == 20
    assert rep["forces"] == [] and rep["vars"]["C"]["y"] == 1   # in 2 kept as set by hand
    bad = write(tmp_path / "bad.txt", "release in 2 later @ 3\n")
    code, out, err = run_cli(capsys, "run", f, "--scenario", bad)
    assert code == 2 and "bad.txt:1:" in err and "is not a target" in err


@pytest.mark.parametrize("lines,where,msg", [
    ("start M05 @ 0\nbind 9=M88:0 @ 0\n", "2", "no procedure named M88"),
    ("# a comment\n\nstart M05 @ 0\nwrite M06.timer=500 @ 2\n", "4",
     "M06 is not running: a write sets a running procedure's variable"),
    ("start M05 @ 0\nforce M05.nope=1 @ 1\n", "2", "M05 has no variable 'nope'"),
    ("start M05 @ 0\nadc 9=1 @ 1\n", "2", "the channel of adc must be from 0 to 7"),
])
def test_a_scenario_file_error_names_its_file_and_line(tmp_path, capsys, lines, where, msg):
    """Issue 25: an error about a scenario file's action is 'FILE:LINE: what is wrong',
    not blamed on an option the user did not give."""
    write(tmp_path / "p" / "hardware" / "M05.plc", DELAY)
    write(tmp_path / "p" / "hardware" / "M06.plc", DELAY)
    sc = write(tmp_path / "s.txt", lines)
    code, out, err = run_cli(capsys, "run", tmp_path / "p", "--scenario", sc)
    assert code == 2, err
    assert msg in err and "--" not in err
    assert f"{sc}:{where}: " in err


def test_an_option_error_names_the_option_as_given(tmp_path, capsys):
    write(tmp_path / "p" / "hardware" / "M05.plc", DELAY)
    write(tmp_path / "p" / "hardware" / "M06.plc", DELAY)
    code, out, err = run_cli(capsys, "run", tmp_path / "p", "--start", "M05@0",
                             "--write", "M06.timer=3@2")
    assert code == 2, err
    assert "--write M06.timer=3@2: M06 is not running" in err
