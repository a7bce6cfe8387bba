"""The debugger's marks in an editor: breakpoint markers in the symbol margin
(they follow edits: Scintilla moves markers with their lines), the line a halted
procedure is at, and inline values at the ends of lines.

:class:`EditorMarks` is attached to one :class:`CodeEditor` by the debug
session; it draws what the session tells it and reports the lines its
breakpoint markers moved to.
"""

from __future__ import annotations

from typing import Iterable, Optional

from PySide6.QtCore import QPointF, Qt
from PySide6.QtGui import QColor, QImage, QPainter, QPen, QPolygonF
from pyside6_scintilla import Scintilla

from plcbuilder.ide.debug.breakpoints import Breakpoint
from plcbuilder.ide.editor import (MK_BREAKPOINT, MK_BREAKPOINT_CONDITIONAL,
                                   MK_BREAKPOINT_DISABLED, MK_BREAKPOINT_UNVERIFIED, MK_EXEC,
                                   MK_EXEC_LINE, MK_FRAME_LINE, MK_LOGPOINT, MK_WAIT, MK_WAIT_LINE)

BREAKPOINT_RED = "#e51400"
EXEC_YELLOW = "#f2c200"
WAIT_BLUE = "#2f7fd1"
#: line backgrounds, opaque (the caret line hides while halted: it would cover them),
#: light and dark: each keeps the theme's text readable on it
LINE_BACKS = {MK_EXEC_LINE: "#fff1a8", MK_WAIT_LINE: "#d6e8fb", MK_FRAME_LINE: "#d9f2d9"}
LINE_BACKS_DARK = {MK_EXEC_LINE: "#4d4316", MK_WAIT_LINE: "#1c3550", MK_FRAME_LINE: "#1f3d24"}
INLINE_STYLE = 60          # the style of inline values (free: lexers use 0..17, Scintilla 32..39)
EOL_BOXED = 2              # EOLANNOTATION_BOXED
SIZE = 14


def _bgr(colour: str) -> int:
    c = QColor(colour)
    return c.red() | (c.green() << 8) | (c.blue() << 16)


def marker_image(kind: str, size: int = SIZE) -> bytes:
    """The RGBA pixels of a debugger marker: breakpoint (red disc), disabled
    (grey ring), conditional (disc with a bar), logpoint (diamond), unverified
    (red ring), exec (yellow arrow), wait (blue arrow with a ring)."""
    img = QImage(size, size, QImage.Format.Format_RGBA8888)
    img.fill(Qt.GlobalColor.transparent)
    p = QPainter(img)
    p.setRenderHint(QPainter.RenderHint.Antialiasing)
    red = QColor(BREAKPOINT_RED)
    if kind in ("breakpoint", "conditional"):
        p.setPen(Qt.PenStyle.NoPen)
        p.setBrush(red)
        p.drawEllipse(QPointF(size / 2, size / 2), size / 2 - 1.5, size / 2 - 1.5)
        if kind == "conditional":
            p.setPen(QPen(QColor("#ffffff"), 1.6))
            p.drawLine(QPointF(size * 0.3, size * 0.4), QPointF(size * 0.7, size * 0.4))
            p.drawLine(QPointF(size * 0.3, size * 0.6), QPointF(size * 0.7, size * 0.6))
    elif kind in ("disabled", "unverified"):
        p.setPen(QPen(QColor("#8a8a8a") if kind == "disabled" else red, 1.6))
        p.setBrush(QColor("#d9d9d9") if kind == "disabled" else Qt.GlobalColor.transparent)
        p.drawEllipse(QPointF(size / 2, size / 2), size / 2 - 2, size / 2 - 2)
    elif kind == "logpoint":
        p.setPen(Qt.PenStyle.NoPen)
        p.setBrush(red)
        h = size / 2
        p.drawPolygon(QPolygonF([QPointF(h, 1), QPointF(size - 1, h), QPointF(h, size - 1),
                                 QPointF(1, h)]))
    elif kind in ("exec", "wait"):
        colour = QColor(EXEC_YELLOW if kind == "exec" else WAIT_BLUE)
        p.setPen(QPen(colour.darker(150), 1))
        p.setBrush(colour)
        p.drawPolygon(QPolygonF([QPointF(1, size * 0.3), QPointF(size * 0.55, size * 0.3),
                                 QPointF(size * 0.55, 1), QPointF(size - 1, size / 2),
                                 QPointF(size * 0.55, size - 1),
                                 QPointF(size * 0.55, size * 0.7), QPointF(1, size * 0.7)]))
    p.end()
    return bytes(img.constBits())


_IMAGES = {MK_BREAKPOINT: "breakpoint", MK_BREAKPOINT_DISABLED: "disabled",
           MK_BREAKPOINT_CONDITIONAL: "conditional", MK_LOGPOINT: "logpoint",
           MK_BREAKPOINT_UNVERIFIED: "unverified", MK_EXEC: "exec", MK_WAIT: "wait"}
BREAKPOINT_MARKERS = (MK_BREAKPOINT, MK_BREAKPOINT_DISABLED, MK_BREAKPOINT_CONDITIONAL,
                      MK_LOGPOINT, MK_BREAKPOINT_UNVERIFIED)


def marker_for(bp: Breakpoint) -> int:
    if not bp.enabled:
        return MK_BREAKPOINT_DISABLED
    if bp.verified is False:
        return MK_BREAKPOINT_UNVERIFIED
    return {"logpoint": MK_LOGPOINT, "conditional": MK_BREAKPOINT_CONDITIONAL}.get(
        bp.kind, MK_BREAKPOINT)


class EditorMarks:
    """The debugger's marks in one editor."""

    def __init__(self, editor):
        self.editor = editor
        self._handles: dict[int, Breakpoint] = {}    # marker handle -> breakpoint
        self.inline: dict[int, str] = {}             # 1-based line -> inline text shown
        self._caret_back = None                       # the caret line's colour while hidden
        self._define()

    # ---------------------------------------------------------------- set-up
    def _define(self) -> None:
        ed = self.editor
        for mk, kind in _IMAGES.items():
            ed.define_rgba_marker(mk, marker_image(kind), SIZE)
        for mk in LINE_BACKS:
            ed.markerDefine(mk, int(Scintilla.MarkerSymbol.Background))
        self.apply_theme(dark=False)
        ed.eOLAnnotationSetVisible(EOL_BOXED)

    def apply_theme(self, dark: bool) -> None:
        """The inline values' style and the halted lines' backgrounds for the
        light or the dark theme."""
        ed = self.editor
        self.line_backs = dict(LINE_BACKS_DARK if dark else LINE_BACKS)
        for mk, colour in self.line_backs.items():
            ed.markerSetBack(mk, _bgr(colour))
        ed.styleSetFore(INLINE_STYLE, _bgr("#9fb8d6" if dark else "#3a5f8a"))
        ed.styleSetBack(INLINE_STYLE, _bgr("#25303b" if dark else "#eef3fa"))
        ed.styleSetItalic(INLINE_STYLE, True)

    def restyle(self) -> None:
        """After the editor's preferences changed: the theme's colours, and the
        caret line (the preferences show it) hidden again while a line is marked."""
        ed = self.editor
        self.apply_theme(self._dark())
        if self.inline:
            for line in self.inline:
                ed.eOLAnnotationSetStyle(line - 1, INLINE_STYLE)
        if self._caret_back is not None:
            self._caret_back = ed.caretLineBack()
            ed.setCaretLineVisible(False)

    def _dark(self) -> bool:
        return getattr(getattr(self.editor, "prefs", None), "theme", "light") == "dark"

    # ------------------------------------------------------------ breakpoints
    def show_breakpoints(self, bps: Iterable[Breakpoint]) -> None:
        ed = self.editor
        for mk in BREAKPOINT_MARKERS:
            ed.markerDeleteAll(mk)
        self._handles.clear()
        count = ed.lineCount()
        for bp in bps:
            if 1 <= bp.line <= count:
                handle = ed.markerAdd(bp.line - 1, marker_for(bp))
                if handle >= 0:
                    self._handles[handle] = bp

    def moved_lines(self) -> dict[int, tuple[Breakpoint, int]]:
        """Where each breakpoint's marker is now: ``{id(bp): (bp, 1-based line)}``."""
        out = {}
        for handle, bp in self._handles.items():
            line0 = self.editor.markerLineFromHandle(handle)
            if line0 >= 0:
                out[id(bp)] = (bp, line0 + 1)
        return out

    def breakpoint_lines(self) -> dict[int, int]:
        """The lines with a breakpoint marker and which marker: ``{line: marker}``."""
        out = {}
        for mk in BREAKPOINT_MARKERS:
            line0 = self.editor.markerNext(0, 1 << mk)
            while line0 >= 0:
                out[line0 + 1] = mk
                line0 = self.editor.markerNext(line0 + 1, 1 << mk)
        return out

    # -------------------------------------------------------------- execution
    def show_exec(self, exec_lines: Iterable[int] = (), wait_lines: Iterable[int] = (),
                  frame_lines: Iterable[int] = ()) -> None:
        """Mark the lines halted procedures are at (arrow + background), the
        loop ends they wait at, and a picked caller's line."""
        ed = self.editor
        self.apply_theme(self._dark())          # the theme may have changed since
        for mk in (MK_EXEC, MK_EXEC_LINE, MK_WAIT, MK_WAIT_LINE, MK_FRAME_LINE):
            ed.markerDeleteAll(mk)
        count = ed.lineCount()
        marked = False
        for lines, arrow, back in ((exec_lines, MK_EXEC, MK_EXEC_LINE),
                                   (wait_lines, MK_WAIT, MK_WAIT_LINE),
                                   (frame_lines, None, MK_FRAME_LINE)):
            for line in lines:
                if 1 <= line <= count:
                    if arrow is not None:
                        ed.markerAdd(line - 1, arrow)
                    ed.markerAdd(line - 1, back)
                    marked = True
        # Scintilla paints the caret line over marker backgrounds: hide it while
        # this editor shows where a halted procedure is (showing it again resets
        # its colour: put the theme's back)
        if marked and self._caret_back is None:
            self._caret_back = ed.caretLineBack()
            ed.setCaretLineVisible(False)
        elif not marked and self._caret_back is not None:
            ed.setCaretLineVisible(True)
            ed.setCaretLineBack(self._caret_back)
            self._caret_back = None

    def exec_lines(self, marker: int = MK_EXEC) -> list[int]:
        out, line0 = [], self.editor.markerNext(0, 1 << marker)
        while line0 >= 0:
            out.append(line0 + 1)
            line0 = self.editor.markerNext(line0 + 1, 1 << marker)
        return out

    # ---------------------------------------------------------- inline values
    def show_inline(self, texts: dict[int, str]) -> None:
        """Inline values at the end of lines: ``{1-based line: text}`` (empty: none)."""
        ed = self.editor
        if texts == self.inline:
            return
        # the preferences' restyle resets every style: set the inline one each time
        self.apply_theme(self._dark())
        ed.eOLAnnotationClearAll()          # (an empty text would still draw its box)
        count = ed.lineCount()
        for line, text in texts.items():
            if 1 <= line <= count:
                ed.eOLAnnotationSetText(line - 1, text)
                ed.eOLAnnotationSetStyle(line - 1, INLINE_STYLE)
        self.inline = dict(texts)

    def inline_text(self, line: int) -> Optional[str]:
        return self.inline.get(line)

    def clear(self) -> None:
        self.show_exec()
        self.show_inline({})
