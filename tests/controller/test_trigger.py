"""Triggers and captures (SPEC §7): each kind, pre/post exact to the tick, modes."""

from __future__ import annotations

import pytest

from plcbuilder import api
from plcbuilder.controller.history import History
from plcbuilder.controller.scenario import Action, Scenario
from plcbuilder.controller.session import run_session
from plcbuilder.controller.trigger import Capturer, TriggerError, parse_trigger

# output 3 on at 20 ms after the start, off 10 ms later; a print and a message at the end
PULSE = ("main(){ proc=33; timer=20; do{timer--;}while(timer>0); portset(3); gvarset(7270, 500);"
         " timer=10; do{timer--;}while(timer>0); portclear(3); gvarset(7270, 100);"
         " gvarset(20002, 7); message=1100; exit(99); };\n")


def _run(trigger: str, pre: int = 5, post: int = 5, mode: str = "single", ms: int = 200,
         start_at: int = 100, extra=()) -> Capturer:
    c = api.Controller(api.default_machine())
    r = api.compile_source(PULSE, "M90.plc")
    assert r.ok, r.diagnostics
    c.load([r.program], autostart=False)
    h = History(c.machine)
    cap = Capturer(h, parse_trigger(trigger), pre, post, mode)
    sc = Scenario([Action(start_at, "start", "M90", 0), *extra])
    run_session(c, sc, ms, history=h, capturer=cap,
                watch=[w for w in ([cap.trigger.signal] if "." in (cap.trigger.signal or "") else [])])
    return cap


@pytest.mark.parametrize("spec,t", [
    ("out 3 rise", 120), ("out 3 fall", 130), ("out 3 edge", 120), ("out3:rise", 120),
    ("dac 0 up 300", 120), ("dac 0 down 300", 130), ("proc = 33", 100),
    ("proc = plc_proc_probing", 100), ("proc = proc_zeroing", None), ("message", 130), ("message = 1100", 130),
    ("message = PLCCMD_REPLY_TO_MYCNC", 130), ("print", 130), ("print = 20002", 130),
    ("print = 20003", None), ("M90.timer up 15", None), ("M90.timer down 1", 119),
    ("M90.timer bit 0 rise", 102), ("M90.timer bit 1 fall", 102)])
def test_each_kind_of_trigger_fires_at_its_tick(spec, t):
    """SPEC §7: 'a condition on one signal — rising, falling or either edge of an
    input, output or a variable's bit; a numeric signal crossing a level up or
    down; proc becoming a value; a message or print being sent'."""
    cap = _run(spec)
    if t is None:
        assert cap.captures == []
    else:
        assert [c.meta["trigger"]["t_ms"] for c in cap.captures] == [t]


@pytest.mark.parametrize("spec,t", [("out 3 rise", 0), ("dac 0 up 300", 0),
                                    ("out 3 fall", 10)])
def test_an_output_switched_in_the_first_tick_rises_from_power_on(spec, t):
    """An output the first tick switches on is a rise at t = 0: outputs, PWM and DAC
    power on at 0 ('run --start M03@0 --trigger "out 0 rise"' captured nothing)."""
    c = api.Controller(api.default_machine())
    r = api.compile_source("main(){ portset(3); gvarset(7270, 500); timer=10;"
                           " do{timer--;}while(timer>0); portclear(3); exit(99); };\n",
                           "M91.plc")
    assert r.ok, r.diagnostics
    c.load([r.program], autostart=False)
    h = History(c.machine)
    cap = Capturer(h, parse_trigger(spec), 0, 5)
    run_session(c, Scenario([Action(0, "start", "M91", 0)]), 40,
                history=h, capturer=cap)
    assert h.t_start == 0
    assert [c.meta["trigger"]["t_ms"] for c in cap.captures] == [t]


def test_capture_holds_every_signal_over_pre_and_post_exactly():
    """SPEC §7: 'A capture holds every signal over [trigger − pre, trigger + post].'"""
    cap = _run("out 3 rise", pre=7, post=4)
    tr = cap.captures[0]
    assert (tr.t_start, tr.t_end) == (113, 124)
    assert tr.signals["out 3"][1] == [(113, 0), (120, 1)]
    assert tr.value_at("dac 0", 124) == 500 and tr.value_at("dac 0", 119) == 0
    assert "in 0" in tr.signals and "axis X" in tr.signals


def test_normal_mode_rearms_and_single_makes_one():
    """SPEC §7: 'in single, normal (re-arm) or auto mode'."""
    again = [Action(300, "start", "M90", 0)]
    single = _run("out 3 rise", mode="single", ms=500, extra=again)
    normal = _run("out 3 rise", mode="normal", ms=500, extra=again)
    assert [c.meta["trigger"]["t_ms"] for c in single.captures] == [120]
    assert [c.meta["trigger"]["t_ms"] for c in normal.captures] == [120, 320]


def test_auto_mode_captures_without_a_trigger():
    cap = _run("in 9 rise", pre=10, post=10, mode="auto", ms=100)
    assert cap.captures, "auto mode captures when no trigger comes"
    assert all(c.t_end - c.t_start == 20 for c in cap.captures)


def test_trigger_now_captures_at_the_current_end():
    c = api.Controller(api.default_machine())
    h = History(c.machine)
    cap = Capturer(h, parse_trigger("in 9 rise"), 5, 5)
    run_session(c, Scenario(), 50, history=h, capturer=cap)
    h.advance_to(60)
    cap.trigger_now()
    done = cap.update(final=True)
    assert [d.meta["trigger"]["t_ms"] for d in done] == [60]


def test_capture_cut_short_by_the_end_of_the_session():
    cap = _run("out 3 fall", pre=5, post=1000, ms=200)
    tr = cap.captures[0]
    assert tr.t_start == 125 and tr.t_end < 1130


@pytest.mark.parametrize("spec,why", [
    ("", "empty"), ("out", "needs a number"), ("out 3", "say what to wait for"),
    ("adc 0 rise", "edges are of inputs"), ("out 3 up", "needs one level"),
    ("proc", "needs '= VALUE'"), ("proc = nosuch", "not a number"), ("foo 3 rise", "unknown signal"),
    ("out 3 wobble", "unknown condition"), ("print = 5", "20000..20100"),
    ("in 3 bit 2 rise", "applies to a variable"), ("M80.x bit 40 rise", "0..31"),
    ("axis Q up 3", "axis letter")])
def test_bad_trigger_specs_say_what_is_wrong(spec, why):
    with pytest.raises(TriggerError, match=why.replace("(", r"\(").replace(")", r"\)")):
        parse_trigger(spec)
