"""What the debugger's IDE tests share: M80's lines, clicking the breakpoint
margin, and halting M80 on the live example."""

from __future__ import annotations

from PySide6.QtCore import QPoint, Qt

from plcbuilder.ide.editor.style import MARGIN_NUMBERS, MARGIN_SYMBOLS

HOME_LINE = 31            # M80.plc: "      sens=portget(INPUT_HOME_Z);"


def margin_point(ed, line: int) -> QPoint:
    """The middle of the breakpoint (symbol) margin beside a 1-based line."""
    x = ed.marginWidthN(MARGIN_NUMBERS) + ed.marginWidthN(MARGIN_SYMBOLS) // 2
    y = ed.pointYFromPosition(ed.positionFromLine(line - 1)) + ed.textHeight(line - 1) // 2
    return QPoint(x, y)


def click_margin(qtbot, ed, line: int, button=Qt.MouseButton.LeftButton) -> None:
    """Click the breakpoint margin beside a line (scrolled into view first)."""
    ed.goto_line(line)
    qtbot.mouseClick(ed.viewport(), button, pos=margin_point(ed, line))


def halt_m80_at_home(w, root, qtbot, wait: int) -> tuple[list, object]:
    """The live example built and loaded, a breakpoint clicked beside M80's
    home-switch line, M80 started and halted there: (the controller's events
    from then on, M80's editor)."""
    events: list = []
    assert w.open_project(root)
    with qtbot.waitSignal(w.sig_build_finished, timeout=wait):
        assert w.build_all()
    c = w.connection
    c.sig_events.connect(events.extend)
    qtbot.waitUntil(lambda: c.connected and w.debug.connected(), timeout=wait)
    # an empty controller gets the project's image
    qtbot.waitUntil(lambda: c.last_state.image_crc32 is not None, timeout=wait)
    w.ensure_run_panels()
    ed = w.open_file(root / "hardware" / "M80.plc")
    click_margin(qtbot, ed, HOME_LINE)
    bp = w.debug.store.at(ed.path, HOME_LINE)
    qtbot.waitUntil(lambda: bp.verified is True, timeout=wait)
    assert w.start_procedure("M80", 0)
    qtbot.waitUntil(lambda: (w.debug.halted or {}).get("line") == HOME_LINE, timeout=wait)
    return events, ed
