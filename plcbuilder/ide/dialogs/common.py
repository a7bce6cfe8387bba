"""What the dialogs share."""

from __future__ import annotations

from PySide6.QtWidgets import QLabel


def error_label(parent) -> QLabel:
    lab = QLabel(parent)
    lab.setWordWrap(True)
    lab.setStyleSheet("color: #c62828;")
    return lab
