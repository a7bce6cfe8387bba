"""The source editor: a :class:`ScintillaEdit` set up for PLC procedures.

Highlighting and folding (:mod:`plcbuilder.ide.highlighter`), line numbers,
brace matching, auto-indent, comment toggling, find/replace, go to line,
autocompletion and call tips, hover help, occurrences of the word under the
caret, and diagnostics shown as squiggles (indicators), margin markers and
hover text.

Positions: Scintilla counts UTF-8 bytes, Python and the diagnostics count
characters. Every conversion goes through :mod:`plcbuilder.ide.offsets`
(:meth:`CodeEditor.position_of` / :meth:`CodeEditor.line_col_of`).
"""

from __future__ import annotations

import ctypes
import os
import re
from dataclasses import dataclass
from typing import Callable, Iterable, Optional

from PySide6.QtCore import Qt, QTimer, Signal
from PySide6.QtGui import QAction, QColor, QFont, QFontDatabase, QImage, QPainter
from PySide6.QtWidgets import QFrame, QMenu, QWidget

from pyside6_scintilla import Scintilla, ScintillaEdit

from plcbuilder.api import Diagnostic, Severity
from plcbuilder.ide import highlighter as hl
from plcbuilder.ide.offsets import byte_to_char, char_to_byte, utf8_len

M = Scintilla.Message

# indicators (0..7 belong to lexers; containers use 8 and up)
IND_ERROR = 8
IND_WARNING = 9
IND_FIND = 10
IND_OCCURRENCE = 11
# markers
MK_ERROR = 0
MK_WARNING = 1
MK_CURRENT = 2          # a line being jumped to (briefly)
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
_BRACE_BYTES = frozenset(BRACES.encode())
WORD_RE = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")

#: completion item kinds, shown with an image in the list
KIND_FUNCTION = 1
KIND_VARIABLE = 2
KIND_PREDEFINED = 3
KIND_CONSTANT = 4
KIND_DEFINE = 5
KIND_KEYWORD = 6
KIND_PROCEDURE = 7
_KIND_LOOK = {  # letter, colour
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
    family = QFontDatabase.systemFont(QFontDatabase.SystemFont.FixedFont).family()
    return family or "DejaVu Sans Mono"


def _rgba_image(letter: str, colour: str, size: int = 14) -> bytes:
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


def _marker_image(kind: str, size: int = 14) -> bytes:
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


class CodeEditor(ScintillaEdit):
    """One editor of a PLC source (or header) file."""

    sig_cursor_moved = Signal(int, int)
    """The caret moved: (line, column), 1-based, the column counting characters."""

    sig_text_changed = Signal()
    """The text changed (typing, undo, replace, reload)."""

    sig_modified_changed = Signal(bool)
    """The document left (True) or returned to (False) its saved state."""

    sig_goto_definition = Signal(str)
    """Go to the definition of this name (F12 / Ctrl+click)."""

    def __init__(self, parent=None, prefs: Optional[EditorPrefs] = None):
        super().__init__(parent)
        self.prefs = prefs or EditorPrefs()
        self.highlighter = hl.Highlighter(self)
        self._diag_ranges: list[tuple[int, int, Diagnostic]] = []
        self._images: list = []           # ctypes buffers Scintilla points to
        self._context_actions: list[QAction] = []
        #: (editor, prefix) -> [(name, kind)]; set by the main window
        self.completion_provider: Optional[Callable[["CodeEditor", str], list]] = None
        #: (editor, byte position) -> hover text or None
        self.hover_provider: Optional[Callable[["CodeEditor", int], Optional[str]]] = None
        #: function name -> call tip text or None
        self.signature_provider: Optional[Callable[[str], Optional[str]]] = None
        self._occurrence_timer = QTimer(self)
        self._occurrence_timer.setSingleShot(True)
        self._occurrence_timer.setInterval(250)
        self._occurrence_timer.timeout.connect(self._mark_occurrences)
        self._line_digits = 0
        self._setup()
        self.apply_prefs(self.prefs)
        self.updateUi.connect(self._on_update_ui)
        self.modified.connect(self._on_modified)
        self.savePointChanged.connect(self.sig_modified_changed.emit)
        self.charAdded.connect(self._on_char_added)
        self.dwellStart.connect(self._on_dwell_start)
        self.dwellEnd.connect(lambda _x, _y: self.callTipCancel())

    # ================================================================ text
    def text(self) -> str:
        """The whole document as a str."""
        n = self.length()
        if n == 0:
            return ""
        return bytes(self.getText(n + 1))[:n].decode("utf-8", "replace")

    def set_text(self, text: str, *, keep_undo: bool = False) -> None:
        """Replace the document (a load or reload). ``keep_undo`` makes it one
        undoable step instead of clearing the history."""
        if keep_undo:
            self.beginUndoAction()
            self.setTargetRange(0, self.length())
            self.replaceTarget(utf8_len(text), text)
            self.endUndoAction()
        else:
            ro = self.readOnly()
            self.setReadOnly(False)
            self.setText(text)
            self.emptyUndoBuffer()
            self.setReadOnly(ro)
        self._update_line_margin()

    def byte_range_text(self, start: int, end: int) -> str:
        if end <= start:
            return ""
        return bytes(self.textRange(start, end)).decode("utf-8", "replace")

    def line_text(self, line0: int) -> str:
        """The text of 0-based line line0, without its line end."""
        start = self.positionFromLine(line0)
        if start < 0:
            return ""
        return self.byte_range_text(start, self.lineEndPosition(line0))

    def position_of(self, line: int, col: int = 1) -> int:
        """The byte position of 1-based (line, col), col counting characters,
        clamped to the document."""
        count = self.lineCount()
        if line < 1:
            return 0
        if line > count:
            return self.length()
        text = self.line_text(line - 1)
        return self.positionFromLine(line - 1) + char_to_byte(text, col - 1)

    def line_col_of(self, pos: int) -> tuple[int, int]:
        """1-based (line, col) of byte position pos, col counting characters."""
        pos = max(0, min(pos, self.length()))
        line0 = self.lineFromPosition(pos)
        start = self.positionFromLine(line0)
        return line0 + 1, byte_to_char(self.line_text(line0), pos - start) + 1

    def cursor_line_col(self) -> tuple[int, int]:
        return self.line_col_of(self.currentPos())

    def selected_text(self) -> str:
        return self.byte_range_text(self.selectionStart(), self.selectionEnd())

    def word_at(self, pos: int) -> tuple[int, int, str]:
        """(start, end, word) of the identifier or number at pos ('' if none)."""
        start = self.wordStartPosition(pos, True)
        end = self.wordEndPosition(pos, True)
        return start, end, self.byte_range_text(start, end)

    def byte_at(self, pos: int) -> int:
        """The document byte at pos (0..255; Scintilla's charAt is signed)."""
        return self.charAt(pos) & 0xFF

    def word_before_caret(self) -> str:
        pos = self.currentPos()
        start = self.wordStartPosition(pos, True)
        word = self.byte_range_text(start, pos)
        return word if WORD_RE.fullmatch(word) else ""

    # ================================================================ setup
    def _setup(self) -> None:
        self.setFrameShape(QFrame.Shape.NoFrame)
        self.send(M.SetCodePage, 65001)
        self.setEOLMode(2)                      # LF: the compiler normalises to \n
        self.setLineEndTypesAllowed(0)
        self.setUseTabs(False)
        self.setTabIndents(True)
        self.setBackSpaceUnIndents(True)
        self.setMultipleSelection(True)
        self.setAdditionalSelectionTyping(True)
        self.setScrollWidth(1)
        self.setScrollWidthTracking(True)
        self.setEndAtLastLine(False)
        self.setMouseDwellTime(450)
        self.usePopUp(0)                        # our own context menu
        self.setCaretWidth(2)
        # keep the caret away from the edges; centre jumped-to lines
        self.setYCaretPolicy(0x01 | 0x04 | 0x08, 3)   # SLOP | STRICT | EVEN
        self.setVisiblePolicy(0x01 | 0x04, 3)
        # margins
        self.setMarginTypeN(MARGIN_NUMBERS, 1)         # SC_MARGIN_NUMBER
        self.setMarginTypeN(MARGIN_SYMBOLS, 0)         # SC_MARGIN_SYMBOL
        self.setMarginMaskN(MARGIN_SYMBOLS, (1 << MK_ERROR) | (1 << MK_WARNING) | (1 << MK_CURRENT))
        self.setMarginWidthN(MARGIN_SYMBOLS, 16)
        self.setMarginSensitiveN(MARGIN_SYMBOLS, False)
        self.setMarginTypeN(MARGIN_FOLD, 0)
        self.setMarginMaskN(MARGIN_FOLD, SC_MASK_FOLDERS)
        self.setMarginWidthN(MARGIN_FOLD, 14)
        self.setMarginSensitiveN(MARGIN_FOLD, True)
        self.setMarginCursorN(MARGIN_FOLD, 2)          # SC_CURSORARROW
        self.setMarginLeft(2)
        self.setMarginRight(4)
        # folding: Scintilla handles clicks and keeps changed blocks open
        self.setAutomaticFold(0x1 | 0x2 | 0x4)
        self.setFoldFlags(16)                          # line below a folded header
        self.setDefaultFoldDisplayText(" … ")
        self.foldDisplayTextSetStyle(2)                # boxed
        folders = {25: "Arrow", 26: "ArrowDown", 27: "Empty", 28: "Empty",
                   29: "Empty", 30: "Arrow", 31: "ArrowDown"}
        for num, sym in folders.items():
            self.markerDefine(num, int(getattr(Scintilla.MarkerSymbol, sym)))
        # diagnostics markers (drawn icons) and indicators
        self._define_rgba_marker(MK_ERROR, _marker_image("error"))
        self._define_rgba_marker(MK_WARNING, _marker_image("warning"))
        self.markerDefine(MK_CURRENT, int(Scintilla.MarkerSymbol.Background))
        self.indicSetStyle(IND_ERROR, int(Scintilla.IndicatorStyle.Squiggle))
        self.indicSetStyle(IND_WARNING, int(Scintilla.IndicatorStyle.Squiggle))
        self.indicSetStyle(IND_FIND, int(Scintilla.IndicatorStyle.FullBox))
        self.indicSetStyle(IND_OCCURRENCE, int(Scintilla.IndicatorStyle.FullBox))
        for ind in (IND_ERROR, IND_WARNING):
            self.indicSetStrokeWidth(ind, 120)
        for ind in (IND_FIND, IND_OCCURRENCE):
            self.indicSetUnder(ind, True)
        # completion
        self.autoCSetIgnoreCase(True)
        self.autoCSetCaseInsensitiveBehaviour(1)       # prefer an exact-case match
        self.autoCSetOrder(1)                           # Scintilla sorts the list
        self.autoCSetMaxHeight(12)
        self.autoCSetAutoHide(True)
        self.autoCSetCancelAtStart(True)
        self.autoCSetTypeSeparator(ord("?"))
        self.autoCSetSeparator(ord(" "))
        self.autoCSetDropRestOfWord(False)
        for kind, (letter, col) in _KIND_LOOK.items():
            self._register_rgba(kind, _rgba_image(letter, col))
        # keys: Alt+Up/Down move lines, Ctrl+Shift+K deletes a line (as in VS Code)
        alt, ctrl, shift = 4, 2, 1
        keys = Scintilla.Keys
        self.assignCmdKey(int(keys.Up) | (alt << 16), int(M.MoveSelectedLinesUp))
        self.assignCmdKey(int(keys.Down) | (alt << 16), int(M.MoveSelectedLinesDown))
        self.assignCmdKey(ord("K") | ((ctrl | shift) << 16), int(M.LineDelete))
        self.clearCmdKey(ord("/") | (ctrl << 16))      # Ctrl+/ is the window's comment toggle

    def _define_rgba_marker(self, marker: int, data: bytes, size: int = 14) -> None:
        buf = (ctypes.c_ubyte * len(data)).from_buffer_copy(data)
        self._images.append(buf)
        self.send(M.RGBAImageSetWidth, size)
        self.send(M.RGBAImageSetHeight, size)
        self.send(M.RGBAImageSetScale, 100)
        self.send(M.MarkerDefineRGBAImage, marker, ctypes.addressof(buf))

    def _register_rgba(self, kind: int, data: bytes, size: int = 14) -> None:
        buf = (ctypes.c_ubyte * len(data)).from_buffer_copy(data)
        self._images.append(buf)
        self.send(M.RGBAImageSetWidth, size)
        self.send(M.RGBAImageSetHeight, size)
        self.send(M.RegisterRGBAImage, kind, ctypes.addressof(buf))

    def apply_prefs(self, prefs: EditorPrefs) -> None:
        """Font, tabs, theme and the other preferences."""
        self.prefs = prefs
        theme = hl.THEMES.get(prefs.theme, hl.LIGHT)
        family = prefs.font_family or default_font_family()
        size = max(6, min(int(prefs.font_size), 48))
        c = hl.colour
        self.styleResetDefault()
        self.styleSetFont(hl.STYLE_DEFAULT, family)
        self.styleSetSize(hl.STYLE_DEFAULT, size)
        self.styleSetFore(hl.STYLE_DEFAULT, c(theme.text))
        self.styleSetBack(hl.STYLE_DEFAULT, c(theme.paper))
        self.styleClearAll()
        for style, (fore, bold, italic) in theme.styles.items():
            self.styleSetFore(style, c(fore))
            self.styleSetBold(style, bold)
            self.styleSetItalic(style, italic)
        self.styleSetFore(hl.STYLE_LINENUMBER, c(theme.margin_fore))
        self.styleSetBack(hl.STYLE_LINENUMBER, c(theme.margin_back))
        self.styleSetSize(hl.STYLE_LINENUMBER, max(6, size - 1))
        self.styleSetBack(hl.STYLE_BRACELIGHT, c(theme.brace_back))
        self.styleSetFore(hl.STYLE_BRACELIGHT, c(theme.brace_fore))
        self.styleSetBold(hl.STYLE_BRACELIGHT, True)
        self.styleSetFore(hl.STYLE_BRACEBAD, c(theme.brace_bad))
        self.styleSetBold(hl.STYLE_BRACEBAD, True)
        self.styleSetFore(hl.STYLE_INDENTGUIDE, c(theme.indent_guide))
        self.styleSetBack(hl.STYLE_CALLTIP, c(theme.calltip_back))
        self.styleSetFore(hl.STYLE_CALLTIP, c(theme.calltip_fore))
        self.styleSetFont(hl.STYLE_CALLTIP, family)
        self.styleSetSize(hl.STYLE_CALLTIP, max(6, size - 1))
        self.callTipUseStyle(0)
        self.callTipSetBack(c(theme.calltip_back))
        self.callTipSetFore(c(theme.calltip_fore))
        self.setMarginBackN(MARGIN_SYMBOLS, c(theme.margin_back))
        self.setMarginBackN(MARGIN_FOLD, c(theme.margin_back))
        self.setFoldMarginColour(True, c(theme.margin_back))
        self.setFoldMarginHiColour(True, c(theme.margin_back))
        for num in range(25, 32):
            self.markerSetFore(num, c(theme.fold_back))
            self.markerSetBack(num, c(theme.fold_back))
        self.markerSetBack(MK_CURRENT, c(theme.find))
        self.markerSetAlpha(MK_CURRENT, 60)
        self.setCaretFore(c(theme.caret))
        self.setCaretLineVisible(True)
        self.setCaretLineVisibleAlways(True)
        self.setCaretLineBack(c(theme.caret_line))
        self.setSelBack(True, c(theme.selection))
        self.setSelectionLayer(1)                          # under the text
        self.setElementColour(10, c(theme.selection) | 0xFF000000)    # SC_ELEMENT_SELECTION_BACK
        self.setElementColour(17, c(theme.selection) | 0x80000000)    # inactive selection
        self.indicSetFore(IND_ERROR, c(theme.error))
        self.indicSetFore(IND_WARNING, c(theme.warning))
        self.indicSetFore(IND_FIND, c(theme.find))
        self.indicSetAlpha(IND_FIND, 110)
        self.indicSetOutlineAlpha(IND_FIND, 200)
        self.indicSetFore(IND_OCCURRENCE, c(theme.occurrence))
        self.indicSetAlpha(IND_OCCURRENCE, 90)
        self.indicSetOutlineAlpha(IND_OCCURRENCE, 0)
        self.setWhitespaceFore(True, c(theme.margin_fore))
        self.setViewWS(1 if prefs.show_whitespace else 0)
        self.setIndentationGuides(3 if prefs.indent_guides else 0)   # SC_IV_LOOKBOTH
        self.setTabWidth(max(1, min(int(prefs.tab_width), 16)))
        self.setIndent(0)                                  # = tab width
        self.setExtraAscent(1)
        self.setExtraDescent(1)
        self._line_digits = 0
        self._update_line_margin()
        self.highlighter.restyle()

    def _update_line_margin(self) -> None:
        digits = max(3, len(str(self.lineCount())))
        if digits != self._line_digits:
            self._line_digits = digits
            width = self.textWidth(hl.STYLE_LINENUMBER, "9" * (digits + 1))
            self.setMarginWidthN(MARGIN_NUMBERS, width + 4)

    # ============================================================ editing
    def indent_unit(self) -> int:
        return self.tabWidth()

    def toggle_comment(self) -> None:
        """Comment or uncomment the selected lines (or the caret's line) with //."""
        if self.readOnly():
            return
        start_line = self.lineFromPosition(self.selectionStart())
        end_pos = self.selectionEnd()
        end_line = self.lineFromPosition(end_pos)
        if end_line > start_line and end_pos == self.positionFromLine(end_line):
            end_line -= 1                      # a selection ending at a line start
        lines = list(range(start_line, end_line + 1))
        texts = {ln: self.line_text(ln) for ln in lines}
        code = [ln for ln in lines if texts[ln].strip()]
        if not code:
            return
        commented = all(texts[ln].lstrip().startswith(COMMENT_PREFIX) for ln in code)
        self.beginUndoAction()
        try:
            if commented:
                for ln in code:
                    t = texts[ln]
                    i = len(t) - len(t.lstrip())
                    n = len(COMMENT_PREFIX) + (1 if t[i + len(COMMENT_PREFIX):].startswith(" ") else 0)
                    start = self.positionFromLine(ln) + char_to_byte(t, i)
                    self.deleteRange(start, utf8_len(t[i:i + n]))
            else:
                col = min(len(texts[ln]) - len(texts[ln].lstrip()) for ln in code)
                for ln in code:
                    start = self.positionFromLine(ln) + char_to_byte(texts[ln], col)
                    self.insertText(start, COMMENT_PREFIX + " ")
        finally:
            self.endUndoAction()

    def goto_line(self, line: int, col: int = 1, *, select_word: bool = False) -> None:
        """Move the caret to 1-based (line, col), unfold it, and scroll it into
        the middle of the view when it was off screen."""
        line = max(1, min(line, self.lineCount()))
        pos = self.position_of(line, col)
        self.ensureVisible(line - 1)
        first = self.firstVisibleLine()
        visible = self.visibleFromDocLine(line - 1)
        on_screen = self.linesOnScreen()
        if not first <= visible < first + max(on_screen - 1, 1):
            self.setFirstVisibleLine(max(0, visible - on_screen // 3))
        self.gotoPos(pos)
        if select_word:
            s, e, w = self.word_at(pos)
            if w:
                self.setSel(s, e)
        self.markerDeleteAll(MK_CURRENT)
        self.markerAdd(line - 1, MK_CURRENT)
        QTimer.singleShot(900, self, self._clear_current_marker)

    def _clear_current_marker(self) -> None:
        self.markerDeleteAll(MK_CURRENT)

    # ------------------------------------------------------------ search
    @staticmethod
    def search_flags(case: bool = False, whole: bool = False, regex: bool = False) -> int:
        f = 0
        if case:
            f |= FIND_MATCHCASE
        if whole:
            f |= FIND_WHOLEWORD
        if regex:
            f |= FIND_REGEXP | FIND_CXX11REGEX
        return f

    def find(self, text: str, flags: int = 0, *, forward: bool = True, wrap: bool = True,
             from_pos: Optional[int] = None) -> bool:
        """Select the next (or previous) match of text; False when there is none."""
        if not text:
            return False
        n = utf8_len(text)
        length = self.length()
        if forward:
            start = self.selectionEnd() if from_pos is None else from_pos
            ranges = [(start, length)] + ([(0, start)] if wrap else [])
        else:
            start = self.selectionStart() if from_pos is None else from_pos
            ranges = [(start, 0)] + ([(length, start)] if wrap else [])
        self.setSearchFlags(flags)
        for a, b in ranges:
            self.setTargetRange(a, b)
            found = self.searchInTarget(n, text)
            if found >= 0:
                s, e = self.targetStart(), self.targetEnd()
                self.ensureVisible(self.lineFromPosition(s))
                self.setSel(s, e)
                self.scrollRange(e, s)
                return True
        return False

    def _matches_selection(self, text: str, flags: int) -> bool:
        s, e = self.selectionStart(), self.selectionEnd()
        if s == e:
            return False
        self.setSearchFlags(flags)
        self.setTargetRange(s, e)
        return self.searchInTarget(utf8_len(text), text) == s and self.targetEnd() == e

    def replace(self, text: str, replacement: str, flags: int = 0) -> bool:
        """Replace the selected match (if the selection is one) and find the next."""
        if self.readOnly() or not text:
            return False
        if self._matches_selection(text, flags):
            if flags & FIND_REGEXP:
                self.replaceTargetRE(utf8_len(replacement), replacement)
            else:
                self.replaceTarget(utf8_len(replacement), replacement)
            self.setSel(self.targetEnd(), self.targetEnd())
        return self.find(text, flags)

    def replace_all(self, text: str, replacement: str, flags: int = 0) -> int:
        """Replace every match; returns how many (one undo step)."""
        if self.readOnly() or not text:
            return 0
        count = 0
        pos = 0
        n = utf8_len(text)
        rn = utf8_len(replacement)
        self.setSearchFlags(flags)
        self.beginUndoAction()
        try:
            while True:
                self.setTargetRange(pos, self.length())
                if self.searchInTarget(n, text) < 0:
                    break
                start, end = self.targetStart(), self.targetEnd()
                if flags & FIND_REGEXP:
                    self.replaceTargetRE(rn, replacement)
                else:
                    self.replaceTarget(rn, replacement)
                count += 1
                pos = self.targetEnd()
                if end == start:           # an empty regex match: step on
                    pos += 1
                if pos > self.length():
                    break
        finally:
            self.endUndoAction()
        return count

    def highlight_matches(self, text: str, flags: int = 0, limit: int = 5000) -> int:
        """Mark every match with the find indicator; returns the count."""
        self.clear_indicator(IND_FIND)
        if not text:
            return 0
        count = 0
        pos = 0
        n = utf8_len(text)
        self.setSearchFlags(flags)
        self.setIndicatorCurrent(IND_FIND)
        while count < limit:
            self.setTargetRange(pos, self.length())
            if self.searchInTarget(n, text) < 0:
                break
            s, e = self.targetStart(), self.targetEnd()
            if e > s:
                self.indicatorFillRange(s, e - s)
            count += 1
            pos = max(e, s + 1)
        return count

    def clear_indicator(self, indicator: int) -> None:
        self.setIndicatorCurrent(indicator)
        self.indicatorClearRange(0, self.length())

    # ======================================================== diagnostics
    def set_diagnostics(self, diagnostics: Iterable[Diagnostic]) -> None:
        """Show these diagnostics (already filtered to this file): squiggles,
        margin markers, and hover text."""
        self.clear_indicator(IND_ERROR)
        self.clear_indicator(IND_WARNING)
        self.markerDeleteAll(MK_ERROR)
        self.markerDeleteAll(MK_WARNING)
        ranges = []
        marked: dict[int, int] = {}
        for d in diagnostics:
            s = d.span
            if s is None:
                continue
            start, end = self.diagnostic_range(d)
            ranges.append((start, end, d))
            ind = IND_ERROR if d.severity == Severity.ERROR else IND_WARNING
            self.setIndicatorCurrent(ind)
            if end > start:
                self.indicatorFillRange(start, end - start)
            line0 = self.lineFromPosition(start)
            mk = MK_ERROR if d.severity == Severity.ERROR else MK_WARNING
            if line0 not in marked or (marked[line0] == MK_WARNING and mk == MK_ERROR):
                if line0 in marked:
                    self.markerDelete(line0, marked[line0])
                self.markerAdd(line0, mk)
                marked[line0] = mk
        self._diag_ranges = ranges

    def diagnostic_range(self, d: Diagnostic) -> tuple[int, int]:
        """The byte range a diagnostic's span covers in this document (at least
        one character, so that a point at a line's end still shows)."""
        s = d.span
        start = self.position_of(s.line, s.col)
        end = self.position_of(s.end_line, s.end_col) if (s.end_line, s.end_col) > (s.line, s.col) \
            else start
        if end <= start:
            line_end = self.lineEndPosition(self.lineFromPosition(start))
            if start < line_end:
                end = self.positionAfter(start)
            elif start > self.positionFromLine(self.lineFromPosition(start)):
                start = self.positionBefore(start)      # at a line end: the char before
                end = line_end
            else:
                end = start
        return start, end

    def diagnostics_at(self, pos: int) -> list[Diagnostic]:
        out = []
        for s, e, d in self._diag_ranges:
            if s <= pos < e or (s == e == pos):
                out.append(d)
        if not out:
            line0 = self.lineFromPosition(pos)
            for s, e, d in self._diag_ranges:
                if self.lineFromPosition(s) == line0 and s <= pos <= e:
                    out.append(d)
        return out

    def diagnostic_lines(self) -> dict[int, int]:
        """{1-based line: marker} of the diagnostics shown (for tests)."""
        out = {}
        line = self.markerNext(0, (1 << MK_ERROR) | (1 << MK_WARNING))
        while line >= 0:
            bits = self.markerGet(line)
            out[line + 1] = MK_ERROR if bits & (1 << MK_ERROR) else MK_WARNING
            line = self.markerNext(line + 1, (1 << MK_ERROR) | (1 << MK_WARNING))
        return out

    def indicator_ranges(self, indicator: int) -> list[tuple[int, int]]:
        """Every (start, end) byte range where indicator is set."""
        out = []
        pos = 0
        length = self.length()
        while pos < length:
            if self.indicatorValueAt(indicator, pos):
                end = self.indicatorEnd(indicator, pos)
                out.append((pos, end))
                pos = max(end, pos + 1)
            else:
                nxt = self.indicatorEnd(indicator, pos)
                if nxt <= pos:
                    break
                pos = nxt
        return out

    # =============================================================== hover
    def hover_text_at(self, pos: int) -> Optional[str]:
        """What hovering over pos shows: the diagnostics there, then help."""
        parts = []
        for d in self.diagnostics_at(pos):
            label = "error" if d.severity == Severity.ERROR else d.severity.label
            parts.append(f"{label}: {d.message}")
            parts.extend(f"  hint: {h}" for h in d.hints)
        if self.hover_provider is not None and self.prefs.hover:
            try:
                extra = self.hover_provider(self, pos)
            except Exception:  # noqa: BLE001 - hover help must never break the editor
                extra = None
            if extra:
                if parts:
                    parts.append("")
                parts.append(extra)
        return "\n".join(parts) if parts else None

    def _on_dwell_start(self, x: int, y: int) -> None:
        if self.autoCActive():
            return
        pos = self.charPositionFromPointClose(x, y)
        if pos < 0:
            return
        text = self.hover_text_at(pos)
        if text:
            self.callTipShow(pos, text)

    # ========================================================== completion
    def show_completions(self, explicit: bool = True) -> bool:
        """Open the completion list for the word before the caret."""
        if self.completion_provider is None:
            return False
        prefix = self.word_before_caret()
        if not explicit and len(prefix) < self.prefs.autocomplete_threshold:
            return False
        items = self.completion_provider(self, prefix)
        low = prefix.lower()
        items = [(n, k) for n, k in items if n.lower().startswith(low)]
        if not explicit and (not items or (len(items) == 1 and items[0][0] == prefix)):
            return False
        if not items:
            return False
        seen = set()
        entries = []
        for name, kind in items:
            if name not in seen:
                seen.add(name)
                entries.append(f"{name}?{kind}" if kind else name)
        self.autoCShow(utf8_len(prefix), " ".join(entries))
        return True

    def _in_comment_or_directive(self, pos: int) -> bool:
        self.highlighter.style_to(pos)
        st = self.styleAt(max(pos - 1, 0))
        return st in (hl.S_COMMENT, hl.S_PREPROC_FILE)

    def _on_char_added(self, ch: int) -> None:
        if ch == 10:
            self._auto_indent()
        elif ch == ord("}"):
            self._dedent_brace()
        elif ch == ord("("):
            self._show_signature()
        elif ch == ord(")"):
            if self.callTipActive():
                self.callTipCancel()
        elif (chr(ch).isalnum() or ch == ord("_")) and ch < 128:
            if self.prefs.autocomplete and not self.autoCActive() \
                    and not self._in_comment_or_directive(self.currentPos()):
                self.show_completions(explicit=False)

    def _show_signature(self) -> None:
        if self.signature_provider is None:
            return
        pos = self.currentPos() - 1
        p = pos
        while p > 0 and self.byte_at(p - 1) in (32, 9):
            p -= 1
        start = self.wordStartPosition(p, True)
        name = self.byte_range_text(start, p)
        if not name:
            return
        tip = self.signature_provider(name)
        if tip:
            self.callTipShow(pos, tip)

    def _auto_indent(self) -> None:
        line0 = self.lineFromPosition(self.currentPos())
        if line0 == 0:
            return
        prev = line0 - 1
        prev_text = self.line_text(prev)
        indent = self.lineIndentation(prev)
        code = prev_text.split("//")[0].rstrip()
        opens = code.endswith("{")
        if opens:
            indent += self.indent_unit()
        rest = self.line_text(line0)
        self.beginUndoAction()
        try:
            self.setLineIndentation(line0, indent)
            caret = self.lineIndentPosition(line0)
            if opens and rest.strip().startswith("}"):
                # Enter between { and }: the } goes one line further down
                self.insertText(caret, "\n")
                self.setLineIndentation(line0 + 1, indent - self.indent_unit())
            self.gotoPos(self.lineIndentPosition(line0))
        finally:
            self.endUndoAction()

    def _dedent_brace(self) -> None:
        pos = self.currentPos() - 1
        line0 = self.lineFromPosition(pos)
        before = self.byte_range_text(self.positionFromLine(line0), pos)
        if before.strip():
            return
        self.highlighter.style_to(self.lineEndPosition(line0))
        match = self.braceMatch(pos, 0)
        if match < 0:
            indent = max(0, self.lineIndentation(line0) - self.indent_unit())
        else:
            indent = self.lineIndentation(self.lineFromPosition(match))
        self.setLineIndentation(line0, indent)
        self.gotoPos(self.lineIndentPosition(line0) + 1)

    # ================================================================= ui
    def _on_update_ui(self, updated: int) -> None:
        if updated & (SC_UPDATE_SELECTION | SC_UPDATE_CONTENT):
            self._match_braces()
            line, col = self.cursor_line_col()
            self.sig_cursor_moved.emit(line, col)
            self._occurrence_timer.start()

    def _match_braces(self) -> None:
        pos = self.currentPos()
        brace = -1
        if pos > 0 and self.byte_at(pos - 1) in _BRACE_BYTES:
            brace = pos - 1
        elif pos < self.length() and self.byte_at(pos) in _BRACE_BYTES:
            brace = pos
        if brace < 0 or self.styleAt(brace) in (hl.S_COMMENT,):
            self.braceHighlight(-1, -1)
            return
        match = self.braceMatch(brace, 0)
        if match >= 0:
            self.braceHighlight(brace, match)
        else:
            self.braceBadLight(brace)

    def _mark_occurrences(self) -> None:
        self.clear_indicator(IND_OCCURRENCE)
        if self.selectionStart() != self.selectionEnd():
            return
        s, e, word = self.word_at(self.currentPos())
        if not WORD_RE.fullmatch(word) or len(word) < 2:
            return
        if self.styleAt(s) in (hl.S_COMMENT, hl.S_KEYWORD):
            return
        text = self.text()
        if len(text) > 200_000:
            return
        self.setIndicatorCurrent(IND_OCCURRENCE)
        hits = 0
        for m in re.finditer(r"(?<![A-Za-z0-9_])" + re.escape(word) + r"(?![A-Za-z0-9_])", text):
            bs = char_to_byte(text, m.start())
            if self.styleAt(bs) == hl.S_COMMENT:
                continue
            self.indicatorFillRange(bs, utf8_len(word))
            hits += 1
        if hits < 2:
            self.clear_indicator(IND_OCCURRENCE)

    def _on_modified(self, mtype: int, position: int, length: int, lines_added: int, *_rest) -> None:
        if mtype & (SC_MOD_INSERTTEXT | SC_MOD_DELETETEXT):
            if lines_added:
                self._update_line_margin()
            self.sig_text_changed.emit()

    # ========================================================= mouse/menu
    def set_context_actions(self, actions: list) -> None:
        """Extra actions for the right-click menu (None is a separator)."""
        self._context_actions = list(actions)

    def contextMenuEvent(self, event) -> None:  # noqa: N802 - Qt override
        menu = QMenu(self)
        ro = self.readOnly()
        has_sel = self.selectionStart() != self.selectionEnd()
        for text, slot, enabled in (
                ("Undo", self.undo, self.canUndo() and not ro),
                ("Redo", self.redo, self.canRedo() and not ro),
                (None, None, None),
                ("Cut", self.cut, has_sel and not ro),
                ("Copy", self.copy, has_sel),
                ("Paste", self.paste, self.canPaste() and not ro),
                (None, None, None),
                ("Select All", self.selectAll, True)):
            if text is None:
                menu.addSeparator()
                continue
            act = menu.addAction(text)
            act.setEnabled(bool(enabled))
            act.triggered.connect(slot)
        if self._context_actions:
            menu.addSeparator()
            for act in self._context_actions:
                if act is None:
                    menu.addSeparator()
                else:
                    menu.addAction(act)
        menu.exec(event.globalPos())

    def mousePressEvent(self, event) -> None:  # noqa: N802 - Qt override
        super().mousePressEvent(event)
        if event.button() == Qt.MouseButton.LeftButton and \
                event.modifiers() & Qt.KeyboardModifier.ControlModifier:
            pos = self.charPositionFromPointClose(int(event.position().x()),
                                                  int(event.position().y()))
            if pos >= 0:
                _s, _e, word = self.word_at(pos)
                if WORD_RE.fullmatch(word):
                    self.sig_goto_definition.emit(word)

    def take_focus(self) -> None:
        """Give the editor keyboard focus (ScintillaEdit.setFocus is SCI_SETFOCUS)."""
        QWidget.setFocus(self)

    def word_under_caret(self) -> str:
        _s, _e, word = self.word_at(self.currentPos())
        return word if WORD_RE.fullmatch(word) else ""


def normalise_newlines(text: str) -> tuple[str, str]:
    """(text with \\n line ends, the line end the file used: '\\n' or '\\r\\n')."""
    eol = "\r\n" if "\r\n" in text else "\n"
    if "\r" in text:
        text = text.replace("\r\n", "\n").replace("\r", "\n")
    return text, eol


def same_file(a: str, b: str) -> bool:
    return file_key(a) == file_key(b)


def file_key(path) -> str:
    """A comparable form of a path (absolute, normalised, case-folded where the
    file system is)."""
    s = str(path)
    if s.startswith("<"):
        return s
    return os.path.normcase(os.path.abspath(s))
