"""The watch panel: the variables of the running (or last run) procedure.

Values come from the controller's ``variables`` verb, which the panels poll a
few times a second while something runs (see :class:`RunPanels`). A value that
changed since the previous poll is shown highlighted.
"""

from __future__ import annotations

import time
from typing import Optional

from PySide6 import QtCore, QtGui, QtWidgets

from plcbuilder.api import abi

Qt = QtCore.Qt

HIGHLIGHT_S = 1.0
_PREDEFINED = ("eparam", "proc", "timer", "vexit", "message", "Param")
_CHANGED = QtGui.QColor("#fff2b3")


def _order(names: list[str]) -> list[str]:
    """The program's own variables first (in slot order), then the predefined
    ones, then var00..var15."""
    own = [n for n in names if n not in abi.SLOT_NAMES and n not in _PREDEFINED]
    pre = [n for n in _PREDEFINED if n in names]
    regs = [n for n in names if n.startswith("var") and n in abi.SLOT_NAMES]
    rest = [n for n in names if n not in own and n not in pre and n not in regs]
    return own + pre + rest + regs


class WatchPanel(QtWidgets.QWidget):
    """A table of one procedure's variables, refreshed from polls."""

    def __init__(self, parent=None):
        super().__init__(parent)
        self.procedure = QtWidgets.QComboBox()
        self.procedure.setToolTip("Whose variables to show (follows the running procedure)")
        self.procedure.setMinimumContentsLength(12)
        self.procedure.activated.connect(self._picked)
        self.follow = QtWidgets.QCheckBox("Follow running")
        self.follow.setChecked(True)
        self.follow.setToolTip("Show the procedure that is running")
        self.show_regs = QtWidgets.QCheckBox("var00–var15")
        self.show_regs.setToolTip("Also show var00..var15 (initialised from plc-variables.xml)")
        self.show_regs.toggled.connect(lambda _: self._fill())
        self.hex = QtWidgets.QCheckBox("Hex")
        self.hex.setChecked(True)
        self.hex.toggled.connect(lambda _: self._fill())
        top = QtWidgets.QHBoxLayout()
        top.setContentsMargins(4, 2, 4, 2)
        top.addWidget(QtWidgets.QLabel("Procedure"))
        top.addWidget(self.procedure, 1)
        top.addWidget(self.follow)
        top.addWidget(self.show_regs)
        top.addWidget(self.hex)

        self.table = QtWidgets.QTableWidget(0, 3)
        self.table.setHorizontalHeaderLabels(["Variable", "Value", "Hex"])
        self.table.verticalHeader().setVisible(False)
        self.table.verticalHeader().setDefaultSectionSize(20)
        self.table.setEditTriggers(QtWidgets.QAbstractItemView.EditTrigger.NoEditTriggers)
        self.table.setSelectionBehavior(QtWidgets.QAbstractItemView.SelectionBehavior.SelectRows)
        self.table.setAlternatingRowColors(True)
        hh = self.table.horizontalHeader()
        hh.setSectionResizeMode(0, QtWidgets.QHeaderView.ResizeMode.Stretch)
        hh.setSectionResizeMode(1, QtWidgets.QHeaderView.ResizeMode.ResizeToContents)
        hh.setSectionResizeMode(2, QtWidgets.QHeaderView.ResizeMode.ResizeToContents)
        self.hint = QtWidgets.QLabel("Variables appear while a procedure runs.")
        self.hint.setStyleSheet("color: #6a6a6a; padding: 2px 6px;")

        lay = QtWidgets.QVBoxLayout(self)
        lay.setContentsMargins(0, 0, 0, 0)
        lay.setSpacing(2)
        lay.addLayout(top)
        lay.addWidget(self.table, 1)
        lay.addWidget(self.hint)

        self.variables: dict[str, dict[str, int]] = {}
        self._changed: dict[tuple[str, str], float] = {}
        self.current: Optional[str] = None

    # ------------------------------------------------------------------ API
    def set_variables(self, variables: dict, running: Optional[str] = None) -> None:
        """A poll's answer: ``{procedure: {variable: value}}``."""
        now = time.monotonic()
        for proc, vals in variables.items():
            old = self.variables.get(proc, {})
            for name, v in vals.items():
                if name in old and old[name] != v:
                    self._changed[(proc, name)] = now + HIGHLIGHT_S
        self.variables = {p: dict(v) for p, v in variables.items()}
        names = sorted(self.variables)
        if [self.procedure.itemText(i) for i in range(self.procedure.count())] != names:
            self.procedure.blockSignals(True)
            self.procedure.clear()
            self.procedure.addItems(names)
            self.procedure.blockSignals(False)
        if self.follow.isChecked() and running and running in self.variables:
            self.current = running
        elif self.current not in self.variables:
            self.current = running if running in self.variables else (names[0] if names else None)
        if self.current is not None:
            self.procedure.setCurrentText(self.current)
        self._fill()

    def clear(self) -> None:
        self.variables = {}
        self._changed.clear()
        self.procedure.clear()
        self.current = None
        self._fill()

    def value(self, name: str, procedure: Optional[str] = None) -> Optional[int]:
        return self.variables.get(procedure or self.current or "", {}).get(name)

    # -------------------------------------------------------------- private
    def _picked(self, index: int) -> None:
        self.current = self.procedure.itemText(index)
        self.follow.setChecked(False)
        self._fill()

    def _fill(self) -> None:
        vals = self.variables.get(self.current or "", {})
        names = _order(list(vals))
        if not self.show_regs.isChecked():
            names = [n for n in names if not (n.startswith("var") and n in abi.SLOT_NAMES)]
        now = time.monotonic()
        self.table.setColumnHidden(2, not self.hex.isChecked())
        if self.table.rowCount() != len(names):
            self.table.setRowCount(len(names))
        bold = QtGui.QFont()
        bold.setBold(True)
        for r, name in enumerate(names):
            v = int(vals[name])
            cells = (name, str(v), f"0x{v & 0xFFFFFFFF:08x}")
            hot = self._changed.get((self.current, name), 0) > now
            for c, text in enumerate(cells):
                item = self.table.item(r, c)
                if item is None:
                    item = QtWidgets.QTableWidgetItem()
                    if c:
                        item.setTextAlignment(Qt.AlignmentFlag.AlignRight
                                              | Qt.AlignmentFlag.AlignVCenter)
                    self.table.setItem(r, c, item)
                if item.text() != text:
                    item.setText(text)
                item.setBackground(_CHANGED if hot else QtGui.QBrush())
                if c == 0:
                    item.setFont(bold if name not in abi.SLOT_NAMES and name not in _PREDEFINED
                                 else QtGui.QFont())
        self.hint.setVisible(not names)
