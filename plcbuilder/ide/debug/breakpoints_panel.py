"""The Breakpoints panel: every breakpoint of the project, one row each, with
a checkbox to enable it; double-click goes to its line; Remove and Remove All."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

from PySide6.QtCore import Qt, QTimer, Signal
from PySide6.QtWidgets import QMenu, QTreeWidgetItem, QWidget

from plcbuilder.ide.debug.breakpoints import Breakpoint, BreakpointStore
from plcbuilder.ide.debug.list_panel import lay_out, list_tree, tool
from plcbuilder.ide.icons import icon

ROLE_BP = Qt.ItemDataRole.UserRole + 1


class BreakpointsPanel(QWidget):
    """A list of the store's breakpoints."""

    sig_open_location = Signal(str, int)
    """Go to a breakpoint's line (its file, 1-based line)."""

    sig_edit = Signal(object)
    """Edit a breakpoint's condition, hit count or log message (the Breakpoint)."""

    def __init__(self, store: BreakpointStore, parent: Optional[QWidget] = None):
        super().__init__(parent)
        self.store = store
        self.tree = list_tree(self, "breakpointsList", ["Breakpoint", "Line", "Details"],
                              self._menu)
        self.tree.setUniformRowHeights(True)
        self.tree.itemDoubleClicked.connect(self._activated)
        self.tree.itemChanged.connect(self._item_changed)
        self.remove_button = tool(self, "delete", "Remove the selected breakpoints (Delete)",
                                   self.remove_selected)
        self.remove_all_button = tool(self, "clear", "Remove every breakpoint",
                                       self.store.clear)
        self.toggle_all_button = tool(self, "disconnected", "Enable or disable every breakpoint",
                                       self.toggle_all)
        lay_out(self, self.tree,
                (self.toggle_all_button, self.remove_button, self.remove_all_button))
        self._filling = False
        self._changing = False          # in an item's own change (its checkbox)
        store.sig_changed.connect(lambda _p: self.refresh())
        self.refresh()

    # ------------------------------------------------------------------ API
    def refresh(self) -> None:
        if self._changing:
            # the store changed from a row's checkbox: the row is still inside
            # its own setData (rebuilding now would delete it under Qt's feet)
            QTimer.singleShot(0, self.refresh)
            return
        self._filling = True
        self.tree.clear()
        for bp in self.store.all():
            item = QTreeWidgetItem(self.tree)
            item.setData(0, ROLE_BP, bp)
            item.setFlags(item.flags() | Qt.ItemFlag.ItemIsUserCheckable)
            item.setCheckState(0, Qt.CheckState.Checked if bp.enabled else Qt.CheckState.Unchecked)
            item.setText(0, Path(bp.path).name)
            item.setToolTip(0, bp.path)
            line = str(bp.line)
            if bp.actual_line and bp.actual_line != bp.line:
                line += f" → {bp.actual_line}"
            item.setText(1, line)
            details = bp.describe()
            if bp.verified is False and bp.reason:
                details = f"not set: {bp.reason}" + (f" ({details})" if details else "")
            item.setText(2, details)
            item.setToolTip(2, details)
            item.setIcon(0, icon("error") if bp.verified is False else icon("debug-breakpoint"))
        for c in range(2):
            self.tree.resizeColumnToContents(c)
        self._filling = False
        self.remove_all_button.setEnabled(len(self.store) > 0)

    def breakpoint_items(self) -> list[QTreeWidgetItem]:
        return [self.tree.topLevelItem(i) for i in range(self.tree.topLevelItemCount())]

    def remove_selected(self) -> None:
        for item in self.tree.selectedItems():
            self.store.remove(item.data(0, ROLE_BP))

    def toggle_all(self) -> None:
        bps = self.store.all()
        self.store.set_all_enabled(not all(bp.enabled for bp in bps))

    def keyPressEvent(self, event) -> None:  # noqa: N802 - Qt override
        if event.key() == Qt.Key.Key_Delete:
            self.remove_selected()
            return
        super().keyPressEvent(event)

    # -------------------------------------------------------------- private
    def _item_changed(self, item: QTreeWidgetItem, column: int) -> None:
        if self._filling or column != 0:
            return
        bp: Breakpoint = item.data(0, ROLE_BP)
        on = item.checkState(0) == Qt.CheckState.Checked
        if bp.enabled != on:
            self._changing = True
            try:
                self.store.update(bp, enabled=on)
            finally:
                self._changing = False

    def _activated(self, item: QTreeWidgetItem, _column: int = 0) -> None:
        bp: Breakpoint = item.data(0, ROLE_BP)
        self.sig_open_location.emit(bp.path, bp.actual_line or bp.line)

    def _menu(self, pos) -> None:
        item = self.tree.itemAt(pos)
        menu = QMenu(self)
        if item is not None:
            bp: Breakpoint = item.data(0, ROLE_BP)
            menu.addAction("Go to Line", lambda: self._activated(item))
            menu.addAction("Edit Condition, Hit Count or Log…", lambda: self.sig_edit.emit(bp))
            menu.addAction("Disable" if bp.enabled else "Enable",
                           lambda: self.store.update(bp, enabled=not bp.enabled))
            menu.addAction("Remove", lambda: self.store.remove(bp))
            menu.addSeparator()
        menu.addAction("Enable or Disable All", self.toggle_all)
        menu.addAction("Remove All", self.store.clear)
        menu.exec(self.tree.viewport().mapToGlobal(pos))

