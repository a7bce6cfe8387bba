"""What the debugger's list panels (Breakpoints, Forces) share: the list, its
icon buttons, and the row of buttons above it."""

from __future__ import annotations

from typing import Callable, Iterable, Optional

from PySide6.QtCore import Qt
from PySide6.QtWidgets import QHBoxLayout, QToolButton, QTreeWidget, QVBoxLayout, QWidget

from plcbuilder.ide.icons import icon


def list_tree(panel: QWidget, name: str, headers: list[str], menu: Callable) -> QTreeWidget:
    """A flat list with these column headers, alternating row colours, extended
    selection, and ``menu(pos)`` as its context menu."""
    tree = QTreeWidget(panel)
    tree.setObjectName(name)
    tree.setColumnCount(len(headers))
    tree.setHeaderLabels(headers)
    tree.setRootIsDecorated(False)
    tree.setAlternatingRowColors(True)
    tree.setSelectionMode(QTreeWidget.SelectionMode.ExtendedSelection)
    tree.setContextMenuPolicy(Qt.ContextMenuPolicy.CustomContextMenu)
    tree.customContextMenuRequested.connect(menu)
    return tree


def tool(parent: QWidget, ic: str, tip: str, slot: Callable[[], object]) -> QToolButton:
    """A flat icon button that calls ``slot()`` when clicked."""
    b = QToolButton(parent)
    b.setIcon(icon(ic))
    b.setToolTip(tip)
    b.setAutoRaise(True)
    b.clicked.connect(lambda _c=False: slot())
    return b


def lay_out(panel: QWidget, tree: QTreeWidget, buttons: Iterable[QWidget],
            lead: Optional[QWidget] = None) -> None:
    """The panel's layout: the buttons in a row above the list, at the right of
    ``lead`` (which takes the row's free room) or of an empty stretch."""
    top = QHBoxLayout()
    top.setContentsMargins(2, 2, 2, 2)
    if lead is None:
        top.addStretch(1)
    else:
        top.addWidget(lead, 1)
    for b in buttons:
        top.addWidget(b)
    lay = QVBoxLayout(panel)
    lay.setContentsMargins(0, 0, 0, 0)
    lay.setSpacing(0)
    lay.addLayout(top)
    lay.addWidget(tree, 1)
