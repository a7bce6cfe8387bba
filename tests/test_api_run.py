"""``api.run``: the composition behind ``plcbuilder run`` (docs/controller.md)."""

from __future__ import annotations

import csv
import gzip
import json
from pathlib import Path

import pytest

from plcbuilder.project.new import create_project
from plcbuilder.api import RunOptions, UsageError, run

DELAY = "main(){ timer=10; do{timer--;}while(timer>0); exit(99); };\n"


def write(path: Path, text: str) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text, encoding="utf-8")
    return path


@pytest.fixture(scope="module")
def project(tmp_path_factory):
    return create_project(tmp_path_factory.mktemp("proj") / "shop").root


def test_a_single_file_runs_as_a_hardware_procedure_and_reports_every_field(tmp_path):
    rep = run(write(tmp_path / "M05.plc", DELAY)).report
    for key in ("ended_at_ms", "procedures", "vars", "outputs", "pwm", "dac", "messages",
                "prints", "faults", "axes", "proc"):
        assert key in rep
    assert rep["ended_at_ms"] == 10
    assert rep["procedures"] == [{"name": "M05", "kind": "hardware", "started_at_ms": 0,
                                  "ended_at_ms": 10, "exit_code": 99,
                                  "exit_name": "plc_exit_normal", "vexit": 0, "eparam": 0}]
    assert rep["vars"]["M05"]["timer"] == 0
    assert rep["outputs"] == [] and rep["pwm"] == [0] * 8 and rep["dac"] == [0] * 8
    assert rep["axes"] == {"X": 10000, "Y": 10000, "Z": 2000} and rep["proc"] == 0
    json.dumps(rep)


def test_messages_prints_and_faults_have_the_spec_fields(tmp_path):
    src = """main(){
      command=120; parameter=eparam; message=PLCCMD_REPLY_TO_MYCNC;
      gvarset(20005, eparam);
      timer=2; do { timer--; } while (timer > 0);
      a = 5 / (eparam - 1500);
    };"""
    rep = run(write(tmp_path / "M03.plc", src), RunOptions(eparam=1500)).report
    assert rep["messages"][0] == {"t_ms": 0, "message": 1100, "name": "PLCCMD_REPLY_TO_MYCNC",
                                  "command": 120, "parameter": 1500, "from": "M03"}
    assert rep["messages"][1]["message"] == -1
    assert rep["prints"] == [{"t_ms": 0, "register": 20005, "value": 1500, "from": "M03"}]
    f = rep["faults"][0]
    assert (f["t_ms"], f["from"], f["line"], f["text"]) == (2, "M03", 5, "division by zero")
    assert rep["procedures"][0]["exit_code"] == -1


def test_software_single_file_gets_eparam_as_param(tmp_path):
    src = "main(){ p = Param; do { n++; } while (n < 3); exit(99); };"
    rep = run(write(tmp_path / "S.plc", src), RunOptions(software=True, eparam=4)).report
    assert rep["procedures"][0]["kind"] == "software"
    assert rep["vars"]["S"]["p"] == 4
    assert rep["procedures"][0]["ended_at_ms"] == 300


def test_the_run_stops_at_ms_and_running_procedures_have_null_ends(tmp_path):
    rep = run(write(tmp_path / "M07.plc", "main(){ do { } while (1); };"),
              RunOptions(ms=250)).report
    assert rep["ended_at_ms"] == 250
    p = rep["procedures"][0]
    assert (p["ended_at_ms"], p["exit_code"], p["exit_name"]) == (None, None, None)
    assert rep["running"] == "M07"


def test_a_project_runs_software_by_itself_and_hardware_with_start(project):
    opts = RunOptions(ms=500, starts=["M03:12000@100"])
    rep = run(project, opts).report
    names = [(p["name"], p["started_at_ms"], p["ended_at_ms"]) for p in rep["procedures"]]
    assert ("__HANDLER_INIT", 0, 0) in names and ("LUBE", 0, None) in names
    assert ("M03", 100, 102) in names
    assert {0, 5, 6} <= set(rep["outputs"])         # spindle, lube pump, charge pump
    assert rep["pwm"][0] == 12000 and rep["proc"] == 70
    assert {"t_ms": 100, "message": 1100, "name": "PLCCMD_REPLY_TO_MYCNC", "command": 120,
            "parameter": 12000, "from": "M03"} in rep["messages"]
    assert {"t_ms": 0, "register": 20000, "value": 1, "from": "__HANDLER_INIT"} in rep["prints"]
    assert rep["ended_at_ms"] == 500


def test_inputs_set_by_the_scenario_override_the_wiring(project, tmp_path):
    ok = run(project, RunOptions(ms=5000, starts=["M71@100"])).report
    m71 = [p for p in ok["procedures"] if p["name"] == "M71"][0]
    assert m71["exit_code"] == 99
    sc = write(tmp_path / "arc.txt", "start M71 @ 100\ninput 5=0 @ 0   # no arc\n")
    bad = run(project, RunOptions(ms=5000, scenario=sc)).report
    m71 = [p for p in bad["procedures"] if p["name"] == "M71"][0]
    assert (m71["exit_code"], m71["exit_name"]) == (3, "plc_exit_plasma_timeout")
    assert any(m["name"] == "PLC_MESSAGE_ERR_PLASMA_TIMEOUT" for m in bad["messages"])


def test_adc_values_can_be_scheduled(tmp_path):
    src = "main(){ do { a = adc01; } while (a < 3000); exit(99); };"
    rep = run(write(tmp_path / "M09.plc", src), RunOptions(adcs=["0=3500@40"])).report
    assert rep["procedures"][0]["ended_at_ms"] == 41


def test_the_trace_has_one_row_a_tick_with_the_documented_columns(tmp_path):
    trace = tmp_path / "t.csv"
    run(write(tmp_path / "M05.plc", "main(){ portset(33); pwm02=7; " + DELAY[7:]),
        RunOptions(trace=trace))
    rows = list(csv.reader(trace.open()))
    assert rows[0] == (["t_ms", "proc", "message", "running", "in0", "in1", "out0", "out1"]
                       + [f"pwm{i}" for i in range(8)] + [f"dac{i}" for i in range(8)]
                       + ["X", "Y", "Z"])
    assert [r[0] for r in rows[1:]] == [str(t) for t in range(11)]
    first = dict(zip(rows[0], rows[1]))
    assert first["running"] == "M05" and first["out1"] == "2" and first["pwm1"] == "7"
    assert first["X"] == "10000"
    assert dict(zip(rows[0], rows[-1]))["running"] == ""


def test_a_gz_trace_is_compressed(tmp_path):
    trace = tmp_path / "t.csv.gz"
    run(write(tmp_path / "M05.plc", DELAY), RunOptions(trace=trace))
    assert len(gzip.decompress(trace.read_bytes()).decode().splitlines()) == 12


def test_compile_errors_give_diagnostics_and_no_report(tmp_path):
    r = run(write(tmp_path / "M05.plc", "main(){ a = ; };"))
    assert not r.ok and r.report is None
    assert any(d.is_error for c in r.compiled for d in c.diagnostics)


@pytest.mark.parametrize("setup,msg", [
    (lambda d: (d / "nope.plc", RunOptions()), "no such file or folder"),
    (lambda d: (write(d / "M05.plc", DELAY), RunOptions(starts=["M99@0"])),
     "no procedure named M99"),
    (lambda d: (write(d / "M05.plc", DELAY), RunOptions(inputs=["100=1@0"])), "no such input"),
    (lambda d: (write(d / "M05.plc", DELAY), RunOptions(inputs=["300=1@0"])),
     "the pin of --input must be from 0 to 255, not 300"),
    (lambda d: (write(d / "M05.plc", DELAY), RunOptions(adcs=["9=1@0"])),
     "the channel of --adc must be from 0 to 7, not 9"),
    (lambda d: (write(d / "M05.plc", DELAY), RunOptions(eparam=1 << 32)),
     "eparam must be from -2147483648 to 4294967295"),
    (lambda d: (write(d / "M05.plc", DELAY), RunOptions(inputs=["3=x"])), "whole number"),
    (lambda d: (write(d / "M05.plc", DELAY), RunOptions(ms=-5)), "--ms"),
    (lambda d: (write(d / "M05.plc", DELAY),
                RunOptions(machine=write(d / "m.toml", "[axes.X]\nrapid = 'fast'\n"))),
     "m.toml"),
    (lambda d: (write(d / "M05.plc", DELAY), RunOptions(scenario=d / "none.txt")),
     "cannot read the scenario"),
    (lambda d: (write(d / "M05.plc", DELAY),
                RunOptions(scenario=write(d / "s.txt", "start M05 @ 0\nfly @ 3\n"))),
     "s.txt:2: unknown action"),
    (lambda d: (write(d / "M05.plc", DELAY), RunOptions(trace=d / "no" / "dir" / "t.csv")),
     "cannot write the trace"),
    (lambda d: ((d / "empty").mkdir() or d / "empty", RunOptions()), "no procedures"),
])
def test_bad_usage_raises_usage_error_with_the_reason(tmp_path, setup, msg):
    target, opts = setup(tmp_path)
    with pytest.raises(UsageError, match=msg):
        run(target, opts)


def test_both_backends_give_the_same_report(project):
    opts = dict(ms=3000, starts=["M71@100", "M03:500@1000", "M05@2000"])
    fast = run(project, RunOptions(**opts)).report
    ref = run(project, RunOptions(backend="reference", **opts)).report
    assert fast == ref


def test_run_start_m03_at_0_leaves_the_spindle_on(project):
    """`run PROJECT --start M03@0`: __HANDLER_INIT "begins in the tick of the first
    load, before any procedure started at that same tick", so output 0 stays on."""
    rep = run(project, RunOptions(ms=500, starts=["M03:12000@0"])).report
    starts = [(p["name"], p["started_at_ms"]) for p in rep["procedures"]]
    assert starts.index(("__HANDLER_INIT", 0)) < starts.index(("M03", 0))
    assert 0 in rep["outputs"] and rep["pwm"][0] == 12000


def test_a_lazy_name_loaded_on_its_own_still_loads_the_rest():
    """api loads its heavy stages on first use; one of them loaded by name
    (api.run_suite) must not keep save_trace from finding the trace module."""
    import subprocess
    import sys
    code = ("from plcbuilder import api; api.run_suite; "
            "import tempfile, os; d = tempfile.mkdtemp(); "
            "api.save_trace(api.Trace(0, 1, {}), os.path.join(d, 't.plctrace')); print('ok')")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         cwd=str(Path(__file__).resolve().parents[1]))
    assert out.stdout.strip() == "ok", out.stderr[-1500:]
