"""The Outline dock: what the current file defines — its procedures, defines
and variables — from :meth:`plcbuilder.lang.symbols.SymbolIndex.outline`.
A click goes there; the entry of the caret's line (or the procedure around
it) is selected as the caret moves. It follows the text as it changes (after a
short pause in typing)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Optional

from PySide6.QtCore import Qt, QTimer, Signal
from PySide6.QtGui import QColor, QFont, QIcon, QImage, QPixmap
from PySide6.QtWidgets import QLabel, QTreeWidget, QTreeWidgetItem, QVBoxLayout, QWidget

from plcbuilder.ide.editor.marks import (KIND_DEFINE, KIND_LOOK, KIND_PROCEDURE, KIND_VARIABLE,
                                         rgba_image)
from plcbuilder.lang import kinds

if TYPE_CHECKING:
    from plcbuilder.lang.symbols import OutlineItem

ROLE_ITEM = Qt.ItemDataRole.UserRole + 1
#: The outline's groups: (kind, title, the editor's completion kind for the icon)
GROUPS = ((kinds.PROCEDURE, "Procedures", KIND_PROCEDURE),
          (kinds.DEFINE, "Defines", KIND_DEFINE),
          (kinds.VARIABLE, "Variables", KIND_VARIABLE))
#: Texts larger than this are not outlined (reading their names would hold up typing).
MAX_OUTLINE_CHARS = 200_000


def _kind_icon(kind: int) -> QIcon:
    letter, colour = KIND_LOOK[kind]
    data = rgba_image(letter, colour)
    img = QImage(data, 14, 14, QImage.Format.Format_RGBA8888).copy()
    return QIcon(QPixmap.fromImage(img))


class OutlinePanel(QWidget):
    """The outline of the current editor."""

    sig_goto = Signal(int, int)
    """Go to this place of the current editor: line, column (1-based)."""

    def __init__(self, parent=None, delay_ms: int = 400):
        super().__init__(parent)
        self.editor = None
        self.items: list[OutlineItem] = []
        self._icons = {kind: _kind_icon(k) for kind, _t, k in GROUPS}
        self.note = QLabel("No file open", self)
        self.note.setContentsMargins(6, 3, 6, 3)
        self.tree = QTreeWidget(self)
        self.tree.setHeaderHidden(True)
        self.tree.setColumnCount(2)
        self.tree.setUniformRowHeights(True)
        self.tree.itemClicked.connect(self._on_item)
        self.tree.itemActivated.connect(self._on_item)
        lay = QVBoxLayout(self)
        lay.setContentsMargins(0, 0, 0, 0)
        lay.setSpacing(0)
        lay.addWidget(self.note)
        lay.addWidget(self.tree)
        self._timer = QTimer(self)
        self._timer.setSingleShot(True)
        self._timer.setInterval(delay_ms)
        self._timer.timeout.connect(self.refresh)
        self._following = False
        #: while held (the window's start), a new editor is outlined on release()
        self.held = False
        self._stale = False

    # ------------------------------------------------------------ public
    def set_editor(self, ed) -> None:
        """Outline this editor (None: no file)."""
        if self.editor is ed:
            return
        if self.editor is not None:
            for sig, slot in ((self.editor.sig_text_changed, self._timer.start),
                              (self.editor.sig_cursor_moved, self.follow)):
                try:
                    sig.disconnect(slot)
                except (RuntimeError, TypeError):
                    pass
        self.editor = ed
        if ed is not None:
            ed.sig_text_changed.connect(self._timer.start)
            ed.sig_cursor_moved.connect(self.follow)
        if self.held:
            self._stale = True
            return
        self.refresh()

    def release(self) -> None:
        """No more held: outline the editor set meanwhile."""
        self.held = False
        if self._stale:
            self._stale = False
            self.refresh()

    def refresh(self) -> None:
        """Read the editor's text again and rebuild the outline."""
        self._timer.stop()
        ed = self.editor
        self.tree.clear()
        self.items = []
        if ed is None:
            self.note.setText("No file open")
            self.note.show()
            return
        if ed.length() > MAX_OUTLINE_CHARS:
            self.note.setText(f"{Path(ed.path).name} is too large to outline "
                              f"(over {MAX_OUTLINE_CHARS // 1000} kB)")
            self.note.show()
            return
        text = ed.text()
        from plcbuilder.lang import symbols as lang_symbols    # (not needed to start up)
        idx = lang_symbols.index(text, ed.path)
        self.items = idx.outline()
        bold = QFont(self.tree.font())
        bold.setBold(True)
        for kind, title, _k in GROUPS:
            members = [it for it in self.items if it.kind == kind]
            if not members:
                continue
            group = QTreeWidgetItem([f"{title} ({len(members)})", ""])
            group.setFont(0, bold)
            group.setFlags(group.flags() & ~Qt.ItemFlag.ItemIsSelectable)
            self.tree.addTopLevelItem(group)
            for it in members:
                label = f"{it.name}()" if kind == kinds.PROCEDURE else it.name
                child = QTreeWidgetItem([label, it.detail])
                child.setIcon(0, self._icons[kind])
                child.setData(0, ROLE_ITEM, it)
                child.setToolTip(0, f"line {it.line}" + (f"–{it.end_line}"
                                                          if it.end_line != it.line else ""))
                child.setForeground(1, QColor("#7f7f7f"))
                group.addChild(child)
            group.setExpanded(True)
        self.tree.resizeColumnToContents(0)
        if self.items:
            self.note.hide()
        else:
            self.note.setText("Nothing defined in this file")
            self.note.show()
        if ed is not None:
            self.follow(*ed.cursor_line_col())

    def follow(self, line: int, _col: int = 1) -> None:
        """Select the entry of ``line``: one defined on it, else the procedure around it."""
        best = None
        for group_i in range(self.tree.topLevelItemCount()):
            group = self.tree.topLevelItem(group_i)
            for i in range(group.childCount()):
                child = group.child(i)
                it: OutlineItem = child.data(0, ROLE_ITEM)
                if it.line == line and it.kind != kinds.PROCEDURE:
                    best = child
                    break
                if it.kind == kinds.PROCEDURE and it.line <= line <= it.end_line \
                        and best is None:
                    best = child
            if best is not None and best.data(0, ROLE_ITEM).line == line:
                break
        self._following = True
        try:
            if best is None:
                self.tree.clearSelection()
                self.tree.setCurrentItem(None)
            elif self.tree.currentItem() is not best:
                self.tree.setCurrentItem(best)
                self.tree.scrollToItem(best)
        finally:
            self._following = False

    def selected(self) -> Optional[OutlineItem]:
        item = self.tree.currentItem()
        return item.data(0, ROLE_ITEM) if item is not None else None

    def item_named(self, name: str) -> Optional[QTreeWidgetItem]:
        for group_i in range(self.tree.topLevelItemCount()):
            group = self.tree.topLevelItem(group_i)
            for i in range(group.childCount()):
                if group.child(i).data(0, ROLE_ITEM).name == name:
                    return group.child(i)
        return None

    # ------------------------------------------------------------ private
    def _on_item(self, item: QTreeWidgetItem, _col: int = 0) -> None:
        it = item.data(0, ROLE_ITEM)
        if it is not None and not self._following:
            self.sig_goto.emit(it.line, it.col)
