"""The IDE's main window: the project, the editors and everything around them.

    ┌ menus, toolbar: New · Save · Build All · Upload · Start · Stop · speed ──────┐
    │ Project │ tabbed editors (+ find/replace bar)          │ run docks (part B) │
    │         ├──────────────────────────────────────────────┤                    │
    │         │ Problems · Build Output · Run log            │                    │
    └ status: message · connection · sim time · running · proc · size · Ln/Col ──┘

The window owns the project (:class:`plcbuilder.project.model.Project`), the
editors, the diagnostics worker, Build All, the recovery autosave and the
disk watcher, and — when the run side is there — the controller connection
and its docks (:mod:`plcbuilder.ide.connection`, :mod:`plcbuilder.ide.panels`).
"""

from __future__ import annotations

import os
import re
from pathlib import Path
from typing import Optional

from PySide6.QtCore import QSize, Qt, QTimer, Signal
from PySide6.QtGui import QAction, QActionGroup, QKeySequence
from PySide6.QtWidgets import (QApplication, QComboBox, QDockWidget, QFileDialog, QHBoxLayout,
                               QLabel, QListWidget, QListWidgetItem, QMainWindow, QMessageBox,
                               QPushButton, QStackedWidget, QTabWidget, QToolBar, QToolButton,
                               QVBoxLayout, QWidget)

from plcbuilder import api
from plcbuilder.link.client import ControllerStatus
from plcbuilder.api import Kind
from plcbuilder.api import Severity
from plcbuilder.ide import completion, dialogs, hover
from plcbuilder.ide.build_panel import BuildPanel, BuildRunner
from plcbuilder.ide.diagnostics_worker import DiagnosticsWorker
from plcbuilder.ide.editor import CodeEditor, file_key, normalise_newlines
from plcbuilder.ide.highlighter import lexer_for
from plcbuilder.ide.icons import icon
from plcbuilder.ide.problems import ProblemsPanel, ProblemStore
from plcbuilder.ide.project_tree import ProjectTree
from plcbuilder._support.files import read_bounded
from plcbuilder.link.protocol import MAX_IMAGE
from plcbuilder.ide.recovery import (MAX_EDIT_BYTES, DiskWatcher, RecoveryManager, digest,
                                     encode_text,
                                     file_digest, save_text)
from plcbuilder.ide.settings import Preferences, Settings
from plcbuilder.lang.preprocess import BUILTIN_PREFIX, builtin_header
from plcbuilder.project.model import Project, ProjectError

APP_NAME = "PLC Builder"
SOURCE_SUFFIXES = (".plc", ".h")
TEXT_SUFFIXES = (".plc", ".h", ".toml", ".xml", ".md", ".txt")

#: simulation speeds: (label, connection mode)
SPEEDS = (("1×", "realtime"), ("10×", "10"), ("Max", "max"), ("Pause", "pause"))


class Act:
    """Names of the window's actions (``window.action(Act.BUILD_ALL)``)."""
    NEW_PROCEDURE = "new_procedure"
    NEW_HEADER = "new_header"
    OPEN_PROJECT = "open_project"
    OPEN_EXAMPLE = "open_example"
    CLOSE_PROJECT = "close_project"
    SAVE = "save"
    SAVE_ALL = "save_all"
    REVERT = "revert"
    CLOSE_EDITOR = "close_editor"
    CLOSE_ALL = "close_all"
    PREFERENCES = "preferences"
    QUIT = "quit"
    UNDO = "undo"
    REDO = "redo"
    CUT = "cut"
    COPY = "copy"
    PASTE = "paste"
    SELECT_ALL = "select_all"
    TOGGLE_COMMENT = "toggle_comment"
    FIND = "find"
    REPLACE = "replace"
    FIND_NEXT = "find_next"
    FIND_PREVIOUS = "find_previous"
    GOTO_LINE = "goto_line"
    GOTO_DEFINITION = "goto_definition"
    COMPLETE = "complete"
    ZOOM_IN = "zoom_in"
    ZOOM_OUT = "zoom_out"
    ZOOM_RESET = "zoom_reset"
    NEXT_TAB = "next_tab"
    PREVIOUS_TAB = "previous_tab"
    RESET_LAYOUT = "reset_layout"
    BUILD_ALL = "build_all"
    UPLOAD = "upload"
    START = "start"
    START_CURRENT = "start_current"
    STOP = "stop"
    RESET_CONTROLLER = "reset_controller"
    CONNECT = "connect"
    EMBEDDED = "embedded"
    ABOUT = "about"


class MainWindow(QMainWindow):
    """The IDE's main window."""

    sig_project_opened = Signal(str)
    """A project was opened (its folder)."""

    sig_build_finished = Signal(object)
    """Build All finished (the BuildResult, or the exception it raised)."""

    sig_diagnostics_updated = Signal(str)
    """New diagnostics of a procedure arrived (its file key)."""

    def __init__(self, settings: Optional[Settings] = None, *, start_controller: bool = True,
                 connection=None, debounce_ms: Optional[int] = None):
        super().__init__()
        self.settings = settings or Settings()
        self.prefs: Preferences = self.settings.preferences()
        self.project: Optional[Project] = None
        self.store = ProblemStore()
        self._results: dict[str, object] = {}        # file key -> latest CompileResult
        self._sizes: dict[str, tuple] = {}           # file key -> (size, limit)
        self._header_defines: dict = {}
        self._header_scan = completion.HeaderDefines()
        self._actions: dict[str, QAction] = {}
        self._prompting: set[str] = set()
        self._last_eparam = 0
        self._last_start = ""
        self._upload_after_build = False
        self._closing = False
        self._last_state = ControllerStatus()
        self.start_controller = start_controller
        self.connection = connection
        self.run_panels = None
        self._right_docks: list = []
        self._shown_once = False
        self._layout_restored = False

        self.setWindowTitle(APP_NAME)
        self.setWindowIcon(icon("app"))
        self.setDockNestingEnabled(True)
        self.setDocumentMode(True)
        self.setAcceptDrops(True)
        self.resize(1360, 860)

        self.worker = DiagnosticsWorker(self, **({"debounce_ms": debounce_ms}
                                                 if debounce_ms is not None else {}))
        self.worker.sig_result.connect(self._on_compile_result)
        self._problems_timer = QTimer(self)
        self._problems_timer.setSingleShot(True)
        self._problems_timer.setInterval(25)
        self._problems_timer.timeout.connect(self._refresh_problems)
        self.build_runner = BuildRunner(self)
        self.build_runner.sig_progress.connect(self._on_build_progress)
        self.build_runner.sig_finished.connect(self._on_build_finished)
        self.disk = DiskWatcher(self)
        self.disk.sig_changed.connect(self._on_disk_changed)
        self.disk.sig_deleted.connect(self._on_disk_deleted)
        self.recovery = RecoveryManager(self.settings.recovery_dir(), self._recovery_snapshot,
                                        self, self.prefs.autosave_seconds)

        self._build_central()
        self._build_docks()
        self._build_actions()
        self._build_menus()
        self._build_toolbar()
        self._build_statusbar()
        self._setup_run_side()
        self._default_state = self.saveState()
        self._restore_layout()
        self._update_actions()
        self._show_welcome()
        self.recovery.start()
        app = QApplication.instance()
        if app is not None:
            app.applicationStateChanged.connect(self._on_app_state)

    # ================================================================ public
    def action(self, name: str) -> QAction:
        return self._actions[name]

    def editors(self) -> list[CodeEditor]:
        return [self.tabs.widget(i) for i in range(self.tabs.count())]

    def current_editor(self) -> Optional[CodeEditor]:
        w = self.tabs.currentWidget()
        return w if isinstance(w, CodeEditor) else None

    def editor_for(self, path) -> Optional[CodeEditor]:
        key = file_key(path)
        for ed in self.editors():
            if file_key(ed.path) == key:
                return ed
        return None

    def busy(self) -> bool:
        """Diagnostics or a build still on their way (tests and screenshots wait)."""
        return self.worker.pending() or self._problems_timer.isActive() or \
            self.build_runner.running()

    def is_modified(self, editor: CodeEditor) -> bool:
        return bool(editor.modify() or getattr(editor, "force_dirty", False))

    def modified_editors(self) -> list[CodeEditor]:
        return [ed for ed in self.editors() if self.is_modified(ed) and not ed.builtin]

    # ------------------------------------------------------------- project
    def open_project(self, path, *, offer_recovery: bool = True) -> bool:
        """Open a project folder (asking about unsaved changes first)."""
        if not self._confirm_discard_all("Open Project"):
            return False
        try:
            project = Project.open(Path(path).expanduser().resolve())
        except ProjectError as exc:
            QMessageBox.critical(self, "Open Project", f"Cannot open the project:\n\n{exc}")
            self.settings.remove_recent_project(str(Path(path).expanduser().resolve()))
            self._fill_recent_menu()
            return False
        self._close_all_editors(force=True)
        self.project = project
        self.store.clear()
        self._results.clear()
        self._sizes.clear()
        self.problems.set_root(project.root)
        self.tree.set_project(project)
        self.settings.add_recent_project(project.root)
        self._fill_recent_menu()
        self._refresh_header_defines()
        self._lint_project()
        for f in self.settings.open_files(project.root):
            if Path(f).exists() or f.startswith(BUILTIN_PREFIX):
                self.open_file(f, focus=False)
        current = self.settings.current_file(project.root)
        if current and self.editor_for(current) is not None:
            self.tabs.setCurrentWidget(self.editor_for(current))
        if offer_recovery:
            self.offer_recovery()
        self._update_title()
        self._update_actions()
        self._show_welcome()
        self._refresh_problems()
        self._start_controller_for_project()
        self.statusBar().showMessage(f"Opened {project.name} ({project.root})", 5000)
        self.sig_project_opened.emit(str(project.root))
        return True

    def close_project(self) -> bool:
        if not self._confirm_discard_all("Close Project"):
            return False
        self._save_session()
        self._close_all_editors(force=True)
        self.project = None
        self.store.clear()
        self._results.clear()
        self.tree.set_project(None)
        self.problems.set_root(None)
        self._refresh_problems()
        self._update_title()
        self._update_actions()
        self._show_welcome()
        return True

    def open_example_project(self) -> bool:
        """Create a copy of the example project (in the default place, or a
        folder the user picks) and open it."""
        from plcbuilder.project.new import create_project
        default_parent = self.settings.example_dir()
        answer = QMessageBox.question(
            self, "Open Example Project",
            "PLC Builder makes a copy of its example project (spindle, coolant, homing, "
            "probing and plasma procedures) for you to edit and run.\n\n"
            f"Create it in {default_parent}?\n\nChoose No to pick another folder.",
            QMessageBox.StandardButton.Yes | QMessageBox.StandardButton.No |
            QMessageBox.StandardButton.Cancel, QMessageBox.StandardButton.Yes)
        if answer == QMessageBox.StandardButton.Cancel:
            return False
        if answer == QMessageBox.StandardButton.Yes:
            parent = default_parent
        else:
            chosen = QFileDialog.getExistingDirectory(self, "Folder for the example project",
                                                      str(Path.home()))
            if not chosen:
                return False
            parent = Path(chosen)
        try:
            parent.mkdir(parents=True, exist_ok=True)
            dest = _unique_folder(parent, "plc-example")
            project = create_project(dest, name="example")
        except (OSError, ProjectError) as exc:
            QMessageBox.critical(self, "Open Example Project",
                                 f"Cannot create the example project:\n\n{exc}")
            return False
        ok = self.open_project(project.root)
        if ok:
            first = next(iter(project.procedures(Kind.HARDWARE)), None)
            if first is not None:
                self.open_file(first.path)
        return ok

    # ------------------------------------------------------------- editors
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
        self._show_welcome()
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
            QMessageBox.critical(self, "Save", f"Cannot save {ed.path}:\n\n{exc}")
            return False
        ed.setSavePoint()
        ed.force_dirty = False
        self.recovery.discard(ed.path)
        self._update_tab(ed)
        self.statusBar().showMessage(f"Saved {Path(ed.path).name}", 3000)
        if self.project is not None and file_key(ed.path) == file_key(self.project.settings_path):
            self._reload_project_settings()
        elif ed.path.endswith(".h"):
            # a header changed: every procedure may include it
            self._refresh_header_defines()
            self._relint_open_procedures()
            self._lint_project()
        self.tree.refresh()
        return True

    def _reload_project_settings(self) -> None:
        """plcbuilder.toml was saved: use its limits, strict mode and machine now;
        a mistake in it becomes a problem on its line."""
        from plcbuilder.api import Span, error
        try:
            project = Project.open(self.project.root)
        except ProjectError as exc:
            line = exc.line or 1
            self.store.set("settings", [error("settings", str(exc.message if exc.key is None
                                                              else f"{exc.key}: {exc.message}"),
                                              Span.point(str(self.project.settings_path), line, 1,
                                                         1 << 16))])
            self._refresh_problems()
            self.statusBar().showMessage("plcbuilder.toml has a mistake: the previous settings "
                                         "stay in use", 8000)
            return
        self.store.remove("settings")
        self.project = project
        self.tree.project = project
        self.tree.refresh(force=True)
        self._relint_open_procedures()
        self._lint_project()
        self._refresh_problems()
        self._update_title()
        self.statusBar().showMessage("Project settings reloaded", 4000)

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
            self.worker.cancel(file_key(ed.path))
            self._relint_from_disk(ed.path)
        self.disk.unwatch(ed.path)
        self.tabs.removeTab(self.tabs.indexOf(ed))
        ed.deleteLater()
        self._show_welcome()
        self._update_actions()
        return True

    def revert_editor(self, editor: Optional[CodeEditor] = None) -> bool:
        ed = editor or self.current_editor()
        if ed is None or ed.builtin or not Path(ed.path).exists():
            return False
        if self.is_modified(ed):
            answer = QMessageBox.question(
                self, "Revert", f"Discard your changes to {Path(ed.path).name} and reload it "
                                "from disk?", QMessageBox.StandardButton.Yes |
                QMessageBox.StandardButton.No, QMessageBox.StandardButton.No)
            if answer != QMessageBox.StandardButton.Yes:
                return False
        self._reload_editor(ed)
        return True

    # ----------------------------------------------------------- recovery
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
            self, "Recover Unsaved Changes",
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
            self.statusBar().showMessage(f"Restored unsaved changes to {restored} "
                                         f"file{'s' * (restored != 1)}", 6000)
        return restored

    # --------------------------------------------------------------- build
    def build_all(self) -> bool:
        """Build All (saving first when the preference says so)."""
        if self.project is None:
            self.statusBar().showMessage("Open a project to build it", 4000)
            return False
        if self.build_runner.running():
            return False
        if self.prefs.save_before_build and not self.save_all():
            return False
        self.build_panel.begin(self.project)
        self.build_dock.show()
        self.build_dock.raise_()
        self.action(Act.BUILD_ALL).setEnabled(False)
        self.statusBar().showMessage("Building…")
        return self.build_runner.start(self.project)

    def upload(self) -> bool:
        """Upload build/eeprom.rom (building first when the preference says so)."""
        if self.project is None:
            return False
        if self.connection is None:
            self.statusBar().showMessage("No controller to upload to", 4000)
            return False
        stale = self.modified_editors() or not self.project.image_path.exists()
        if self.prefs.build_before_upload or stale:
            self._upload_after_build = True
            if not self.build_all():
                self._upload_after_build = False
                return False
            return True
        return self._upload_image()

    def start_procedure(self, name: Optional[str] = None, eparam: Optional[int] = None) -> bool:
        """Start a procedure on the controller (asking which, when not given)."""
        if self.connection is None or self.project is None:
            self.statusBar().showMessage("No controller to start a procedure on", 4000)
            return False
        if name is None:
            procs = [(p.name, p.kind) for p in self.project.procedures()
                     if p.kind is Kind.HARDWARE or p.system]
            initial = self._last_start
            ed = self.current_editor()
            if ed is not None and ed.kind is Kind.HARDWARE:
                initial = Path(ed.path).stem
            res = dialogs.StartDialog.get_start(self, procs, initial, self._last_eparam)
            if res is None:
                return False
            name, eparam = res
        eparam = self._last_eparam if eparam is None else int(eparam)
        self._last_start, self._last_eparam = name, eparam
        self.connection.start(name, eparam)
        self.statusBar().showMessage(f"Start {name} (eparam {eparam})", 4000)
        return True

    def stop(self) -> None:
        """Stop: the first press starts M02, the second OFF (the controller decides)."""
        if self.connection is not None:
            self.connection.stop()
            self.statusBar().showMessage("Stop", 3000)

    def set_speed(self, mode: str) -> None:
        for label, m in SPEEDS:
            if m == mode:
                i = self.speed_combo.findData(m)
                if i >= 0 and self.speed_combo.currentIndex() != i:
                    self.speed_combo.blockSignals(True)
                    self.speed_combo.setCurrentIndex(i)
                    self.speed_combo.blockSignals(False)
                act = self._speed_actions.get(m)
                if act is not None:
                    act.setChecked(True)
        if self.connection is not None:
            self.connection.set_speed(mode)

    # ========================================================= construction
    def _build_central(self) -> None:
        central = QWidget(self)
        lay = QVBoxLayout(central)
        lay.setContentsMargins(0, 0, 0, 0)
        lay.setSpacing(0)
        self.stack = QStackedWidget(central)
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
        self.welcome = self._make_welcome()
        self.stack.addWidget(self.welcome)
        self.stack.addWidget(self.tabs)
        self.find_bar = dialogs.FindReplaceBar(central)
        self.find_bar.sig_message.connect(lambda m: self.statusBar().showMessage(m, 3000))
        lay.addWidget(self.stack, 1)
        lay.addWidget(self.find_bar)
        self.setCentralWidget(central)

    def _make_welcome(self) -> QWidget:
        w = QWidget()
        w.setObjectName("welcome")
        outer = QVBoxLayout(w)
        outer.addStretch(1)
        box = QWidget(w)
        box.setMaximumWidth(560)
        lay = QVBoxLayout(box)
        title = QLabel(f"<span style='font-size:20pt; font-weight:600'>{APP_NAME}</span>", box)
        lay.addWidget(title)
        self.welcome_text = QLabel(box)
        self.welcome_text.setWordWrap(True)
        self.welcome_text.setTextFormat(Qt.TextFormat.RichText)
        lay.addWidget(self.welcome_text)
        row = QHBoxLayout()
        self.welcome_open = QPushButton(icon("open"), "Open Project…", box)
        self.welcome_example = QPushButton(icon("example"), "Open Example Project…", box)
        self.welcome_new = QPushButton(icon("new"), "New Procedure…", box)
        row.addWidget(self.welcome_open)
        row.addWidget(self.welcome_example)
        row.addWidget(self.welcome_new)
        row.addStretch(1)
        lay.addLayout(row)
        self.welcome_recent_label = QLabel("<b>Recent projects</b>", box)
        lay.addSpacing(10)
        lay.addWidget(self.welcome_recent_label)
        self.welcome_recent = QListWidget(box)
        self.welcome_recent.setMaximumHeight(180)
        self.welcome_recent.itemActivated.connect(
            lambda it: self.open_project(it.data(Qt.ItemDataRole.UserRole)))
        lay.addWidget(self.welcome_recent)
        h = QHBoxLayout()
        h.addStretch(1)
        h.addWidget(box, 3)
        h.addStretch(1)
        outer.addLayout(h)
        outer.addStretch(2)
        self.welcome_open.clicked.connect(self._open_project_dialog)
        self.welcome_example.clicked.connect(self.open_example_project)
        self.welcome_new.clicked.connect(lambda: self.tree.new_procedure(Kind.HARDWARE))
        return w

    def _build_docks(self) -> None:
        self.tree = ProjectTree(self)
        self.tree.sig_open_file.connect(lambda p: self.open_file(p))
        self.tree.sig_file_created.connect(self._on_file_created)
        self.tree.sig_file_renamed.connect(self._on_file_renamed)
        self.tree.sig_file_deleted.connect(self._on_file_deleted)
        self.tree.sig_start_procedure.connect(lambda n: self.start_procedure(n, self._last_eparam))
        self.tree.sig_changed.connect(self._on_tree_changed)
        self.project_dock = self._dock("Project", "projectDock", self.tree,
                                       Qt.DockWidgetArea.LeftDockWidgetArea)
        self.problems = ProblemsPanel(self)
        self.problems.sig_open_location.connect(self.open_location)
        self.problems_dock = self._dock("Problems", "problemsDock", self.problems,
                                        Qt.DockWidgetArea.BottomDockWidgetArea)
        self.build_panel = BuildPanel(self)
        self.build_panel.sig_open_location.connect(self.open_location)
        self.build_dock = self._dock("Build Output", "buildDock", self.build_panel,
                                     Qt.DockWidgetArea.BottomDockWidgetArea)
        self.tabifyDockWidget(self.problems_dock, self.build_dock)
        self.problems_dock.raise_()
        self.resizeDocks([self.project_dock], [250], Qt.Orientation.Horizontal)
        self.resizeDocks([self.problems_dock], [200], Qt.Orientation.Vertical)

    def _dock(self, title, name, widget, area) -> QDockWidget:
        dock = QDockWidget(title, self)
        dock.setObjectName(name)
        dock.setWidget(widget)
        dock.setFeatures(QDockWidget.DockWidgetFeature.DockWidgetClosable |
                         QDockWidget.DockWidgetFeature.DockWidgetMovable |
                         QDockWidget.DockWidgetFeature.DockWidgetFloatable)
        self.addDockWidget(area, dock)
        return dock

    def _add_action(self, name, text, slot=None, shortcut=None, ic=None, tip=None,
                    editor_scope=False, checkable=False) -> QAction:
        act = QAction(text, self)
        act.setObjectName(name)
        if ic:
            act.setIcon(icon(ic))
        if shortcut:
            act.setShortcuts(shortcut if isinstance(shortcut, list) else [QKeySequence(shortcut)])
        if tip:
            act.setStatusTip(tip)
            act.setToolTip(f"{tip} ({act.shortcut().toString(QKeySequence.SequenceFormat.NativeText)})"
                           if shortcut else tip)
        act.setCheckable(checkable)
        if slot is not None:
            act.triggered.connect(lambda _checked=False: slot())
        if editor_scope:
            act.setShortcutContext(Qt.ShortcutContext.WidgetWithChildrenShortcut)
            self.stack.addAction(act)
        else:
            self.addAction(act)
        self._actions[name] = act
        return act

    def _build_actions(self) -> None:
        A, K = self._add_action, QKeySequence.StandardKey
        ed = self._with_editor
        A(Act.NEW_PROCEDURE, "&New Procedure…", lambda: self.tree.new_procedure(Kind.HARDWARE),
          "Ctrl+N", "new", "Create a procedure")
        A(Act.NEW_HEADER, "New &Header…", self.tree.new_header, None, "file-header",
          "Create a header in include/")
        A(Act.OPEN_PROJECT, "&Open Project…", self._open_project_dialog, "Ctrl+Shift+O", "open",
          "Open a project folder")
        A(Act.OPEN_EXAMPLE, "Open &Example Project…", self.open_example_project, None, "example",
          "Make a copy of the example project and open it")
        A(Act.CLOSE_PROJECT, "Close Project", self.close_project)
        A(Act.SAVE, "&Save", self.save_editor, "Ctrl+S", "save", "Save the file")
        A(Act.SAVE_ALL, "Save A&ll", self.save_all, "Ctrl+Shift+S", "save-all", "Save every file")
        A(Act.REVERT, "&Revert to Saved", self.revert_editor)
        A(Act.CLOSE_EDITOR, "&Close Editor", self.close_editor, "Ctrl+W")
        A(Act.CLOSE_ALL, "Close All Editors", lambda: self._close_all_editors(), "Ctrl+Shift+W")
        A(Act.PREFERENCES, "&Preferences…", self.edit_preferences, "Ctrl+,")
        A(Act.QUIT, "&Quit", self.close, "Ctrl+Q")
        A(Act.UNDO, "&Undo", ed(lambda e: e.undo()), K.Undo, editor_scope=True)
        A(Act.REDO, "&Redo", ed(lambda e: e.redo()), [QKeySequence("Ctrl+Y"),
                                                     QKeySequence("Ctrl+Shift+Z")], editor_scope=True)
        A(Act.CUT, "Cu&t", ed(lambda e: e.cut()), K.Cut, editor_scope=True)
        A(Act.COPY, "&Copy", ed(lambda e: e.copy()), K.Copy, editor_scope=True)
        A(Act.PASTE, "&Paste", ed(lambda e: e.paste()), K.Paste, editor_scope=True)
        A(Act.SELECT_ALL, "Select &All", ed(lambda e: e.selectAll()), K.SelectAll,
          editor_scope=True)
        A(Act.TOGGLE_COMMENT, "Toggle &Comment", ed(lambda e: e.toggle_comment()), "Ctrl+/",
          "comment", "Comment or uncomment the selected lines", editor_scope=True)
        A(Act.FIND, "&Find…", lambda: self.show_find(False), "Ctrl+F", "find", "Find in the file")
        A(Act.REPLACE, "R&eplace…", lambda: self.show_find(True), "Ctrl+H", None,
          "Find and replace in the file")
        A(Act.FIND_NEXT, "Find &Next", self.find_bar.find_next, "F3")
        A(Act.FIND_PREVIOUS, "Find Pre&vious", self.find_bar.find_previous, "Shift+F3")
        A(Act.GOTO_LINE, "&Go to Line…", self.goto_line_dialog, "Ctrl+G", "goto",
          "Go to a line of the file")
        A(Act.GOTO_DEFINITION, "Go to &Definition", ed(lambda e: self.goto_definition(
            e.word_under_caret())), "F12", None, "Go to where the name under the caret is defined",
          editor_scope=True)
        A(Act.COMPLETE, "Complete", ed(lambda e: e.show_completions(explicit=True)), "Ctrl+Space",
          editor_scope=True)
        A(Act.ZOOM_IN, "Zoom &In", ed(lambda e: e.zoomIn()), [QKeySequence("Ctrl++"),
                                                           QKeySequence("Ctrl+=")])
        A(Act.ZOOM_OUT, "Zoom &Out", ed(lambda e: e.zoomOut()), "Ctrl+-")
        A(Act.ZOOM_RESET, "Reset Zoom", ed(lambda e: e.setZoom(0)), "Ctrl+0")
        A(Act.NEXT_TAB, "Next Editor", lambda: self._cycle_tab(1), "Ctrl+PgDown")
        A(Act.PREVIOUS_TAB, "Previous Editor", lambda: self._cycle_tab(-1), "Ctrl+PgUp")
        A(Act.RESET_LAYOUT, "Reset Layout", self.reset_layout)
        A(Act.BUILD_ALL, "&Build All", self.build_all, "Ctrl+B", "build",
          "Compile every procedure and write build/eeprom.rom")
        A(Act.UPLOAD, "&Upload", self.upload, "Ctrl+U", "upload",
          "Upload build/eeprom.rom to the controller")
        A(Act.START, "&Start…", self.start_procedure, "F5", "start",
          "Start a procedure on the controller (by name or M-code, with eparam)")
        A(Act.START_CURRENT, "Start &This Procedure", self._start_current, "Ctrl+F5", None,
          "Start the procedure of the current editor with the last eparam")
        A(Act.STOP, "S&top", self.stop, "Shift+F5", "stop",
          "Stop: the first press starts M02, the second OFF")
        A(Act.RESET_CONTROLLER, "&Reset Controller", self._reset_controller, None, "reset",
          "A fresh controller with the same image (time starts again at 0)")
        A(Act.CONNECT, "&Connect to Controller…", self.connect_dialog, None, "connect",
          "Connect to a running plcbuilder controller")
        A(Act.EMBEDDED, "Use the &Embedded Controller", self._use_embedded, None, "controller",
          "Run the simulated controller as a child process of the IDE")
        A(Act.ABOUT, "&About PLC Builder", self.about)
        self._speed_group = QActionGroup(self)
        self._speed_actions: dict[str, QAction] = {}
        for label, mode in SPEEDS:
            act = QAction(f"Speed {label}", self)
            act.setCheckable(True)
            act.setActionGroup(self._speed_group)
            act.triggered.connect(lambda _c=False, m=mode: self.set_speed(m))
            self._speed_actions[mode] = act
        self._speed_actions["realtime"].setChecked(True)
        context = [self._actions[a] for a in (Act.TOGGLE_COMMENT, Act.GOTO_DEFINITION)] + \
            [None] + [self._actions[a] for a in (Act.FIND, Act.GOTO_LINE)]
        self._editor_context_actions = context

    def _build_menus(self) -> None:
        mb = self.menuBar()
        a = self.action
        m = mb.addMenu("&File")
        for name in (Act.NEW_PROCEDURE, Act.NEW_HEADER, None, Act.OPEN_PROJECT, Act.OPEN_EXAMPLE):
            m.addAction(a(name)) if name else m.addSeparator()
        self.recent_menu = m.addMenu("Recent &Projects")
        m.addAction(a(Act.CLOSE_PROJECT))
        m.addSeparator()
        for name in (Act.SAVE, Act.SAVE_ALL, Act.REVERT, None, Act.CLOSE_EDITOR, Act.CLOSE_ALL,
                     None, Act.PREFERENCES, None, Act.QUIT):
            m.addAction(a(name)) if name else m.addSeparator()
        m = mb.addMenu("&Edit")
        for name in (Act.UNDO, Act.REDO, None, Act.CUT, Act.COPY, Act.PASTE, Act.SELECT_ALL, None,
                     Act.TOGGLE_COMMENT, Act.COMPLETE, None, Act.FIND, Act.REPLACE, Act.FIND_NEXT,
                     Act.FIND_PREVIOUS, None, Act.GOTO_LINE, Act.GOTO_DEFINITION):
            m.addAction(a(name)) if name else m.addSeparator()
        self.view_menu = mb.addMenu("&View")
        m = mb.addMenu("&Build")
        for name in (Act.BUILD_ALL, Act.UPLOAD):
            m.addAction(a(name))
        m = mb.addMenu("&Run")
        for name in (Act.START, Act.START_CURRENT, Act.STOP):
            m.addAction(a(name))
        m.addSeparator()
        speed = m.addMenu(icon("speed"), "Simulation &Speed")
        for act in self._speed_actions.values():
            speed.addAction(act)
        m.addAction(a(Act.RESET_CONTROLLER))
        m.addSeparator()
        m.addAction(a(Act.CONNECT))
        m.addAction(a(Act.EMBEDDED))
        m = mb.addMenu("&Help")
        m.addAction(a(Act.ABOUT))
        self._fill_recent_menu()

    def _fill_view_menu(self) -> None:
        m = self.view_menu
        m.clear()
        for dock in self.findChildren(QDockWidget):
            if dock.parent() is self:
                m.addAction(dock.toggleViewAction())
        m.addSeparator()
        m.addAction(self.toolbar.toggleViewAction())
        m.addSeparator()
        for name in (Act.ZOOM_IN, Act.ZOOM_OUT, Act.ZOOM_RESET, None, Act.NEXT_TAB,
                     Act.PREVIOUS_TAB, None, Act.RESET_LAYOUT):
            m.addAction(self.action(name)) if name else m.addSeparator()

    def _fill_recent_menu(self) -> None:
        m = self.recent_menu
        m.clear()
        recent = self.settings.recent_projects()
        for path in recent:
            act = m.addAction(icon("project"), path)
            act.triggered.connect(lambda _c=False, p=path: self.open_project(p))
        if recent:
            m.addSeparator()
            m.addAction("Clear List", self._clear_recent)
        else:
            act = m.addAction("(none yet)")
            act.setEnabled(False)
        if hasattr(self, "welcome_recent"):
            self.welcome_recent.clear()
            for path in recent:
                it = QListWidgetItem(icon("project"), f"{Path(path).name}    {path}")
                it.setData(Qt.ItemDataRole.UserRole, path)
                self.welcome_recent.addItem(it)
            self.welcome_recent.setVisible(bool(recent))
            self.welcome_recent_label.setVisible(bool(recent))

    def _clear_recent(self) -> None:
        self.settings.clear_recent_projects()
        self._fill_recent_menu()

    def _build_toolbar(self) -> None:
        tb = QToolBar("Main Toolbar", self)
        tb.setObjectName("mainToolbar")
        tb.setIconSize(QSize(20, 20))
        tb.setMovable(False)
        tb.setToolButtonStyle(Qt.ToolButtonStyle.ToolButtonTextBesideIcon)
        for name in (Act.NEW_PROCEDURE, Act.SAVE, Act.SAVE_ALL):
            tb.addAction(self.action(name))
            tb.widgetForAction(self.action(name)).setToolButtonStyle(
                Qt.ToolButtonStyle.ToolButtonIconOnly)
        tb.addSeparator()
        tb.addAction(self.action(Act.BUILD_ALL))
        tb.addAction(self.action(Act.UPLOAD))
        tb.addSeparator()
        tb.addAction(self.action(Act.START))
        tb.addAction(self.action(Act.STOP))
        tb.addSeparator()
        lab = QLabel(" Speed ", tb)
        lab.setPixmap(icon("speed").pixmap(16, 16))
        tb.addWidget(lab)
        self.speed_combo = QComboBox(tb)
        self.speed_combo.setToolTip("Simulation speed: real time, 10× real time, as fast as "
                                    "possible, or paused")
        for label, mode in SPEEDS:
            self.speed_combo.addItem(label, mode)
        self.speed_combo.currentIndexChanged.connect(
            lambda i: self.set_speed(self.speed_combo.itemData(i)))
        tb.addWidget(self.speed_combo)
        self.toolbar = tb
        self.addToolBar(Qt.ToolBarArea.TopToolBarArea, tb)

    def _build_statusbar(self) -> None:
        sb = self.statusBar()
        sb.setSizeGripEnabled(True)

        def lab(name, tip, min_width=0):
            w = QLabel(self)
            w.setObjectName(name)
            w.setToolTip(tip)
            w.setContentsMargins(6, 0, 6, 0)
            if min_width:
                w.setMinimumWidth(min_width)
            sb.addPermanentWidget(w)
            return w

        self.problems_button = QToolButton(self)
        self.problems_button.setAutoRaise(True)
        self.problems_button.setToolTip("Errors and warnings (show the Problems panel)")
        self.problems_button.clicked.connect(lambda: (self.problems_dock.show(),
                                                      self.problems_dock.raise_()))
        sb.addPermanentWidget(self.problems_button)
        self.connection_label = lab("connectionLabel", "The controller the IDE talks to")
        self.time_label = lab("timeLabel", "Simulated time on the controller", 90)
        self.running_label = lab("runningLabel", "The hardware procedure running", 80)
        self.proc_label = lab("procLabel", "proc: the running procedure's state code", 100)
        self.size_label = lab("sizeLabel", "Code size of this procedure against its limit "
                                           "(from the last compile)", 120)
        self.cursor_label = lab("cursorLabel", "Line and column of the caret", 110)
        self.eol_label = lab("eolLabel", "Encoding and line ends of the file (kept on save)")
        self._update_problem_counts()
        self._set_connection_text("no controller", False)

    def _setup_run_side(self) -> None:
        """The controller connection and the run docks."""
        if self.connection is None and self.start_controller:
            from plcbuilder.ide.connection import ControllerConnection
            self.connection = ControllerConnection(self)
        if self.connection is not None:
            c = self.connection
            c.sig_connected.connect(self._on_connected)
            c.sig_disconnected.connect(self._on_disconnected)
            c.sig_state.connect(self._on_state)
            c.sig_error.connect(lambda t: self.statusBar().showMessage(t, 6000))
            from plcbuilder.ide.panels import RunPanels
            try:
                self.run_panels = RunPanels(self, c)
            except Exception as exc:  # noqa: BLE001 - the editor side works without them
                import traceback
                traceback.print_exc()
                self.run_panels = None
                self.statusBar().showMessage(f"The run panels are not available: {exc}")
            if self.run_panels is not None:
                self.run_panels.sig_open_location.connect(
                    lambda f, ln: self.open_location(f, ln))
                self._place_run_docks(self.run_panels.docks())
        self._fill_view_menu()

    def _place_run_docks(self, docks: list) -> None:
        """Right: the plots (tabbed) over inputs and watch (tabbed); the run log
        beside Problems and Build Output at the bottom."""
        by_name = {d.objectName(): d for d in docks}
        right = [by_name[n] for n in ("runOutputsDock", "runProcDock", "runAnalogDock",
                                      "runAxesDock") if n in by_name]
        lower = [by_name[n] for n in ("runInputsDock", "runWatchDock") if n in by_name]
        log = by_name.get("runLogDock")
        placed = set(right) | set(lower) | ({log} if log else set())
        area = Qt.DockWidgetArea.RightDockWidgetArea
        if right:
            self.addDockWidget(area, right[0])
        if lower:
            if right:
                self.splitDockWidget(right[0], lower[0], Qt.Orientation.Vertical)
            else:
                self.addDockWidget(area, lower[0])
        for d in right[1:]:
            self.tabifyDockWidget(right[0], d)
        for d in lower[1:]:
            self.tabifyDockWidget(lower[0], d)
        if log is not None:
            self.tabifyDockWidget(self.build_dock, log)
        for d in docks:
            if d not in placed:
                self.addDockWidget(area, d)
        for d in (right[:1] + lower[:1]):
            d.raise_()
        self.problems_dock.raise_()
        self._right_docks = right[:1] + lower[:1]

    # ============================================================ settings
    def _restore_layout(self) -> None:
        geom, state = self.settings.window_state()
        if geom is not None:
            self.restoreGeometry(geom)
        self._layout_restored = state is not None and self.restoreState(state)

    def _default_dock_sizes(self) -> None:
        """Sizes for the default layout (they only apply once the window is shown)."""
        w = max(self.width(), 800)
        self.resizeDocks([self.project_dock], [230], Qt.Orientation.Horizontal)
        if self._right_docks:
            self.resizeDocks(self._right_docks[:1], [int(w * 0.32)], Qt.Orientation.Horizontal)
            if len(self._right_docks) > 1:
                h = max(self.height() - 200, 400)
                self.resizeDocks(self._right_docks, [int(h * 0.62), int(h * 0.38)],
                                 Qt.Orientation.Vertical)
        self.resizeDocks([self.problems_dock], [max(190, int(self.height() * 0.24))],
                         Qt.Orientation.Vertical)

    def showEvent(self, event) -> None:  # noqa: N802 - Qt override
        super().showEvent(event)
        if not self._shown_once:
            self._shown_once = True
            if not self._layout_restored:
                QTimer.singleShot(0, self._default_dock_sizes)

    def reset_layout(self) -> None:
        self.restoreState(self._default_state)
        for dock in self.findChildren(QDockWidget):
            if dock.parent() is self:
                dock.show()
        self.problems_dock.raise_()
        self._default_dock_sizes()

    def _save_session(self) -> None:
        if self.project is not None:
            files = [ed.path for ed in self.editors()]
            cur = self.current_editor()
            self.settings.save_session(self.project.root, files, cur.path if cur else "")

    def edit_preferences(self) -> bool:
        prefs = dialogs.PreferencesDialog.get_preferences(self, self.prefs)
        if prefs is None:
            return False
        self.apply_preferences(prefs)
        return True

    def apply_preferences(self, prefs: Preferences) -> None:
        self.prefs = prefs
        self.settings.save_preferences(prefs)
        ep = prefs.editor_prefs()
        for ed in self.editors():
            ed.apply_prefs(ep)
        self.recovery.set_interval(prefs.autosave_seconds)
        app = QApplication.instance()
        if app is not None:
            from plcbuilder.ide.app import apply_theme
            apply_theme(app, prefs.theme)

    # =============================================================== editors
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
                    QMessageBox.critical(self, "Open", f"Cannot open {path}:\n\n{exc.strerror or exc}")
                    return None
                data = b""
            if b"\0" in data[:8192]:
                QMessageBox.warning(self, "Open", f"{Path(path).name} is not a text file.")
                return None
            disk = digest(data)
            text, eol = normalise_newlines(data.decode("utf-8", "replace"))
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
        ed.completion_provider = self._complete
        ed.hover_provider = self._hover
        ed.signature_provider = completion.signature
        ed.set_context_actions(self._editor_context_actions)
        ed.sig_text_changed.connect(lambda e=ed: self._on_text_changed(e))
        ed.sig_modified_changed.connect(lambda _m, e=ed: self._update_tab(e))
        ed.sig_cursor_moved.connect(self._on_cursor_moved)
        ed.sig_goto_definition.connect(self.goto_definition)
        name = Path(path).name + (" (built-in)" if builtin else "")
        ic = "file-header" if path.endswith(".h") else (
            "file-plc-sw" if ed.kind is Kind.SOFTWARE else "file-plc" if ed.kind else "file")
        idx = self.tabs.addTab(ed, icon(ic), name)
        self.tabs.setTabToolTip(idx, path)
        if not builtin:
            self.disk.watch(path, disk if disk is not None else file_digest(path))
        self._apply_defines(ed)
        ed.set_diagnostics(self.store.for_file(path))
        if ed.kind is not None and not builtin:
            self._schedule_compile(ed, immediate=True)
        self._update_actions()
        return ed

    def _update_tab(self, ed: CodeEditor) -> None:
        i = self.tabs.indexOf(ed)
        if i < 0:
            return
        name = Path(ed.path).name + (" (built-in)" if ed.builtin else "")
        self.tabs.setTabText(i, name + (" ●" if self.is_modified(ed) else ""))
        if ed is self.current_editor():
            self._update_title()

    def _update_title(self) -> None:
        ed = self.current_editor()
        parts = []
        if ed is not None:
            parts.append(Path(ed.path).name + "[*]")
            self.setWindowModified(self.is_modified(ed))
        else:
            self.setWindowModified(False)
        if self.project is not None:
            parts.append(self.project.name)
        parts.append(APP_NAME)
        self.setWindowTitle(" — ".join(parts))

    def _close_all_editors(self, force: bool = False) -> bool:
        if not force and not self._confirm_discard_all("Close All"):
            return False
        for ed in self.editors():
            if self.is_modified(ed):
                self.recovery.discard(ed.path)
            self.close_editor(ed, force=True)
        return True

    def _confirm_discard_all(self, title: str) -> bool:
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

    def _ask_save(self, editors: list, title: str):
        if len(editors) == 1:
            text = f"{Path(editors[0].path).name} has unsaved changes. Save them?"
        else:
            names = "\n".join(f"  • {Path(e.path).name}" for e in editors)
            text = f"These files have unsaved changes:\n\n{names}\n\nSave them?"
        return QMessageBox.warning(
            self, title, text, QMessageBox.StandardButton.Save |
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

    def _with_editor(self, fn):
        def run():
            ed = self.current_editor()
            if ed is not None:
                fn(ed)
        return run

    def tab_menu(self, index: int):
        """The context menu of an editor tab (built, not shown: tests use it)."""
        from PySide6.QtWidgets import QMenu
        ed = self.tabs.widget(index)
        menu = QMenu(self)
        if not isinstance(ed, CodeEditor):
            return menu
        menu.addAction("Close", lambda: self.close_editor(ed)).setObjectName("close")
        menu.addAction("Close Others", lambda: self._close_others(ed)).setObjectName("others")
        menu.addAction("Close All", lambda: self._close_all_editors()).setObjectName("all")
        menu.addSeparator()
        menu.addAction("Copy Path", lambda: QApplication.clipboard().setText(ed.path)) \
            .setObjectName("copy_path")
        act = menu.addAction("Show in Project", lambda: self._reveal(ed.path))
        act.setObjectName("reveal")
        act.setEnabled(self.tree.find_item(ed.path) is not None)
        return menu

    def _tab_context_menu(self, point) -> None:
        index = self.tabs.tabBar().tabAt(point)
        if index >= 0:
            self.tab_menu(index).exec(self.tabs.tabBar().mapToGlobal(point))

    def _close_others(self, keep: CodeEditor) -> None:
        for ed in self.editors():
            if ed is not keep and not self.close_editor(ed):
                return

    def _reveal(self, path: str) -> None:
        self.project_dock.show()
        self.project_dock.raise_()
        self.tree.select_path(path)

    def eventFilter(self, obj, event) -> bool:  # noqa: N802 - Qt override
        from PySide6.QtCore import QEvent
        if obj is self.tabs.tabBar() and event.type() == QEvent.Type.MouseButtonRelease \
                and event.button() == Qt.MouseButton.MiddleButton:
            index = obj.tabAt(event.position().toPoint())
            if index >= 0:
                self.close_editor(self.tabs.widget(index))
                return True
        return super().eventFilter(obj, event)

    # ---------------------------------------------------------- drag & drop
    def dragEnterEvent(self, event) -> None:  # noqa: N802 - Qt override
        if event.mimeData().hasUrls() and any(u.isLocalFile() for u in event.mimeData().urls()):
            event.acceptProposedAction()

    def dropEvent(self, event) -> None:  # noqa: N802 - Qt override
        self.open_paths([u.toLocalFile() for u in event.mimeData().urls() if u.isLocalFile()])
        event.acceptProposedAction()

    def open_paths(self, paths: list) -> None:
        """Dropped files and folders: a folder opens as the project, files open
        in editors."""
        for p in map(Path, paths):
            if p.is_dir():
                self.open_project(p)
                return
        for p in map(Path, paths):
            if p.is_file() and p.suffix.lower() in TEXT_SUFFIXES:
                self.open_file(p)

    def _cycle_tab(self, step: int) -> None:
        n = self.tabs.count()
        if n:
            self.tabs.setCurrentIndex((self.tabs.currentIndex() + step) % n)

    def _show_welcome(self) -> None:
        has_tabs = self.tabs.count() > 0
        self.stack.setCurrentWidget(self.tabs if has_tabs else self.welcome)
        if not has_tabs:
            self.find_bar.hide()
        if self.project is None:
            self.welcome_text.setText(
                "An editor, compiler and simulated controller for myCNC PLC procedures.<br><br>"
                "Open a project folder (with <tt>hardware/</tt> and <tt>software/</tt>), or start "
                "from a copy of the example project.")
            self.welcome_new.hide()
        else:
            p = self.project
            hw = len(p.procedures(Kind.HARDWARE))
            sw = len(p.procedures(Kind.SOFTWARE))
            self.welcome_text.setText(
                f"<b>{p.name}</b> — {p.root}<br>{hw} hardware and {sw} software procedures."
                "<br><br>Open a procedure from the <b>Project</b> panel, or press "
                "<b>Ctrl+B</b> to build them all.")
            self.welcome_new.show()

    # ---------------------------------------------------------- find / goto
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
        res = dialogs.GoToLineDialog.get_line(self, line, ed.lineCount())
        if res is None:
            return False
        ed.goto_line(*res)
        ed.take_focus()
        return True

    def goto_definition(self, word: str) -> bool:
        if not word:
            return False
        ed = self.current_editor()
        result = self._results.get(file_key(ed.path)) if ed is not None else None
        symbols = getattr(result, "symbols", None)
        if symbols is not None:
            d = (symbols.defines or {}).get(word)
            if d is not None and d[1] is not None:
                self.open_location(d[1].file, d[1].line, d[1].col)
                return True
            span = (symbols.procedures or {}).get(word)
            if span is not None:
                self.open_location(span.file, span.line, span.col)
                return True
        hd = self._header_defines.get(word)
        if hd is not None:
            self.open_location(hd[1], hd[2], 1)
            return True
        if ed is not None:
            m = re.search(rf"^[ \t]*{re.escape(word)}[ \t]*\([ \t]*\)", ed.text(), re.M)
            if m:
                line = ed.text().count("\n", 0, m.start()) + 1
                ed.goto_line(line)
                return True
        self.statusBar().showMessage(f"No definition of {word} in the project "
                                     "(built-in names have none)", 4000)
        return False

    # =========================================================== diagnostics
    def _options_for(self, path: str) -> api.CompileOptions:
        if self.project is None:
            return api.CompileOptions(kind=api.kind_of(path))
        return self.project.compile_options(path)

    def _schedule_compile(self, ed: CodeEditor, immediate: bool = False) -> None:
        if ed.kind is None or ed.builtin:
            return
        key = file_key(ed.path)
        if immediate:
            self.worker.submit(key, ed.path, ed.text(), self._options_for(ed.path))
        else:
            self.worker.schedule(key, lambda e=ed: (e.path, e.text(), self._options_for(e.path)))

    def _relint_from_disk(self, path: str) -> None:
        if path.endswith(".plc") and Path(path).exists():
            self.worker.submit(file_key(path), path, None, self._options_for(path))

    def _relint_open_procedures(self) -> None:
        for ed in self.editors():
            if ed.kind is not None and not ed.builtin:
                self._schedule_compile(ed, immediate=True)

    def _lint_project(self) -> None:
        """Check every procedure of the project in the background (Problems)."""
        if self.project is None:
            return
        try:
            procs = self.project.procedures()
        except ProjectError:
            return
        for proc in procs:
            if self.editor_for(proc.path) is None:
                self._relint_from_disk(str(proc.path))

    def _on_text_changed(self, ed: CodeEditor) -> None:
        if ed.kind is not None:
            self._schedule_compile(ed)
        # headers: the procedures that include them are checked when they are saved
        self._update_tab(ed)

    def _on_compile_result(self, key: str, result) -> None:
        if self.project is not None or self.editors():       # not after Close Project
            self._results[key] = result
            self._sizes[key] = (result.size, result.limit)
            self.store.set(f"proc:{key}", result.diagnostics)
            self._problems_timer.start()           # many results in a row: one refresh
            ed = self.editor_for(result.path) if not result.path.startswith("<") else None
            if ed is not None:
                self._apply_defines(ed)
            if ed is not None and ed is self.current_editor():
                self._update_size_label()
            self.sig_diagnostics_updated.emit(key)

    def _apply_defines(self, ed: CodeEditor) -> None:
        result = self._results.get(file_key(ed.path))
        names = set(self._header_defines)
        if result is not None and getattr(result, "symbols", None) is not None:
            names |= set(result.symbols.defines or {})
        names |= set(completion.scan_defines(ed.text()) if ed.length() < 200_000 else ())
        ed.highlighter.set_defines(names)

    def _refresh_problems(self) -> None:
        self.problems.set_problems(self.store.all())
        for ed in self.editors():
            ed.set_diagnostics(self.store.for_file(ed.path))
        marks: dict[str, int] = {}
        for d in self.store.all():
            if d.span is None:
                continue
            k = file_key(d.span.file)
            level = 1 if d.severity == Severity.ERROR else 2
            marks[k] = min(marks.get(k, 3), level)
        self.tree.set_problem_files(marks)
        self._update_problem_counts()

    def _update_problem_counts(self) -> None:
        e, w = self.store.counts()
        self.problems_button.setIcon(icon("error" if e else "warning" if w else "ok"))
        self.problems_button.setText(f" {e} error{'s' * (e != 1)}, {w} warning{'s' * (w != 1)}")
        self.problems_button.setToolButtonStyle(Qt.ToolButtonStyle.ToolButtonTextBesideIcon)
        self.problems_dock.setWindowTitle(f"Problems ({e + w})" if e + w else "Problems")

    def _refresh_header_defines(self) -> None:
        dirs = self.project.include_dirs() if self.project is not None else ()
        self._header_defines = self._header_scan.defines(dirs)
        if self.run_panels is not None:
            try:
                from plcbuilder.ide.panels import pin_names_from_defines
                self.run_panels.set_pin_names(*pin_names_from_defines(
                    {k: v[0] for k, v in self._header_defines.items()}))
            except Exception:  # noqa: BLE001 - pin names are a nicety
                pass

    # --------------------------------------------------------- completion/hover
    def _complete(self, ed: CodeEditor, prefix: str) -> list:
        result = self._results.get(file_key(ed.path))
        return completion.completions(prefix, kind=ed.kind or Kind.HARDWARE, text=ed.text(),
                                      symbols=getattr(result, "symbols", None),
                                      defines=self._header_defines)

    def _hover(self, ed: CodeEditor, pos: int) -> Optional[str]:
        start, end, word = ed.word_at(pos)
        if not word:
            return None
        line0 = ed.lineFromPosition(start)
        before = ed.byte_range_text(ed.positionFromLine(line0), start)
        result = self._results.get(file_key(ed.path))
        text = ed.text()
        return hover.hover_text(word, before, kind=ed.kind or Kind.HARDWARE,
                                symbols=getattr(result, "symbols", None),
                                header_defines=self._header_defines,
                                variables=tuple(completion.scan_variables(text)))

    # ================================================================ build
    def _on_build_progress(self, done: int, total: int, name: str) -> None:
        self.build_panel.on_progress(done, total, name)
        if name:
            self.statusBar().showMessage(f"Building {done}/{total}: {name}")

    def _on_build_finished(self, result) -> None:
        self.build_panel.show_result(result, self.build_runner.elapsed)
        self.action(Act.BUILD_ALL).setEnabled(self.project is not None)
        upload = self._upload_after_build
        self._upload_after_build = False
        if isinstance(result, BaseException):
            self.statusBar().showMessage(f"Build failed: {result}", 8000)
            self.sig_build_finished.emit(result)
            return
        modified = {file_key(e.path) for e in self.modified_editors()}
        for pb in result.procedures:
            key = file_key(pb.path)
            if key in modified:
                continue                        # the editor's live diagnostics stay
            self.store.set(f"proc:{key}", pb.diagnostics)
            self._sizes[key] = (pb.size, pb.limit)
        live = {f"proc:{file_key(pb.path)}" for pb in result.procedures}
        for src in self.store.sources():
            if src.startswith("proc:") and src not in live and self.editor_for(src[5:]) is None:
                self.store.remove(src)          # procedures that are gone
        self.store.set("project", result.diagnostics)
        self._refresh_problems()
        self._update_size_label()
        e, w = result.error_count, result.warning_count
        if result.ok:
            self.statusBar().showMessage(f"Build succeeded: {result.image_message}", 8000)
        else:
            self.statusBar().showMessage(f"Build failed: {e} error{'s' * (e != 1)}, "
                                         f"{w} warning{'s' * (w != 1)}", 8000)
            self.problems_dock.raise_()
        self.tree.refresh()
        self.sig_build_finished.emit(result)
        if upload and result.ok:
            self._upload_image()

    def _upload_image(self) -> bool:
        if self.project is None or self.connection is None:
            return False
        try:
            data = read_bounded(self.project.image_path, MAX_IMAGE, "controller image")
        except OSError as exc:
            QMessageBox.warning(self, "Upload", f"Cannot read {self.project.image_path}:\n\n"
                                                f"{exc.strerror or exc}\n\nBuild the project first.")
            return False
        self.connection.upload(data)
        self.statusBar().showMessage(f"Uploading {self.project.image_path.name} "
                                     f"({len(data)} bytes)…", 5000)
        return True

    # ============================================================ controller
    def _start_controller_for_project(self) -> None:
        c = self.connection
        if c is None or not self.start_controller or not hasattr(c, "start_embedded"):
            return
        p = self.project
        address = p.settings.controller_address if p is not None else ""
        if address:
            self._connect_to_address(address)
            return
        c.start_embedded(self._controller_args())

    def _controller_args(self) -> list[str]:
        p = self.project
        args: list[str] = []
        if p is None:
            return args
        if p.machine_path.is_file():
            args += ["--machine", str(p.machine_path)]
        if p.variables_path.is_file():
            args += ["--variables", str(p.variables_path)]
        lim = p.limits
        args += ["--limits", f"{lim.hw_proc},{lim.hw_total},{lim.sw_proc}"]
        return args

    def _connect_to_address(self, address: str) -> None:
        host, _, port = address.rpartition(":")
        token = ""
        try:
            from plcbuilder.link import runtime
            ep = runtime.read()
            if str(ep.port) == port:
                token = ep.token
        except Exception:  # noqa: BLE001 - no runtime file: ask
            pass
        if not token:
            res = dialogs.ConnectDialog.get_address(self, host.strip("[]"), int(port or 5700))
            if res is None:
                return
            host, port, token = res
        self.connection.connect_to(host.strip("[]"), int(port), token)

    def connect_dialog(self) -> bool:
        if self.connection is None:
            return False
        host, port, token = "127.0.0.1", 5700, ""
        try:
            from plcbuilder.link import runtime
            ep = runtime.read()
            host, port, token = ep.host, ep.port, ep.token
        except Exception:  # noqa: BLE001
            pass
        res = dialogs.ConnectDialog.get_address(self, host, port, token)
        if res is None:
            return False
        host, port, token = res
        if not token:
            try:
                from plcbuilder.link import runtime
                token = runtime.read().token
            except Exception:  # noqa: BLE001
                pass
        self.connection.connect_to(host, port, token)
        self.statusBar().showMessage(f"Connecting to {host}:{port}…", 4000)
        return True

    def _use_embedded(self) -> None:
        if self.connection is not None and hasattr(self.connection, "start_embedded"):
            self.connection.start_embedded(self._controller_args())

    def _reset_controller(self) -> None:
        if self.connection is not None:
            self.connection.reset()

    def _start_current(self) -> None:
        ed = self.current_editor()
        if ed is not None and ed.kind is not None:
            self.start_procedure(Path(ed.path).stem, self._last_eparam)
        else:
            self.start_procedure()

    def _set_connection_text(self, text: str, connected: bool) -> None:
        self.connection_label.setText(("● " if connected else "○ ") + text)
        self.connection_label.setStyleSheet("color: #1a7f37;" if connected else "color: #6e7781;")

    def _on_connected(self, address: str) -> None:
        embedded = getattr(self.connection, "embedded", False)
        self._set_connection_text(f"{'embedded ' if embedded else ''}controller {address}", True)
        self._update_actions()

    def _on_disconnected(self, reason: str) -> None:
        self._set_connection_text("disconnected", False)
        self.connection_label.setToolTip(reason)
        if reason and not self._closing:
            self.statusBar().showMessage(f"Controller: {reason}", 6000)
        self._update_actions()

    def _on_state(self, st: ControllerStatus, missed: int = 0) -> None:
        self._last_state = st
        self.time_label.setText(f"t = {st.t_ms / 1000:.3f} s")
        running = st.running
        self.running_label.setText(f"▶ {running}" if running else "idle")
        self.running_label.setStyleSheet("color: #1a7f37; font-weight: 600;" if running else "")
        name = st.proc_name or api.proc_name(st.proc)
        self.proc_label.setText(f"proc {st.proc}" + (f" {name}" if name else ""))
        self.tree.set_running(running)

    def connected(self) -> bool:
        return bool(getattr(self.connection, "connected", False))

    # ================================================================= files
    def _on_file_created(self, path: str) -> None:
        self.open_file(path)
        self._lint_project()
        self._show_welcome()

    def _on_file_renamed(self, old: str, new: str) -> None:
        ed = self.editor_for(old)
        self.store.remove(f"proc:{file_key(old)}")
        self._results.pop(file_key(old), None)
        self.recovery.discard(old)
        if ed is not None:
            self.disk.unwatch(old)
            self.worker.cancel(file_key(old))
            ed.path = new
            ed.kind = api.kind_of(new) if new.endswith(".plc") else None
            self.tabs.setTabToolTip(self.tabs.indexOf(ed), new)
            self.disk.watch(new, file_digest(new))
            self._update_tab(ed)
            self._schedule_compile(ed, immediate=True)
        else:
            self._relint_from_disk(new)
        self._refresh_problems()

    def _on_file_deleted(self, path: str) -> None:
        ed = self.editor_for(path)
        if ed is not None:
            self.recovery.discard(path)
            self.close_editor(ed, force=True)
        self.store.remove(f"proc:{file_key(path)}")
        self._results.pop(file_key(path), None)
        self._refresh_problems()

    def _on_tree_changed(self) -> None:
        self._refresh_header_defines()
        self._lint_project()
        self._show_welcome()

    def _on_disk_changed(self, path: str) -> None:
        ed = self.editor_for(path)
        if ed is None or path in self._prompting or self._closing:
            return
        name = Path(path).name
        if not self.is_modified(ed) and self.prefs.reload_unmodified:
            self._reload_editor(ed)
            self.statusBar().showMessage(f"Reloaded {name}: it changed on disk", 5000)
            return
        self._prompting.add(path)
        try:
            answer = QMessageBox.question(
                self, "File Changed on Disk",
                f"{name} was changed on disk by another program."
                + ("\n\nReload it and lose your unsaved changes?" if self.is_modified(ed)
                   else "\n\nReload it?"),
                QMessageBox.StandardButton.Yes | QMessageBox.StandardButton.No,
                QMessageBox.StandardButton.Yes if not self.is_modified(ed)
                else QMessageBox.StandardButton.No)
        finally:
            self._prompting.discard(path)
        if answer == QMessageBox.StandardButton.Yes:
            self._reload_editor(ed)
        else:
            ed.force_dirty = True       # the editor's text now differs from the file
            self._update_tab(ed)

    def _on_disk_deleted(self, path: str) -> None:
        ed = self.editor_for(path)
        if ed is None or path in self._prompting or self._closing:
            return
        self._prompting.add(path)
        try:
            answer = QMessageBox.question(
                self, "File Deleted",
                f"{Path(path).name} was deleted from disk.\n\nKeep it open in the editor "
                "(save it to write it back)?",
                QMessageBox.StandardButton.Yes | QMessageBox.StandardButton.No,
                QMessageBox.StandardButton.Yes)
        finally:
            self._prompting.discard(path)
        if answer == QMessageBox.StandardButton.Yes:
            ed.force_dirty = True
            self._update_tab(ed)
        else:
            self.close_editor(ed, force=True)

    def _on_app_state(self, state) -> None:
        if state == Qt.ApplicationState.ApplicationActive and not self._closing:
            self.disk.check_all()

    def _recovery_snapshot(self) -> list:
        root = str(self.project.root) if self.project is not None else ""
        return [(ed.path, ed.text(), root) for ed in self.modified_editors()]

    # =================================================================== ui
    def _on_current_changed(self, _index: int) -> None:
        ed = self.current_editor()
        self.find_bar.set_editor(ed)
        if ed is not None:
            line, col = ed.cursor_line_col()
            self._on_cursor_moved(line, col)
            self.eol_label.setText("UTF-8  " + ("CRLF" if ed.eol == "\r\n" else "LF") +
                                   ("  read-only" if ed.readOnly() else ""))
        else:
            self.cursor_label.setText("")
            self.eol_label.setText("")
        self._update_size_label()
        self._update_title()
        self._update_actions()

    def _on_cursor_moved(self, line: int, col: int) -> None:
        self.cursor_label.setText(f"Ln {line}, Col {col}")

    def _update_size_label(self) -> None:
        ed = self.current_editor()
        if ed is None or ed.kind is None:
            self.size_label.setText("")
            self.size_label.setStyleSheet("")
            return
        size, limit = self._sizes.get(file_key(ed.path), (None, None))
        if limit is None:
            limit = self._options_for(ed.path).limit
        used = "-" if size is None else str(size)
        self.size_label.setText(f"{Path(ed.path).stem}: {used}/{limit} bytes")
        if size is None:
            style = "color: #9a6700;"
        elif size > limit:
            style = "color: #d1242f; font-weight: 600;"
        elif size > 0.9 * limit:
            style = "color: #9a6700;"
        else:
            style = ""
        self.size_label.setStyleSheet(style)

    def size_text(self) -> str:
        return self.size_label.text()

    def _update_actions(self) -> None:
        has_project = self.project is not None
        ed = self.current_editor()
        has_editor = ed is not None
        for name in (Act.NEW_PROCEDURE, Act.NEW_HEADER, Act.CLOSE_PROJECT):
            self.action(name).setEnabled(has_project)
        self.action(Act.BUILD_ALL).setEnabled(has_project and not self.build_runner.running())
        for name in (Act.SAVE, Act.REVERT, Act.CLOSE_EDITOR, Act.CLOSE_ALL, Act.FIND,
                     Act.REPLACE, Act.GOTO_LINE, Act.TOGGLE_COMMENT, Act.GOTO_DEFINITION):
            self.action(name).setEnabled(has_editor)
        if has_editor and ed.builtin:
            self.action(Act.SAVE).setEnabled(False)
            self.action(Act.TOGGLE_COMMENT).setEnabled(False)
        run = self.connection is not None and has_project
        for name in (Act.UPLOAD, Act.START, Act.START_CURRENT, Act.STOP, Act.RESET_CONTROLLER):
            self.action(name).setEnabled(run)
        for name in (Act.CONNECT, Act.EMBEDDED):
            self.action(name).setEnabled(self.connection is not None)
        self.speed_combo.setEnabled(self.connection is not None)
        if self.connection is None:
            tip = "The run side (controller connection) is not available"
            for name in (Act.UPLOAD, Act.START, Act.STOP):
                self.action(name).setToolTip(tip)

    def _open_project_dialog(self) -> bool:
        start = str(self.project.root.parent) if self.project else str(Path.home())
        folder = QFileDialog.getExistingDirectory(self, "Open Project Folder", start)
        if not folder:
            return False
        return self.open_project(folder)

    def about(self) -> None:
        from plcbuilder import __version__
        QMessageBox.about(
            self, f"About {APP_NAME}",
            f"<h3>{APP_NAME} {__version__}</h3>"
            "<p>An editor, compiler and simulated controller for myCNC PLC procedures.</p>"
            "<p>Write hardware and software PLC procedures, see problems while you type, "
            "Build All into <tt>build/eeprom.rom</tt>, upload it to the simulated controller "
            "and watch it run.</p>")

    # ================================================================ close
    def closeEvent(self, event) -> None:  # noqa: N802 - Qt override
        if not self._confirm_discard_all("Quit"):
            event.ignore()
            return
        self._closing = True
        self._save_session()
        self.settings.save_window_state(self.saveGeometry(), self.saveState())
        self.settings.sync()
        self.shutdown()
        self.recovery.discard_all_own()
        event.accept()

    def shutdown(self) -> None:
        """Stop the timers, threads and the controller (also for tests)."""
        self._closing = True
        self.recovery.stop()
        self.worker.shutdown()
        self.build_runner.wait(10)
        if self.run_panels is not None:
            try:
                self.run_panels.shutdown()
            except Exception:  # noqa: BLE001
                pass
        if self.connection is not None and hasattr(self.connection, "shutdown"):
            try:
                self.connection.shutdown()
            except Exception:  # noqa: BLE001
                pass


class _PlainLexer:
    """Plain text: one token."""

    @staticmethod
    def get_tokens_unprocessed(text):
        from pygments.token import Text
        yield 0, Text, text


def _unique_folder(parent: Path, base: str) -> Path:
    cand = parent / base
    i = 2
    while cand.exists():
        cand = parent / f"{base}-{i}"
        i += 1
    return cand


def _rel(path: str, root: Path) -> str:
    try:
        return os.path.relpath(path, root)
    except ValueError:
        return path
