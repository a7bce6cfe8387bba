"""Quick Open (Ctrl+P): type a few letters of a file's name, pick it, Enter.

Matching is fuzzy: the letters typed must appear in the file name in order
(``m3`` finds ``M03.plc``, ``hinit`` finds ``__HANDLER_INIT.plc``); a query
with a ``/`` is matched against the path in the project. Better matches come
first: letters that follow each other, that start words, that start the name.
"""

from __future__ import annotations

from pathlib import Path
from typing import Optional, Sequence

from PySide6.QtCore import Qt
from PySide6.QtWidgets import (QDialog, QLabel, QLineEdit, QListWidget, QListWidgetItem,
                               QVBoxLayout)

from plcbuilder.ide.icons import icon

ROLE_PATH = Qt.ItemDataRole.UserRole + 1
MAX_LISTED = 200


def fuzzy_score(query: str, candidate: str) -> Optional[int]:
    """How well ``query`` matches ``candidate`` (higher is better), or None
    when its letters do not all appear in order. Case is ignored."""
    q, c = query.lower(), candidate.lower()
    if not q:
        return 0
    score = 0
    pos = -1
    prev = -2
    for ch in q:
        i = c.find(ch, pos + 1)
        if i < 0:
            return None
        if i == prev + 1:
            score += 5                       # follows the letter before
        if i == 0:
            score += 8                       # starts the name
        elif not candidate[i - 1].isalnum() or (candidate[i].isupper() and
                                                candidate[i - 1].islower()):
            score += 4                       # starts a word
        score -= min(i - pos - 1, 5)         # a gap
        pos = prev = i
    if c.startswith(q):
        score += 10
    return score - len(candidate) // 10


def rank(query: str, files: Sequence[tuple[str, str]]) -> list[tuple[str, str]]:
    """The (path, shown path) pairs that match, best first (then by name)."""
    scored = []
    for path, shown in files:
        target = shown if "/" in query else Path(shown).name
        s = fuzzy_score(query.replace(" ", ""), target)
        if s is not None:
            scored.append((-s, shown.lower(), path, shown))
    scored.sort()
    return [(p, sh) for _s, _k, p, sh in scored]


class QuickOpenDialog(QDialog):
    """A search box over the project's files."""

    def __init__(self, parent, files: Sequence[tuple[str, str]]):
        super().__init__(parent)
        self.setWindowTitle("Quick Open")
        self.files = list(files)
        self.edit = QLineEdit(self)
        self.edit.setPlaceholderText("File name (letters in order: m3 finds M03.plc)")
        self.list = QListWidget(self)
        self.list.setUniformItemSizes(True)
        self.note = QLabel("", self)
        lay = QVBoxLayout(self)
        lay.addWidget(self.edit)
        lay.addWidget(self.list)
        lay.addWidget(self.note)
        self.edit.textChanged.connect(self.refresh)
        self.edit.returnPressed.connect(self.accept)
        self.list.itemActivated.connect(lambda _i: self.accept())
        self.edit.installEventFilter(self)
        self.resize(520, 380)
        self.refresh()

    def refresh(self) -> None:
        self.list.clear()
        hits = rank(self.edit.text(), self.files)
        for path, shown in hits[:MAX_LISTED]:
            item = QListWidgetItem(icon("file-header" if path.endswith(".h") else
                                        "file-plc" if path.endswith(".plc") else "file"),
                                   f"{Path(shown).name}    {shown}")
            item.setData(ROLE_PATH, path)
            self.list.addItem(item)
        if hits:
            self.list.setCurrentRow(0)
        self.note.setText(f"{len(hits)} of {len(self.files)} files" if self.edit.text()
                          else f"{len(self.files)} files")

    def chosen(self) -> Optional[str]:
        item = self.list.currentItem()
        return item.data(ROLE_PATH) if item is not None else None

    def eventFilter(self, obj, event) -> bool:  # noqa: N802 - Qt override
        # Up/Down/PgUp/PgDn in the search box move through the list
        if obj is self.edit and event.type() == event.Type.KeyPress and event.key() in (
                Qt.Key.Key_Up, Qt.Key.Key_Down, Qt.Key.Key_PageUp, Qt.Key.Key_PageDown):
            self.list.keyPressEvent(event)
            return True
        return super().eventFilter(obj, event)

    @classmethod
    def get_file(cls, parent, files: Sequence[tuple[str, str]], text: str = "") -> Optional[str]:
        dlg = cls(parent, files)
        if text:
            dlg.edit.setText(text)
        if dlg.exec() != QDialog.DialogCode.Accepted:
            return None
        return dlg.chosen()
