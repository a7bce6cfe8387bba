"""What the dialogs share."""

from __future__ import annotations

from PySide6.QtWidgets import QDialog, QDialogButtonBox, QLabel, QLayout


def error_label(parent) -> QLabel:
    lab = QLabel(parent)
    lab.setWordWrap(True)
    lab.setStyleSheet("color: #c62828;")
    return lab


def ok_cancel(dialog: QDialog, layout: QLayout) -> QDialogButtonBox:
    """An OK / Cancel row at the end of ``layout`` that accepts or rejects ``dialog``."""
    box = QDialogButtonBox(QDialogButtonBox.StandardButton.Ok |
                           QDialogButtonBox.StandardButton.Cancel, dialog)
    box.accepted.connect(dialog.accept)
    box.rejected.connect(dialog.reject)
    layout.addWidget(box)
    return box
