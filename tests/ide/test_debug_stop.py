"""Stop while the debugger is halted (docs/debugging.md, "Stop while
halted"): Stop ends the procedure that halted and starts M02 as it always
does, but time stays stopped; the status bar, the call stack, the Watch and
the editor's current-line marker say so (M80 ended, M02 waits at its first
line), and a step or Continue goes on from there. Driven like a user against
the real embedded controller."""

from __future__ import annotations

from plcbuilder.controller import events as ev
from plcbuilder.ide.actions import Act

from tests.ide._debug import HOME_LINE, halt_m80_at_home

WAIT = 30_000
M02_FIRST = 7          # M02.plc: "  gvarset(8635,0);  //stop any jog"


def test_stop_while_halted_after_a_step_says_what_is_true(live_example, qtbot):
    w, root = live_example
    events, m80 = halt_m80_at_home(w, root, qtbot, WAIT)
    c = w.connection
    panels = w.ensure_run_panels()
    w.action(Act.STEP_OVER).trigger()
    qtbot.waitUntil(lambda: (w.debug.halted or {}).get("line") == HOME_LINE + 1, timeout=WAIT)
    assert w.statusBar().currentMessage().startswith("Halted after a step in M80")
    t_halt = w.debug.halted["t_ms"]

    w.action(Act.STOP).trigger()
    qtbot.waitUntil(lambda: any(isinstance(e, ev.Started) and e.name == "M02" for e in events),
                    timeout=WAIT)
    qtbot.waitUntil(lambda: "M80 ended" in w.statusBar().currentMessage(), timeout=WAIT)
    # still halted, time stood still: nothing ran that the user did not ask for
    qtbot.wait(600)
    assert w.debug.is_halted() and c.last_state.t_ms == t_halt
    assert w.statusBar().currentMessage() == (
        f"Halted, t = {t_halt} ms: M80 ended; M02 waits at M02.plc:{M02_FIRST} "
        "(Continue runs on)")
    ended = next(e for e in events if isinstance(e, ev.Ended) and e.name == "M80")
    assert ended.exit_code == 100
    # the call stack and the editors agree: M80 has no frame and no marker,
    # M02 is opened at the line it waits at
    assert w.debug.call_stack.frame_texts()[0] == ("main()  ◀", f"M02.plc:{M02_FIRST}")
    assert all("M80" not in where for _call, where in w.debug.call_stack.frame_texts())
    assert w.debug.call_stack.header.text() == w.statusBar().currentMessage()
    assert m80.debug_marks.exec_lines() == []
    m02 = w.current_editor()
    assert m02.path.endswith("M02.plc") and m02.debug_marks.exec_lines() == [M02_FIRST]
    assert "M80" not in panels.watch.variables
    assert w.debug.step_procedure() == "M02"

    # a step steps M02 now (M80 is gone): the rest of the halted tick runs and
    # M02 halts before its first line in the next one; the next step runs it
    w.action(Act.STEP_OVER).trigger()
    qtbot.waitUntil(lambda: (w.debug.halted or {}).get("procedure") == "M02", timeout=WAIT)
    assert w.statusBar().currentMessage() == \
        f"Halted after a step in M02 at M02.plc:{M02_FIRST}, t = {t_halt + 1} ms"
    w.action(Act.STEP_OVER).trigger()
    qtbot.waitUntil(lambda: (w.debug.halted or {}).get("line") == M02_FIRST + 1, timeout=WAIT)
    assert m02.debug_marks.exec_lines() == [M02_FIRST + 1]
    w.action(Act.START).trigger()
    qtbot.waitUntil(lambda: any(isinstance(e, ev.Ended) and e.name == "M02" for e in events),
                    timeout=WAIT)
    qtbot.waitUntil(lambda: not w.debug.is_halted(), timeout=WAIT)
    assert m02.debug_marks.exec_lines() == []
