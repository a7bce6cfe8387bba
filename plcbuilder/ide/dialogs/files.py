"""Dialogs about the project's files: a new procedure's or header's name, go to line."""

from __future__ import annotations

import re
from typing import Iterable, Optional

from PySide6.QtCore import Qt
from PySide6.QtGui import QPalette
from PySide6.QtWidgets import (QComboBox, QDialog, QDialogButtonBox, QFormLayout, QLabel,
                               QLineEdit, QVBoxLayout)

from plcbuilder.api import Kind
from plcbuilder.ide.icons import icon
from plcbuilder.ide.dialogs.common import error_label, fit_height, ok_cancel

NAME_RE = re.compile(r"[A-Za-z0-9_\-]{1,64}")
HEADER_RE = re.compile(r"[A-Za-z0-9_\-.]{1,64}\.h")


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
        self.hint.setTextFormat(Qt.TextFormat.PlainText)
        self.hint.setForegroundRole(QPalette.ColorRole.PlaceholderText)   # dim in both themes
        lay.addWidget(self.hint)
        self.error = error_label(self)
        lay.addWidget(self.error)
        self.buttons = ok_cancel(self, lay)
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
        fit_height(self)


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
        self.error = error_label(self)
        lay.addWidget(self.error)
        self.buttons = ok_cancel(self, lay)
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
        self.error = error_label(self)
        lay.addWidget(self.error)
        self.buttons = ok_cancel(self, lay)
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
