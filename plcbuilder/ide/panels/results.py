"""A list of places in files, grouped by file: what Find in Files and Find
References show. A click (or Enter) on a line opens it in the editor."""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Iterable, Optional

from PySide6.QtCore import Qt, Signal
from PySide6.QtGui import QBrush, QColor, QFont
from PySide6.QtWidgets import (QHeaderView, QLabel, QTreeWidget, QTreeWidgetItem, QVBoxLayout,
                               QWidget)

from plcbuilder.ide.icons import icon

ROLE_LOCATION = Qt.ItemDataRole.UserRole + 1


@dataclass(frozen=True)
class Hit:
    """One place: a file, a 1-based line, the columns of the match (1-based,
    end exclusive) and the line's text."""
    file: str
    line: int
    col: int
    end_col: int
    text: str
    note: str = ""          # "definition", …


def display_path(path: str, root: Optional[Path]) -> str:
    """A file's path relative to the project (as the tree shows it)."""
    if root is not None and not path.startswith("<"):
        try:
            return os.path.relpath(path, root)
        except ValueError:
            pass
    return path


class ResultsTree(QTreeWidget):
    """Places grouped by file; activating a place asks to open it."""

    sig_open_location = Signal(str, int, int)
    """Open this place: file, line, column."""

    def __init__(self, parent=None):
        super().__init__(parent)
        self.root: Optional[Path] = None
        self.setColumnCount(2)
        self.setHeaderLabels(["Line", "Text"])
        self.setRootIsDecorated(True)
        self.setUniformRowHeights(True)
        self.setAlternatingRowColors(True)
        self.header().setSectionResizeMode(0, QHeaderView.ResizeMode.ResizeToContents)
        self.header().setStretchLastSection(True)
        self.itemActivated.connect(self._on_activated)
        self.itemClicked.connect(self._on_activated)

    def set_hits(self, hits: Iterable[Hit]) -> int:
        """Show these places (in their order, grouped by file, one row a line:
        ``12  ×3`` is three places on line 12); returns how many places."""
        self.clear()
        groups: dict[str, QTreeWidgetItem] = {}
        n = 0
        mono = QFont("monospace")
        mono.setStyleHint(QFont.StyleHint.Monospace)
        last = None                       # (file, line) of the row before: one row a line
        for h in hits:
            n += 1
            if last == (h.file, h.line):
                item = top.child(top.childCount() - 1)
                count = item.data(1, ROLE_LOCATION) + 1
                item.setData(1, ROLE_LOCATION, count)
                item.setText(0, f"{h.line}  ×{count}")
                continue
            last = (h.file, h.line)
            top = groups.get(h.file)
            if top is None:
                top = QTreeWidgetItem([display_path(h.file, self.root), ""])
                top.setIcon(0, icon("file-header" if h.file.endswith(".h") else "file-plc"))
                top.setData(0, ROLE_LOCATION, (h.file, 1, 1))
                top.setData(1, ROLE_LOCATION, 0)
                self.addTopLevelItem(top)
                top.setFirstColumnSpanned(True)
                groups[h.file] = top
            text = h.text.replace("\t", "    ")
            item = QTreeWidgetItem([str(h.line), text.strip() + (f"    ({h.note})" if h.note else "")])
            item.setData(0, ROLE_LOCATION, (h.file, h.line, h.col))
            item.setData(1, ROLE_LOCATION, 1)
            item.setData(0, Qt.ItemDataRole.TextAlignmentRole,
                         int(Qt.AlignmentFlag.AlignRight | Qt.AlignmentFlag.AlignVCenter))
            item.setFont(1, mono)
            item.setToolTip(1, h.text.strip())
            if h.note:
                item.setForeground(1, QBrush(QColor("#2e7d32")))
            top.addChild(item)
        for top in groups.values():
            found = sum(top.child(i).data(1, ROLE_LOCATION) for i in range(top.childCount()))
            top.setText(0, f"{top.text(0)}  ({found})")
        self.expandAll()
        return n

    def hits_shown(self) -> list[tuple[str, int, int]]:
        """(file, line, column) of every row listed, in order (for tests)."""
        out = []
        for i in range(self.topLevelItemCount()):
            top = self.topLevelItem(i)
            for j in range(top.childCount()):
                out.append(top.child(j).data(0, ROLE_LOCATION))
        return out

    def _on_activated(self, item: QTreeWidgetItem, _col: int = 0) -> None:
        loc = item.data(0, ROLE_LOCATION)
        if loc and item.parent() is not None:
            self.sig_open_location.emit(*loc)


class ResultsPanel(QWidget):
    """A one-line summary over a :class:`ResultsTree` (the References dock)."""

    sig_open_location = Signal(str, int, int)
    """Open this place: file, line, column."""

    def __init__(self, parent=None, empty: str = ""):
        super().__init__(parent)
        self.summary = QLabel(empty, self)
        self.summary.setContentsMargins(6, 3, 6, 3)
        self.summary.setTextInteractionFlags(Qt.TextInteractionFlag.TextSelectableByMouse)
        self.tree = ResultsTree(self)
        self.tree.sig_open_location.connect(self.sig_open_location)
        lay = QVBoxLayout(self)
        lay.setContentsMargins(0, 0, 0, 0)
        lay.setSpacing(0)
        lay.addWidget(self.summary)
        lay.addWidget(self.tree)

    def show_hits(self, summary: str, hits: Iterable[Hit]) -> int:
        n = self.tree.set_hits(hits)
        self.summary.setText(summary)
        return n
