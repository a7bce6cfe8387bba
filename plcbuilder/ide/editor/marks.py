"""The numbers of the editor's indicators, markers and completion kinds (with
their images), and the preferences every editor follows: no Scintilla, for
the modules that only name them (the settings, completion, the outline).
:mod:`.style` gives them too, with the looks that use them."""

from __future__ import annotations

from dataclasses import dataclass


# indicators (0..7 belong to lexers; containers use 8 and up)
IND_ERROR = 8
IND_WARNING = 9
IND_FIND = 10
IND_OCCURRENCE = 11
# markers
MK_ERROR = 0
MK_WARNING = 1
MK_CURRENT = 2          # a line being jumped to (briefly)
MK_COVERED = 3          # test coverage: a line that ran
MK_UNCOVERED = 4        # ... a line with code that did not
# the debugger's markers (plcbuilder.ide.debug.markers draws them); a higher
# number is drawn over a lower one
MK_BREAKPOINT = 5
MK_BREAKPOINT_DISABLED = 6
MK_BREAKPOINT_CONDITIONAL = 7
MK_LOGPOINT = 8
MK_BREAKPOINT_UNVERIFIED = 9
MK_EXEC_LINE = 10       # background of the line a halted procedure is at
MK_WAIT_LINE = 11       # ... of a loop's end where a procedure waits for the next tick
MK_FRAME_LINE = 12      # ... of a caller's line (a call stack frame picked)
MK_EXEC = 13            # the arrow of the line a halted procedure is at
MK_WAIT = 14            # the arrow of a loop's end it waits at
MK_DEBUG_MASK = sum(1 << m for m in range(MK_BREAKPOINT, MK_WAIT + 1))
MK_BACKGROUNDS = (1 << MK_EXEC_LINE) | (1 << MK_WAIT_LINE) | (1 << MK_FRAME_LINE)

#: completion item kinds, shown with an image in the list
KIND_FUNCTION = 1
KIND_VARIABLE = 2
KIND_PREDEFINED = 3
KIND_CONSTANT = 4
KIND_DEFINE = 5
KIND_KEYWORD = 6
KIND_PROCEDURE = 7
KIND_LOOK = {  # letter, colour
    KIND_FUNCTION: ("f", "#7a3e9d"), KIND_VARIABLE: ("v", "#1f6feb"),
    KIND_PREDEFINED: ("v", "#00838f"), KIND_CONSTANT: ("c", "#b35900"),
    KIND_DEFINE: ("#", "#2e7d32"), KIND_KEYWORD: ("k", "#5c5c5c"),
    KIND_PROCEDURE: ("p", "#00627a"),
}


@dataclass(frozen=True)
class EditorPrefs:
    """What the Preferences dialog changes in every editor."""
    font_family: str = ""
    font_size: int = 11
    tab_width: int = 4
    theme: str = "light"
    show_whitespace: bool = False
    indent_guides: bool = True
    autocomplete: bool = True
    autocomplete_threshold: int = 2
    hover: bool = True


def default_font_family() -> str:
    from PySide6.QtGui import QFontDatabase
    family = QFontDatabase.systemFont(QFontDatabase.SystemFont.FixedFont).family()
    return family or "DejaVu Sans Mono"


def rgba_image(letter: str, colour: str, size: int = 14) -> bytes:
    # these here, not at import: the settings import this module before the
    # window's first frame, which does without their enum classes (a Qt
    # class first used from Python makes them; the Qt namespace's take 35 ms)
    from PySide6.QtCore import Qt
    from PySide6.QtGui import QColor, QFont, QImage, QPainter
    img = QImage(size, size, QImage.Format.Format_RGBA8888)
    img.fill(Qt.GlobalColor.transparent)
    p = QPainter(img)
    p.setRenderHint(QPainter.RenderHint.Antialiasing)
    p.setPen(Qt.PenStyle.NoPen)
    p.setBrush(QColor(colour))
    p.drawRoundedRect(1, 1, size - 2, size - 2, 3, 3)
    f = QFont(default_font_family())
    f.setPixelSize(size - 4)
    f.setBold(True)
    p.setFont(f)
    p.setPen(QColor("#ffffff"))
    p.drawText(img.rect(), Qt.AlignmentFlag.AlignCenter, letter)
    p.end()
    return bytes(img.constBits())
