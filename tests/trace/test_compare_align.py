"""Comparing captures of different moments (issue 23 item 5: two captures from
one session said "no tick in common"): the second trace lined up with the
first on the triggers, the starts, or a chosen offset, then compared."""

from __future__ import annotations

import json

import pytest

from plcbuilder import api
from plcbuilder.controller.history import History
from plcbuilder.controller.scenario import Action, Scenario
from plcbuilder.controller.session import run_session
from plcbuilder.trace import compare
from tests.cli._run import run_cli

#: M90 pulses out 3 for 10 ms, 20 ms after it starts, each time it is started
PULSE = ("main(){ timer=20; do{timer--;}while(timer>0); portset(3);"
         " timer=10; do{timer--;}while(timer>0); portclear(3); exit(99); };\n")
#: the same, its pulse 5 ms longer
LONGER = PULSE.replace("timer=10;", "timer=15;")


def _session(src: str = PULSE, starts=(100, 1000)) -> History:
    c = api.Controller(api.default_machine())
    r = api.compile_source(src, "M90.plc")
    assert r.ok, r.diagnostics
    c.load([r.program], autostart=False)
    h = History(c.machine)
    run_session(c, Scenario([Action(t, "start", "M90", 0) for t in starts]), 1200, history=h)
    return h


def _capture(h: History, t: int, pre: int = 10, post: int = 40):
    """A capture of ``out 3 rise`` at t, as the trigger makes it."""
    trig = {"spec": "out 3 rise", "t_ms": t, "pre_ms": pre, "post_ms": post, "mode": "single"}
    return h.snapshot(t - pre, t + post, meta={"trigger": trig})


def test_two_captures_of_one_session_line_up_on_their_triggers():
    h = _session()
    first, second = _capture(h, 120), _capture(h, 1020)     # the two rises of out 3
    plain = compare.compare(first, second)
    assert not plain.overlap and "no tick in common" in plain.text()
    assert "--align trigger" in plain.text()
    d = compare.compare(first, second, align="trigger")
    assert d.shift_ms == -900 and d.overlap and d.span == (110, 160)
    # the same pulse, its start and end events at the same moments relative to
    # the trigger: nothing differs
    assert d.same, d.text()
    assert "the traces are the same from 110 to 160 ms" in d.text()
    assert "the second trace moved by -900 ms (triggers together)" in d.text()
    assert d.to_dict()["align"] == "trigger" and d.to_dict()["shift_ms"] == -900


def test_a_change_shows_at_the_first_traces_time_and_the_seconds_own():
    before = _capture(_session(), 120)
    after = _capture(_session(LONGER, starts=(500,)), 520)
    d = compare.compare(before, after, align="trigger")
    assert d.shift_ms == -400
    assert d.t_ms == 130 and ("out 3", "0", "1") in d.signals      # off at 130 before, 135 after
    assert "first difference at 130 ms (530 ms in the second)" in d.text()


def test_align_on_the_start_and_an_offset():
    a = _session(starts=(100,)).snapshot(0, 300)
    b = _session(starts=(100,)).snapshot(0, 300)
    late = compare.shifted(b, 5000)                              # the same run 5 s later
    assert (late.t_start, late.t_end) == (5000, 5300)
    assert not compare.compare(a, late).overlap
    assert compare.compare(a, late, align="start").same
    assert compare.compare(a, late, offset_ms=-5000).same
    d = compare.compare(a, late, align="start", offset_ms=3)      # 3 ms off: they differ
    assert d.shift_ms == -4997 and not d.same and d.t_ms == 100       # M90 starts 3 ms late


def test_shifted_moves_everything():
    tr = _capture(_session(), 120)
    s = compare.shifted(tr, -100)
    assert (s.t_start, s.t_end) == (tr.t_start - 100, tr.t_end - 100)
    assert s.meta["trigger"]["t_ms"] == 20 and tr.meta["trigger"]["t_ms"] == 120
    assert [e["t_ms"] for e in s.events] == [e["t_ms"] - 100 for e in tr.events]
    assert s.value_at("out 3", 20) == 1 == tr.value_at("out 3", 120)
    assert compare.shifted(tr, 0) is tr


def test_align_on_a_trigger_that_is_not_there_says_so():
    h = _session()
    with pytest.raises(compare.CompareError, match="the second trace has no trigger"):
        compare.compare(_capture(h, 120), h.snapshot(), align="trigger")
    with pytest.raises(compare.CompareError, match="the first and the second traces have"):
        compare.compare(h.snapshot(), h.snapshot(), align="trigger")
    with pytest.raises(compare.CompareError, match="align on none, start, trigger"):
        compare.compare(h.snapshot(), h.snapshot(), align="middle")


def test_the_cli_aligns_too(tmp_path, capsys):
    h = _session()
    a, b, whole = (tmp_path / f"{n}.plctrace" for n in ("a", "b", "whole"))
    api.save_trace(_capture(h, 120), a)
    api.save_trace(_capture(h, 1020), b)
    api.save_trace(h.snapshot(), whole)
    code, out, _ = run_cli(capsys, "trace", "compare", a, b)
    assert code == 1 and "no tick in common" in out
    code, out, _ = run_cli(capsys, "trace", "compare", a, b, "--align", "trigger")
    assert code == 0 and "the same from 110 to 160 ms" in out and "-900 ms" in out
    code, out, _ = run_cli(capsys, "trace", "compare", a, b, "--offset", "-900", "--json")
    d = json.loads(out)
    assert code == 0 and d["same"] and d["shift_ms"] == -900 and d["align"] == "none"
    code, out, _ = run_cli(capsys, "trace", "compare", a, b, "--align", "start",
                           "--offset", "0x10")
    assert code == 1 and json.loads(run_cli(capsys, "trace", "compare", a, b, "--align",
                                            "start", "--json")[1])["shift_ms"] == -900
    code, _out, err = run_cli(capsys, "trace", "compare", a, whole, "--align", "trigger")
    assert code == 2 and "the second trace has no trigger" in err
    code, _out, err = run_cli(capsys, "trace", "compare", a, b, "--offset", "1e400")
    assert code == 2 and "--offset" in err


def test_a_procedure_not_started_yet_is_not_running():
    """``run NAME`` has no value before NAME first starts: in a capture from
    before its first start it compares as 0 with a later capture where it ended."""
    h = _session()
    first = _capture(h, 120, pre=30)                 # M90 starts at 100: from 90 no run M90
    assert first.value_at("run M90", 90) is None
    second = _capture(h, 1020, pre=30)               # ended at ~131, 0 from then on
    assert second.value_at("run M90", 990) == 0
    d = compare.compare(first, second, align="trigger")
    assert d.same, d.text()
