"""The source editor: a :class:`ScintillaEdit` set up for PLC procedures.

Highlighting and folding (:mod:`plcbuilder.ide.highlighter`), line numbers,
brace matching, go to line, occurrences of the word under the caret and the
context menu live here; find/replace (:mod:`.search`), diagnostics and hover
(:mod:`.diagnostics`) and typing help (:mod:`.keys`) are mixed in.

Positions: Scintilla counts UTF-8 bytes, Python and the diagnostics count
characters. Every conversion goes through :mod:`plcbuilder.ide.offsets`
(:meth:`CodeEditor.position_of` / :meth:`CodeEditor.line_col_of`).
"""

from __future__ import annotations

import ctypes
import re
from typing import Callable, Optional

from PySide6.QtCore import Qt, QTimer, Signal
from PySide6.QtGui import QAction
from PySide6.QtWidgets import QFrame, QMenu, QWidget
from pyside6_scintilla import Scintilla, ScintillaEdit

from plcbuilder.api import Diagnostic
from plcbuilder.ide import highlighter as hl
from plcbuilder.ide.offsets import byte_to_char, char_to_byte, utf8_len
from plcbuilder.ide.editor.diagnostics import DiagnosticsMixin
from plcbuilder.ide.editor.keys import KeysMixin
from plcbuilder.ide.editor.search import SearchMixin
from plcbuilder.ide.editor.style import (BRACE_BYTES, EL_SELECTION_ADDITIONAL_BACK, EL_SELECTION_BACK,
                                         EL_SELECTION_INACTIVE_BACK, EL_SELECTION_SECONDARY_BACK,
                                         SELECTION_TEXT_ELEMENTS, IND_ERROR, IND_FIND, IND_OCCURRENCE,
                                         IND_WARNING, KIND_LOOK, MARGIN_FOLD, MARGIN_NUMBERS,
                                         MARGIN_SYMBOLS, MK_BACKGROUNDS, MK_CURRENT,
                                         MK_DEBUG_MASK, MK_ERROR, MK_WARNING,
                                         SC_MASK_FOLDERS, SC_MOD_DELETETEXT, SC_MOD_INSERTTEXT,
                                         SC_UPDATE_CONTENT, SC_UPDATE_SELECTION, WORD_RE,
                                         EditorPrefs, M, default_font_family, marker_image,
                                         rgba_image)


class CodeEditor(SearchMixin, DiagnosticsMixin, KeysMixin, ScintillaEdit):
    """One editor of a PLC source (or header) file."""

    sig_cursor_moved = Signal(int, int)
    """The caret moved: (line, column), 1-based, the column counting characters."""

    sig_text_changed = Signal()
    """The text changed (typing, undo, replace, reload)."""

    sig_modified_changed = Signal(bool)
    """The document left (True) or returned to (False) its saved state."""

    sig_goto_definition = Signal(str)
    """Go to the definition of this name (F12 / Ctrl+click)."""

    sig_margin_clicked = Signal(int, int)
    """A click in the symbol margin (the breakpoint margin): the 1-based line
    and the keyboard modifiers (Qt flags as an int)."""

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
        #: (editor, 1-based line) -> the menu of a right-click in the symbol margin, or None
        self.margin_menu_provider: Optional[Callable[["CodeEditor", int], Optional[QMenu]]] = None
        self._occurrence_timer = QTimer(self)
        self._occurrence_timer.setSingleShot(True)
        self._occurrence_timer.setInterval(250)
        self._occurrence_timer.timeout.connect(self._mark_occurrences)
        self._line_digits = 0
        self._setup()
        self.apply_prefs(self.prefs)
        self.marginClicked.connect(self._on_margin_clicked)
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
        self.setMarginMaskN(MARGIN_SYMBOLS, (1 << MK_ERROR) | (1 << MK_WARNING) | (1 << MK_CURRENT)
                            | (MK_DEBUG_MASK & ~MK_BACKGROUNDS))
        self.setMarginWidthN(MARGIN_SYMBOLS, 18)
        self.setMarginSensitiveN(MARGIN_SYMBOLS, True)         # a click toggles a breakpoint
        self.setMarginCursorN(MARGIN_SYMBOLS, 2)               # SC_CURSORARROW
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
        self.define_rgba_marker(MK_ERROR, marker_image("error"))
        self.define_rgba_marker(MK_WARNING, marker_image("warning"))
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
        for kind, (letter, col) in KIND_LOOK.items():
            self._register_rgba(kind, rgba_image(letter, col))
        # keys: Alt+Up/Down move lines, Ctrl+Shift+K deletes a line (as in VS Code)
        alt, ctrl, shift = 4, 2, 1
        keys = Scintilla.Keys
        self.assignCmdKey(int(keys.Up) | (alt << 16), int(M.MoveSelectedLinesUp))
        self.assignCmdKey(int(keys.Down) | (alt << 16), int(M.MoveSelectedLinesDown))
        self.assignCmdKey(ord("K") | ((ctrl | shift) << 16), int(M.LineDelete))
        self.clearCmdKey(ord("/") | (ctrl << 16))      # Ctrl+/ is the window's comment toggle

    def define_rgba_marker(self, marker: int, data: bytes, size: int = 14) -> None:
        """Marker ``marker`` drawn as an RGBA image of size × size pixels."""
        self._send_rgba(M.MarkerDefineRGBAImage, marker, data, size, scale=True)

    def _register_rgba(self, kind: int, data: bytes, size: int = 14) -> None:
        self._send_rgba(M.RegisterRGBAImage, kind, data, size, scale=False)

    def _send_rgba(self, message, n: int, data: bytes, size: int, scale: bool) -> None:
        buf = (ctypes.c_ubyte * len(data)).from_buffer_copy(data)
        self._images.append(buf)
        self.send(M.RGBAImageSetWidth, size)
        self.send(M.RGBAImageSetHeight, size)
        if scale:
            self.send(M.RGBAImageSetScale, 100)
        self.send(message, n, ctypes.addressof(buf))

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
        self.setSelectionLayer(1)                          # under the text
        for element in SELECTION_TEXT_ELEMENTS:            # text keeps its own colours
            self.resetElementColour(element)
        opaque = c(theme.selection) | 0xFF000000
        for element in (EL_SELECTION_BACK, EL_SELECTION_ADDITIONAL_BACK, EL_SELECTION_SECONDARY_BACK):
            self.setElementColour(element, opaque)
        self.setElementColour(EL_SELECTION_INACTIVE_BACK, c(theme.selection) | 0x80000000)
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
        marks = getattr(self, "debug_marks", None)      # the debugger's, while halted too
        if marks is not None:
            marks.restyle()

    def _update_line_margin(self) -> None:
        digits = max(3, len(str(self.lineCount())))
        if digits != self._line_digits:
            self._line_digits = digits
            width = self.textWidth(hl.STYLE_LINENUMBER, "9" * (digits + 1))
            self.setMarginWidthN(MARGIN_NUMBERS, width + 4)


    def scroll_to_line(self, line: int) -> None:
        """Bring 1-based ``line`` into view (unfolded, and in the middle of the
        view when it was off screen) without moving the caret."""
        self.ensureVisible(line - 1)
        first = self.firstVisibleLine()
        visible = self.visibleFromDocLine(line - 1)
        on_screen = self.linesOnScreen()
        if not first <= visible < first + max(on_screen - 1, 1):
            self.setFirstVisibleLine(max(0, visible - on_screen // 3))

    def goto_line(self, line: int, col: int = 1, *, select_word: bool = False) -> None:
        """Move the caret to 1-based (line, col), unfold it, and scroll it into
        the middle of the view when it was off screen."""
        line = max(1, min(line, self.lineCount()))
        pos = self.position_of(line, col)
        self.scroll_to_line(line)
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
        if pos > 0 and self.byte_at(pos - 1) in BRACE_BYTES:
            brace = pos - 1
        elif pos < self.length() and self.byte_at(pos) in BRACE_BYTES:
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

    def margin_line_at(self, x: int, y: int) -> Optional[int]:
        """The 1-based line beside point (x, y) when it is in the margins, else None."""
        width = sum(self.marginWidthN(m) for m in range(MARGIN_FOLD + 1))
        if x < 0 or x >= width:
            return None
        pos = self.positionFromPoint(width + 1, y)
        return self.lineFromPosition(pos) + 1 if pos >= 0 else None

    def _on_margin_clicked(self, position: int, modifiers: int, margin: int) -> None:
        if margin == MARGIN_SYMBOLS:
            self.sig_margin_clicked.emit(self.lineFromPosition(position) + 1, int(modifiers))

    def contextMenuEvent(self, event) -> None:  # noqa: N802 - Qt override
        if self.margin_menu_provider is not None:
            line = self.margin_line_at(event.pos().x(), event.pos().y())
            if line is not None:
                margin_menu = self.margin_menu_provider(self, line)
                if margin_menu is not None:
                    margin_menu.exec(event.globalPos())
                    return
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

