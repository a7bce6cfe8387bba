"""What the debugger's IDE tests share: M80's lines and clicking the breakpoint margin."""

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
