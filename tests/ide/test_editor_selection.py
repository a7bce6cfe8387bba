"""Selected text stays readable: the selection paints under the text, which keeps
its own colours (issue 13, defect 1: a double-clicked word, Home then Shift+End and
a line moved with Alt+Down turned into a plain block of the selection colour)."""

import pytest
from PySide6.QtCore import QPoint, Qt
from PySide6.QtGui import QColor

from plcbuilder.ide import highlighter as hl
from plcbuilder.ide.editor import CodeEditor, EditorPrefs

SRC = "main()\n{\n  pwm01=0;\n  proc=plc_proc_idle;\n}\n"


def _luminance(c: QColor) -> float:
    return 0.2126 * c.redF() + 0.7152 * c.greenF() + 0.0722 * c.blueF()


def _text_pixels(ed: CodeEditor, start: int, end: int, back: str) -> int:
    """Pixels inside the selection's box that differ clearly from its background."""
    img = ed.grab().toImage()
    end = min(end, ed.lineEndPosition(ed.lineFromPosition(start)))     # the first line's part
    x0, x1 = ed.pointXFromPosition(start), ed.pointXFromPosition(end)
    y0 = ed.pointYFromPosition(start)
    bg = _luminance(QColor(back))
    count = 0
    for x in range(x0, x1):
        for y in range(y0, y0 + ed.textHeight(0)):
            if abs(_luminance(img.pixelColor(x, y)) - bg) > 0.25:
                count += 1
    return count


@pytest.fixture(params=["light", "dark"])
def ed(qtbot, request):
    e = CodeEditor(prefs=EditorPrefs(theme=request.param))
    qtbot.addWidget(e)
    e.resize(600, 300)
    e.show()
    qtbot.waitExposed(e)
    e.activateWindow()
    e.take_focus()
    qtbot.waitUntil(e.hasFocus)
    e.set_text(SRC)
    e.theme_name = request.param
    return e


def _wait_painted(qtbot):
    qtbot.wait(30)


def test_double_clicked_word_keeps_its_text(ed, qtbot):
    start = ed.position_of(3, 3)
    x, y = ed.pointXFromPosition(start + 2), ed.pointYFromPosition(start) + 4
    for _ in range(2):           # Scintilla tells a double click by itself: two quick presses
        qtbot.mouseClick(ed.viewport(), Qt.MouseButton.LeftButton, pos=QPoint(x, y))
    _wait_painted(qtbot)
    assert ed.selected_text() == "pwm01"
    back = hl.THEMES[ed.theme_name].selection
    # "pwm01" in a monospace font at 11 pt: dozens of glyph pixels, not a blank block
    assert _text_pixels(ed, ed.selectionStart(), ed.selectionEnd(), back) > 30


def test_home_shift_end_and_alt_down_keep_the_line_readable(ed, qtbot):
    ed.goto_line(4, 8)
    qtbot.keyClick(ed, Qt.Key.Key_Home)
    qtbot.keyClick(ed, Qt.Key.Key_End, Qt.KeyboardModifier.ShiftModifier)
    _wait_painted(qtbot)
    assert ed.selected_text().strip() == "proc=plc_proc_idle;"
    back = hl.THEMES[ed.theme_name].selection
    assert _text_pixels(ed, ed.selectionStart(), ed.selectionEnd(), back) > 100
    qtbot.keyClick(ed, Qt.Key.Key_Down, Qt.KeyboardModifier.AltModifier)
    _wait_painted(qtbot)
    assert ed.line_text(4).strip() == "proc=plc_proc_idle;"      # moved below the "}"
    assert ed.selected_text().strip() == "proc=plc_proc_idle;"
    assert _text_pixels(ed, ed.selectionStart(), ed.selectionEnd(), back) > 100
