"""Hostile trace files (issue 24 item 7): every number is range-checked, the
nesting is bounded, and each is refused with the file, the member and the
field, never "internal error" (an OverflowError for ``"t_start": Infinity``,
a RecursionError for JSON nested 200,000 deep)."""

from __future__ import annotations

import json
import struct
import zipfile

import pytest

from plcbuilder.trace import file as tfile

GOOD_HEAD = {"format": "plcbuilder-trace", "version": 1, "t_start": 0, "t_end": 9,
             "tick_ms": 1, "strings": ["", "M03"], "meta": {},
             "signals": [{"name": "out 1", "kind": "bit", "changes": 2},
                         {"name": "running", "kind": "text", "changes": 1}]}
GOOD_EVENTS = [{"t_ms": 1, "name": "M03", "kind": "hardware", "eparam": 0, "type": "started"}]


def _bin(times, values) -> bytes:
    return struct.pack(f"<{len(times)}q", *times) + struct.pack(f"<{len(values)}q", *values)


def _write(path, head="good", events="good", bins=None, raw_head=None, raw_events=None):
    head = GOOD_HEAD if head == "good" else head
    events = GOOD_EVENTS if events == "good" else events
    bins = bins if bins is not None else [_bin([0, 5], [0, 1]), _bin([1], [1])]
    with zipfile.ZipFile(path, "w") as z:
        z.writestr("trace.json", raw_head if raw_head is not None else json.dumps(head))
        for i, b in enumerate(bins):
            z.writestr(f"signals/{i}.bin", b)
        z.writestr("events.json", raw_events if raw_events is not None else json.dumps(events))
    return path


def _head(**changes):
    h = json.loads(json.dumps(GOOD_HEAD))
    for k, v in changes.items():
        h[k] = v
    return h


def _raw(**fields) -> str:
    """trace.json with fields given as JSON text (Infinity, NaN, 1e400)."""
    text = json.dumps(GOOD_HEAD)
    for k, v in fields.items():
        text = text.replace(f'"{k}": {json.dumps(GOOD_HEAD[k])}', f'"{k}": {v}')
    return text


def test_the_good_file_reads(tmp_path):
    tr = tfile.load(_write(tmp_path / "good.plctrace"))
    assert tr.signals["out 1"] == ("bit", [(0, 0), (5, 1)])


@pytest.mark.parametrize("raw,field", [
    (_raw(t_start="Infinity"), "t_start: Infinity is not a number"),
    (_raw(t_start="-Infinity"), "Infinity"),
    (_raw(t_start="NaN"), "t_start: NaN is not a number"),
    (_raw(t_start="1e400"), "t_start: Infinity is not a number"),
    (_raw(t_end="1e400"), "t_end: Infinity is not a number"),
    (_raw(t_start="2.5"), "t_start: must be a whole number"),
    (_raw(t_start="-1"), "t_start: must be a whole number of ms from 0"),
    (_raw(t_start='"0"'), "t_start: must be a whole number"),
    (_raw(t_start="true"), "t_start: must be a whole number"),
    (_raw(t_start="null"), "t_start: must be a whole number"),
    (_raw(t_end=str(1 << 64)), "t_end: must be a whole number of ms"),
    (_raw(t_start="5", t_end="4"), "t_end: 4 is before t_start"),
    (_raw(t_start="1" * 5000), "trace.json is not valid JSON"),
    (_raw(version="1.0"), "bad version"),
    (_raw(version="Infinity"), "version: Infinity"),
])
def test_numbers_out_of_range_in_the_header_are_refused_with_the_field(tmp_path, raw, field):
    p = _write(tmp_path / "bad.plctrace", raw_head=raw)
    with pytest.raises(tfile.TraceFileError) as e:
        tfile.load(p)
    assert str(p) in str(e.value) and "trace.json" in str(e.value)
    assert field in str(e.value)


def _sig(i, **kw):
    h = _head()
    h["signals"][i].update(kw)
    return h


@pytest.mark.parametrize("head,field", [
    (_sig(0, changes=1e300), "signals[0].changes: signal 'out 1': must be a whole number"),
    (_sig(0, changes=float("inf")), "signals[0].changes: Infinity is not a number"),
    (_sig(0, changes=float("nan")), "signals[0].changes: NaN is not a number"),
    (_sig(0, changes=-1), "signals[0].changes"),
    (_sig(0, changes=True), "signals[0].changes"),
    (_sig(0, changes="2"), "signals[0].changes"),
    (_sig(0, changes=1 << 70), "signals[0].changes"),
    (_sig(0, name=7), "signals[0].name: must be a text"),
    (_sig(0, name=""), "signals[0].name: must be 1 to 256 characters"),
    (_sig(0, name="a\x00b"), "without control characters"),
    (_sig(0, name="x" * 300), "signals[0].name"),
    (_sig(1, name="out 1"), "signals[1].name: 'out 1' is named twice"),
    (_sig(0, kind=["bit"]), "signals[0].kind: signal 'out 1': unknown kind"),
    (_head(signals=[7]), "signals[0]: must be an object"),
    (_head(signals={"a": 1}), "signals: must be a list"),
    (_head(strings=[1, 2]), "strings[0]: must be a text"),
    (_head(strings="ab"), "strings: must be a list"),
    (_head(meta=[1]), "meta: must be an object"),
    (_head(meta={"trigger": 5}), "meta.trigger: must be an object"),
    (_head(meta={"trigger": {"spec": "out 1 rise"}}), "meta.trigger.t_ms: missing"),
    (_head(meta={"trigger": {"spec": "out 1 rise", "t_ms": 1e400}}),
     "meta.trigger.t_ms: Infinity is not a number"),
    (_head(meta={"trigger": {"spec": "out 1 rise", "t_ms": "5"}}), "meta.trigger.t_ms"),
    (_head(meta={"trigger": {"t_ms": 5}}), "meta.trigger.spec: missing"),
    (_head(meta={"trigger": {"spec": "x", "t_ms": 5, "pre_ms": -3}}), "meta.trigger.pre_ms"),
])
def test_bad_fields_of_the_header_are_refused_with_the_field(tmp_path, head, field):
    p = _write(tmp_path / "bad.plctrace", head=head)
    with pytest.raises(tfile.TraceFileError) as e:
        tfile.load(p)
    assert str(p) in str(e.value) and field in str(e.value)


@pytest.mark.parametrize("bins,why", [
    ([_bin([0, 5], [0, 7]), _bin([1], [1])], "a bit signal holds a value other than 0 and 1"),
    ([_bin([-5, 5], [0, 1]), _bin([1], [1])], "a change time is outside 0.."),
    ([_bin([0, (1 << 63) - 1], [0, 1]), _bin([1], [1])], "a change time is outside 0.."),
    ([_bin([0, 5], [0, 1]), _bin([1], [9])], "a value names no string"),
])
def test_bad_changes_are_refused(tmp_path, bins, why):
    p = _write(tmp_path / "bad.plctrace", bins=bins)
    with pytest.raises(tfile.TraceFileError, match=why):
        tfile.load(p)


@pytest.mark.parametrize("events,field", [
    ('[{"t_ms": Infinity, "type": "note", "text": "x"}]', "[0].t_ms: Infinity is not"),
    ('[{"t_ms": 1e400, "type": "note", "text": "x"}]', "[0].t_ms: Infinity is not"),
    ('[{"t_ms": 1, "type": "halted", "state": {"a": [1, NaN]}}]', "[0].state.a[1]: NaN is not"),
    ('[{"t_ms": "7", "type": "note", "text": "x"}]', "[0].t_ms"),
    ('[{"type": "note", "text": "x"}]', "[0].t_ms: missing"),
    ('[{"t_ms": 1, "text": "x"}]', "[0].type: missing"),
    ('[{"t_ms": 1, "type": 5}]', "[0].type: must be a text"),
    ('[{"t_ms": 1, "type": "message", "message": "x"}]', "[0].message: must be a whole number"),
    ('[{"t_ms": 1, "type": "print", "register": -1e400}]', "[0].register: -Infinity"),
    ('[{"t_ms": 1, "type": "print", "register": %d}]' % (1 << 64), "beyond a 64-bit number"),
    ('[{"t_ms": 1, "type": "fault", "line": "x"}]', "[0].line"),
    ('[{"t_ms": 1, "type": "note", "t_ms": 2}]', "appears twice"),
    ('{"t_ms": 1}', "not a list of objects"),
    ('[5]', "not a list of objects"),
])
def test_bad_events_are_refused_with_the_field(tmp_path, events, field):
    p = _write(tmp_path / "bad.plctrace", raw_events=events)
    with pytest.raises(tfile.TraceFileError) as e:
        tfile.load(p)
    assert str(p) in str(e.value) and "events.json" in str(e.value) and field in str(e.value)


@pytest.mark.parametrize("member", ["trace.json", "events.json"])
@pytest.mark.parametrize("depth", [200_000, 33])
def test_deeply_nested_json_is_refused(tmp_path, member, depth):
    deep = "[" * depth + "]" * depth
    if member == "trace.json":
        raw = json.dumps(_head(meta={"x": 0})).replace('{"x": 0}', '{"x": %s}' % deep)
        p = _write(tmp_path / "deep.plctrace", raw_head=raw)
    else:
        raw = '[{"t_ms": 1, "type": "halted", "state": {"x": %s}}]' % deep
        p = _write(tmp_path / "deep.plctrace", raw_events=raw)
    with pytest.raises(tfile.TraceFileError, match=f"{member}: nested too deeply"):
        tfile.load(p)


def test_nesting_within_the_bound_reads(tmp_path):
    raw = json.dumps(_head(meta={"x": [[[[1]]]]}))
    assert tfile.load(_write(tmp_path / "ok.plctrace", raw_head=raw)).meta == {"x": [[[[1]]]]}


def test_the_cli_refuses_them_with_the_field_and_exit_2(tmp_path, capsys):
    from plcbuilder.cli.main import main
    p = _write(tmp_path / "inf.plctrace", raw_head=_raw(t_start="1e400"))
    for argv in (["trace", "info", str(p)], ["trace", "export", str(p), str(tmp_path / "x.vcd")],
                 ["trace", "compare", str(p), str(p)]):
        assert main(argv) == 2
        err = capsys.readouterr().err
        assert "internal error" not in err and "t_start" in err and str(p) in err
