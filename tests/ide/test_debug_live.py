"""The debugger in the IDE against the real embedded controller (a child
process), driven like a user: a breakpoint clicked into M80's margin, Start,
the halt on the line that reads the home switch with inline values and the
call stack, step over, INPUT_HOME_Z forced from the Inputs dock, the loop
ending, continue to the end."""

from __future__ import annotations

from plcbuilder.controller import events as ev
from plcbuilder.ide.actions import Act

from tests.ide._debug import HOME_LINE, click_margin, halt_m80_at_home

WAIT = 30_000
LOOP_END = 62          # M80.plc: "  gvarset(8635,0); //stop jog" right after the loop
FOUND = 34             # M80.plc: "        statez=1;" (the switch was found)
HOME_Z_PIN = 2         # pins.h: INPUT_HOME_Z


def _halted_at(w, line):
    st = w.debug.halted
    return st is not None and st.get("line") == line


def test_halt_step_force_and_continue_in_m80(live_example, qtbot):
    w, root = live_example
    events, ed = halt_m80_at_home(w, root, qtbot, WAIT)
    panels = w.ensure_run_panels()
    st = w.debug.halted
    assert st["reason"] == "breakpoint" and st["procedure"] == "M80"
    assert w.current_editor() is ed and ed.debug_marks.exec_lines() == [HOME_LINE]
    assert ed.debug_marks.inline_text(HOME_LINE) == "sens = 0"
    assert ed.debug_marks.inline_text(29) == "statez = 0"
    assert w.debug.call_stack.frame_texts()[:2] == [
        ("find_home_z()  ◀", f"M80.plc:{HOME_LINE}"), ("main()", "M80.plc:75")]
    assert w.action(Act.START).text() == "&Continue"
    assert "M80.sens = 0" in ed.hover_text_at(ed.position_of(HOME_LINE, 8))

    # step over: the next statement, the switch still open
    t0 = st["t_ms"]
    w.action(Act.STEP_OVER).trigger()
    qtbot.waitUntil(lambda: _halted_at(w, HOME_LINE + 1), timeout=WAIT)
    assert w.debug.halted["reason"] == "step" and w.debug.halted["t_ms"] == t0

    # force the home switch closed from the Inputs dock; halt where it is found
    menu = panels.inputs.pin_menu(HOME_Z_PIN)
    next(a for a in menu.actions() if a.objectName() == "force_on").trigger()
    qtbot.waitUntil(lambda: "in 2" in w.debug.forces_panel.targets(), timeout=WAIT)
    qtbot.waitUntil(lambda: panels.inputs.button(HOME_Z_PIN).property("forced") == "true",
                    timeout=WAIT)
    click_margin(qtbot, ed, HOME_LINE)                     # off
    w.debug.toggle_breakpoint(ed, FOUND)
    w.action(Act.START).trigger()                           # F5: continue
    qtbot.waitUntil(lambda: _halted_at(w, FOUND), timeout=WAIT)
    assert ed.debug_marks.inline_text(32) == "sens = 1"

    # release it to the wiring (Z is above its switch): the loop ends
    w.debug.store.clear(ed.path)
    w.debug.toggle_breakpoint(ed, LOOP_END)
    w.debug.release(f"in {HOME_Z_PIN}", "restore")
    qtbot.waitUntil(lambda: w.debug.forces_panel.targets() == [], timeout=WAIT)
    w.action(Act.START).trigger()
    qtbot.waitUntil(lambda: _halted_at(w, LOOP_END), timeout=WAIT)
    assert panels.watch.value("statez", "M80") == 2
    assert ed.debug_marks.exec_lines() == [LOOP_END]

    # continue to the end
    w.debug.store.clear()
    w.action(Act.START).trigger()
    qtbot.waitUntil(lambda: any(isinstance(e, ev.Ended) and e.name == "M80" for e in events),
                    timeout=WAIT)
    qtbot.waitUntil(lambda: not w.debug.is_halted(), timeout=WAIT)
    assert ed.debug_marks.exec_lines() == [] and ed.debug_marks.inline == {}
    ended = next(e for e in events if isinstance(e, ev.Ended) and e.name == "M80")
    assert ended.exit_code == 99
    assert w.action(Act.START).text() == "&Start…"
    assert ed.debug_marks.breakpoint_lines() == {}
