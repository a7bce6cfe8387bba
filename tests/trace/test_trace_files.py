"""Trace files, CSV and VCD export, comparison (SPEC §7)."""

from __future__ import annotations

import csv
import io
import json
import zipfile

import pytest
from tests.vcd_reader import VCDVCD

from plcbuilder import api
from plcbuilder.controller.history import History
from plcbuilder.controller.scenario import Action, Scenario
from plcbuilder.controller.session import run_session
from plcbuilder.trace import compare, export, file as tfile

PULSE = ("main(){ proc=33; timer=20; do{timer--;}while(timer>0); portset(3); gvarset(7270, 0-500);"
         " timer=10; do{timer--;}while(timer>0); portclear(3); message=1100; exit(99); };\n")


def _trace(start_at: int = 10, ms: int = 100, src: str = PULSE):
    c = api.Controller(api.default_machine())
    r = api.compile_source(src, "M90.plc")
    assert r.ok, r.diagnostics
    c.load([r.program], autostart=False)
    h = History(c.machine)
    run_session(c, Scenario([Action(start_at, "start", "M90", 0)]), ms, history=h,
                watch=["M90.timer"])
    return h.snapshot(meta={"target": "test"})


def test_a_saved_trace_reopens_the_same(tmp_path):
    """SPEC §7: 'a capture or a whole session saves to one documented file that
    the IDE reopens'."""
    tr = _trace()
    path = tmp_path / "run.plctrace"
    tfile.save(tr, path)
    back = tfile.load(path)
    assert (back.t_start, back.t_end) == (tr.t_start, tr.t_end)
    assert back.signals == tr.signals
    assert back.strings == tr.strings and back.events == tr.events and back.meta == tr.meta
    with zipfile.ZipFile(path) as z:
        head = json.loads(z.read("trace.json"))
    assert head["format"] == "plcbuilder-trace" and head["version"] == 1


def _zip(path, members: dict) -> None:
    with zipfile.ZipFile(path, "w") as z:
        for name, data in members.items():
            z.writestr(name, data)


@pytest.mark.parametrize("case,why", [
    ("text", "not a ZIP archive"), ("truncated", "not a ZIP archive"),
    ("future", "newer than this"), ("foreign", "not a PLC Builder trace"),
    ("short", "not the 32 its 2 changes need"), ("nojson", "not valid JSON"),
    ("missing", "signals/0.bin is missing"), ("order", "not increasing")])
def test_bad_trace_files_are_refused_with_a_reason(tmp_path, case, why):
    good = tmp_path / "good.plctrace"
    tfile.save(_trace(), good)
    p = tmp_path / "bad.plctrace"
    head = {"format": "plcbuilder-trace", "version": 1, "t_start": 0, "t_end": 9,
            "strings": [""], "meta": {},
            "signals": [{"name": "out 1", "kind": "bit", "changes": 2}]}
    import struct
    data = struct.pack("<2q", 0, 5) + struct.pack("<2q", 0, 1)
    if case == "text":
        p.write_text("hello")
    elif case == "truncated":
        p.write_bytes(good.read_bytes()[:200])
    elif case == "future":
        _zip(p, {"trace.json": json.dumps(dict(head, version=9)), "signals/0.bin": data,
                 "events.json": "[]"})
    elif case == "foreign":
        _zip(p, {"trace.json": json.dumps(dict(head, format="other"))})
    elif case == "short":
        _zip(p, {"trace.json": json.dumps(head), "signals/0.bin": data[:30], "events.json": "[]"})
    elif case == "nojson":
        _zip(p, {"trace.json": "{nope"})
    elif case == "missing":
        _zip(p, {"trace.json": json.dumps(head), "events.json": "[]"})
    elif case == "order":
        bad = struct.pack("<2q", 5, 0) + struct.pack("<2q", 0, 1)
        _zip(p, {"trace.json": json.dumps(head), "signals/0.bin": bad, "events.json": "[]"})
    with pytest.raises(tfile.TraceFileError, match=why):
        tfile.load(p)


def test_saving_where_it_cannot_be_written_says_so_and_keeps_the_old_file(tmp_path):
    path = tmp_path / "keep.plctrace"
    tfile.save(_trace(), path)
    before = path.read_bytes()
    with pytest.raises(tfile.TraceFileError, match="cannot write"):
        tfile.save(_trace(), tmp_path / "nofolder" / "x.plctrace")
    assert path.read_bytes() == before


def test_vcd_export_reads_back_with_an_independent_reader(tmp_path):
    """SPEC §7: 'Export … to VCD (IEEE 1364 value change dump, readable by GTKWave
    and PulseView, one wire per digital signal and a vector per numeric one,
    timescale 1 ms)'."""
    tr = _trace()
    path = tmp_path / "run.vcd"
    export.export(tr, path)
    v = VCDVCD(str(path))
    assert v.timescale["unit"] == "ms" and v.timescale["magnitude"] == 1
    out3 = v["outputs.out3"]
    assert int(out3.size) == 1
    assert [(t, int(x, 2)) for t, x in out3.tv] == [(0, 0), (30, 1), (40, 0)]
    dac = v["dac.dac0"]
    assert int(dac.size) == 10                         # -500 needs 10 bits (issue 24 item 9)
    got = [(t, int(x, 2)) for t, x in dac.tv]
    assert got[-1] == (30, (-500) & 0x3FF)                 # two's complement
    timer = v["variables.M90.timer"].tv
    assert timer[0] == (0, "x")                        # not recorded before it ran: unknown
    assert [(t, int(x, 2)) for t, x in timer[1:3]] == [(10, 19), (11, 18)]
    msg = [(t, int(x, 2)) for t, x in v["plc.message"].tv]
    assert msg == [(0, 0), (40, 1100)] and tr.t_end == 40     # the run ended in that tick


def test_csv_export_per_change_and_per_tick(tmp_path):
    """SPEC §7: 'Export to CSV (one row per change or per tick)'."""
    tr = _trace()
    export.export(tr, tmp_path / "c.csv")
    rows = list(csv.reader(io.StringIO((tmp_path / "c.csv").read_text())))
    assert rows[0] == ["t_ms", "signal", "value"]
    assert ["30", "out 3", "1"] in rows and ["40", "out 3", "0"] in rows
    assert ["10", "running", "M90"] in rows
    export.export(tr, tmp_path / "t.csv", per_tick=True)
    rows = list(csv.DictReader(io.StringIO((tmp_path / "t.csv").read_text())))
    assert len(rows) == tr.t_end - tr.t_start + 1
    by_t = {int(r["t_ms"]): r for r in rows}
    assert by_t[29]["out 3"] == "0" and by_t[30]["out 3"] == "1" and by_t[39]["out 3"] == "1"
    assert by_t[20]["running"] == "M90"


def test_traces_with_no_tick_in_common_are_not_the_same():
    """Two captures of different moments (0..20 and 50..80 ms) have nothing to
    compare: compare said 'the same from 50 to 20 ms' and exited 0."""
    c = api.Controller(api.default_machine())
    r = api.compile_source(PULSE, "M90.plc")
    c.load([r.program], autostart=False)
    h = History(c.machine)
    run_session(c, Scenario([Action(10, "start", "M90", 0)]), 100, history=h)
    early, late = h.snapshot(0, 20), h.snapshot(50, 80)
    d = compare.compare(early, late)
    assert not d.overlap and not d.same and d.t_ms is None
    assert d.text().startswith("the traces have no tick in common (the first covers "
                               "0..20 ms, the second 50..80 ms)")
    assert d.to_dict()["same"] is False and d.to_dict()["overlap"] is False
    touching = compare.compare(h.snapshot(0, 50), late)        # one tick in common
    assert touching.overlap and touching.span == (50, 50)


def test_export_to_a_folder_that_cannot_be_written_says_so(tmp_path):
    with pytest.raises(export.ExportError, match="cannot write"):
        export.export(_trace(), tmp_path / "no" / "x.vcd")
    with pytest.raises(export.ExportError, match="csv or vcd"):
        export.export(_trace(), tmp_path / "x.txt")


def test_compare_finds_the_first_tick_and_signal_that_differ():
    """SPEC §7: 'a second trace can be compared against (the first tick where they
    differ, and in what)'."""
    a, b = _trace(start_at=10), _trace(start_at=10)
    assert compare.compare(a, b).same
    c = _trace(start_at=12)
    d = compare.compare(a, c)
    assert d.t_ms == 10
    names = {n for n, _x, _y in d.signals}
    assert "running" in names and "proc" in names
    assert ("running", "M90", "") in d.signals
    assert d.events
    assert "first difference at 10 ms" in d.text()
