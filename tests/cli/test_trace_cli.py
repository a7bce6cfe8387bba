"""``plcbuilder run --trigger/--capture/--history/--watch`` and ``plcbuilder trace``."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from tests.cli._run import run_cli
from tests.vcd_reader import VCDVCD

PULSE = ("main(){ timer=20; do{timer--;}while(timer>0); portset(3);"
         " timer=10; do{timer--;}while(timer>0); portclear(3); exit(99); };\n")


@pytest.fixture
def pulse(tmp_path) -> Path:
    f = tmp_path / "M90.plc"
    f.write_text(PULSE)
    return f


def test_trigger_writes_a_capture_around_the_trigger(tmp_path, capsys, pulse):
    """SPEC §7: 'Headless: plcbuilder run … --trigger SPEC --pre MS --post MS --capture FILE.'"""
    cap = tmp_path / "cap.plctrace"
    code, out, err = run_cli(capsys, "run", pulse, "--trigger", "out 3 rise", "--pre", "5",
                             "--post", "3", "--capture", cap, "--json")
    assert code == 0, err
    rep = json.loads(out)
    assert rep["capture"]["t_ms"] == 20
    assert (rep["capture"]["from_ms"], rep["capture"]["to_ms"]) == (15, 23)
    code, out, err = run_cli(capsys, "trace", "info", cap, "--json")
    assert code == 0, err
    info = json.loads(out)
    assert (info["t_start"], info["t_end"]) == (15, 23)
    assert info["meta"]["trigger"]["spec"] == "out 3 rise"


def test_trigger_that_never_fires_reports_null(tmp_path, capsys, pulse):
    cap = tmp_path / "cap.plctrace"
    code, out, _ = run_cli(capsys, "run", pulse, "--trigger", "out 4 rise", "--capture", cap,
                           "--json")
    assert code == 0 and json.loads(out)["capture"] is None and not cap.exists()


def test_history_without_a_trigger_says_nothing_of_a_capture(tmp_path, capsys, pulse):
    """Issue 25: --history alone printed 'capture: the trigger never fired; nothing
    written' though no trigger was asked for."""
    hist = tmp_path / "all.plctrace"
    code, out, err = run_cli(capsys, "run", pulse, "--history", hist)
    assert code == 0, err
    assert "capture:" not in out and "never fired" not in out
    assert f"history: {hist}" in out and hist.exists()
    code, out, err = run_cli(capsys, "run", pulse, "--history", hist, "--json")
    rep = json.loads(out)
    assert "capture" not in rep and rep["history"]["file"] == str(hist)


def test_capture_straight_to_vcd_and_history_of_the_session(tmp_path, capsys, pulse):
    code, out, err = run_cli(capsys, "run", pulse, "--trigger", "out 3 fall", "--pre", "2",
                             "--capture", tmp_path / "c.vcd", "--history", tmp_path / "all.plctrace",
                             "--watch", "M90.timer", "--json")
    assert code == 0, err
    v = VCDVCD(str(tmp_path / "c.vcd"))
    assert [(t, x) for t, x in v["outputs.out3"].tv] == [(28, "1"), (30, "0")]
    code, out, err = run_cli(capsys, "trace", "export", tmp_path / "all.plctrace",
                             tmp_path / "all.csv", "--per-tick")
    assert code == 0, err
    lines = (tmp_path / "all.csv").read_text().splitlines()
    assert "M90.timer" in lines[0].split(",") and len(lines) == 1 + 31


def test_compare_exit_status_says_whether_traces_differ(tmp_path, capsys, pulse):
    a, b, c = (tmp_path / f"{n}.plctrace" for n in "abc")
    assert run_cli(capsys, "run", pulse, "--history", a)[0] == 0
    assert run_cli(capsys, "run", pulse, "--history", b)[0] == 0
    assert run_cli(capsys, "run", pulse, "--eparam", "1", "--ms", "5", "--history", c)[0] == 0
    code, out, _ = run_cli(capsys, "trace", "compare", a, b)
    assert code == 0 and "the same" in out
    code, out, _ = run_cli(capsys, "trace", "compare", a, c, "--json")
    d = json.loads(out)
    assert code == 1 and not d["same"] and d["t_ms"] == 0


def test_compare_of_traces_with_no_tick_in_common_exits_1(tmp_path, capsys, pulse):
    early, late = tmp_path / "early.plctrace", tmp_path / "late.plctrace"
    for path, trigger in ((early, "out 3 rise"), (late, "out 3 fall")):
        assert run_cli(capsys, "run", pulse, "--trigger", trigger, "--pre", "0",
                       "--post", "3", "--capture", path)[0] == 0      # 20..23, 30..33
    code, out, _ = run_cli(capsys, "trace", "compare", early, late)
    assert code == 1 and "no tick in common" in out, out


@pytest.mark.skipif(__import__("shutil").which("sigrok-cli") is None,
                    reason="sigrok-cli is not installed (apt install sigrok-cli)")
def test_export_split_bits_is_read_by_sigrok(tmp_path, capsys, pulse):
    """Issue 25 item 9: `trace export TRACE OUT.vcd --split-bits` writes one-bit
    lanes that libsigrok 0.5 (sigrok-cli, PulseView) reads every sample of."""
    import subprocess
    hist = tmp_path / "all.plctrace"
    assert run_cli(capsys, "run", pulse, "--watch", "M90.timer", "--history", hist)[0] == 0
    out_vcd = tmp_path / "lanes.vcd"
    code, out, err = run_cli(capsys, "trace", "export", hist, out_vcd, "--split-bits")
    assert code == 0 and "wrote" in out, err
    r = subprocess.run(["sigrok-cli", "-I", "vcd", "-i", str(out_vcd), "-O", "csv"],
                       capture_output=True, text=True, timeout=120, check=True)
    names = next(line for line in r.stdout.splitlines()
                 if line.startswith("; Channels")).split(": ", 1)[1].split(", ")
    rows = [[int(x) for x in line.split(",")] for line in r.stdout.splitlines()
            if line[:1] in ("0", "1")]
    assert len(rows) == 30                      # ticks 0..29; the run ended at 30
    out3 = names.index("out3")
    assert [row[out3] for row in rows] == [0] * 20 + [1] * 10
    timer = [names.index(f"timer[{b}]") for b in range(5)]
    values = [sum(row[c] << b for b, c in enumerate(timer)) for row in rows]
    assert values[:3] == [19, 18, 17]            # the loop counts down from 20
    code, _out, err = run_cli(capsys, "trace", "export", hist, tmp_path / "x.csv",
                              "--split-bits")
    assert code == 2 and "for VCD" in err
