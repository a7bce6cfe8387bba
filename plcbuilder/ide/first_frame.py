"""The IDE's first frame: the project's tree and its front file, on screen
while the IDE's window is made.

Making the IDE's window (Scintilla and the highlighter, the docks, menus and
toolbars, the project's editors) takes about three times as long as a bare Qt
window takes to appear, and a window of those widget kinds with none of our
code already takes 1.5 times as long. When PLC Builder starts with a project,
this plain window shows first, where the IDE's window will be: the project's
procedures and headers, the session's tabs and the file that was in front,
read-only, and "Opening NAME…" in its status bar. The IDE's window is made
while it shows, takes its place at the same geometry, and the frame goes.

Nothing is lost meanwhile: keys typed into the frame are kept and given, in
order, to the editor that shows the same file once it is there (or to the
window's focus); a shortcut (a key with Ctrl, Alt or Meta) is not run on a
window that was not there, and the window's status bar names it. Closing the
frame quits before the IDE's window is shown. The preference
``first_frame`` (Preferences › Files & Build) turns it off.

Before its paint the frame does without the Python types whose first use
makes big enum classes: the ``Qt`` namespace (93 classes, 35 ms), QStyle (the
light theme's palette comes after the paint), QFont and the text formats (the
text, its font and line height are given as HTML).
"""

from __future__ import annotations

import html
import os
from pathlib import Path
from typing import Callable, Optional

from PySide6.QtCore import QEvent, QObject, QPoint, QRect, QTimer
from PySide6.QtGui import QKeyEvent
from PySide6.QtWidgets import (QApplication, QMainWindow, QTextEdit, QSplitter, QTabBar,
                               QTreeWidget, QTreeWidgetItem, QVBoxLayout, QWidget)

from plcbuilder.ide.icons import icon

__all__ = ["FirstFrame", "HARDWARE_GROUP", "HEADERS_GROUP", "MENU_TITLES", "SOFTWARE_GROUP",
           "TARGET_LABEL", "frame_title", "procedure_icon", "session_files"]

#: the main window's menus, left to right (actions.build_menus, debug/actions.py)
MENU_TITLES = ("&File", "&Edit", "&Go", "&View", "&Build", "&Run", "&Debug", "&Help")
#: the project tree's groups, (label, icon) (plcbuilder.ide.project_tree's too)
HARDWARE_GROUP = ("Hardware PLC", "folder-hw")
SOFTWARE_GROUP = ("Software PLC", "folder-sw")
HEADERS_GROUP = ("Headers", "folder")
#: the tree's label of the hardware procedures for a target other than myCNC
TARGET_LABEL = {"huazhong": "Huazhong PLC", "tgmotion": "TG Motion PLC"}
#: the application's name in titles (also welcome.APP_NAME)
APP_NAME = "PLC Builder"
#: where a QTextDocument's text starts in its widget (its default margin)
DOCUMENT_MARGIN = 4
#: the most of the front file the frame shows: its start (the editor opens at
#: its top; the frame is read-only and goes within a second)
MAX_TEXT, MAX_LINES = 64 * 1024, 400


def frame_title(file: Optional[str], project: Optional[str]) -> str:
    """The window title for the front file and project (the main window's too)."""
    parts = [Path(file).name + "[*]"] if file else []
    if project:
        parts.append(project)
    return " — ".join(parts + [APP_NAME])


def procedure_icon(hardware: bool, system: bool) -> str:
    """The project tree's icon of a procedure (system: a software __NAME one)."""
    return "file-plc" if hardware else "file-plc-sys" if system else "file-plc-sw"


def session_files(settings, folder: Path) -> tuple[list[str], str]:
    """The last session's editors of the project at ``folder`` that still
    exist, and the one in front ('' when none): what the frame shows and the
    main window opens."""
    from plcbuilder.lang.builtin_headers import BUILTIN_PREFIX
    files = [f for f in settings.open_files(folder)
             if f.startswith(BUILTIN_PREFIX) or os.path.exists(f)]
    current = settings.current_file(folder)
    return files, current if current in files else ""


def _project_names(folder: Path) -> tuple[str, str]:
    """The project's name and target from its settings file (the folder's name
    and myCNC when it cannot be read: the IDE's window says why)."""
    try:
        import tomllib
        with open(folder / "plcbuilder.toml", "rb") as f:
            data = tomllib.load(f)
        name, target = data.get("name"), data.get("target", "mycnc")
        return (name if isinstance(name, str) and name else folder.name,
                target if isinstance(target, str) else "mycnc")
    except (OSError, ValueError):
        return folder.name, "mycnc"


def _names(folder: Path, suffix: str) -> list[tuple[str, str]]:
    """(name, path) of the files of ``folder`` ending in ``suffix``, by name."""
    try:
        with os.scandir(folder) as it:
            found = [(e.name, e.path) for e in it if e.name.endswith(suffix) and e.is_file()]
    except OSError:
        return []
    return sorted(found)


class _Keys(QObject):
    """Keeps the keys typed into the frame (and keeps them from it)."""

    def __init__(self, frame: "FirstFrame"):
        super().__init__(frame)
        self.frame = frame
        self.kept: list[tuple] = []
        self.watching = False

    def _widgets(self) -> tuple:
        """The frame's widgets that can have the keyboard, and the frame."""
        f = self.frame
        return (f, f.tree, f.text, f.tabs, f.menuBar())

    def watch(self) -> None:
        """Keep the keys from now on."""
        for w in self._widgets():
            w.installEventFilter(self)
        self.watching = True

    def unwatch(self) -> None:
        for w in self._widgets():
            w.removeEventFilter(self)
        self.watching = False

    def eventFilter(self, obj, event) -> bool:  # noqa: N802 - Qt override
        t = event.type()
        if t in (QEvent.Type.KeyPress, QEvent.Type.KeyRelease, QEvent.Type.ShortcutOverride):
            if t != QEvent.Type.ShortcutOverride:
                self.kept.append((t, event.key(), event.modifiers(), event.text(),
                                  event.isAutoRepeat(), event.count()))
            return True
        return False


class FirstFrame(QMainWindow):
    """The first frame of the project at ``folder`` (see the module)."""

    def __init__(self, settings, folder: Path, *, front: Optional[Path] = None,
                 font_family: str = "", font_size: int = 11):
        super().__init__()
        self.folder = Path(folder)
        self.cancelled = False              # closed before the IDE's window took over
        self.handed_over = False
        self._on_paint: Optional[Callable[[], None]] = None
        self._painted = False
        name, target = _project_names(self.folder)
        self.files, self.current = session_files(settings, self.folder)
        if front is not None:                # a file the IDE opens with the project
            self.current = str(Path(front).resolve())
            if self.current not in self.files:
                self.files.append(self.current)
        self.setWindowTitle(frame_title(self.current, name))
        self.setWindowIcon(icon("app"))
        geom, _state = settings.window_state()
        if geom is None or not self.restoreGeometry(geom):
            self.resize(1360, 860)
        for title in MENU_TITLES:
            self.menuBar().addMenu(title)

        self.tree = QTreeWidget()
        self.tree.setHeaderHidden(True)
        self._fill_tree(name, target)
        self.tabs = QTabBar()
        self.tabs.setDocumentMode(True)
        self.tabs.setExpanding(False)
        for f in self.files:
            self.tabs.addTab(Path(f).name)
        if self.current:
            self.tabs.setCurrentIndex(self.files.index(self.current))
        sketch = settings.frame_sketch()
        placed = sketch is not None and sketch["size"] == (self.width(), self.height())
        self.text = QTextEdit()
        self.text.setReadOnly(True)
        self.text.setLineWrapMode(QTextEdit.LineWrapMode.NoWrap)
        self._show_text(self._front_text(), font_family, font_size,
                        sketch["text"] if placed else (0, 0))
        right = QWidget()
        lay = QVBoxLayout(right)
        lay.setContentsMargins(0, 0, 0, 0)
        lay.setSpacing(0)
        lay.addWidget(self.tabs)
        lay.addWidget(self.text)
        if placed:
            # where the window had them: they stay put as the window takes over
            self.setCentralWidget(_Placed({self.tree: sketch["tree"], right: sketch["editor"]}))
        else:
            split = QSplitter()
            split.addWidget(self.tree)
            split.addWidget(right)
            split.setSizes([max(230, min(360, int(self.width() * 0.22))), self.width()])
            split.setStretchFactor(1, 1)
            self.setCentralWidget(split)
        self.statusBar().showMessage(f"Opening {name}…")
        # the keys are kept from the paint on (a filter in Python before it would
        # take part in every event of the window's first show: its cost)
        self.keys = _Keys(self)

    # ----------------------------------------------------------------- view
    def _fill_tree(self, name: str, target: str) -> None:
        root = QTreeWidgetItem(self.tree, [name])
        root.setIcon(0, icon("project"))
        root.setToolTip(0, str(self.folder))
        f = root.font(0)
        f.setBold(True)
        root.setFont(0, f)
        groups = ((TARGET_LABEL.get(target, HARDWARE_GROUP[0]), HARDWARE_GROUP[1], "hardware",
                   ".plc"), (*SOFTWARE_GROUP, "software", ".plc"), (*HEADERS_GROUP, "include", ".h"))
        for label, ic, sub, suffix in groups:
            names = _names(self.folder / sub, suffix)
            if sub == "software" and target != "mycnc" and not names:
                continue
            group = QTreeWidgetItem(root, [label])
            group.setIcon(0, icon(ic))
            for fname, path in names:
                stem = fname[:-len(suffix)]
                shown = fname if suffix == ".h" else stem
                kind = "file-header" if suffix == ".h" else \
                    procedure_icon(sub == "hardware", stem.startswith("__"))
                item = QTreeWidgetItem(group, [shown])
                item.setIcon(0, icon(kind))
                item.setToolTip(0, path)
                if path == self.current:
                    self.tree.setCurrentItem(item)
            group.setExpanded(True)
        root.setExpanded(True)

    def _show_text(self, text: str, family: str, size: int, where: tuple) -> None:
        """The file's text in the editor's font (a monospace one when none is
        set, as the editor's) and, with ``where`` = (x, line height) from the
        window's sketch, where the editor's text will be: right of its margins,
        its lines as high (0: not known). Given as HTML: the font, size and
        line height without the Python types of QFont and the text formats
        (each first use makes their enum classes)."""
        x, line_height = where
        if x > DOCUMENT_MARGIN:
            self.text.setViewportMargins(x - DOCUMENT_MARGIN, 0, 0, 0)
        family = family.replace("'", "").replace('"', "")
        face = f"'{family}', monospace" if family else "monospace"
        style = f"margin:0; font-family:{face}; font-size:{int(size)}pt" + \
            (f"; line-height:{int(line_height)}px" if line_height > 0 else "")
        self.text.setHtml(f'<pre style="{style}">{html.escape(text, quote=False)}</pre>')

    def _front_text(self) -> str:
        if not self.current or not os.path.isfile(self.current):
            return ""
        try:
            with open(self.current, "rb") as f:
                data = f.read(MAX_TEXT + 1)
        except OSError:
            return ""
        text = data[:MAX_TEXT].decode("utf-8", errors="replace")
        return "\n".join(text.split("\n", MAX_LINES)[:MAX_LINES])

    # ------------------------------------------------------------ hand-over
    def after_paint(self, then: Callable[[], None]) -> None:
        """Call ``then`` once the frame has painted (at the event loop's turn
        after its first paint pass)."""
        self._on_paint = then

    def paintEvent(self, event) -> None:  # noqa: N802 - Qt override
        super().paintEvent(event)
        if not self._painted:
            self._painted = True
            QTimer.singleShot(0, self._painted_now)

    def _painted_now(self) -> None:
        self.keys.watch()
        then, self._on_paint = self._on_paint, None
        if then is not None and not self.cancelled:
            from PySide6.QtCore import Qt        # after the paint: the namespace is due anyway
            self.setCursor(Qt.CursorShape.BusyCursor)
            then()

    def hand_over(self, win) -> None:
        """Show the IDE's window ``win`` in the frame's place; once it has
        painted, the frame goes and the keys typed into it go to ``win``."""
        self.handed_over = True
        if self.isMaximized() or self.isFullScreen():
            win.restoreGeometry(self.saveGeometry())
        else:
            # exactly the frame's place (a geometry restored from the frame's
            # would be moved by the guess of a window frame it makes)
            win.setGeometry(self.geometry())
        watch = _PaintWatch(win, lambda: self._done(win))
        win.installEventFilter(watch)
        win.show()

    def _done(self, win) -> None:
        self.keys.unwatch()
        kept, self.keys.kept = self.keys.kept, []
        self.hide()
        if not win.isActiveWindow():
            win.activateWindow()
        if kept:
            self._give_keys(win, kept)
        self.deleteLater()

    def _give_keys(self, win, kept: list) -> None:
        """The keys typed into the frame, to ``win``: keys with Ctrl, Alt or
        Meta are commands (shortcuts), not run on a window that was not there
        yet, and named in its status bar; the others go to its editor."""
        from PySide6.QtCore import Qt
        from PySide6.QtGui import QKeySequence
        mod = Qt.KeyboardModifier
        command = mod.ControlModifier | mod.AltModifier | mod.MetaModifier
        typed = [k for k in kept if not k[2] & command]
        if typed:
            target = self._key_target(win)
            for t, key, mods, text, auto, count in typed:
                QApplication.postEvent(target, QKeyEvent(t, key, mods, text, auto, count))
        alone = {Qt.Key.Key_Control, Qt.Key.Key_Alt, Qt.Key.Key_Meta, Qt.Key.Key_Shift,
                 Qt.Key.Key_AltGr}                      # (a modifier pressed on its own)
        commands = [QKeySequence(k[1] | k[2].value).toString(QKeySequence.SequenceFormat.NativeText)
                    for k in kept if k[2] & command and k[0] == QEvent.Type.KeyPress
                    and k[1] not in alone]
        if commands:
            win.statusBar().showMessage(
                "Not run (typed while the window opened): " + ", ".join(commands), 10000)

    def _key_target(self, win):
        """The editor of the frame's front file (else the window's focus)."""
        ed = win.editor_for(self.current) if self.current else None
        if ed is None:
            ed = win.current_editor()
        if ed is not None:
            win.tabs.setCurrentWidget(ed)
            QWidget.setFocus(ed)                 # (Scintilla's own setFocus is another)
            return ed
        return win.focusWidget() or win

    def closeEvent(self, event) -> None:  # noqa: N802 - Qt override
        if not self.handed_over:
            self.cancelled = True
        event.accept()


class _Placed(QWidget):
    """A central widget whose children stand at given places of the window
    (x, y, width, height in the window's coordinates)."""

    def __init__(self, places: dict):
        super().__init__()
        self.places = places
        for w in places:
            w.setParent(self)

    def resizeEvent(self, event) -> None:  # noqa: N802 - Qt override
        super().resizeEvent(event)
        at = self.mapTo(self.window(), QPoint(0, 0))
        for w, (x, y, width, height) in self.places.items():
            w.setGeometry(QRect(x - at.x(), y - at.y(), width, height))


class _PaintWatch(QObject):
    """Calls ``then`` at the event loop's turn after ``win``'s first paint."""

    def __init__(self, win, then: Callable[[], None]):
        super().__init__(win)
        self.then = then

    def eventFilter(self, obj, event) -> bool:  # noqa: N802 - Qt override
        if event.type() == QEvent.Type.Paint and self.then is not None:
            then, self.then = self.then, None
            obj.removeEventFilter(self)
            QTimer.singleShot(0, then)
        return False
