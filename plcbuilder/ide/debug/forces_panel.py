"""The Forces panel: everything forced on the controller, in one list (SPEC §6),
with Release (keep or restore), Release All and a way to force something new.

Targets are named as the command line names them: ``PROC.var``, ``in N``,
``out N``, ``adc N``, ``pwm N``, ``dac N``, ``gvar N``.
"""

from __future__ import annotations

import re
from typing import Optional

from PySide6.QtCore import Qt, Signal
from PySide6.QtWidgets import (QComboBox, QDialog, QDialogButtonBox, QFormLayout, QLineEdit,
                               QMenu, QSpinBox, QTreeWidgetItem, QWidget)

from plcbuilder.ide.debug.list_panel import lay_out, list_tree, tool
from plcbuilder.ide.icons import icon

TARGET_RE = re.compile(r"(?:[A-Za-z_][A-Za-z0-9_]*\.[A-Za-z_][A-Za-z0-9_]*|"
                       r"(?:in|out|adc|pwm|dac|gvar) +\d+)\Z")
RELEASE_MODES = {"keep": "keep the value it has now", "restore":
                 "go back to what the program (or the wiring) gives"}


def valid_target(text: str) -> bool:
    """Whether text names a target as SPEC §6 does (``PROC.var``, ``in 3``...)."""
    return bool(TARGET_RE.match(text.strip()))


class ForcesPanel(QWidget):
    """The list of forces."""

    sig_release = Signal(str, str)
    """Release a target (its name, ``keep`` or ``restore``)."""

    sig_release_all = Signal(str)
    """Release everything (``keep`` or ``restore``)."""

    sig_force = Signal(str, int)
    """Force a target to a value."""

    def __init__(self, parent: Optional[QWidget] = None):
        super().__init__(parent)
        self.tree = list_tree(self, "forcesList", ["Forced", "Value", "Since"], self._menu)
        self.tree.itemDoubleClicked.connect(lambda item, _c: self.ask_force(item.text(0),
                                                                             item.text(1)))
        self.mode = QComboBox(self)
        self.mode.addItem("Release keeps the value", "keep")
        self.mode.addItem("Release restores the program's value", "restore")
        self.mode.setToolTip("What a release does: " + "; ".join(
            f"{k}: {v}" for k, v in RELEASE_MODES.items()))
        self.add_button = tool(self, "debug-force", "Force a variable, input, output, ADC, "
                                "PWM, DAC or register…", lambda: self.ask_force())
        self.release_button = tool(self, "delete", "Release the selected forces",
                                    self.release_selected)
        self.release_all_button = tool(self, "clear", "Release everything forced",
                                        lambda: self.sig_release_all.emit(self.release_mode()))
        lay_out(self, self.tree, (self.add_button, self.release_button, self.release_all_button),
                lead=self.mode)
        self.forces: list[dict] = []
        self.show_forces([])

    # ------------------------------------------------------------------ API
    def show_forces(self, forces: list[dict]) -> None:
        self.forces = [dict(f) for f in forces]
        self.tree.clear()
        for f in self.forces:
            item = QTreeWidgetItem(self.tree)
            item.setText(0, str(f.get("target")))
            item.setIcon(0, icon("debug-force"))
            item.setText(1, str(f.get("value")))
            since = f.get("since_ms")
            item.setText(2, f"t = {since} ms" if since is not None else "")
            item.setTextAlignment(1, Qt.AlignmentFlag.AlignRight | Qt.AlignmentFlag.AlignVCenter)
        self.release_all_button.setEnabled(bool(self.forces))
        self.release_button.setEnabled(bool(self.forces))

    def targets(self) -> list[str]:
        return [str(f.get("target")) for f in self.forces]

    def release_mode(self) -> str:
        return self.mode.currentData() or "keep"

    def release_selected(self) -> None:
        for item in self.tree.selectedItems():
            self.sig_release.emit(item.text(0), self.release_mode())

    def ask_force(self, target: str = "", value: str = "0") -> bool:
        """Ask for a target and a value, then force it."""
        dlg = ForceDialog(self, target, value)
        if dlg.exec() != QDialog.DialogCode.Accepted:
            return False
        self.sig_force.emit(dlg.target(), dlg.value())
        return True

    # -------------------------------------------------------------- private
    def _menu(self, pos) -> None:
        item = self.tree.itemAt(pos)
        menu = QMenu(self)
        if item is not None:
            t = item.text(0)
            menu.addAction("Change Value…", lambda: self.ask_force(t, item.text(1)))
            for mode, text in (("keep", "Release (keep the value)"),
                               ("restore", "Release (restore the program's value)")):
                menu.addAction(text, lambda m=mode: self.sig_release.emit(t, m))
            menu.addSeparator()
        menu.addAction("Force…", lambda: self.ask_force())
        act = menu.addAction("Release All", lambda: self.sig_release_all.emit(self.release_mode()))
        act.setEnabled(bool(self.forces))
        menu.exec(self.tree.viewport().mapToGlobal(pos))


class ForceDialog(QDialog):
    """A target and a value to force."""

    def __init__(self, parent, target: str = "", value="0"):
        super().__init__(parent)
        self.setWindowTitle("Force")
        self.edit = QLineEdit(target)
        self.edit.setPlaceholderText("M80.statez, in 12, out 3, adc 0, pwm 1, dac 0, gvar 5000")
        self.spin = QSpinBox()
        self.spin.setRange(-(1 << 31), (1 << 31) - 1)
        try:
            self.spin.setValue(int(str(value), 0))
        except ValueError:
            self.spin.setValue(0)
        form = QFormLayout(self)
        form.addRow("Target", self.edit)
        form.addRow("Value", self.spin)
        self.buttons = QDialogButtonBox(QDialogButtonBox.StandardButton.Ok |
                                        QDialogButtonBox.StandardButton.Cancel)
        self.buttons.accepted.connect(self.accept)
        self.buttons.rejected.connect(self.reject)
        form.addRow(self.buttons)
        self.edit.textChanged.connect(self._check)
        self._check()

    def target(self) -> str:
        return re.sub(r"\s+", " ", self.edit.text().strip())

    def value(self) -> int:
        return int(self.spin.value())

    def _check(self) -> None:
        ok = valid_target(self.edit.text())
        self.buttons.button(QDialogButtonBox.StandardButton.Ok).setEnabled(ok)
        self.edit.setStyleSheet("" if ok or not self.edit.text() else "color: #c62828;")

