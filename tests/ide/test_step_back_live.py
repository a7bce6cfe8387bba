"""Stepping back in the IDE against the real embedded controller (a child
process), driven like a user: halted in M80 at the home-switch line, Step
Over, then Debug › Step Back, Step Back 1 ms and Run Back (SPEC §7)."""

from __future__ import annotations

from plcbuilder.ide.actions import Act

from tests.ide._debug import HOME_LINE, click_margin

WAIT = 30_000


def _halted(w, line=None, reason=None, t_ms=None):
    st = w.debug.halted
    return st is not None and (line is None or st.get("line") == line) and \
        (reason is None or st.get("reason") == reason) and \
        (t_ms is None or st.get("t_ms") == t_ms)


def test_step_back_step_back_a_tick_and_run_back_in_m80(live_example, qtbot):
    """SPEC §7: 'Step back (one tick, or one statement) and run back (to the
    previous breakpoint hit) work by deterministic re-execution from the recording'."""
    w, root = live_example
    assert w.open_project(root)
    with qtbot.waitSignal(w.sig_build_finished, timeout=WAIT):
        assert w.build_all()
    c = w.connection
    qtbot.waitUntil(lambda: c.connected and w.debug.connected(), timeout=WAIT)
    qtbot.waitUntil(lambda: c.last_state.image_crc32 is not None, timeout=WAIT)
    ed = w.open_file(root / "hardware" / "M80.plc")
    click_margin(qtbot, ed, HOME_LINE)
    bp = w.debug.store.at(ed.path, HOME_LINE)
    qtbot.waitUntil(lambda: bp.verified is True, timeout=WAIT)
    assert not w.action(Act.STEP_BACK).isEnabled()          # not halted: nothing to step

    assert w.start_procedure("M80", 0)
    qtbot.waitUntil(lambda: _halted(w, HOME_LINE, "breakpoint"), timeout=WAIT)
    first = w.debug.halted["t_ms"]
    assert w.action(Act.STEP_BACK).isEnabled() and w.action(Act.RUN_BACK).isEnabled()
    w.action(Act.STEP_OVER).trigger()
    qtbot.waitUntil(lambda: _halted(w, HOME_LINE + 1, "step"), timeout=WAIT)

    # Debug › Step Back: the statement before, in the same tick, with the same values
    w.action(Act.STEP_BACK).trigger()
    qtbot.waitUntil(lambda: _halted(w, HOME_LINE, "step", first), timeout=WAIT)
    assert ed.debug_marks.exec_lines() == [HOME_LINE]
    assert ed.debug_marks.inline_text(HOME_LINE) == "sens = 0"

    # continue to the next hit, then Run Back to the first one
    w.action(Act.START).trigger()
    qtbot.waitUntil(lambda: _halted(w, HOME_LINE, "breakpoint")
                    and w.debug.halted["t_ms"] > first, timeout=WAIT)
    w.action(Act.RUN_BACK).trigger()
    qtbot.waitUntil(lambda: _halted(w, HOME_LINE, "breakpoint", first), timeout=WAIT)

    # Step Back 1 ms: the start of that tick, and then the tick before it
    w.action(Act.STEP_BACK_TICK).trigger()
    qtbot.waitUntil(lambda: _halted(w, reason="step", t_ms=first)
                    and w.debug.halted["procedure"] is None, timeout=WAIT)
    w.action(Act.STEP_BACK_TICK).trigger()
    qtbot.waitUntil(lambda: _halted(w, reason="step", t_ms=first - 1), timeout=WAIT)
    # the controller's own time went back too (its state follows the halt)
    qtbot.waitUntil(lambda: c.last_state.t_ms <= first, timeout=WAIT)
