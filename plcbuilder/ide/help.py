"""Help: the manual (``docs/*.md``) in a window of its own, and the list of
keyboard shortcuts, made from the window's actions.

The manual is found beside the package in a checkout (``docs/``) and, from an
installed wheel, where the wheel puts it (``share/plcbuilder/docs`` under the
installation's data folder); ``PLCBUILDER_DOCS`` overrides both. Links between
chapters open the chapter (at its heading); links out of the manual open in
the browser.
"""

from __future__ import annotations

import os
import re
import sys
import sysconfig
from pathlib import Path
from typing import Iterable, Optional

from PySide6.QtCore import QEvent, Qt, QTimer, QUrl
from PySide6.QtGui import QDesktopServices, QImageReader, QKeySequence, QTextCursor
from PySide6.QtWidgets import (QDialog, QHeaderView, QLabel, QLineEdit, QListWidget,
                               QListWidgetItem, QSplitter, QTableWidget, QTableWidgetItem,
                               QTextBrowser, QVBoxLayout, QWidget)

from plcbuilder.ide.icons import icon

#: The chapters first in the list, in this order; the others follow by name.
CHAPTER_ORDER = ("ide", "projects", "language", "controller", "machine", "tests")


def docs_dirs() -> list[Path]:
    """Where the manual may be, in the order they are tried."""
    out = []
    env = os.environ.get("PLCBUILDER_DOCS")
    if env:
        out.append(Path(env))
    import plcbuilder
    out.append(Path(plcbuilder.__file__).resolve().parent.parent / "docs")     # a checkout
    for base in (sysconfig.get_path("data"), sys.prefix, getattr(sys, "base_prefix", "")):
        if base:
            out.append(Path(base) / "share" / "plcbuilder" / "docs")            # a wheel
    try:
        import site
        out.append(Path(site.getuserbase()) / "share" / "plcbuilder" / "docs")
    except Exception:  # noqa: BLE001 - no user site
        pass
    return out


def find_docs() -> Optional[Path]:
    """The folder of the manual, or None when it is nowhere to be found."""
    for d in docs_dirs():
        if (d / "ide.md").is_file():
            return d
    return None


def chapter_title(path: Path) -> str:
    try:
        for line in path.read_text(encoding="utf-8").splitlines():
            if line.startswith("# "):
                return line[2:].strip().replace("`", "")
    except OSError:
        pass
    return path.stem


def chapters(folder: Path) -> list[Path]:
    files = sorted(folder.glob("*.md"))
    order = {name: i for i, name in enumerate(CHAPTER_ORDER)}
    return sorted(files, key=lambda p: (order.get(p.stem, len(order)), p.stem))


def slug(heading: str) -> str:
    """GitHub's anchor of a heading (as the manual's own links use them)."""
    text = re.sub(r"!?\[([^\]]*)\]\([^)]*\)", r"\1", heading)
    text = re.sub(r"<[^>]+>", "", text).replace("`", "")
    return re.sub(r"[^\w\- ]", "", text.lower()).replace(" ", "-")


class HelpWindow(QWidget):
    """The manual: its chapters on the left, the chapter on the right."""

    def __init__(self, parent=None, folder: Optional[Path] = None):
        super().__init__(parent, Qt.WindowType.Window)
        self.setWindowTitle("PLC Builder Manual")
        self.setWindowIcon(icon("app"))
        self.folder = folder if folder is not None else find_docs()
        self.current: Optional[Path] = None
        self.list = QListWidget(self)
        self.browser = QTextBrowser(self)
        self.browser.setOpenLinks(False)
        self.browser.viewport().installEventFilter(self)
        self._fit_due = False
        self.browser.anchorClicked.connect(self._on_link)
        split = QSplitter(self)
        split.addWidget(self.list)
        split.addWidget(self.browser)
        split.setStretchFactor(1, 1)
        split.setSizes([240, 760])
        lay = QVBoxLayout(self)
        lay.setContentsMargins(0, 0, 0, 0)
        lay.addWidget(split)
        self.resize(1000, 720)
        if self.folder is None:
            tried = "\n".join(f"  {d}" for d in docs_dirs())
            self.browser.setPlainText("The manual was not found. PLC Builder looked in:\n\n"
                                      f"{tried}\n\nSet PLCBUILDER_DOCS to its folder.")
            return
        self.browser.setSearchPaths([str(self.folder)])
        for p in chapters(self.folder):
            item = QListWidgetItem(chapter_title(p))
            item.setData(Qt.ItemDataRole.UserRole, str(p))
            self.list.addItem(item)
        self.list.currentItemChanged.connect(
            lambda item, _prev: item is not None and self.open_chapter(
                Path(item.data(Qt.ItemDataRole.UserRole))))
        if self.list.count():
            self.list.setCurrentRow(0)

    def open_chapter(self, path: Path, anchor: str = "") -> bool:
        """Show a chapter (at the heading whose anchor is ``anchor``)."""
        try:
            text = path.read_text(encoding="utf-8")
        except OSError as exc:
            self.browser.setPlainText(f"Cannot read {path}: {exc.strerror or exc}")
            return False
        if self.current != path:
            self.current = path
            self.browser.setSearchPaths([str(path.parent)])
            self.browser.document().setBaseUrl(QUrl.fromLocalFile(str(path)))
            self.browser.setMarkdown(text)
            self._one_picture_each()
            self.fit_images()
            for i in range(self.list.count()):
                if self.list.item(i).data(Qt.ItemDataRole.UserRole) == str(path):
                    self.list.blockSignals(True)
                    self.list.setCurrentRow(i)
                    self.list.blockSignals(False)
        if anchor:
            return self.scroll_to_heading(anchor)
        self.browser.verticalScrollBar().setValue(0)
        return True

    def eventFilter(self, obj, event) -> bool:  # noqa: N802 - Qt override
        """The view's width changed: the pictures fit it again (fitted only
        when the window was resized, they kept the width of a view not laid
        out yet: 200 px on a real desktop)."""
        if event.type() == QEvent.Type.Resize and obj is self.browser.viewport() \
                and self.current is not None and not self._fit_due:
            # after the resize is over (a picture fitted now can make the
            # scroll bar come or go, and the view narrower again)
            self._fit_due = True
            QTimer.singleShot(0, self, self._fit_now)
        return False

    def _fit_now(self) -> None:
        self._fit_due = False
        if self.current is not None:
            self.fit_images()

    def fit_images(self) -> int:
        """Scale the chapter's pictures down to the width of the view (the
        screenshots are larger than it); returns how many were scaled."""
        doc = self.browser.document()
        widest = max(200, self.browser.viewport().width() - 40)
        n = 0
        block = doc.begin()
        while block.isValid():
            it = block.begin()
            while not it.atEnd():
                frag = it.fragment()
                fmt = frag.charFormat()
                if frag.isValid() and fmt.isImageFormat():
                    img_fmt = fmt.toImageFormat()
                    size = QImageReader(self._image_path(img_fmt.name())).size()
                    want = min(widest, size.width()) if size.isValid() else 0
                    if want and abs(img_fmt.width() - want) > 0.5:
                        img_fmt.setWidth(want)
                        img_fmt.setHeight(size.height() * want / size.width())
                        cur = QTextCursor(doc)
                        cur.setPosition(frag.position())
                        cur.setPosition(frag.position() + frag.length(),
                                        QTextCursor.MoveMode.KeepAnchor)
                        cur.setCharFormat(img_fmt)
                        n += 1
                it += 1
            block = block.next()
        return n

    def _one_picture_each(self) -> int:
        """Qt's Markdown reader makes a picture of every piece of an image's
        alt text (a long one, over several lines, gave a dozen copies side by
        side, issue 23.7): keep the first of each run of the same picture.
        Returns how many copies went."""
        doc = self.browser.document()
        extra: list[tuple[int, int]] = []          # (position, length) to delete
        block = doc.begin()
        while block.isValid():
            last_name, last_end = None, -1
            it = block.begin()
            while not it.atEnd():
                frag = it.fragment()
                fmt = frag.charFormat()
                if frag.isValid() and fmt.isImageFormat():
                    name = fmt.toImageFormat().name()
                    start, length = frag.position(), frag.length()
                    if name == last_name and start == last_end:
                        extra.append((start, length))
                    elif length > 1:
                        extra.append((start + 1, length - 1))
                    last_name, last_end = name, start + length
                else:
                    last_name = None
                it += 1
            block = block.next()
        cur = QTextCursor(doc)
        for start, length in reversed(extra):
            cur.setPosition(start)
            cur.setPosition(start + length, QTextCursor.MoveMode.KeepAnchor)
            cur.removeSelectedText()
        doc.setModified(False)
        return sum(n for _s, n in extra)

    def _image_path(self, name: str) -> str:
        p = Path(QUrl(name).toLocalFile() or name)
        if not p.is_absolute() and self.current is not None:
            p = self.current.parent / p
        return str(p)

    def open_named(self, stem: str, anchor: str = "") -> bool:
        if self.folder is None:
            return False
        return self.open_chapter(self.folder / f"{stem}.md", anchor)

    def scroll_to_heading(self, anchor: str) -> bool:
        """Scroll to the heading with this anchor (GitHub's slug of its text)."""
        block = self.browser.document().begin()
        while block.isValid():
            if block.blockFormat().headingLevel() > 0 and slug(block.text()) == anchor:
                cur = QTextCursor(block)
                self.browser.setTextCursor(cur)
                bar = self.browser.verticalScrollBar()
                bar.setValue(bar.maximum())               # then back: the heading ends on top
                self.browser.ensureCursorVisible()
                return True
            block = block.next()
        return False

    def headings(self) -> list[str]:
        out = []
        block = self.browser.document().begin()
        while block.isValid():
            if block.blockFormat().headingLevel() > 0:
                out.append(block.text())
            block = block.next()
        return out

    def _on_link(self, url: QUrl) -> None:
        if url.scheme() in ("http", "https", "mailto"):
            QDesktopServices.openUrl(url)
            return
        target = url.path() or (str(self.current) if self.current else "")
        anchor = url.fragment()
        p = Path(target)
        if not p.is_absolute() and self.current is not None:
            p = self.current.parent / p
        if p.suffix == ".md" and p.is_file():
            self.open_chapter(p.resolve(), anchor)
        elif not url.path() and anchor:
            self.scroll_to_heading(anchor)
        elif p.exists():
            QDesktopServices.openUrl(QUrl.fromLocalFile(str(p)))


# ------------------------------------------------------------ shortcuts
def shortcut_rows(actions: Iterable) -> list[tuple[str, str, str]]:
    """(action, keys, what it does) of every action that has a shortcut, in
    the order given; the text loses its ``&`` and trailing dots."""
    out = []
    for act in actions:
        keys = [k.toString(QKeySequence.SequenceFormat.NativeText) for k in act.shortcuts()]
        keys = [k for k in keys if k]
        if not keys:
            continue
        text = act.text().replace("&&", "\0").replace("&", "").replace("\0", "&").rstrip(".…")
        out.append((text, ", ".join(keys), act.statusTip()))
    return out


class ShortcutsDialog(QDialog):
    """Help → Keyboard Shortcuts: the keys of the window's actions, searchable."""

    def __init__(self, parent, actions: Iterable):
        super().__init__(parent)
        self.setWindowTitle("Keyboard Shortcuts")
        self.rows = shortcut_rows(actions)
        self.search = QLineEdit(self)
        self.search.setPlaceholderText("Search actions and keys…")
        self.search.setClearButtonEnabled(True)
        self.table = QTableWidget(len(self.rows), 3, self)
        self.table.setHorizontalHeaderLabels(["Action", "Keys", "What it does"])
        self.table.verticalHeader().hide()
        self.table.verticalHeader().setDefaultSectionSize(self.table.fontMetrics().height() + 8)
        self.table.setWordWrap(False)
        self.table.setAlternatingRowColors(True)
        self.table.setEditTriggers(QTableWidget.EditTrigger.NoEditTriggers)
        self.table.setSelectionBehavior(QTableWidget.SelectionBehavior.SelectRows)
        for r, (text, keys, tip) in enumerate(self.rows):
            for c, v in enumerate((text, keys, tip)):
                self.table.setItem(r, c, QTableWidgetItem(v))
        self.table.resizeColumnsToContents()
        self.table.horizontalHeader().setSectionResizeMode(2, QHeaderView.ResizeMode.Stretch)
        self.search.textChanged.connect(self._filter)
        lay = QVBoxLayout(self)
        lay.addWidget(self.search)
        lay.addWidget(self.table)
        lay.addWidget(QLabel("Editor keys of the text itself (Alt+Up/Down moves lines, "
                             "Ctrl+Shift+K deletes one) are in the manual's IDE chapter.", self))
        self.resize(760, 560)

    def _filter(self, text: str) -> None:
        t = text.strip().lower()
        for r, row in enumerate(self.rows):
            self.table.setRowHidden(r, bool(t) and not any(t in v.lower() for v in row))
