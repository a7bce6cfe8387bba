"""Rename Symbol (F2): the new name, and a preview of every line it changes,
file by file, before anything is written. OK stays disabled while the new
name is refused (the reason shows under it)."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Callable, Optional

from PySide6.QtCore import Qt, QTimer
from PySide6.QtGui import QBrush, QColor, QFontDatabase
from PySide6.QtWidgets import (QDialog, QDialogButtonBox, QLabel, QLineEdit, QTreeWidget,
                               QTreeWidgetItem, QVBoxLayout)

from plcbuilder.ide.dialogs.common import error_label
from plcbuilder.lang.references import RenamePlan, Scope, renamed_line


class RenameDialog(QDialog):
    """Ask for a new name and preview the rename (``planner(new) -> RenamePlan``)."""

    def __init__(self, parent, scope: Scope, planner: Callable[[str], RenamePlan],
                 root: Optional[Path] = None):
        super().__init__(parent)
        self.setWindowTitle(f"Rename {scope.name}")
        self.scope = scope
        self.planner = planner
        self.root = root
        self.plan: Optional[RenamePlan] = None
        where = ""
        if scope.definition is not None:
            where = f", defined in {Path(scope.definition.file).name}:{scope.definition.line}"
        files = len(scope.files)
        intro = QLabel(f"Rename the {scope.kind} <b>{scope.name}</b>{where} — "
                       f"{files} file{'s' * (files != 1)} can see it.", self)
        intro.setWordWrap(True)
        self.edit = QLineEdit(scope.name, self)
        self.edit.selectAll()
        self.error = error_label(self)
        self.preview = QTreeWidget(self)
        self.preview.setHeaderLabels(["Line", "Before", "After"])
        self.preview.setRootIsDecorated(True)
        self.preview.setUniformRowHeights(True)
        self.preview.setFont(QFontDatabase.systemFont(QFontDatabase.SystemFont.FixedFont))
        self.summary = QLabel("", self)
        self.buttons = QDialogButtonBox(QDialogButtonBox.StandardButton.Ok |
                                        QDialogButtonBox.StandardButton.Cancel, self)
        self.buttons.button(QDialogButtonBox.StandardButton.Ok).setText("Rename")
        self.buttons.accepted.connect(self.accept)
        self.buttons.rejected.connect(self.reject)
        lay = QVBoxLayout(self)
        lay.addWidget(intro)
        lay.addWidget(QLabel("New name:", self))
        lay.addWidget(self.edit)
        lay.addWidget(self.error)
        lay.addWidget(self.preview, 1)
        lay.addWidget(self.summary)
        lay.addWidget(self.buttons)
        self._timer = QTimer(self)
        self._timer.setSingleShot(True)
        self._timer.setInterval(150)
        self._timer.timeout.connect(self.update_preview)
        self.edit.textChanged.connect(lambda _t: self._timer.start())
        self.resize(720, 460)
        self.update_preview()

    def ok_button(self):
        return self.buttons.button(QDialogButtonBox.StandardButton.Ok)

    def update_preview(self) -> None:
        """Plan the rename to the name typed and show every changed line."""
        self._timer.stop()
        new = self.edit.text().strip()
        plan = self.planner(new)
        self.plan = plan
        self.preview.clear()
        if plan.error and new == self.scope.name:
            self.error.setText("")
        else:
            self.error.setText(plan.error or "")
        self.ok_button().setEnabled(plan.error is None and plan.count > 0)
        if plan.error:
            self.summary.setText("")
            return
        for path, refs in plan.edits.items():
            shown = os.path.relpath(path, self.root) if self.root and not path.startswith("<") \
                else path
            top = QTreeWidgetItem([f"{shown}  ({len(refs)})", "", ""])
            self.preview.addTopLevelItem(top)
            top.setFirstColumnSpanned(True)
            by_line: dict[int, list] = {}
            for r in refs:
                by_line.setdefault(r.line, []).append(r)
            for line, on_line in by_line.items():
                before = on_line[0].text.strip()
                after = renamed_line(on_line[0], on_line, new).strip()
                item = QTreeWidgetItem([str(line), before, after])
                item.setToolTip(1, before)
                item.setToolTip(2, after)
                item.setForeground(1, QBrush(QColor("#b71c1c")))
                item.setForeground(2, QBrush(QColor("#1b5e20")))
                item.setTextAlignment(0, Qt.AlignmentFlag.AlignRight)
                top.addChild(item)
        self.preview.expandAll()
        self.preview.resizeColumnToContents(0)
        half = max(200, (self.preview.viewport().width() - self.preview.columnWidth(0)) // 2)
        self.preview.setColumnWidth(1, half)
        n, files = plan.count, len(plan.edits)
        self.summary.setText(f"{n} change{'s' * (n != 1)} in {files} file{'s' * (files != 1)}")

    @classmethod
    def get_plan(cls, parent, scope: Scope, planner: Callable[[str], RenamePlan],
                 root: Optional[Path] = None) -> Optional[RenamePlan]:
        """Run the dialog: the plan to apply, or None when cancelled."""
        dlg = cls(parent, scope, planner, root)
        if dlg.exec() != QDialog.DialogCode.Accepted:
            return None
        dlg.update_preview()
        return dlg.plan if dlg.plan is not None and dlg.plan.error is None else None
