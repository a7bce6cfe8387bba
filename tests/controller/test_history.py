"""The session history: every change kept, as changes (SPEC §7)."""

from __future__ import annotations

import random

from plcbuilder import api
from plcbuilder.controller.history import CHUNK, History, Signal
from plcbuilder.controller.session import run_session
from plcbuilder.controller.scenario import Action, Scenario

TOGGLE = "main(){ do{ portset(7); timer=1; do{timer--;}while(timer>0); portclear(7); }while(1); };\n"
BLINK = ("main(){ do{ if (gvarget(0x407)) { portclear(7); } else { portset(7); }; }while(1); };\n")


def _controller(sources: dict[str, str], **kw) -> api.Controller:
    c = api.Controller(api.default_machine(), **kw)
    programs = []
    for name, text in sources.items():
        r = api.compile_source(text, f"{name}.plc")
        assert r.ok, r.diagnostics
        programs.append(r.program)
    c.load(programs, autostart=False)
    return c


def test_signal_keeps_every_change_and_answers_any_tick():
    """A signal is a list of changes: the value holds from its tick until the
    next change (checked against a plain list over several sealed chunks)."""
    rng = random.Random(7)
    s = Signal("x")
    plain: list[tuple[int, int]] = []
    t = 0
    for _ in range(CHUNK * 3 + 17):
        t += rng.randint(1, 5)
        v = rng.randint(-3, 3)
        if s.append(t, v):
            plain.append((t, v))
    assert s.changes() == plain
    assert len(s) == len(plain)
    for probe in range(0, t + 3, 7):
        want = None
        for ct, cv in plain:
            if ct <= probe:
                want = cv
        assert s.value_at(probe) == want, probe
    lo, hi = plain[100][0], plain[CHUNK + 50][0]
    assert s.changes(lo, hi) == [c for c in plain if lo <= c[0] <= hi]


def test_signal_same_value_is_no_change_and_last_write_of_a_tick_wins():
    s = Signal("x")
    assert s.append(0, 1)
    assert not s.append(3, 1)
    assert s.append(5, 2)
    assert s.append(5, 3)            # the value at the tick's end
    assert s.changes() == [(0, 1), (5, 3)]
    assert s.append(5, 1)            # back to the value before: no change at 5
    assert s.changes() == [(0, 1)]


def test_every_output_edge_of_a_tick_toggle_is_in_the_history():
    """SPEC §7: 'A session keeps the whole history of what changed (inputs,
    outputs, PWM/DAC/ADC, proc, messages, prints, procedure starts and ends,
    axes, watched variables), not a fixed window, stored as changes'."""
    c = _controller({"M90": BLINK})
    h = History(c.machine)
    sc = Scenario([Action(0, "start", "M90", 0)])
    run_session(c, sc, 20_000, history=h)
    ch = h.signals["out 7"].changes()
    assert len(ch) == 20_000            # one edge every tick, for 20 s
    assert ch[:3] == [(0, 1), (1, 0), (2, 1)]
    assert all(v == (t + 1) % 2 for t, v in ch)
    assert h.signals["run M90"].changes() == [(0, 1)]
    # stored compressed: far less than 16 bytes a change
    assert h.signals["out 7"].nbytes() < 20_000 * 16 // 8


def test_history_records_starts_ends_messages_prints_and_proc():
    src = ("main(){ proc=33; timer=3; do{timer--;}while(timer>0); gvarset(20001, 5); "
           "message=1100; timer=2; do{timer--;}while(timer>0); exit(99); };\n")
    c = _controller({"M91": src})
    h = History(c.machine)
    run_session(c, Scenario([Action(10, "start", "M91", 0)]), 1000, history=h)
    assert h.signals["run M91"].changes() == [(10, 1), (15, 0)]
    assert h.signals["proc"].value_at(12) == 33
    msg = h.signals["message"].changes()
    assert (13, 1100) in msg and (14, 0) in msg
    assert any(e["type"] == "print" and e["register"] == 20001 and e["value"] == 5
               for e in h.events)


def test_watched_variables_are_recorded_each_tick():
    c = _controller({"M05": "main(){ timer=5; do{timer--;}while(timer>0); exit(99); };\n"})
    h = History(c.machine)
    run_session(c, Scenario([Action(0, "start", "M05", 0)]), 100, history=h,
                watch=["M05.timer"])
    assert h.signals["M05.timer"].changes() == [(0, 4), (1, 3), (2, 2), (3, 1), (4, 0)]


def test_snapshot_starts_with_the_value_that_held():
    c = _controller({"M90": BLINK})
    h = History(c.machine)
    run_session(c, Scenario([Action(0, "start", "M90", 0)]), 100, history=h)
    tr = h.snapshot(50, 60)
    assert tr.t_start == 50 and tr.t_end == 60
    kind, ch = tr.signals["out 7"]
    assert kind == "bit"
    assert ch[0] == (50, 1) and ch[-1] == (60, 1) and len(ch) == 11
    assert tr.signals["in 0"][1] == [(50, h.signals["in 0"].value_at(50))]


def test_samples_with_fewer_axes_or_words_are_taken_as_they_are():
    """A client's samples may carry fewer axes or I/O words than the history has
    signals for (another machine, another target): nothing fails, what is there
    is recorded."""
    from plcbuilder.controller.events import Sample
    h = History(input_count=64, output_count=64, axes=("X", "Y", "Z"))
    h.feed_samples([Sample(0, None, 0, 0, (1,), (2,), (0,) * 8, (0,) * 8, (0,) * 8, (150,)),
                    Sample(5, None, 0, 0, (1, 4), (2, 0), (0,) * 8, (0,) * 8, (0,) * 8, (150, 7))])
    assert h.signals["axis X"].changes() == [(0, 150)]
    assert h.signals["axis Y"].changes() == [(5, 7)]
    assert h.signals["in 0"].changes() == [(0, 1)] and h.signals["in 34"].changes() == [(5, 1)]
    assert h.signals["out 1"].changes() == [(0, 1)]
