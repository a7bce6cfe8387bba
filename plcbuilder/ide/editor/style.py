"""The editor's marks and looks: indicators, markers, margins, the images of
margin markers and completion kinds, and the preferences every editor follows
(the numbers and the preferences are defined in :mod:`.marks`, which does not
load Scintilla)."""

from __future__ import annotations

import re

from PySide6.QtCore import Qt
from PySide6.QtGui import QColor, QFont, QImage, QPainter
from pyside6_scintilla import Scintilla

from plcbuilder.ide.editor.marks import (  # noqa: F401 - this module gives them too
    IND_ERROR, IND_WARNING, IND_FIND, IND_OCCURRENCE, MK_ERROR, MK_WARNING, MK_CURRENT,
    MK_COVERED, MK_UNCOVERED, MK_BREAKPOINT, MK_BREAKPOINT_DISABLED, MK_BREAKPOINT_CONDITIONAL,
    MK_LOGPOINT, MK_BREAKPOINT_UNVERIFIED, MK_EXEC_LINE, MK_WAIT_LINE, MK_FRAME_LINE, MK_EXEC,
    MK_WAIT, MK_DEBUG_MASK, MK_BACKGROUNDS, KIND_FUNCTION, KIND_VARIABLE, KIND_PREDEFINED,
    KIND_CONSTANT, KIND_DEFINE, KIND_KEYWORD, KIND_PROCEDURE, KIND_LOOK, EditorPrefs,
    default_font_family, rgba_image)

M = Scintilla.Message

# elements (SCI_SETELEMENTCOLOUR): the selection's text colours are left unset, so
# selected text keeps its syntax colours over the selection background
EL_SELECTION_TEXT = 10
EL_SELECTION_BACK = 11
EL_SELECTION_ADDITIONAL_TEXT = 12
EL_SELECTION_ADDITIONAL_BACK = 13
EL_SELECTION_SECONDARY_TEXT = 14
EL_SELECTION_SECONDARY_BACK = 15
EL_SELECTION_INACTIVE_TEXT = 16
EL_SELECTION_INACTIVE_BACK = 17
SELECTION_TEXT_ELEMENTS = (EL_SELECTION_TEXT, EL_SELECTION_ADDITIONAL_TEXT,
                           EL_SELECTION_SECONDARY_TEXT, EL_SELECTION_INACTIVE_TEXT)
# margins
MARGIN_NUMBERS = 0
MARGIN_SYMBOLS = 1
MARGIN_FOLD = 2

SC_MOD_INSERTTEXT = 0x1
SC_MOD_DELETETEXT = 0x2
SC_UPDATE_CONTENT = 0x1
SC_UPDATE_SELECTION = 0x2
SC_MASK_FOLDERS = 0xFE000000

FIND_MATCHCASE = 0x4
FIND_WHOLEWORD = 0x2
FIND_REGEXP = 0x00200000
FIND_CXX11REGEX = 0x00800000

COMMENT_PREFIX = "//"
BRACES = "(){}"
BRACE_BYTES = frozenset(BRACES.encode())
WORD_RE = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")

def marker_image(kind: str, size: int = 14) -> bytes:
    """An error (red disc with a cross) or warning (amber triangle with !) icon."""
    img = QImage(size, size, QImage.Format.Format_RGBA8888)
    img.fill(Qt.GlobalColor.transparent)
    p = QPainter(img)
    p.setRenderHint(QPainter.RenderHint.Antialiasing)
    p.setPen(Qt.PenStyle.NoPen)
    if kind == "error":
        p.setBrush(QColor("#e51400"))
        p.drawEllipse(1, 1, size - 2, size - 2)
        pen = p.pen()
        p.setPen(QColor("#ffffff"))
        m = size * 0.32
        p.drawLine(int(m), int(m), int(size - m), int(size - m))
        p.drawLine(int(size - m), int(m), int(m), int(size - m))
        p.setPen(pen)
    else:
        from PySide6.QtCore import QPointF
        from PySide6.QtGui import QPolygonF
        p.setBrush(QColor("#e0a000"))
        p.drawPolygon(QPolygonF([QPointF(size / 2, 1), QPointF(size - 1, size - 1.5),
                                 QPointF(1, size - 1.5)]))
        p.setPen(QColor("#000000"))
        f = QFont(default_font_family())
        f.setPixelSize(size - 5)
        f.setBold(True)
        p.setFont(f)
        p.drawText(img.rect().adjusted(0, 2, 0, 0), Qt.AlignmentFlag.AlignCenter, "!")
    p.end()
    return bytes(img.constBits())
