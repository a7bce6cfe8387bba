"""Dialogs of the run side: start a procedure (by name or M-code number, with
eparam), connect to a controller."""

from __future__ import annotations

import re
from typing import Iterable, Optional

from PySide6.QtCore import Qt
from PySide6.QtWidgets import (QDialog, QDialogButtonBox, QFormLayout, QHBoxLayout, QLabel,
                               QLineEdit, QListWidget, QListWidgetItem, QRadioButton, QSpinBox,
                               QVBoxLayout)

from plcbuilder.api import Kind
from plcbuilder.ide.icons import icon
from plcbuilder.ide.dialogs.common import error_label, ok_cancel

INT32_MIN, INT32_MAX = -2 ** 31, 2 ** 31 - 1


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
        self.error = error_label(self)
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
        # Alt+M (or a click) on "By M-code number" goes on into its box, the
        # number selected: the digits typed next are the M-code (issue 23.11)
        self.by_mcode.clicked.connect(self._to_mcode)
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
        # no M-code procedure (a Huazhong or TG Motion project): no M-code row
        if not any(re.fullmatch(r"M\d+", name) for name, _k in self.procedures):
            for w in (self.by_mcode, self.mcode_spin, self.mcode_status):
                w.hide()
        self._validate()
        # typing goes to the list at once (M8 jumps to M80), not to a radio button
        self.list.setFocus(Qt.FocusReason.OtherFocusReason)

    def showEvent(self, event) -> None:  # noqa: N802 - Qt override
        super().showEvent(event)
        self.activateWindow()
        self.list.setFocus(Qt.FocusReason.ActiveWindowFocusReason)

    def _pick_name(self) -> None:
        self.by_name.setChecked(True)
        self._validate()

    def _to_mcode(self) -> None:
        self.by_mcode.setChecked(True)
        self.mcode_spin.setFocus(Qt.FocusReason.ShortcutFocusReason)
        self.mcode_spin.selectAll()
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
        self.buttons = ok_cancel(self, lay)
        self.buttons.button(QDialogButtonBox.StandardButton.Ok).setText("Connect")
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
