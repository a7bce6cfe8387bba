"""The find/replace bar under the editors."""

from __future__ import annotations

from PySide6.QtCore import Qt, Signal
from PySide6.QtGui import QKeySequence, QShortcut
from PySide6.QtWidgets import (QCheckBox, QHBoxLayout, QLabel, QLineEdit, QPushButton, QToolButton,
                               QVBoxLayout, QWidget)



class FindReplaceBar(QWidget):
    """The find/replace bar under the editors (Ctrl+F, Ctrl+H), searching
    with Scintilla's own search (plain, whole word, case, regular expression)."""

    sig_closed = Signal()
    """The bar was closed (Escape or ×); focus goes back to the editor."""

    sig_message = Signal(str)
    """A message for the status bar ("3 matches", "not found")."""

    def __init__(self, parent=None):
        super().__init__(parent)
        self.editor = None
        self.setObjectName("findBar")
        self.setStyleSheet("QWidget#findBar { border-top: 1px solid palette(mid); }")
        outer = QVBoxLayout(self)
        outer.setContentsMargins(6, 4, 6, 4)
        outer.setSpacing(3)
        row1 = QHBoxLayout()
        row1.setSpacing(4)
        self.find_edit = QLineEdit(self)
        self.find_edit.setPlaceholderText("Find")
        self.find_edit.setClearButtonEnabled(True)
        self.case_box = QCheckBox("Aa", self)
        self.case_box.setToolTip("Match case")
        self.word_box = QCheckBox("Word", self)
        self.word_box.setToolTip("Whole words only")
        self.regex_box = QCheckBox(".*", self)
        self.regex_box.setToolTip("Regular expression")
        self.prev_button = QToolButton(self)
        self.prev_button.setText("↑")
        self.prev_button.setToolTip("Find previous (Shift+F3)")
        self.next_button = QToolButton(self)
        self.next_button.setText("↓")
        self.next_button.setToolTip("Find next (F3)")
        self.count_label = QLabel(self)
        self.count_label.setMinimumWidth(90)
        self.close_button = QToolButton(self)
        self.close_button.setText("×")
        self.close_button.setAutoRaise(True)
        self.close_button.setToolTip("Close (Esc)")
        row1.addWidget(QLabel("Find:", self))
        row1.addWidget(self.find_edit, 1)
        for w in (self.case_box, self.word_box, self.regex_box, self.prev_button,
                  self.next_button, self.count_label, self.close_button):
            row1.addWidget(w)
        row2 = QHBoxLayout()
        row2.setSpacing(4)
        self.replace_edit = QLineEdit(self)
        self.replace_edit.setPlaceholderText("Replace")
        self.replace_button = QPushButton("Replace", self)
        self.replace_all_button = QPushButton("Replace All", self)
        self.replace_label = QLabel("Replace:", self)
        row2.addWidget(self.replace_label)
        row2.addWidget(self.replace_edit, 1)
        row2.addWidget(self.replace_button)
        row2.addWidget(self.replace_all_button)
        row2.addSpacing(self.close_button.sizeHint().width() + 94)
        self.replace_row = QWidget(self)
        self.replace_row.setLayout(row2)
        row2.setContentsMargins(0, 0, 0, 0)
        outer.addLayout(row1)
        outer.addWidget(self.replace_row)
        self.find_edit.textChanged.connect(self._incremental)
        self.find_edit.returnPressed.connect(self.find_next)
        self.replace_edit.returnPressed.connect(self.replace_one)
        self.next_button.clicked.connect(self.find_next)
        self.prev_button.clicked.connect(self.find_previous)
        self.replace_button.clicked.connect(self.replace_one)
        self.replace_all_button.clicked.connect(self.replace_all)
        self.close_button.clicked.connect(self.close_bar)
        for box in (self.case_box, self.word_box, self.regex_box):
            box.toggled.connect(self._incremental)
        QShortcut(QKeySequence(Qt.Key.Key_Escape), self, self.close_bar,
                  context=Qt.ShortcutContext.WidgetWithChildrenShortcut)
        self.hide()

    def set_editor(self, editor) -> None:
        if self.editor is not None and self.editor is not editor:
            try:
                self.editor.clear_indicator(10)
            except RuntimeError:
                pass
        self.editor = editor
        if self.isVisible():
            self._update_count()

    def open(self, replace: bool = False) -> None:
        self.replace_row.setVisible(replace)
        self.show()
        if self.editor is not None:
            sel = self.editor.selected_text()
            if sel and "\n" not in sel:
                self.find_edit.setText(sel)
        self.find_edit.setFocus()
        self.find_edit.selectAll()
        self._update_count()

    def close_bar(self) -> None:
        self.hide()
        if self.editor is not None:
            self.editor.clear_indicator(10)
            self.editor.take_focus()
        self.sig_closed.emit()

    def flags(self) -> int:
        from plcbuilder.ide.editor.widget import CodeEditor    # (loaded with the first editor)
        return CodeEditor.search_flags(self.case_box.isChecked(), self.word_box.isChecked(),
                                       self.regex_box.isChecked())

    def find_next(self) -> bool:
        return self._find(True)

    def find_previous(self) -> bool:
        return self._find(False)

    def replace_one(self) -> bool:
        if self.editor is None:
            return False
        found = self.editor.replace(self.find_edit.text(), self.replace_edit.text(), self.flags())
        self._update_count()
        return found

    def replace_all(self) -> int:
        if self.editor is None:
            return 0
        n = self.editor.replace_all(self.find_edit.text(), self.replace_edit.text(), self.flags())
        self.sig_message.emit(f"Replaced {n} occurrence{'s' * (n != 1)}")
        self._update_count()
        return n

    def _find(self, forward: bool) -> bool:
        if self.editor is None:
            return False
        text = self.find_edit.text()
        found = self.editor.find(text, self.flags(), forward=forward)
        self._set_found(found or not text)
        if not found and text:
            self.sig_message.emit(f"'{text}' not found")
        return found

    def _incremental(self, *_a) -> None:
        if self.editor is None:
            return
        text = self.find_edit.text()
        if text:
            start = self.editor.selectionStart()
            found = self.editor.find(text, self.flags(), forward=True, from_pos=start)
            self._set_found(found)
        else:
            self._set_found(True)
        self._update_count()

    def _set_found(self, ok: bool) -> None:
        self.find_edit.setProperty("notFound", not ok)
        self.find_edit.setStyleSheet("" if ok else
                                     "QLineEdit { background: rgba(229, 20, 0, 55); }")

    def _update_count(self) -> None:
        if self.editor is None:
            return
        text = self.find_edit.text()
        n = self.editor.highlight_matches(text, self.flags()) if text else 0
        self.count_label.setText("" if not text else
                                 ("No results" if n == 0 else f"{n} match{'es' * (n != 1)}"))
