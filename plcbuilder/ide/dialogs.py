"""The IDE's dialogs: go to line, the find/replace bar, the start-procedure
picker (by name or M-code number, with eparam), procedure and header names,
connect to a controller, and preferences.

Each modal dialog has a ``get_…`` class method that runs it and returns the
result, or None when cancelled; tests drive the widgets and call
``accept()`` through a patched ``exec``.
"""

from __future__ import annotations

import re
from typing import Iterable, Optional

from PySide6.QtCore import Qt, Signal
from PySide6.QtGui import QFontDatabase, QKeySequence, QShortcut
from PySide6.QtWidgets import (QCheckBox, QComboBox, QDialog, QDialogButtonBox, QFontComboBox,
                               QFormLayout, QHBoxLayout, QLabel, QLineEdit,
                               QListWidget, QListWidgetItem, QPushButton, QRadioButton,
                               QSpinBox, QTabWidget, QToolButton, QVBoxLayout, QWidget)

from plcbuilder.api import Kind
from plcbuilder.ide.icons import icon
from plcbuilder.ide.settings import Preferences

NAME_RE = re.compile(r"[A-Za-z0-9_\-]{1,64}")
HEADER_RE = re.compile(r"[A-Za-z0-9_\-.]{1,64}\.h")
INT32_MIN, INT32_MAX = -2 ** 31, 2 ** 31 - 1


def _error_label(parent) -> QLabel:
    lab = QLabel(parent)
    lab.setWordWrap(True)
    lab.setStyleSheet("color: #c62828;")
    return lab


# ------------------------------------------------------------------ names
def check_procedure_name(name: str, existing: Iterable[str]) -> Optional[str]:
    """Why name cannot be a new procedure's name, or None."""
    if not name:
        return "Type a name."
    if not NAME_RE.fullmatch(name):
        return "Use letters, digits, '_' and '-' (at most 64), as in M03 or __HANDLER_INIT."
    if name in set(existing):
        return f"There is a procedure named {name} already (names are unique in a project)."
    return None


class ProcedureNameDialog(QDialog):
    """A procedure's name (and kind) for New / Rename / Duplicate."""

    def __init__(self, parent=None, *, title="New Procedure", kind=Kind.HARDWARE,
                 existing: Iterable[str] = (), initial: str = "", allow_kind=False):
        super().__init__(parent)
        self.setWindowTitle(title)
        self.existing = set(existing)
        lay = QVBoxLayout(self)
        form = QFormLayout()
        self.name_edit = QLineEdit(initial, self)
        self.name_edit.selectAll()
        form.addRow("&Name:", self.name_edit)
        self.kind_combo = QComboBox(self)
        self.kind_combo.addItem(icon("folder-hw"), "Hardware PLC (hardware/)", Kind.HARDWARE)
        self.kind_combo.addItem(icon("folder-sw"), "Software PLC (software/)", Kind.SOFTWARE)
        self.kind_combo.setCurrentIndex(0 if Kind(kind) is Kind.HARDWARE else 1)
        self.kind_combo.setEnabled(allow_kind)
        form.addRow("&Kind:", self.kind_combo)
        lay.addLayout(form)
        self.hint = QLabel(self)
        self.hint.setWordWrap(True)
        self.hint.setStyleSheet("color: palette(mid);")
        lay.addWidget(self.hint)
        self.error = _error_label(self)
        lay.addWidget(self.error)
        self.buttons = QDialogButtonBox(QDialogButtonBox.StandardButton.Ok |
                                        QDialogButtonBox.StandardButton.Cancel, self)
        self.buttons.accepted.connect(self.accept)
        self.buttons.rejected.connect(self.reject)
        lay.addWidget(self.buttons)
        self.name_edit.textChanged.connect(self._validate)
        self.kind_combo.currentIndexChanged.connect(self._validate)
        self.setMinimumWidth(420)
        self._validate()

    def kind(self) -> Kind:
        return Kind(self.kind_combo.currentData())

    def name(self) -> str:
        return self.name_edit.text().strip()

    def _validate(self) -> None:
        problem = check_procedure_name(self.name(), self.existing)
        self.error.setText(problem or "")
        self.buttons.button(QDialogButtonBox.StandardButton.Ok).setEnabled(problem is None)
        n = self.name()
        if self.kind() is Kind.HARDWARE:
            if re.fullmatch(r"M\d+", n):
                self.hint.setText(f"The M-code {n} starts this procedure.")
            else:
                self.hint.setText("Hardware procedures run in 1 ms ticks; one named like an "
                                  "M-code (M03) is what that M-code starts.")
        else:
            if n.startswith("__"):
                self.hint.setText("A system procedure: __HANDLER_INIT, __HANDLER_EXIT, "
                                  "__HANDLER_GCODE_START/STOP start on events, others by hand.")
            else:
                self.hint.setText("Software procedures start with the controller and run "
                                  "side by side in 100 ms ticks.")

    def accept(self) -> None:
        if check_procedure_name(self.name(), self.existing) is None:
            super().accept()

    @classmethod
    def get_name(cls, parent=None, **kw) -> Optional[tuple[str, Kind]]:
        dlg = cls(parent, **kw)
        if dlg.exec() == QDialog.DialogCode.Accepted:
            return dlg.name(), dlg.kind()
        return None


class HeaderNameDialog(QDialog):
    def __init__(self, parent=None, existing: Iterable[str] = (), initial="", title="New Header"):
        super().__init__(parent)
        self.setWindowTitle(title)
        self.existing = set(existing)
        lay = QVBoxLayout(self)
        form = QFormLayout()
        self.name_edit = QLineEdit(initial or "my_defines.h", self)
        self.name_edit.selectAll()
        form.addRow("&File name:", self.name_edit)
        lay.addLayout(form)
        self.error = _error_label(self)
        lay.addWidget(self.error)
        self.buttons = QDialogButtonBox(QDialogButtonBox.StandardButton.Ok |
                                        QDialogButtonBox.StandardButton.Cancel, self)
        self.buttons.accepted.connect(self.accept)
        self.buttons.rejected.connect(self.reject)
        lay.addWidget(self.buttons)
        self.name_edit.textChanged.connect(self._validate)
        self.setMinimumWidth(380)
        self._validate()

    def name(self) -> str:
        n = self.name_edit.text().strip()
        return n if n.endswith(".h") or not n else n + ".h"

    def problem(self) -> Optional[str]:
        n = self.name()
        if not n:
            return "Type a name."
        if not HEADER_RE.fullmatch(n) or n.startswith("."):
            return "Use letters, digits, '_', '-' and '.', ending in .h"
        if n in self.existing:
            return f"{n} exists already."
        return None

    def _validate(self) -> None:
        p = self.problem()
        self.error.setText(p or "")
        self.buttons.button(QDialogButtonBox.StandardButton.Ok).setEnabled(p is None)

    def accept(self) -> None:
        if self.problem() is None:
            super().accept()

    @classmethod
    def get_name(cls, parent=None, existing=(), initial="", title="New Header") -> Optional[str]:
        dlg = cls(parent, existing, initial, title)
        if dlg.exec() == QDialog.DialogCode.Accepted:
            return dlg.name()
        return None


# ------------------------------------------------------------- go to line
class GoToLineDialog(QDialog):
    """Line (and optional column): ``12`` or ``12:5``."""

    def __init__(self, parent=None, current: int = 1, maximum: int = 1):
        super().__init__(parent)
        self.setWindowTitle("Go to Line")
        self.maximum = max(1, maximum)
        lay = QVBoxLayout(self)
        self.label = QLabel(f"Line (1–{self.maximum}), optionally :column", self)
        lay.addWidget(self.label)
        self.edit = QLineEdit(str(current), self)
        self.edit.selectAll()
        lay.addWidget(self.edit)
        self.error = _error_label(self)
        lay.addWidget(self.error)
        self.buttons = QDialogButtonBox(QDialogButtonBox.StandardButton.Ok |
                                        QDialogButtonBox.StandardButton.Cancel, self)
        self.buttons.accepted.connect(self.accept)
        self.buttons.rejected.connect(self.reject)
        lay.addWidget(self.buttons)
        self.edit.textChanged.connect(self._validate)
        self.setMinimumWidth(300)

    def value(self) -> Optional[tuple[int, int]]:
        m = re.fullmatch(r"\s*(\d+)\s*(?:[:,]\s*(\d+)\s*)?", self.edit.text())
        if not m:
            return None
        line = int(m.group(1))
        col = int(m.group(2)) if m.group(2) else 1
        if not 1 <= line <= self.maximum or col < 1:
            return None
        return line, col

    def _validate(self) -> None:
        ok = self.value() is not None
        self.error.setText("" if ok else f"Type a line number from 1 to {self.maximum}.")
        self.buttons.button(QDialogButtonBox.StandardButton.Ok).setEnabled(ok)

    def accept(self) -> None:
        if self.value() is not None:
            super().accept()

    @classmethod
    def get_line(cls, parent=None, current=1, maximum=1) -> Optional[tuple[int, int]]:
        dlg = cls(parent, current, maximum)
        if dlg.exec() == QDialog.DialogCode.Accepted:
            return dlg.value()
        return None


# ------------------------------------------------------------ find/replace
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
        from plcbuilder.ide.editor import CodeEditor
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


# ------------------------------------------------------------ start picker
class StartDialog(QDialog):
    """Start a procedure on the controller: pick it by name or type an M-code
    number, with its eparam."""

    def __init__(self, parent=None, procedures: Iterable[tuple[str, Kind]] = (),
                 initial: str = "", eparam: int = 0):
        super().__init__(parent)
        self.setWindowTitle("Start Procedure")
        self.procedures = list(procedures)
        lay = QVBoxLayout(self)
        self.by_name = QRadioButton("By &name", self)
        self.by_mcode = QRadioButton("By &M-code number", self)
        self.by_name.setChecked(True)
        self.list = QListWidget(self)
        self.list.setMinimumHeight(180)
        for name, kind in self.procedures:
            it = QListWidgetItem(icon("file-plc" if kind is Kind.HARDWARE else "file-plc-sys"), name)
            it.setData(Qt.ItemDataRole.UserRole, name)
            if kind is not Kind.HARDWARE:
                it.setToolTip("software system procedure")
            self.list.addItem(it)
        mrow = QHBoxLayout()
        self.mcode_spin = QSpinBox(self)
        self.mcode_spin.setRange(0, 9999)
        self.mcode_spin.setPrefix("M")
        self.mcode_status = QLabel(self)
        mrow.addWidget(self.by_mcode)
        mrow.addWidget(self.mcode_spin)
        mrow.addWidget(self.mcode_status, 1)
        form = QFormLayout()
        self.eparam_spin = QSpinBox(self)
        self.eparam_spin.setRange(INT32_MIN, INT32_MAX)
        self.eparam_spin.setValue(int(eparam))
        self.eparam_spin.setToolTip("the value of eparam when the procedure starts (the M-code's P)")
        form.addRow("&eparam:", self.eparam_spin)
        lay.addWidget(self.by_name)
        lay.addWidget(self.list, 1)
        lay.addLayout(mrow)
        lay.addLayout(form)
        self.error = _error_label(self)
        lay.addWidget(self.error)
        self.buttons = QDialogButtonBox(self)
        self.start_button = self.buttons.addButton("Start", QDialogButtonBox.ButtonRole.AcceptRole)
        self.start_button.setIcon(icon("start"))
        self.buttons.addButton(QDialogButtonBox.StandardButton.Cancel)
        self.buttons.accepted.connect(self.accept)
        self.buttons.rejected.connect(self.reject)
        lay.addWidget(self.buttons)
        self.list.itemDoubleClicked.connect(lambda _it: self.accept())
        self.list.currentItemChanged.connect(lambda *_: self._pick_name())
        self.mcode_spin.valueChanged.connect(lambda *_: self._pick_mcode())
        self.by_name.toggled.connect(self._validate)
        self.setMinimumWidth(360)
        sel = 0
        for i, (name, _k) in enumerate(self.procedures):
            if name == initial:
                sel = i
        if self.procedures:
            self.list.setCurrentRow(sel)
            m = re.fullmatch(r"M(\d+)", self.procedures[sel][0])
            if m:
                self.mcode_spin.blockSignals(True)
                self.mcode_spin.setValue(int(m.group(1)))
                self.mcode_spin.blockSignals(False)
        self.by_name.setChecked(True)
        self._validate()

    def _pick_name(self) -> None:
        self.by_name.setChecked(True)
        self._validate()

    def _pick_mcode(self) -> None:
        self.by_mcode.setChecked(True)
        self._validate()

    def mcode_name(self) -> Optional[str]:
        """The procedure the M-code number starts (M3 and M03 both start M03.plc)."""
        n = self.mcode_spin.value()
        names = [p for p, k in self.procedures if k is Kind.HARDWARE]
        for cand in (f"M{n:02d}", f"M{n}", f"M{n:03d}"):
            if cand in names:
                return cand
        return None

    def selected(self) -> Optional[str]:
        if self.by_mcode.isChecked():
            return self.mcode_name()
        it = self.list.currentItem()
        return it.data(Qt.ItemDataRole.UserRole) if it is not None else None

    def eparam(self) -> int:
        return self.eparam_spin.value()

    def _validate(self, *_a) -> None:
        name = self.mcode_name()
        self.mcode_status.setText(f"→ {name}.plc" if name else "no such procedure")
        sel = self.selected()
        self.error.setText("" if sel else ("The project has no procedure for this M-code."
                                           if self.by_mcode.isChecked() else "Pick a procedure."))
        self.start_button.setEnabled(sel is not None)

    def accept(self) -> None:
        if self.selected() is not None:
            super().accept()

    @classmethod
    def get_start(cls, parent=None, procedures=(), initial="", eparam=0) -> Optional[tuple[str, int]]:
        dlg = cls(parent, procedures, initial, eparam)
        if dlg.exec() == QDialog.DialogCode.Accepted:
            return dlg.selected(), dlg.eparam()
        return None


# --------------------------------------------------------------- connect
class ConnectDialog(QDialog):
    """Connect to a controller that already runs (``plcbuilder controller``)."""

    def __init__(self, parent=None, host="127.0.0.1", port=5700, token=""):
        super().__init__(parent)
        self.setWindowTitle("Connect to Controller")
        lay = QVBoxLayout(self)
        info = QLabel("Connect to a controller started with <tt>plcbuilder controller</tt>. "
                      "Its address and token are in the runtime file it writes; leave the "
                      "token empty to read it from there.", self)
        info.setWordWrap(True)
        lay.addWidget(info)
        form = QFormLayout()
        self.host_edit = QLineEdit(host, self)
        self.port_spin = QSpinBox(self)
        self.port_spin.setRange(1, 65535)
        self.port_spin.setValue(int(port))
        self.token_edit = QLineEdit(token, self)
        self.token_edit.setEchoMode(QLineEdit.EchoMode.Password)
        form.addRow("&Host:", self.host_edit)
        form.addRow("&Port:", self.port_spin)
        form.addRow("&Token:", self.token_edit)
        lay.addLayout(form)
        self.buttons = QDialogButtonBox(QDialogButtonBox.StandardButton.Ok |
                                        QDialogButtonBox.StandardButton.Cancel, self)
        self.buttons.button(QDialogButtonBox.StandardButton.Ok).setText("Connect")
        self.buttons.accepted.connect(self.accept)
        self.buttons.rejected.connect(self.reject)
        lay.addWidget(self.buttons)
        self.setMinimumWidth(380)

    def value(self) -> tuple[str, int, str]:
        return self.host_edit.text().strip() or "127.0.0.1", self.port_spin.value(), \
            self.token_edit.text().strip()

    @classmethod
    def get_address(cls, parent=None, host="127.0.0.1", port=5700, token=""):
        dlg = cls(parent, host, port, token)
        if dlg.exec() == QDialog.DialogCode.Accepted:
            return dlg.value()
        return None


# ------------------------------------------------------------- preferences
class PreferencesDialog(QDialog):
    def __init__(self, parent=None, prefs: Preferences = Preferences()):
        super().__init__(parent)
        self.setWindowTitle("Preferences")
        self.original = prefs
        lay = QVBoxLayout(self)
        tabs = QTabWidget(self)
        lay.addWidget(tabs)
        # editor
        ed = QWidget()
        f = QFormLayout(ed)
        self.font_combo = QFontComboBox(ed)
        self.font_combo.setFontFilters(QFontComboBox.FontFilter.MonospacedFonts)
        family = prefs.font_family or QFontDatabase.systemFont(
            QFontDatabase.SystemFont.FixedFont).family()
        self.font_combo.setCurrentText(family)
        self.size_spin = QSpinBox(ed)
        self.size_spin.setRange(6, 48)
        self.size_spin.setValue(prefs.font_size)
        self.size_spin.setSuffix(" pt")
        self.tab_spin = QSpinBox(ed)
        self.tab_spin.setRange(1, 16)
        self.tab_spin.setValue(prefs.tab_width)
        self.theme_combo = QComboBox(ed)
        self.theme_combo.addItem("Light", "light")
        self.theme_combo.addItem("Dark", "dark")
        self.theme_combo.setCurrentIndex(max(0, self.theme_combo.findData(prefs.theme)))
        self.ws_box = QCheckBox("Show whitespace", ed)
        self.ws_box.setChecked(prefs.show_whitespace)
        self.guides_box = QCheckBox("Indentation guides", ed)
        self.guides_box.setChecked(prefs.indent_guides)
        self.ac_box = QCheckBox("Complete while typing", ed)
        self.ac_box.setChecked(prefs.autocomplete)
        self.ac_spin = QSpinBox(ed)
        self.ac_spin.setRange(1, 10)
        self.ac_spin.setValue(prefs.autocomplete_threshold)
        self.ac_spin.setSuffix(" characters")
        self.hover_box = QCheckBox("Hover help", ed)
        self.hover_box.setChecked(prefs.hover)
        f.addRow("Font:", self.font_combo)
        f.addRow("Size:", self.size_spin)
        f.addRow("Tab width:", self.tab_spin)
        f.addRow("Theme:", self.theme_combo)
        f.addRow("", self.ws_box)
        f.addRow("", self.guides_box)
        f.addRow("", self.ac_box)
        f.addRow("Complete after:", self.ac_spin)
        f.addRow("", self.hover_box)
        tabs.addTab(ed, "Editor")
        # files and build
        fb = QWidget()
        g = QFormLayout(fb)
        self.autosave_spin = QSpinBox(fb)
        self.autosave_spin.setRange(1, 600)
        self.autosave_spin.setValue(prefs.autosave_seconds)
        self.autosave_spin.setSuffix(" s")
        self.autosave_spin.setToolTip("unsaved changes are copied to a recovery folder this "
                                      "often, and offered back after a crash")
        self.reload_box = QCheckBox("Reload files changed on disk when they have no unsaved changes", fb)
        self.reload_box.setChecked(prefs.reload_unmodified)
        self.save_build_box = QCheckBox("Save all files before Build All", fb)
        self.save_build_box.setChecked(prefs.save_before_build)
        self.build_upload_box = QCheckBox("Build All before Upload", fb)
        self.build_upload_box.setChecked(prefs.build_before_upload)
        self.reopen_box = QCheckBox("Open the last project on start", fb)
        self.reopen_box.setChecked(prefs.open_last_project)
        g.addRow("Recovery autosave every:", self.autosave_spin)
        g.addRow("", self.reload_box)
        g.addRow("", self.save_build_box)
        g.addRow("", self.build_upload_box)
        g.addRow("", self.reopen_box)
        tabs.addTab(fb, "Files && Build")
        self.buttons = QDialogButtonBox(QDialogButtonBox.StandardButton.Ok |
                                        QDialogButtonBox.StandardButton.Cancel, self)
        self.buttons.accepted.connect(self.accept)
        self.buttons.rejected.connect(self.reject)
        lay.addWidget(self.buttons)
        self.setMinimumWidth(460)

    def preferences(self) -> Preferences:
        return self.original.with_changes(
            font_family=self.font_combo.currentFont().family(),
            font_size=self.size_spin.value(), tab_width=self.tab_spin.value(),
            theme=self.theme_combo.currentData(), show_whitespace=self.ws_box.isChecked(),
            indent_guides=self.guides_box.isChecked(), autocomplete=self.ac_box.isChecked(),
            autocomplete_threshold=self.ac_spin.value(), hover=self.hover_box.isChecked(),
            autosave_seconds=self.autosave_spin.value(),
            reload_unmodified=self.reload_box.isChecked(),
            save_before_build=self.save_build_box.isChecked(),
            build_before_upload=self.build_upload_box.isChecked(),
            open_last_project=self.reopen_box.isChecked())

    @classmethod
    def get_preferences(cls, parent=None, prefs: Preferences = Preferences()) -> Optional[Preferences]:
        dlg = cls(parent, prefs)
        if dlg.exec() == QDialog.DialogCode.Accepted:
            return dlg.preferences()
        return None
