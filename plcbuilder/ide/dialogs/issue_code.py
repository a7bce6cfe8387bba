"""Run › Issue Code…: the simulated CNC issues M, S, B or T codes to the
running controller (``M3``, ``S12000 M3``), as a scenario's ``code M3`` does,
with the project's last codes to pick again."""

from __future__ import annotations

import re
from typing import Iterable, Optional

from PySide6.QtCore import Qt
from PySide6.QtWidgets import QComboBox, QDialog, QDialogButtonBox, QLabel, QVBoxLayout

from plcbuilder.ide.dialogs.common import error_label, fit_height
from plcbuilder.ide.icons import icon

#: the most codes the history keeps
HISTORY = 20
#: a code: its letter and number (as the link's ``code`` request takes them)
_CODE = re.compile(r"([MSBTmsbt])\s*(\d{1,10})")
VALUE_MAX = (1 << 31) - 1

#: what a code does on each target (docs/ide.md, Issue Code)
HINTS = {
    "mycnc": "An M code starts its hardware procedure (M3 starts M03), as a G-code "
             "program's M3 does. myCNC takes S, B and T from a G-code program only "
             "(S is M03/M04's eparam): the controller refuses them here.",
    "huazhong": "Each code goes to the handler init() registered for its letter "
                "(set_m_func, set_s_func, set_b_func, set_t_func), which reads it at "
                "M_CODE, S_CODE, B_CODE or T_CODE.",
    "tgmotion": "TG Motion runs its Program_… procedures on their periods: an M code "
                "starts a hardware procedure only where the project has one named for it "
                "(M03), and the controller refuses S, B and T.",
}


def parse_codes(text: str) -> tuple[list[tuple[str, int]], Optional[str]]:
    """([(letter, value), …], None), or ([], why not): one or more codes
    (``M3``, ``S12000 M3``, ``m 5``), separated by spaces or commas."""
    words = [w for w in re.split(r"[\s,;]+(?=[A-Za-z])", text.strip()) if w.strip()]
    if not words:
        return [], "Type a code: a letter M, S, B or T and a number (M3, S12000)."
    out = []
    for w in words:
        m = _CODE.fullmatch(w.strip().rstrip(",;"))
        if m is None:
            return [], (f"{w.strip()!r} is not a code: a letter M, S, B or T and a number "
                        "(M3, S12000).")
        value = int(m.group(2))
        if value > VALUE_MAX:
            return [], f"{w.strip()}: the number is at most {VALUE_MAX}."
        out.append((m.group(1).upper(), value))
    return out, None


def code_text(codes: Iterable[tuple[str, int]]) -> str:
    return " ".join(f"{letter}{value}" for letter, value in codes)


class IssueCodeDialog(QDialog):
    """A code (or several) to issue, typed or picked from the project's history."""

    def __init__(self, parent=None, history: Iterable[str] = (), target: str = "mycnc"):
        super().__init__(parent)
        self.setWindowTitle("Issue Code")
        self.setObjectName("issueCodeDialog")
        lay = QVBoxLayout(self)
        lab = QLabel("&Code (M3, S12000 M3, T5):", self)
        self.combo = QComboBox(self)
        self.combo.setEditable(True)
        self.combo.setInsertPolicy(QComboBox.InsertPolicy.NoInsert)
        self.combo.setObjectName("codeBox")
        for text in history:
            self.combo.addItem(text)
        self.combo.setCurrentIndex(0 if self.combo.count() else -1)
        self.combo.lineEdit().selectAll()
        self.combo.setToolTip("The codes issued last in this project are in the list")
        lab.setBuddy(self.combo)
        self.hint = QLabel(HINTS.get(target, HINTS["mycnc"]), self)
        self.hint.setWordWrap(True)
        self.hint.setStyleSheet("color: #505050;")
        self.error = error_label(self)
        lay.addWidget(lab)
        lay.addWidget(self.combo)
        lay.addWidget(self.hint)
        lay.addWidget(self.error)
        self.buttons = QDialogButtonBox(self)
        self.issue_button = self.buttons.addButton("Issue",
                                                   QDialogButtonBox.ButtonRole.AcceptRole)
        self.issue_button.setIcon(icon("start"))
        self.buttons.addButton(QDialogButtonBox.StandardButton.Cancel)
        self.buttons.accepted.connect(self.accept)
        self.buttons.rejected.connect(self.reject)
        lay.addWidget(self.buttons)
        self.combo.editTextChanged.connect(self._validate)
        self.setMinimumWidth(420)
        self.resize(420, 10)
        fit_height(self)
        self._validate()
        self.combo.setFocus(Qt.FocusReason.OtherFocusReason)

    def codes(self) -> list[tuple[str, int]]:
        return parse_codes(self.combo.currentText())[0]

    def _validate(self, *_a) -> None:
        codes, why = parse_codes(self.combo.currentText())
        self.error.setText("" if codes or not self.combo.currentText().strip() else why or "")
        self.issue_button.setEnabled(bool(codes))

    def accept(self) -> None:
        if self.codes():
            super().accept()

    @classmethod
    def get_codes(cls, parent=None, history: Iterable[str] = (),
                  target: str = "mycnc") -> Optional[list[tuple[str, int]]]:
        dlg = cls(parent, history, target)
        if dlg.exec() == QDialog.DialogCode.Accepted:
            return dlg.codes()
        return None
