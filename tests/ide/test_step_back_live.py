"""Stepping back in the IDE against the real embedded controller (a child
process), driven like a user: halted in M80 at the home-switch line, Step
Over, then Debug › Step Back, Step Back 1 ms and Run Back (SPEC §7)."""

from __future__ import annotations

from PySide6.QtCore import Qt

from plcbuilder.ide.actions import Act

from tests.ide._debug import HOME_LINE, click_margin, halt_m80_at_home

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


def _edit_cell(qtbot, table, row: int, col: int, text: str) -> None:
    """Open the editor of a cell of a table (as a double-click does), type
    ``text`` and press Enter."""
    from PySide6.QtWidgets import QLineEdit
    table.setCurrentCell(row, col)
    table.editItem(table.item(row, col))
    editor = table.viewport().findChild(QLineEdit) or table.findChild(QLineEdit)
    assert editor is not None, "no cell editor opened"
    editor.selectAll()
    qtbot.keyClicks(editor, text)
    qtbot.keyClick(editor, Qt.Key.Key_Return)


def test_every_action_while_halted_is_recorded_so_step_back_works(live_example, qtbot):
    """Issue 23 point 4: after a write in the Watch, a force and a release in the
    Inputs dock and an ADC value, all while halted in M80 at its second hit of
    the home-switch line, Step Back (Shift+F10) goes back one statement, to where
    they were done (before: "running the session again did not reach M80")."""
    w, root = live_example
    halt_m80_at_home(w, root, qtbot, WAIT)
    assert _halted(w, HOME_LINE, "breakpoint")
    c, panels = w.connection, w.ensure_run_panels()
    w.action(Act.START).trigger()                    # on to the next tick's hit
    first = w.debug.halted["t_ms"]
    qtbot.waitUntil(lambda: _halted(w, HOME_LINE, "breakpoint")
                    and w.debug.halted["t_ms"] > first, timeout=WAIT)
    at = w.debug.halted["t_ms"]
    errors = []
    c.sig_error.connect(errors.append)

    # the Watch: write statez = 1 (the procedure took the branch to this line
    # because it was 0: done at the tick's start, the line is never reached)
    panels.dock("watch").show()
    panels.dock("watch").raise_()
    watch = panels.watch
    qtbot.waitUntil(lambda: "statez" in watch._rows, timeout=WAIT)
    _edit_cell(qtbot, watch.table, watch.row_of("statez"), 1, "1")
    qtbot.waitUntil(lambda: (watch.value("statez", "M80") or 0) == 1, timeout=WAIT)
    # the Inputs: force input 5 on with a click, release it from its menu;
    # ADC1 typed into its box
    panels.dock("inputs").show()
    panels.dock("inputs").raise_()
    inputs = panels.inputs
    qtbot.mouseClick(inputs.button(5), Qt.MouseButton.LeftButton)
    qtbot.waitUntil(lambda: 5 in inputs.forced_pins, timeout=WAIT)
    menu = inputs.pin_menu(5)
    next(a for a in menu.actions() if a.objectName() == "release_keep").trigger()
    qtbot.waitUntil(lambda: 5 not in inputs.forced_pins, timeout=WAIT)
    spin = inputs.spins[1]
    spin.setFocus()
    spin.selectAll()
    qtbot.keyClicks(spin, "777")
    qtbot.keyClick(spin, Qt.Key.Key_Return)
    qtbot.waitUntil(lambda: 1 in inputs.forced_adc, timeout=WAIT)

    w.action(Act.STEP_OVER).trigger()
    qtbot.waitUntil(lambda: _halted(w, HOME_LINE + 1, "step", at), timeout=WAIT)
    w.action(Act.STEP_BACK).trigger()
    qtbot.waitUntil(lambda: _halted(w, HOME_LINE, "step", at) or bool(errors), timeout=WAIT)
    assert not errors
    assert _halted(w, HOME_LINE, "step", at)
    # there, as forward: the write and the ADC force were done, the force of input 5 released
    qtbot.waitUntil(lambda: (watch.value("statez", "M80") or 0) == 1, timeout=WAIT)
    assert 1 in inputs.forced_adc and 5 not in inputs.forced_pins
    # and a tick back: the start of that tick, before any of them
    w.action(Act.STEP_BACK_TICK).trigger()
    qtbot.waitUntil(lambda: _halted(w, reason="step", t_ms=at) and
                    w.debug.halted["procedure"] is None or bool(errors), timeout=WAIT)
    assert not errors
    qtbot.waitUntil(lambda: 1 not in inputs.forced_adc, timeout=WAIT)
