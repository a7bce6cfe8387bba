"""The dialog that edits what a breakpoint does: a condition (a PLC-language
expression, checked by our compiler before it is accepted), a hit count, or a
log message that makes it a logpoint."""

from __future__ import annotations

from typing import Callable, Optional

from PySide6.QtWidgets import (QCheckBox, QComboBox, QDialog, QDialogButtonBox, QFormLayout,
                               QHBoxLayout, QLabel, QLineEdit, QSpinBox, QWidget)

from plcbuilder.ide.debug.breakpoints import HIT_MODES, Breakpoint


class BreakpointDialog(QDialog):
    """Condition, hit count and log message of one breakpoint.

    ``check_condition(text)`` returns an error message for a condition that
    does not compile (None when it does); OK stays disabled until it compiles.
    """

    def __init__(self, parent: Optional[QWidget], bp: Breakpoint,
                 check_condition: Optional[Callable[[str], Optional[str]]] = None,
                 focus: str = "condition"):
        super().__init__(parent)
        self.setWindowTitle(f"Breakpoint at {bp.file_name}:{bp.line}")
        self.check_condition = check_condition
        self.condition = QLineEdit(bp.condition or "")
        self.condition.setObjectName("condition")
        self.condition.setPlaceholderText("an expression, e.g. statez == 1 && timer > 100")
        self.use_hit = QCheckBox("Halt")
        self.use_hit.setChecked(bp.hit is not None)
        self.hit_mode = QComboBox()
        for mode, text in (("eq", "on hit N"), ("ge", "from hit N on"), ("every", "every N hits")):
            self.hit_mode.addItem(text, mode)
        self.hit_n = QSpinBox()
        self.hit_n.setRange(1, 1_000_000_000)
        if bp.hit:
            self.hit_mode.setCurrentIndex(max(0, self.hit_mode.findData(bp.hit.get("mode"))))
            self.hit_n.setValue(int(bp.hit.get("n", 1)))
        hit_row = QHBoxLayout()
        hit_row.addWidget(self.use_hit)
        hit_row.addWidget(self.hit_mode)
        hit_row.addWidget(QLabel("N ="))
        hit_row.addWidget(self.hit_n, 1)
        self.log = QLineEdit(bp.log or "")
        self.log.setObjectName("log")
        self.log.setPlaceholderText("a message, e.g. statez={statez} sens={sens} (no halt)")
        self.error = QLabel("")
        self.error.setStyleSheet("color: #c62828;")
        self.error.setWordWrap(True)
        form = QFormLayout(self)
        form.addRow("Condition", self.condition)
        form.addRow("Hit count", hit_row)
        form.addRow("Log message", self.log)
        form.addRow(self.error)
        form.addRow(QLabel("A log message makes it a logpoint: it writes the message to the "
                           "run log and does not halt."))
        self.buttons = QDialogButtonBox(QDialogButtonBox.StandardButton.Ok |
                                        QDialogButtonBox.StandardButton.Cancel)
        self.buttons.accepted.connect(self.accept)
        self.buttons.rejected.connect(self.reject)
        form.addRow(self.buttons)
        self.condition.textChanged.connect(self._check)
        self.use_hit.toggled.connect(self._hit_enabled)
        self._hit_enabled(self.use_hit.isChecked())
        self._check()
        {"condition": self.condition, "log": self.log, "hit": self.hit_n}.get(
            focus, self.condition).setFocus()

    def values(self) -> dict:
        """The changes for :meth:`BreakpointStore.update`."""
        cond = self.condition.text().strip() or None
        hit = ({"mode": self.hit_mode.currentData(), "n": int(self.hit_n.value())}
               if self.use_hit.isChecked() else None)
        return {"condition": cond, "hit": hit, "log": self.log.text().strip() or None}

    def _hit_enabled(self, on: bool) -> None:
        self.hit_mode.setEnabled(on)
        self.hit_n.setEnabled(on)

    def _check(self) -> None:
        text = self.condition.text().strip()
        msg = self.check_condition(text) if (text and self.check_condition) else None
        self.error.setText(f"The condition does not compile: {msg}" if msg else "")
        self.buttons.button(QDialogButtonBox.StandardButton.Ok).setEnabled(not msg)


__all__ = ["BreakpointDialog", "HIT_MODES"]
