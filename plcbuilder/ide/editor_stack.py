"""The editor stack: the tabbed editors (or the welcome page) over the find bar.

It opens, saves, reverts and closes editors (asking about unsaved changes),
follows the files on disk (:class:`~plcbuilder.ide.recovery.DiskWatcher`) and
keeps the recovery autosave (:class:`~plcbuilder.ide.recovery.RecoveryManager`).
What it knows nothing about — diagnostics, the project tree, the status bar —
it tells with signals; the main window wires them.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING, Callable, Optional

from PySide6.QtCore import Qt, Signal
from PySide6.QtWidgets import (QApplication, QMessageBox, QStackedWidget, QTabWidget, QVBoxLayout,
                               QWidget)

from plcbuilder import api
from plcbuilder._support.files import read_bounded
from plcbuilder.api import Kind
from plcbuilder.ide import dialogs
from plcbuilder.ide.editor import file_key, is_editor, normalise_newlines
from plcbuilder.ide.icons import icon, icon_path
from plcbuilder.ide.recovery import (MAX_EDIT_BYTES, DiskWatcher, RecoveryManager, digest,
                                     encode_text,
                                     file_digest, save_text)
from plcbuilder.ide.settings import Preferences
from plcbuilder.ide.welcome import WelcomePage
from plcbuilder.lang.builtin_headers import BUILTIN_PREFIX, builtin_header

if TYPE_CHECKING:
    from plcbuilder.ide.editor import CodeEditor


#: The editor tabs' look (the tab bar's own sheet: an application-wide one
#: would make every widget slower to build and paint).
TAB_SHEET = """
QTabBar::tab { padding: 5px 10px; }
QTabBar::close-button { image: url(%(close)s); subcontrol-position: right; }
QTabBar::close-button:hover { image: url(%(close_hover)s); }
"""


class EditorStack(QWidget):
    """The editors of the open files, as tabs (the welcome page when none)."""

    sig_message = Signal(str, int)
    """A message for the status bar (text, milliseconds to show it; 0: until the next)."""

    sig_editor_created = Signal(object)
    """A new editor (its CodeEditor): diagnostics and completion attach to it."""

    sig_editors_changed = Signal()
    """An editor was opened or closed (the actions follow)."""

    sig_current_changed = Signal(object)
    """Another editor is current (the CodeEditor, or None)."""

    sig_title_changed = Signal()
    """The current editor's name or modified state changed (the window title follows)."""

    sig_cursor_moved = Signal(int, int)
    """The caret of an editor moved (line, column; both from 1)."""

    sig_goto_definition = Signal(str)
    """Ctrl+click on a name in an editor (the name)."""

    sig_file_saved = Signal(str)
    """An editor was saved to its file (the path)."""

    sig_changes_discarded = Signal(str)
    """An editor closed without saving: the file on disk counts again (the path)."""

    sig_reveal = Signal(str)
    """"Show in Project" from a tab's menu (the path)."""

    def __init__(self, parent: QWidget, prefs: Preferences, recovery_dir: Path):
        super().__init__(parent)
        self.prefs = prefs
        self.project = None
        self.closing = False
        #: whether "Show in Project" applies to a path (the main window sets it)
        self.can_reveal: Callable[[str], bool] = lambda path: False
        #: the actions of an editor's context menu (the main window sets them)
        self.context_actions: list = []
        self._prompting: set[str] = set()
        self.disk = DiskWatcher(self)
        self.disk.sig_changed.connect(self._on_disk_changed)
        self.disk.sig_deleted.connect(self._on_disk_deleted)
        self.recovery = RecoveryManager(recovery_dir, self._recovery_snapshot, self,
                                        prefs.autosave_seconds)

        lay = QVBoxLayout(self)
        lay.setContentsMargins(0, 0, 0, 0)
        lay.setSpacing(0)
        self.stack = QStackedWidget(self)
        self.tabs = QTabWidget(self.stack)
        self.tabs.setObjectName("editorTabs")
        self.tabs.setDocumentMode(True)
        self.tabs.setTabsClosable(True)
        self.tabs.setMovable(True)
        self.tabs.setUsesScrollButtons(True)
        self.tabs.setElideMode(Qt.TextElideMode.ElideNone)
        self.tabs.tabCloseRequested.connect(lambda i: self.close_editor(self.tabs.widget(i)))
        bar = self.tabs.tabBar()
        bar.setContextMenuPolicy(Qt.ContextMenuPolicy.CustomContextMenu)
        bar.customContextMenuRequested.connect(self._tab_context_menu)
        bar.installEventFilter(self)
        self.tabs.currentChanged.connect(self._on_current_changed)
        self.welcome = WelcomePage()
        self.stack.addWidget(self.welcome)
        self.stack.addWidget(self.tabs)
        self._find_bar = None               # made when first opened (see find_bar)
        lay.addWidget(self.stack, 1)

    # ================================================================ public
    @property
    def find_bar(self):
        """The find/replace bar under the editors, made the first time it is
        opened or asked for (hidden until then: the first paint does not wait
        for it)."""
        if self._find_bar is None:
            from plcbuilder.ide.editor.find_bar import FindReplaceBar
            bar = self._find_bar = FindReplaceBar(self)        # hidden until opened
            bar.sig_message.connect(lambda m: self.sig_message.emit(m, 3000))
            self.layout().addWidget(bar)
            bar.set_editor(self.current_editor())
        return self._find_bar

    def editors(self) -> list[CodeEditor]:
        return [self.tabs.widget(i) for i in range(self.tabs.count())]

    def current_editor(self) -> Optional[CodeEditor]:
        w = self.tabs.currentWidget()
        return w if is_editor(w) else None

    def editor_for(self, path) -> Optional[CodeEditor]:
        key = file_key(path)
        for ed in self.editors():
            if file_key(ed.path) == key:
                return ed
        return None

    def is_modified(self, editor: CodeEditor) -> bool:
        return bool(editor.modify() or getattr(editor, "force_dirty", False))

    def modified_editors(self) -> list[CodeEditor]:
        return [ed for ed in self.editors() if self.is_modified(ed) and not ed.builtin]

    def open_file(self, path, line: Optional[int] = None, col: int = 1, *,
                  focus: bool = True) -> Optional[CodeEditor]:
        """Open (or show) a file in an editor tab, optionally at a line."""
        path = str(path)
        if not path.startswith(BUILTIN_PREFIX):
            path = self._resolve_path(path)
            if path is None:
                return None
        ed = self.editor_for(path)
        if ed is None:
            ed = self._create_editor(path)
            if ed is None:
                return None
        self.tabs.setCurrentWidget(ed)
        self.show_welcome()
        if line is not None:
            ed.goto_line(line, col)
        if focus:
            ed.take_focus()
        return ed

    def open_location(self, file: str, line: int, col: int = 1) -> Optional[CodeEditor]:
        """Open a diagnostic's or a fault's location (a path, a built-in header,
        or a name the compiler recorded relative to the procedure)."""
        return self.open_file(file, line, col)

    def save_editor(self, editor: Optional[CodeEditor] = None) -> bool:
        ed = editor or self.current_editor()
        if ed is None or ed.builtin:
            return False
        text = ed.text()
        data = encode_text(text, ed.eol)
        self.disk.set_digest(ed.path, digest(data))     # our own change: not "changed on disk"
        try:
            Path(ed.path).parent.mkdir(parents=True, exist_ok=True)
            save_text(ed.path, text, ed.eol)
        except OSError as exc:
            self.disk.set_digest(ed.path, file_digest(ed.path))
            QMessageBox.critical(self.window(), "Save", f"Cannot save {ed.path}:\n\n{exc}")
            return False
        ed.setSavePoint()
        ed.force_dirty = False
        self.recovery.discard(ed.path)
        self._update_tab(ed)
        self.sig_message.emit(f"Saved {Path(ed.path).name}", 3000)
        self.sig_file_saved.emit(ed.path)
        return True

    def save_all(self) -> bool:
        ok = True
        for ed in self.modified_editors():
            ok = self.save_editor(ed) and ok
        return ok

    def close_editor(self, editor: Optional[CodeEditor] = None, *, force: bool = False) -> bool:
        ed = editor or self.current_editor()
        if ed is None:
            return False
        if not force and self.is_modified(ed) and not ed.builtin:
            answer = self._ask_save([ed], "Close")
            if answer == QMessageBox.StandardButton.Cancel:
                return False
            if answer == QMessageBox.StandardButton.Save and not self.save_editor(ed):
                return False
        if self.is_modified(ed) and not ed.builtin:
            # closed without saving: what counts now is the file on disk
            self.recovery.discard(ed.path)
            self.sig_changes_discarded.emit(ed.path)
        self.disk.unwatch(ed.path)
        self.tabs.removeTab(self.tabs.indexOf(ed))
        ed.deleteLater()
        self.show_welcome()
        self.sig_editors_changed.emit()
        return True

    def close_all(self, force: bool = False) -> bool:
        if not force and not self.confirm_discard_all("Close All"):
            return False
        for ed in self.editors():
            if self.is_modified(ed):
                self.recovery.discard(ed.path)
            self.close_editor(ed, force=True)
        return True

    def confirm_discard_all(self, title: str) -> bool:
        """Ask about unsaved changes before they go: save them, discard them or cancel."""
        mod = self.modified_editors()
        if not mod:
            return True
        answer = self._ask_save(mod, title)
        if answer == QMessageBox.StandardButton.Cancel:
            return False
        if answer == QMessageBox.StandardButton.Save:
            return self.save_all()
        for ed in mod:
            self.recovery.discard(ed.path)
            ed.setSavePoint()
            ed.force_dirty = False
        return True

    def revert_editor(self, editor: Optional[CodeEditor] = None) -> bool:
        ed = editor or self.current_editor()
        if ed is None or ed.builtin or not Path(ed.path).exists():
            return False
        if self.is_modified(ed):
            answer = QMessageBox.question(
                self.window(), "Revert", f"Discard your changes to {Path(ed.path).name} and "
                                         "reload it from disk?", QMessageBox.StandardButton.Yes |
                QMessageBox.StandardButton.No, QMessageBox.StandardButton.No)
            if answer != QMessageBox.StandardButton.Yes:
                return False
        self._reload_editor(ed)
        return True

    def offer_recovery(self) -> int:
        """Offer back the unsaved changes a crashed session left (of this
        project); returns how many files were restored."""
        if self.project is None:
            return 0
        pending = self.recovery.pending(self.project.root)
        if not pending:
            return 0
        names = "\n".join(f"  • {_rel(p['path'], self.project.root)}" for p in pending)
        answer = QMessageBox.question(
            self.window(), "Recover Unsaved Changes",
            f"PLC Builder did not close properly last time. Unsaved changes to these files "
            f"were kept:\n\n{names}\n\nRestore them? (No discards the copies.)",
            QMessageBox.StandardButton.Yes | QMessageBox.StandardButton.No,
            QMessageBox.StandardButton.Yes)
        restored = 0
        for entry in pending:
            if answer == QMessageBox.StandardButton.Yes:
                ed = self.open_file(entry["path"], focus=False) if Path(entry["path"]).exists() \
                    else self._create_editor(entry["path"], text="", missing_ok=True)
                if ed is not None:
                    ed.set_text(normalise_newlines(entry["text"])[0], keep_undo=True)
                    if not ed.modify():
                        ed.force_dirty = True
                    self._update_tab(ed)
                    restored += 1
            self.recovery.forget(entry["path"])
        if restored:
            self.recovery.autosave_now()
            self.sig_message.emit(f"Restored unsaved changes to {restored} "
                                  f"file{'s' * (restored != 1)}", 6000)
        return restored

    def apply_prefs(self, prefs: Preferences) -> None:
        self.prefs = prefs
        ep = prefs.editor_prefs()
        for ed in self.editors():
            ed.apply_prefs(ep)
        self.recovery.set_interval(prefs.autosave_seconds)

    def tab_menu(self, index: int):
        """The context menu of an editor tab (built, not shown: tests use it)."""
        from PySide6.QtWidgets import QMenu
        ed = self.tabs.widget(index)
        menu = QMenu(self)
        if not is_editor(ed):
            return menu
        menu.addAction("Close", lambda: self.close_editor(ed)).setObjectName("close")
        menu.addAction("Close Others", lambda: self._close_others(ed)).setObjectName("others")
        menu.addAction("Close All", lambda: self.close_all()).setObjectName("all")
        menu.addSeparator()
        menu.addAction("Copy Path", lambda: QApplication.clipboard().setText(ed.path)) \
            .setObjectName("copy_path")
        act = menu.addAction("Show in Project", lambda: self.sig_reveal.emit(ed.path))
        act.setObjectName("reveal")
        act.setEnabled(self.can_reveal(ed.path))
        return menu

    def cycle_tab(self, step: int) -> None:
        n = self.tabs.count()
        if n:
            self.tabs.setCurrentIndex((self.tabs.currentIndex() + step) % n)

    def show_welcome(self) -> None:
        """The welcome page when no editor is open, the tabs otherwise."""
        has_tabs = self.tabs.count() > 0
        self.stack.setCurrentWidget(self.tabs if has_tabs else self.welcome)
        if not has_tabs and self._find_bar is not None:
            self._find_bar.hide()
        self.welcome.show_project(self.project)

    def show_find(self, replace: bool = False) -> None:
        ed = self.current_editor()
        if ed is None:
            return
        self.find_bar.set_editor(ed)
        self.find_bar.open(replace)

    def goto_line_dialog(self) -> bool:
        ed = self.current_editor()
        if ed is None:
            return False
        line, _col = ed.cursor_line_col()
        res = dialogs.GoToLineDialog.get_line(self.window(), line, ed.lineCount())
        if res is None:
            return False
        ed.goto_line(*res)
        ed.take_focus()
        return True

    # --------------------------------------------------- the project's files
    def on_file_renamed(self, old: str, new: str) -> None:
        """A file was renamed in the project: its editor follows."""
        ed = self.editor_for(old)
        self.recovery.discard(old)
        if ed is not None:
            self.disk.unwatch(old)
            ed.path = new
            ed.kind = api.kind_of(new) if new.endswith(".plc") else None
            self.tabs.setTabToolTip(self.tabs.indexOf(ed), new)
            self.disk.watch(new, file_digest(new))
            self._update_tab(ed)

    def on_file_deleted(self, path: str) -> None:
        """A file was deleted in the project: its editor closes."""
        ed = self.editor_for(path)
        if ed is not None:
            self.recovery.discard(path)
            self.close_editor(ed, force=True)

    def check_disk(self) -> None:
        """Look again at the files on disk (the application became active)."""
        if not self.closing:
            self.disk.check_all()

    # ============================================================== private
    def _resolve_path(self, path: str) -> Optional[str]:
        """An existing file for a path the compiler or the controller named."""
        p = Path(path)
        if p.is_absolute():
            return str(p) if p.exists() else None
        candidates = []
        if self.project is not None:
            root = self.project.root
            candidates += [root / p, self.project.hardware_dir / p, self.project.software_dir / p,
                           self.project.include_dir / p]
            candidates += [self.project.include_dir / p.name]
        candidates.append(Path.cwd() / p)
        for c in candidates:
            try:
                if c.is_file():
                    return str(c.resolve())
            except OSError:
                continue
        if self.project is not None and p.suffix == ".plc":
            proc = self.project.procedure(p.stem)
            if proc is not None:
                return str(proc.path)
        return None

    def _create_editor(self, path: str, *, text: Optional[str] = None,
                       missing_ok: bool = False) -> Optional[CodeEditor]:
        builtin = path.startswith(BUILTIN_PREFIX)
        eol = "\n"
        disk = None
        if builtin:
            text = builtin_header(path[len(BUILTIN_PREFIX):])
            if text is None:
                return None
        elif text is None:
            try:
                data = read_bounded(path, MAX_EDIT_BYTES, "file to edit")
            except OSError as exc:
                if not missing_ok or not isinstance(exc, FileNotFoundError):
                    QMessageBox.critical(self.window(), "Open",
                                         f"Cannot open {path}:\n\n{exc.strerror or exc}")
                    return None
                data = b""
            if b"\0" in data[:8192]:
                QMessageBox.warning(self.window(), "Open", f"{Path(path).name} is not a text file.")
                return None
            disk = digest(data)
            text, eol = normalise_newlines(data.decode("utf-8", "replace"))
        # the editor (Scintilla) and the highlighter (pygments) load with the first editor
        from plcbuilder.ide.editor.widget import CodeEditor
        from plcbuilder.ide.highlighter import lexer_for
        ed = CodeEditor(self.tabs, self.prefs.editor_prefs())
        ed.path = path
        ed.eol = eol
        ed.builtin = builtin
        ed.force_dirty = False
        ed.kind = None
        if path.endswith(".plc"):
            ed.kind = api.kind_of(path)
        lexer = lexer_for(path)
        if lexer is not None:
            ed.highlighter.lexer = lexer if lexer is not False else _PlainLexer()
        ed.set_text(text)
        ed.setSavePoint()
        if builtin:
            ed.setReadOnly(True)
        ed.set_context_actions(self.context_actions)
        ed.sig_modified_changed.connect(lambda _m, e=ed: self._update_tab(e))
        ed.sig_cursor_moved.connect(self.sig_cursor_moved)
        ed.sig_goto_definition.connect(self.sig_goto_definition)
        name = Path(path).name + (" (built-in)" if builtin else "")
        ic = "file-header" if path.endswith(".h") else (
            "file-plc-sw" if ed.kind is Kind.SOFTWARE else "file-plc" if ed.kind else "file")
        self._style_tabs()
        idx = self.tabs.addTab(ed, icon(ic), name)
        self.tabs.setTabToolTip(idx, path)
        if not builtin:
            self.disk.watch(path, disk if disk is not None else file_digest(path))
        self.sig_editor_created.emit(ed)
        ed.sig_text_changed.connect(lambda e=ed: self._update_tab(e))
        self.sig_editors_changed.emit()
        return ed

    def _style_tabs(self) -> None:
        """The tabs' own look, given with the first tab: a style sheet is
        parsed and makes the widget draw through the style-sheet style, which
        the window's first paint (the welcome page) need not wait for."""
        bar = self.tabs.tabBar()
        if not bar.styleSheet():
            bar.setStyleSheet(TAB_SHEET % {"close": icon_path("close"),
                                           "close_hover": icon_path("close-hover")})

    def _update_tab(self, ed: CodeEditor) -> None:
        i = self.tabs.indexOf(ed)
        if i < 0:
            return
        name = Path(ed.path).name + (" (built-in)" if ed.builtin else "")
        modified = self.is_modified(ed)
        self.tabs.setTabText(i, name + (" ●" if modified else ""))
        if modified:
            self.recovery.poke()            # something to autosave (the timer runs again)
        if ed is self.current_editor():
            self.sig_title_changed.emit()

    def _ask_save(self, editors: list, title: str):
        if len(editors) == 1:
            text = f"{Path(editors[0].path).name} has unsaved changes. Save them?"
        else:
            names = "\n".join(f"  • {Path(e.path).name}" for e in editors)
            text = f"These files have unsaved changes:\n\n{names}\n\nSave them?"
        return QMessageBox.warning(
            self.window(), title, text, QMessageBox.StandardButton.Save |
            QMessageBox.StandardButton.Discard | QMessageBox.StandardButton.Cancel,
            QMessageBox.StandardButton.Save)

    def _reload_editor(self, ed: CodeEditor) -> None:
        try:
            data = read_bounded(ed.path, MAX_EDIT_BYTES, "file to edit")
        except OSError:
            return
        text, ed.eol = normalise_newlines(data.decode("utf-8", "replace"))
        line = ed.firstVisibleLine()
        pos = ed.currentPos()
        ed.set_text(text, keep_undo=True)
        ed.setSavePoint()
        ed.force_dirty = False
        ed.gotoPos(min(pos, ed.length()))
        ed.setFirstVisibleLine(line)
        self.disk.set_digest(ed.path, digest(data))
        self.recovery.discard(ed.path)
        self._update_tab(ed)

    def _tab_context_menu(self, point) -> None:
        index = self.tabs.tabBar().tabAt(point)
        if index >= 0:
            self.tab_menu(index).exec(self.tabs.tabBar().mapToGlobal(point))

    def _close_others(self, keep: CodeEditor) -> None:
        for ed in self.editors():
            if ed is not keep and not self.close_editor(ed):
                return

    def eventFilter(self, obj, event) -> bool:  # noqa: N802 - Qt override
        from PySide6.QtCore import QEvent
        if obj is self.tabs.tabBar() and event.type() == QEvent.Type.MouseButtonRelease \
                and event.button() == Qt.MouseButton.MiddleButton:
            index = obj.tabAt(event.position().toPoint())
            if index >= 0:
                self.close_editor(self.tabs.widget(index))
                return True
        return super().eventFilter(obj, event)

    def _on_current_changed(self, _index: int) -> None:
        ed = self.current_editor()
        if self._find_bar is not None:
            self._find_bar.set_editor(ed)
        self.sig_current_changed.emit(ed)

    def _on_disk_changed(self, path: str) -> None:
        ed = self.editor_for(path)
        if ed is None or path in self._prompting or self.closing:
            return
        name = Path(path).name
        if not self.is_modified(ed) and self.prefs.reload_unmodified:
            self._reload_editor(ed)
            self.sig_message.emit(f"Reloaded {name}: it changed on disk", 5000)
            return
        answer = self._ask_about_file(
            path, "File Changed on Disk",
            f"{name} was changed on disk by another program."
            + ("\n\nReload it and lose your unsaved changes?" if self.is_modified(ed)
               else "\n\nReload it?"),
            QMessageBox.StandardButton.Yes if not self.is_modified(ed)
            else QMessageBox.StandardButton.No)
        if answer == QMessageBox.StandardButton.Yes:
            self._reload_editor(ed)
        else:
            ed.force_dirty = True       # the editor's text now differs from the file
            self._update_tab(ed)

    def _on_disk_deleted(self, path: str) -> None:
        ed = self.editor_for(path)
        if ed is None or path in self._prompting or self.closing:
            return
        answer = self._ask_about_file(
            path, "File Deleted",
            f"{Path(path).name} was deleted from disk.\n\nKeep it open in the editor "
            "(save it to write it back)?", QMessageBox.StandardButton.Yes)
        if answer == QMessageBox.StandardButton.Yes:
            ed.force_dirty = True
            self._update_tab(ed)
        else:
            self.close_editor(ed, force=True)

    def _ask_about_file(self, path: str, title: str, text: str, default):
        """Yes or No about a file on disk (no second prompt for it meanwhile)."""
        self._prompting.add(path)
        try:
            return QMessageBox.question(
                self.window(), title, text,
                QMessageBox.StandardButton.Yes | QMessageBox.StandardButton.No, default)
        finally:
            self._prompting.discard(path)

    def _recovery_snapshot(self) -> list:
        root = str(self.project.root) if self.project is not None else ""
        return [(ed.path, ed.text(), root) for ed in self.modified_editors()]


class _PlainLexer:
    """Plain text: one token."""

    @staticmethod
    def get_tokens_unprocessed(text):
        from pygments.token import Text
        yield 0, Text, text


def _rel(path: str, root: Path) -> str:
    try:
        return os.path.relpath(path, root)
    except ValueError:
        return path
