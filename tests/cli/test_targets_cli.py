"""plcbuilder new --target, run and test on the targets of SPEC §9 (docs/targets.md)."""

from __future__ import annotations

import json

from plcbuilder.cli.main import main


def test_new_huazhong_run_json_and_test(tmp_path, capsys):
    dest = tmp_path / "mill"
    assert main(["new", "--target", "huazhong", str(dest)]) == 0
    assert "target: huazhong, program: plc" in capsys.readouterr().out
    assert main(["run", str(dest), "--ms", "200", "--input", "0=0@0", "--input", "0=1@100",
                 "--json"]) == 0
    rep = json.loads(capsys.readouterr().out)
    assert rep["target_profile"] == "huazhong" and 7 in rep["outputs"]
    assert rep["registers"]["Y"]["0"] & 0x80 and rep["registers"]["P"] == {"0": 5}
    # only the non-zero ones: the CNC's axis status words axis_stat(0..2), X, Y, Z
    # standing still (AX_FSTOP_LAMP)
    assert rep["registers"]["F"] == {"0": 0x20, "10": 0x20, "20": 0x20}
    assert rep["calls"]["init"] == 1 and rep["calls"]["plc1"] == 13
    assert main(["test", str(dest)]) == 0
    assert "5 passed, 0 failed" in capsys.readouterr().out


def test_new_tgmotion_run_reports_calls_and_budget(tmp_path, capsys):
    dest = tmp_path / "tg"
    assert main(["new", "--target", "tgmotion", str(dest)]) == 0
    capsys.readouterr()
    assert main(["run", str(dest), "--ms", "10", "--json"]) == 0
    rep = json.loads(capsys.readouterr().out)
    # Program_Ini clears 16384 words of TGM_Data (3.3 ms at 20 ns an instruction):
    # the cycles (2 a ms, 5 slots each) begin in tick 4
    assert rep["cycles"] == 6 * 2
    assert rep["calls"]["Program_05"] == 6 * 2 * 5 and rep["calls"]["Program_04"] == 6 * 2
    assert rep["budget"] == [] and rep["registers"]["TGM_Data"]["0"] == 250
    assert main(["run", str(dest), "--ms", "6"]) == 0
    assert "calls: Program_01" in capsys.readouterr().out
    assert main(["test", str(dest)]) == 0


def test_unknown_target_refused_naming_the_line(tmp_path, capsys):
    dest = tmp_path / "p"
    assert main(["new", str(dest)]) == 0
    text = (dest / "plcbuilder.toml").read_text()
    (dest / "plcbuilder.toml").write_text(text.replace('machine = "machine.toml"',
                                                       'machine = "machine.toml"\ntarget = "s7"'))
    capsys.readouterr()
    assert main(["build", str(dest)]) != 0
    err = capsys.readouterr().err
    assert "plcbuilder.toml:4:" in err and "unknown target 's7'" in err


def test_tgmotion_prints_show_in_the_run_summary(tmp_path, capsys):
    """docs/targets.md "Diagnostic prints": the seed's functions "are used to output
    texts to RTX Server console"; here they print in the run log, and the summary of
    ``plcbuilder run`` (no --json) shows it, as the IDE's Run log does."""
    dest = tmp_path / "tg"
    assert main(["new", "--target", "tgmotion", str(dest)]) == 0
    capsys.readouterr()
    assert main(["run", str(dest), "--ms", "3"]) == 0
    out = capsys.readouterr().out
    assert "log:\n        0 ms  Program_Ini: RtWprintf_Long(524288) (Program.plc:13)\n" in out


def test_the_summary_shows_the_oscilloscope_and_the_softmc_parts(tmp_path, capsys):
    """Without --json the summary shows what issue 27 added to the run: the
    oscilloscope's signals and last sample (docs/targets.md, "capture the values
    of desired registers"), and softMC's virtual outputs and PLSs ("There is no
    limit of the number of positions or PLSs that can be defined")."""
    dest = tmp_path / "tg"
    assert main(["new", "--target", "tgmotion", str(dest)]) == 0
    capsys.readouterr()
    assert main(["run", str(dest), "--ms", "20", "--scope", "gvar 2000000",
                 "--scope", "Program.target_x"]) == 0
    out = capsys.readouterr().out
    assert "oscilloscope: 32 samples of gvar 2000000, Program.target_x; the last at " in out
    # cycles count from Program_Ini's end (tick 4 here): the sample's time is from
    # the first cycle, 31 cycles of 500 us and 300.36 us into the 32nd
    assert "the last at 15800.36 us (cycle 31): 250 " in out
    proj = tmp_path / "my"
    assert main(["new", str(proj)]) == 0
    with (proj / "machine.toml").open("a", encoding="utf-8") as f:
        f.write('\n[[pls]]\nname = "cam"\naxis = "X"\nvout = 3\npositions = [50.0]\n'
                'polarity = 1\nenabled = true\n')
        for k in range(2, 11):
            f.write(f'\n[[pls]]\naxis = "Y"\nvout = {k + 10}\npositions = [1.0]\n')
    capsys.readouterr()
    assert main(["run", str(proj), "--ms", "10"]) == 0
    out = capsys.readouterr().out
    assert "virtual outputs on: 3\n" in out
    assert "PLS1 cam: X -> VOUT.3, enabled, output 1\n" in out
    assert "PLS10 PLS10: Y -> VOUT.20, disabled, output 0\n" in out
