"""VCD and CSV exports as their readers read them (issues 24 item 9, 25 item 9):
each VCD variable as wide as its values need (64-bit values were cut to 32
bits), read back by GTKWave's own reader (``vcd2fst``) and by vcdvcd; with
``split_bits`` every number as one-bit lanes that libsigrok 0.5 (PulseView,
``sigrok-cli``) reads; CSV cells that a spreadsheet would run as a formula
quoted as OWASP advises."""

from __future__ import annotations

import csv
import io
import shutil
import subprocess

import pytest
from tests.vcd_reader import VCDVCD

from plcbuilder.controller.history import Trace
from plcbuilder.trace import export

I64 = (-(1 << 63), (1 << 63) - 1)


def _wide() -> Trace:
    """Numbers of every size: 64-bit extremes, negatives, a small counter, a
    text signal and bits; a watched variable first recorded at 3 ms."""
    return Trace(0, 9, {
        "out 1": ("bit", [(0, 0), (2, 1), (7, 0)]),
        "axis X": ("int", [(0, I64[0]), (3, I64[1]), (5, -1), (6, 0)]),
        "pwm 0": ("int", [(0, 0), (4, 1000)]),
        "dac 0": ("int", [(0, -500), (8, 7)]),
        "adc 0": ("int", [(0, 0)]),
        "running": ("text", [(0, 0), (1, 1)]),
        "M80.timer": ("int", [(3, 5), (4, -2)]),
    }, ["", "M80"], [], {})


def _value_at(trace: Trace, name: str, t: int):
    return trace.value_at(name, t)


def _number(bits: str, signed: bool) -> int:
    """A vector's bits as a number: two's complement when the signal is ever negative."""
    v = int(bits, 2)
    return v - (1 << len(bits)) if signed and bits[0] == "1" else v


def test_each_variable_is_as_wide_as_its_values_need():
    tr = _wide()
    assert export.width("int", tr.signals["axis X"][1]) == 64
    assert export.width("int", tr.signals["pwm 0"][1]) == 10         # 1000 < 1024
    assert export.width("int", tr.signals["dac 0"][1]) == 10         # -500 .. 7, a sign bit
    assert export.width("int", tr.signals["adc 0"][1]) == 1
    assert export.width("int", [(0, I64[1])]) == 63
    assert export.width("int", [(0, -1)]) == 1
    assert export.width("int", [(0, -2)]) == 2
    assert export.width("bit", [(0, 1)]) == 1


def _check_vcd(v, tr: Trace, names: dict[str, str]) -> None:
    """Every signal's every change, read back from ``v`` (a VCDVCD)."""
    for signal, ref in names.items():
        kind, changes = tr.signals[signal]
        var = v[ref]
        assert int(var.size) == export.width(kind, changes), signal
        got = [(t, x) for t, x in var.tv if "x" not in x]
        want = [(t, val) for t, val in changes]
        signed = any(val < 0 for _t, val in changes)
        assert [(t, _number(x.zfill(int(var.size)), signed) if kind != "bit" else int(x))
                for t, x in got] == want, signal


NAMES = {"out 1": "outputs.out1", "axis X": "axes.X", "pwm 0": "pwm.pwm0", "dac 0": "dac.dac0",
         "adc 0": "adc.adc0", "running": "plc.running", "M80.timer": "variables.M80.timer"}


def test_64_bit_values_read_back_whole(tmp_path):
    """-2^63 was written ``b0`` in a 32-bit ``integer``."""
    tr = _wide()
    path = tmp_path / "wide.vcd"
    export.export(tr, path)
    text = path.read_text()
    assert "$var integer 64" in text and "$var integer 32" not in text
    _check_vcd(VCDVCD(str(path)), tr, NAMES)


@pytest.mark.skipif(shutil.which("vcd2fst") is None or shutil.which("fst2vcd") is None,
                    reason="GTKWave's vcd2fst/fst2vcd are not installed (apt install gtkwave)")
def test_gtkwave_reads_the_vcd(tmp_path):
    """GTKWave's own VCD reader (``vcd2fst``, headless) reads every value back:
    converted to FST and back to VCD (``fst2vcd``), the values are the same."""
    tr = _wide()
    for split in (False, True):
        src, fst = tmp_path / f"w{split}.vcd", tmp_path / f"w{split}.fst"
        export.export(tr, src, split_bits=split)
        r = subprocess.run(["vcd2fst", str(src), str(fst)], capture_output=True, text=True,
                           timeout=60)
        assert r.returncode == 0 and fst.stat().st_size > 0, r.stderr
        back = tmp_path / f"back{split}.vcd"
        with open(back, "w") as f:
            subprocess.run(["fst2vcd", str(fst)], stdout=f, check=True, timeout=60)
        v = VCDVCD(str(back))
        if not split:
            _check_vcd(v, tr, NAMES)
        else:
            lanes = {n: [k for k in v.references_to_ids if k.startswith(ref + "[")]
                     for n, ref in NAMES.items() if tr.signals[n][0] != "bit"}
            assert len(lanes["axis X"]) == 64 and len(lanes["pwm 0"]) == 10


def _sigrok(path) -> tuple[list[str], list[list[int]]]:
    """``sigrok-cli -I vcd -O csv``: the channel names and a row of 0/1 per sample."""
    r = subprocess.run(["sigrok-cli", "-I", "vcd", "-i", str(path), "-O", "csv"],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    names: list[str] = []
    rows = []
    for line in r.stdout.splitlines():
        if line.startswith("; Channels"):
            names = line.split(": ", 1)[1].split(", ")
        elif line and line[0] in "01":
            rows.append([int(x) for x in line.split(",")])
    return names, rows


needs_sigrok = pytest.mark.skipif(shutil.which("sigrok-cli") is None,
                                  reason="sigrok-cli is not installed (apt install sigrok-cli)")


@needs_sigrok
def test_sigrok_reads_no_samples_from_vectors_but_every_sample_from_one_bit_lanes(tmp_path):
    """libsigrok 0.5.2 stops at the first vector ("Unexpected vector format"):
    the default export gives it no sample; ``split_bits`` gives it every tick of
    every signal, each number rebuilt from its lanes."""
    tr = _wide()
    plain, split = tmp_path / "plain.vcd", tmp_path / "split.vcd"
    export.export(tr, plain)
    export.export(tr, split, split_bits=True)
    assert _sigrok(plain)[1] == []
    names, rows = _sigrok(split)
    assert len(rows) == tr.t_end - tr.t_start          # one a tick (the last has no length)
    col = {n: i for i, n in enumerate(names)}
    for signal, ref in NAMES.items():
        kind, changes = tr.signals[signal]
        short = ref.rsplit(".", 1)[1]
        for i, row in enumerate(rows):
            t = tr.t_start + i
            want = _value_at(tr, signal, t)
            if want is None:                            # not recorded yet (x)
                continue
            if kind == "bit":
                assert row[col[short]] == want, (signal, t)
                continue
            bits = export.width(kind, changes)
            got = sum(row[col[f"{short}[{b}]"]] << b for b in range(bits))
            if got >= 1 << (bits - 1) and any(v < 0 for _t, v in changes):
                got -= 1 << bits
            assert got == want, (signal, t)


@needs_sigrok
def test_a_capture_that_starts_later_reads_from_its_first_tick(tmp_path):
    tr = Trace(62, 70, {"out 1": ("bit", [(62, 0), (65, 1), (68, 0)]),
                        "pwm 0": ("int", [(62, 5), (66, -3)])}, [""], [], {})
    path = tmp_path / "late.vcd"
    export.export(tr, path, split_bits=True)
    names, rows = _sigrok(path)
    assert names == ["out1", "pwm0[0]", "pwm0[1]", "pwm0[2]", "pwm0[3]"]
    assert [r[0] for r in rows] == [0, 0, 0, 1, 1, 1, 0, 0]
    assert [sum(b << i for i, b in enumerate(r[1:])) for r in rows] == [5] * 4 + [0b1101] * 4


def test_split_bits_is_for_vcd_only(tmp_path):
    with pytest.raises(export.ExportError, match="for VCD"):
        export.export(_wide(), tmp_path / "x.csv", split_bits=True)


def test_hostile_names_and_strings_keep_the_vcd_whole(tmp_path):
    """Names that map to one identifier get their own; a ``$end`` in a string
    does not end the file's comment."""
    tr = Trace(0, 3, {"a b": ("bit", [(0, 1)]), "a_b": ("bit", [(0, 0)]),
                      "in 3": ("bit", [(0, 1)]), "in in3": ("bit", [(0, 0)]),
                      "run x $end y": ("bit", [(0, 1)]), "running": ("text", [(0, 1)])},
               ["", "M03 $end $var wire 1 ! evil $end"], [], {})
    text = export.vcd_text(tr)
    head = text.split("$enddefinitions")[0]
    assert head.count("$var") == 6 and "evil" not in head.split("$comment")[0]
    assert "$end $var" not in head
    path = tmp_path / "names.vcd"
    path.write_text(text)
    refs = set(VCDVCD(str(path)).references_to_ids)
    assert {"plc.a_b", "plc.a_b_2", "inputs.in3", "inputs.in3_2", "procedures.x__end_y"} <= refs


@pytest.mark.parametrize("name", ["=HYPERLINK(\"http://x\")", "+1+2", "-2+3", "@SUM(A1)",
                                  "\tx", "\rx", "\uff1dcmd"])
def test_csv_cells_that_would_be_formulas_are_quoted(tmp_path, name):
    """OWASP, CSV Injection: a cell starting with = + - @ tab or CR gets a
    single quote before it and the whole cell in double quotes; numbers (also
    negative ones) stay numbers."""
    tr = Trace(0, 2, {name: ("int", [(0, -5), (1, 7)]), "running": ("text", [(0, 1)])},
               ["", name], [], {})
    for per_tick in (False, True):
        path = tmp_path / f"x{per_tick}.csv"
        export.export(tr, path, per_tick=per_tick)
        text = path.read_bytes().decode("utf-8")
        quoted = '"' + ("'" + name).replace('"', '""') + '"'
        assert quoted in text
        rows = list(csv.reader(io.StringIO(text)))
        cells = [c for r in rows for c in r]
        assert all(not c.startswith(export._FORMULA_START) or c.lstrip("-").isdigit()
                   for c in cells)
        assert "'" + name in cells
        assert "-5" in cells                              # a negative number stays a number


def test_the_signal_kinds_are_the_historys():
    from plcbuilder.controller import history
    assert (export.BIT, export.TEXT) == (history.BIT, history.TEXT)


def test_each_way_of_exporting_is_one_row_and_every_front_end_offers_it(tmp_path, monkeypatch,
                                                                      capsys):
    """Issue 28: adding an export format is one row of EXPORTERS. A row added
    here (JSON lines, picked by --pretty) is offered by `trace export`
    (--format, its flag and help), written by `run --history`/`--capture`
    (by the suffix) and offered by the IDE's Export Trace dialog, with
    nothing else changed."""
    import json

    from tests.cli._run import run_cli

    def json_lines(trace):
        return "".join(json.dumps([t, n, v]) + "\n" for n, (_k, ch) in trace.signals.items()
                       for t, v in ch)

    rows = export.EXPORTERS + (
        export.Exporter("jsonl", None, "JSON lines", "", json_lines),
        export.Exporter("jsonl", "pretty", "JSON lines, pretty", "JSONL: indented",
                        lambda t: json_lines(t).replace(",", ", ")))
    monkeypatch.setattr(export, "EXPORTERS", rows)
    tr = _wide()
    src = tmp_path / "a.plctrace"
    from plcbuilder.trace import file as trace_file
    trace_file.save(tr, src)

    code, out, _err = run_cli(capsys, "trace", "export", "--help")
    assert "--pretty" in out and "JSONL: indented" in out and "jsonl" in out
    code, out, err = run_cli(capsys, "trace", "export", src, tmp_path / "o.jsonl")
    assert code == 0, err
    assert (tmp_path / "o.jsonl").read_text() == json_lines(tr)
    code, out, err = run_cli(capsys, "trace", "export", src, tmp_path / "p.jsonl", "--pretty")
    assert code == 0, err
    assert ", " in (tmp_path / "p.jsonl").read_text()
    code, out, err = run_cli(capsys, "trace", "export", src, tmp_path / "p.csv", "--pretty")
    assert code == 2 and "--pretty is for JSONL, not CSV" in err
    prog = tmp_path / "M90.plc"
    prog.write_text("main(){ portset(3); timer=5; do{timer--;}while(timer>0); exit(99); };\n")
    code, out, err = run_cli(capsys, "run", prog, "--history", tmp_path / "h.jsonl")
    assert code == 0, err
    assert '"out 3", 1]' in (tmp_path / "h.jsonl").read_text()

    from plcbuilder.ide import trace_actions     # no Qt object is made: the dialog's filters
    assert trace_actions.export_filter().split(";;")[-2:] == [
        "JSON lines (*.jsonl)", "JSON lines, pretty (*.jsonl)"]
