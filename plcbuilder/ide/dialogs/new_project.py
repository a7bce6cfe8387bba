"""File › New Project…: the controller the project is for (myCNC, Huazhong,
TG Motion), its name and the folder it goes in, as ``plcbuilder new DIR --name
NAME --target TARGET`` takes them; the project is that target's example
(docs/targets.md)."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Optional

from PySide6.QtCore import Qt
from PySide6.QtWidgets import (QComboBox, QDialog, QDialogButtonBox, QFileDialog, QFormLayout,
                               QHBoxLayout, QLabel, QLineEdit, QPushButton, QVBoxLayout)

from plcbuilder.ide.dialogs.common import error_label, fit_height, ok_cancel

#: (target, what the user reads, what its example holds)
TARGETS = (("mycnc", "myCNC",
            "hardware procedures M02…OFF, software procedures LUBE and __HANDLER_INIT, "
            "include/pins.h and scenario tests"),
           ("huazhong", "Huazhong",
            "one PLC source (hardware/plc.plc: init(), plc1() and plc2() over the X, Y, "
            "F, G and B registers), its parameters and a scenario test"),
           ("tgmotion", "TG Motion",
            "one program (hardware/Program.plc: Program_Ini and Program_01 … 05, each at "
            "its own period) and a scenario test"))
#: a name the folder may have: no path separators, not "." or ".."
_BAD = re.compile(r"[/\\\x00]")


def check_name(name: str) -> Optional[str]:
    """Why ``name`` cannot name a new project's folder, or None."""
    if not name.strip():
        return "Type a name."
    if _BAD.search(name) or name.strip() in (".", ".."):
        return "A name is one folder's name: no '/' or '\\'."
    if len(name) > 128:
        return "At most 128 characters."
    return None


class NewProjectDialog(QDialog):
    """The target, name and folder of a new project."""

    def __init__(self, parent=None, folder: Optional[Path] = None, name: str = "plc-project"):
        super().__init__(parent)
        self.setWindowTitle("New Project")
        lay = QVBoxLayout(self)
        form = QFormLayout()
        self.target_combo = QComboBox(self)
        for target, label, _what in TARGETS:
            self.target_combo.addItem(label, target)
        form.addRow("&Controller:", self.target_combo)
        self.what = QLabel(self)
        self.what.setWordWrap(True)
        form.addRow("", self.what)
        self.name_edit = QLineEdit(name, self)
        self.name_edit.selectAll()
        form.addRow("&Name:", self.name_edit)
        row = QHBoxLayout()
        self.folder_edit = QLineEdit(str(folder or Path.home()), self)
        self.browse = QPushButton("&Browse…", self)
        self.browse.clicked.connect(self._browse)
        row.addWidget(self.folder_edit, 1)
        row.addWidget(self.browse)
        folder_label = QLabel("&In folder:", self)
        folder_label.setBuddy(self.folder_edit)       # (a row that is a layout has none)
        form.addRow(folder_label, row)
        lay.addLayout(form)
        self.where = QLabel(self)
        self.where.setTextFormat(Qt.TextFormat.PlainText)
        self.where.setWordWrap(True)
        lay.addWidget(self.where)
        self.error = error_label(self)
        lay.addWidget(self.error)
        self.buttons = ok_cancel(self, lay)
        self.buttons.button(QDialogButtonBox.StandardButton.Ok).setText("Create")
        for sig in (self.name_edit.textChanged, self.folder_edit.textChanged,
                    self.target_combo.currentIndexChanged):
            sig.connect(self._validate)
        self.setMinimumWidth(520)
        self._validate()
        fit_height(self)
        self.name_edit.setFocus()

    # ------------------------------------------------------------------ API
    def target(self) -> str:
        return self.target_combo.currentData()

    def name(self) -> str:
        return self.name_edit.text().strip()

    def destination(self) -> Path:
        """The folder the project goes in (``In folder`` / ``Name``)."""
        return Path(self.folder_edit.text().strip()).expanduser() / self.name()

    def problem(self) -> Optional[str]:
        """Why the project cannot be made as the dialog says, or None."""
        why = check_name(self.name())
        if why:
            return why
        parent = Path(self.folder_edit.text().strip()).expanduser()
        if not self.folder_edit.text().strip():
            return "Choose the folder the project goes in."
        if not parent.is_dir():
            return f"{parent}: no such folder."
        dest = self.destination()
        if dest.exists() and (not dest.is_dir() or any(dest.iterdir())):
            return f"{dest} exists and is not an empty folder: choose another name."
        return None

    def accept(self) -> None:
        if self.problem() is None:
            super().accept()

    @classmethod
    def get_new(cls, parent=None, folder: Optional[Path] = None,
                name: str = "plc-project") -> Optional[tuple[Path, str, str]]:
        """(destination, name, target), or None when cancelled."""
        dlg = cls(parent, folder, name)
        if dlg.exec() == QDialog.DialogCode.Accepted:
            return dlg.destination(), dlg.name(), dlg.target()
        return None

    # -------------------------------------------------------------- private
    def _browse(self) -> None:
        chosen = QFileDialog.getExistingDirectory(self, "Folder for the new project",
                                                  self.folder_edit.text())
        if chosen:
            self.folder_edit.setText(chosen)

    def _validate(self, *_a) -> None:
        i = self.target_combo.currentIndex()
        self.what.setText(f"Starts from the {TARGETS[i][1]} example: {TARGETS[i][2]}.")
        why = self.problem()
        self.error.setText(why or "")
        self.where.setText("" if why else f"Creates {self.destination()}")
        self.buttons.button(QDialogButtonBox.StandardButton.Ok).setEnabled(why is None)
