"""What the dialogs share."""

from __future__ import annotations

from PySide6.QtCore import Qt
from PySide6.QtWidgets import QDialog, QDialogButtonBox, QLabel, QLayout


def error_label(parent) -> QLabel:
    lab = QLabel(parent)
    lab.setWordWrap(True)
    lab.setTextFormat(Qt.TextFormat.PlainText)       # names like __HANDLER_INIT as typed
    lab.setStyleSheet("color: #c62828;")
    return lab


def fit_height(dialog: QDialog) -> None:
    """Make a dialog tall enough for its wrapped labels at its width (a label
    that wraps to another line must not be cut: the underscores of
    __HANDLER_INIT went first)."""
    lay = dialog.layout()
    if lay is None:
        return
    lay.activate()
    need = lay.totalHeightForWidth(dialog.width()) if lay.hasHeightForWidth() else \
        lay.totalSizeHint().height()
    if need > dialog.height():
        dialog.resize(dialog.width(), need)
    dialog.setMinimumHeight(need)


def ok_cancel(dialog: QDialog, layout: QLayout) -> QDialogButtonBox:
    """An OK / Cancel row at the end of ``layout`` that accepts or rejects ``dialog``."""
    box = QDialogButtonBox(QDialogButtonBox.StandardButton.Ok |
                           QDialogButtonBox.StandardButton.Cancel, dialog)
    box.accepted.connect(dialog.accept)
    box.rejected.connect(dialog.reject)
    layout.addWidget(box)
    return box
