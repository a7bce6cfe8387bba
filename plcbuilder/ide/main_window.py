"""The IDE's main window: it makes the parts and wires them together.

    ┌ menus, toolbar: New · Save · Build All · Upload · Start · Stop · speed ──────┐
    │ Project │ tabbed editors (+ find/replace bar)          │ run docks          │
    │         ├──────────────────────────────────────────────┤                    │
    │         │ Problems · Build Output · Run log            │                    │
    └ status: message · connection · sim time · running · proc · size · Ln/Col ──┘

The parts, each with its own signals (``sig_…``):

* :class:`~plcbuilder.ide.editor_stack.EditorStack` — the editor tabs, save,
  revert, close prompts, files changed on disk, the recovery autosave;
* :class:`~plcbuilder.ide.lint.Lint` — the diagnostics worker, the problem store
  and the symbol caches (completion, hover, go to definition);
* :class:`~plcbuilder.ide.run_actions.RunActions` — Build All, Upload, Start,
  Stop, the speed, and the controller connection;
* :class:`~plcbuilder.ide.project_tree.ProjectTree`, the Problems and Build
  Output panels, :class:`~plcbuilder.ide.status_bar.StatusBar` and the run docks
  (:mod:`plcbuilder.ide.panels`).

The window owns the project (:class:`plcbuilder.project.model.Project`) and
tells the parts when it changes; the actions are named by :class:`Act`.
"""

from __future__ import annotations

from pathlib import Path
from typing import Optional

from PySide6.QtCore import QSize, Qt, QTimer, Signal
from PySide6.QtGui import QAction, QKeySequence
from PySide6.QtWidgets import (QApplication, QDockWidget, QFileDialog, QLabel, QMainWindow,
                               QMessageBox, QToolBar)

from plcbuilder.api import Kind
from plcbuilder.ide import dialogs
from plcbuilder.ide.build_panel import BuildPanel
from plcbuilder.ide.editor import CodeEditor, file_key
from plcbuilder.ide.editor_stack import EditorStack
from plcbuilder.ide.icons import icon
from plcbuilder.ide.lint import Lint
from plcbuilder.ide.problems import ProblemsPanel
from plcbuilder.ide.project_tree import ProjectTree
from plcbuilder.ide.run_actions import SPEEDS, RunActions
from plcbuilder.ide.settings import Preferences, Settings
from plcbuilder.ide.status_bar import StatusBar
from plcbuilder.ide.welcome import APP_NAME
from plcbuilder.lang.preprocess import BUILTIN_PREFIX
from plcbuilder.link.client import ControllerStatus
from plcbuilder.project.model import Project, ProjectError

__all__ = ["APP_NAME", "Act", "MainWindow", "SPEEDS"]

SOURCE_SUFFIXES = (".plc", ".h")
TEXT_SUFFIXES = (".plc", ".h", ".toml", ".xml", ".md", ".txt")


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
        self._project: Optional[Project] = None
        self._actions: dict[str, QAction] = {}
        self._closing = False
        self._last_state = ControllerStatus()
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

        # the parts
        self.editor_stack = EditorStack(self, self.prefs, self.settings.recovery_dir())
        self.setCentralWidget(self.editor_stack)
        self.tree = ProjectTree(self)
        self.problems = ProblemsPanel(self)
        self.build_panel = BuildPanel(self)
        self.lint = Lint(self, self.editor_stack, self.problems, debounce_ms)
        self.run_actions = RunActions(self, self.editor_stack, self.build_panel, self.prefs,
                                      connection=connection, start_controller=start_controller)
        self.status = StatusBar(self)
        self.setStatusBar(self.status)
        # the parts' widgets, by the names the window always had
        es = self.editor_stack
        self.tabs, self.stack, self.find_bar = es.tabs, es.stack, es.find_bar
        self.welcome, self.welcome_recent = es.welcome, es.welcome.welcome_recent
        self.recovery, self.store = es.recovery, self.lint.store

        self._build_docks()
        self._build_actions()
        self._build_menus()
        self._build_toolbar()
        self._wire()
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
    @property
    def project(self) -> Optional[Project]:
        """The open project (None: no project)."""
        return self._project

    @project.setter
    def project(self, project: Optional[Project]) -> None:
        self._project = project
        self.editor_stack.project = self.lint.project = self.run_actions.project = project

    @property
    def connection(self):
        """The controller connection (None: no run side)."""
        return self.run_actions.connection

    def action(self, name: str) -> QAction:
        return self._actions[name]

    def editors(self) -> list[CodeEditor]:
        return self.editor_stack.editors()

    def current_editor(self) -> Optional[CodeEditor]:
        return self.editor_stack.current_editor()

    def editor_for(self, path) -> Optional[CodeEditor]:
        return self.editor_stack.editor_for(path)

    def busy(self) -> bool:
        """Diagnostics or a build still on their way (tests and screenshots wait)."""
        return self.lint.busy() or self.run_actions.building()

    def is_modified(self, editor: CodeEditor) -> bool:
        return self.editor_stack.is_modified(editor)

    def modified_editors(self) -> list[CodeEditor]:
        return self.editor_stack.modified_editors()

    def open_file(self, path, line: Optional[int] = None, col: int = 1, *,
                  focus: bool = True) -> Optional[CodeEditor]:
        """Open (or show) a file in an editor tab, optionally at a line."""
        return self.editor_stack.open_file(path, line, col, focus=focus)

    def open_location(self, file: str, line: int, col: int = 1) -> Optional[CodeEditor]:
        return self.editor_stack.open_location(file, line, col)

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

    def save_editor(self, editor: Optional[CodeEditor] = None) -> bool:
        return self.editor_stack.save_editor(editor)

    def save_all(self) -> bool:
        return self.editor_stack.save_all()

    def close_editor(self, editor: Optional[CodeEditor] = None, *, force: bool = False) -> bool:
        return self.editor_stack.close_editor(editor, force=force)

    def revert_editor(self, editor: Optional[CodeEditor] = None) -> bool:
        return self.editor_stack.revert_editor(editor)

    def offer_recovery(self) -> int:
        """Offer back the unsaved changes a crashed session left (of this project)."""
        return self.editor_stack.offer_recovery()

    def tab_menu(self, index: int):
        """The context menu of an editor tab (built, not shown: tests use it)."""
        return self.editor_stack.tab_menu(index)

    def show_find(self, replace: bool = False) -> None:
        self.editor_stack.show_find(replace)

    def goto_line_dialog(self) -> bool:
        return self.editor_stack.goto_line_dialog()

    def goto_definition(self, word: str) -> bool:
        return self.lint.goto_definition(word)

    def build_all(self) -> bool:
        """Build All (saving first when the preference says so)."""
        return self.run_actions.build_all()

    def upload(self) -> bool:
        """Upload build/eeprom.rom (building first when the preference says so)."""
        return self.run_actions.upload()

    def start_procedure(self, name: Optional[str] = None, eparam: Optional[int] = None) -> bool:
        """Start a procedure on the controller (asking which, when not given)."""
        return self.run_actions.start_procedure(name, eparam)

    def stop(self) -> None:
        self.run_actions.stop()

    def set_speed(self, mode: str) -> None:
        self.run_actions.set_speed(mode)

    def connect_dialog(self) -> bool:
        return self.run_actions.connect_dialog()

    def connected(self) -> bool:
        return self.run_actions.connected()

    def size_text(self) -> str:
        return self.status.size_label.text()

    # ------------------------------------------------------------- project
    def open_project(self, path, *, offer_recovery: bool = True) -> bool:
        """Open a project folder (asking about unsaved changes first)."""
        if not self.editor_stack.confirm_discard_all("Open Project"):
            return False
        try:
            project = Project.open(Path(path).expanduser().resolve())
        except ProjectError as exc:
            QMessageBox.critical(self, "Open Project", f"Cannot open the project:\n\n{exc}")
            self.settings.remove_recent_project(str(Path(path).expanduser().resolve()))
            self._fill_recent_menu()
            return False
        self.editor_stack.close_all(force=True)
        self.project = project
        self.lint.clear()
        self.problems.set_root(project.root)
        self.tree.set_project(project)
        self.settings.add_recent_project(project.root)
        self._fill_recent_menu()
        self.lint.refresh_header_defines()
        self.lint.lint_project()
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
        self.lint.refresh_problems()
        self.run_actions.start_controller_for_project()
        self.statusBar().showMessage(f"Opened {project.name} ({project.root})", 5000)
        self.sig_project_opened.emit(str(project.root))
        return True

    def close_project(self) -> bool:
        if not self.editor_stack.confirm_discard_all("Close Project"):
            return False
        self._save_session()
        self.editor_stack.close_all(force=True)
        self.project = None
        self.lint.clear(sizes=False)
        self.tree.set_project(None)
        self.problems.set_root(None)
        self.lint.refresh_problems()
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


    def _open_project_dialog(self) -> bool:
        start = str(self.project.root.parent) if self.project else str(Path.home())
        folder = QFileDialog.getExistingDirectory(self, "Open Project Folder", start)
        if not folder:
            return False
        return self.open_project(folder)

    def _on_file_saved(self, path: str) -> None:
        if self.project is not None and file_key(path) == file_key(self.project.settings_path):
            self._reload_project_settings()
        else:
            self.lint.on_file_saved(path)
        self.tree.refresh()

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
            self.lint.refresh_problems()
            self.statusBar().showMessage("plcbuilder.toml has a mistake: the previous settings "
                                         "stay in use", 8000)
            return
        self.store.remove("settings")
        self.project = project
        self.tree.project = project
        self.tree.refresh(force=True)
        self.lint.relint_open_procedures()
        self.lint.lint_project()
        self.lint.refresh_problems()
        self._update_title()
        self.statusBar().showMessage("Project settings reloaded", 4000)


    # ========================================================= construction
    def _build_docks(self) -> None:
        self.project_dock = self._dock("Project", "projectDock", self.tree,
                                       Qt.DockWidgetArea.LeftDockWidgetArea)
        self.problems_dock = self._dock("Problems", "problemsDock", self.problems,
                                        Qt.DockWidgetArea.BottomDockWidgetArea)
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
        A(Act.CLOSE_ALL, "Close All Editors", lambda: self.editor_stack.close_all(), "Ctrl+Shift+W")
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
        A(Act.NEXT_TAB, "Next Editor", lambda: self.editor_stack.cycle_tab(1), "Ctrl+PgDown")
        A(Act.PREVIOUS_TAB, "Previous Editor", lambda: self.editor_stack.cycle_tab(-1), "Ctrl+PgUp")
        A(Act.RESET_LAYOUT, "Reset Layout", self.reset_layout)
        A(Act.BUILD_ALL, "&Build All", self.build_all, "Ctrl+B", "build",
          "Compile every procedure and write build/eeprom.rom")
        A(Act.UPLOAD, "&Upload", self.upload, "Ctrl+U", "upload",
          "Upload build/eeprom.rom to the controller")
        A(Act.START, "&Start…", self.start_procedure, "F5", "start",
          "Start a procedure on the controller (by name or M-code, with eparam)")
        A(Act.START_CURRENT, "Start &This Procedure", self.run_actions.start_current, "Ctrl+F5", None,
          "Start the procedure of the current editor with the last eparam")
        A(Act.STOP, "S&top", self.stop, "Shift+F5", "stop",
          "Stop: the first press starts M02, the second OFF")
        A(Act.RESET_CONTROLLER, "&Reset Controller", self.run_actions.reset_controller, None, "reset",
          "A fresh controller with the same image (time starts again at 0)")
        A(Act.CONNECT, "&Connect to Controller…", self.connect_dialog, None, "connect",
          "Connect to a running plcbuilder controller")
        A(Act.EMBEDDED, "Use the &Embedded Controller", self.run_actions.use_embedded, None, "controller",
          "Run the simulated controller as a child process of the IDE")
        A(Act.ABOUT, "&About PLC Builder", self.about)
        context = [self._actions[a] for a in (Act.TOGGLE_COMMENT, Act.GOTO_DEFINITION)] + \
            [None] + [self._actions[a] for a in (Act.FIND, Act.GOTO_LINE)]
        self.editor_stack.context_actions = context

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
        for act in self.run_actions.speed_actions.values():
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
        self.welcome.set_recent(recent)

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
        tb.addWidget(self.run_actions.make_speed_combo(tb))
        self.toolbar = tb
        self.addToolBar(Qt.ToolBarArea.TopToolBarArea, tb)

    def _wire(self) -> None:
        """Connect the parts' signals."""
        msg = self.statusBar().showMessage
        es, lint, run, tree = self.editor_stack, self.lint, self.run_actions, self.tree
        for part in (es, lint, run):
            part.sig_message.connect(lambda text, ms: msg(text, ms) if ms else msg(text))
        # the editors
        es.can_reveal = lambda path: tree.find_item(path) is not None
        es.sig_editor_created.connect(lint.attach)
        es.sig_editors_changed.connect(self._update_actions)
        es.sig_current_changed.connect(self._on_current_changed)
        es.sig_title_changed.connect(self._update_title)
        es.sig_cursor_moved.connect(self.status.show_cursor)
        es.sig_goto_definition.connect(lint.goto_definition)
        es.sig_file_saved.connect(self._on_file_saved)
        es.sig_changes_discarded.connect(lint.on_changes_discarded)
        es.sig_reveal.connect(self._reveal)
        es.welcome.sig_open_project.connect(self.open_project)
        es.welcome.sig_open_project_dialog.connect(self._open_project_dialog)
        es.welcome.sig_open_example.connect(self.open_example_project)
        es.welcome.sig_new_procedure.connect(lambda: tree.new_procedure(Kind.HARDWARE))
        # the project tree
        tree.sig_open_file.connect(lambda p: self.open_file(p))
        tree.sig_file_created.connect(lambda p: self.open_file(p))
        tree.sig_file_created.connect(lint.lint_project)
        tree.sig_file_created.connect(self._show_welcome)
        tree.sig_file_renamed.connect(es.on_file_renamed)
        tree.sig_file_renamed.connect(lint.on_file_renamed)
        tree.sig_file_deleted.connect(es.on_file_deleted)
        tree.sig_file_deleted.connect(lint.on_file_deleted)
        tree.sig_start_procedure.connect(lambda n: run.start_procedure(n, run.last_eparam))
        tree.sig_changed.connect(lint.refresh_header_defines)
        tree.sig_changed.connect(lint.lint_project)
        tree.sig_changed.connect(self._show_welcome)
        # problems and diagnostics
        self.problems.sig_open_location.connect(self.open_location)
        self.build_panel.sig_open_location.connect(self.open_location)
        lint.sig_problem_files.connect(tree.set_problem_files)
        lint.sig_problem_counts.connect(self._show_problem_counts)
        lint.sig_header_defines.connect(self._set_pin_names)
        lint.sig_current_size.connect(self._update_size_label)
        lint.sig_diagnostics_updated.connect(self.sig_diagnostics_updated)
        self.status.sig_show_problems.connect(lambda: (self.problems_dock.show(),
                                                       self.problems_dock.raise_()))
        # Build All
        run.sig_build_started.connect(self.build_dock.show)
        run.sig_build_started.connect(self.build_dock.raise_)
        run.sig_build_started.connect(lambda: self.action(Act.BUILD_ALL).setEnabled(False))
        run.sig_build_ended.connect(
            lambda: self.action(Act.BUILD_ALL).setEnabled(self.project is not None))
        run.sig_build_result.connect(self._on_build_result)
        run.sig_build_finished.connect(self.sig_build_finished)

    def _setup_run_side(self) -> None:
        """The controller connection and the run docks."""
        run = self.run_actions
        if run.connection is None and run.start_controller:
            from plcbuilder.ide.connection import ControllerConnection
            run.connection = ControllerConnection(self)
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
        self.prefs = self.run_actions.prefs = prefs
        self.settings.save_preferences(prefs)
        self.editor_stack.apply_prefs(prefs)
        app = QApplication.instance()
        if app is not None:
            from plcbuilder.ide.app import apply_theme
            apply_theme(app, prefs.theme)

    # ====================================================== the parts' news
    def _with_editor(self, fn):
        def run():
            ed = self.current_editor()
            if ed is not None:
                fn(ed)
        return run

    def _show_welcome(self) -> None:
        self.editor_stack.show_welcome()

    def _reveal(self, path: str) -> None:
        self.project_dock.show()
        self.project_dock.raise_()
        self.tree.select_path(path)

    def _on_current_changed(self, ed: Optional[CodeEditor]) -> None:
        self.status.show_editor(ed)
        self._update_size_label()
        self._update_title()
        self._update_actions()

    def _update_size_label(self) -> None:
        ed = self.current_editor()
        if ed is None or ed.kind is None:
            self.status.show_size(None)
            return
        self.status.show_size(ed.path, *self.lint.size_of(ed.path))

    def _show_problem_counts(self, e: int, w: int) -> None:
        self.status.show_problem_counts(e, w)
        self.problems_dock.setWindowTitle(f"Problems ({e + w})" if e + w else "Problems")

    def _set_pin_names(self, header_defines: dict) -> None:
        if self.run_panels is not None:
            try:
                from plcbuilder.ide.panels import pin_names_from_defines
                self.run_panels.set_pin_names(*pin_names_from_defines(
                    {k: v[0] for k, v in header_defines.items()}))
            except Exception:  # noqa: BLE001 - pin names are a nicety
                pass

    def _on_build_result(self, result) -> None:
        self.lint.apply_build_result(result)
        self._update_size_label()
        if not result.ok:
            self.problems_dock.raise_()
        self.tree.refresh()

    def _on_connected(self, address: str) -> None:
        self.status.show_connected(address, getattr(self.connection, "embedded", False))
        self._update_actions()

    def _on_disconnected(self, reason: str) -> None:
        self.status.show_disconnected(reason)
        if reason and not self._closing:
            self.statusBar().showMessage(f"Controller: {reason}", 6000)
        self._update_actions()

    def _on_state(self, st: ControllerStatus, missed: int = 0) -> None:
        self._last_state = st
        self.status.show_state(st)
        self.tree.set_running(st.running)

    def _on_app_state(self, state) -> None:
        if state == Qt.ApplicationState.ApplicationActive and not self._closing:
            self.editor_stack.check_disk()

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

    def _update_actions(self) -> None:
        has_project = self.project is not None
        ed = self.current_editor()
        has_editor = ed is not None
        for name in (Act.NEW_PROCEDURE, Act.NEW_HEADER, Act.CLOSE_PROJECT):
            self.action(name).setEnabled(has_project)
        self.action(Act.BUILD_ALL).setEnabled(has_project and not self.run_actions.building())
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
        self.run_actions.speed_combo.setEnabled(self.connection is not None)
        if self.connection is None:
            tip = "The run side (controller connection) is not available"
            for name in (Act.UPLOAD, Act.START, Act.STOP):
                self.action(name).setToolTip(tip)

    # ---------------------------------------------------------- drag & drop
    def dragEnterEvent(self, event) -> None:  # noqa: N802 - Qt override
        if event.mimeData().hasUrls() and any(u.isLocalFile() for u in event.mimeData().urls()):
            event.acceptProposedAction()

    def dropEvent(self, event) -> None:  # noqa: N802 - Qt override
        self.open_paths([u.toLocalFile() for u in event.mimeData().urls() if u.isLocalFile()])
        event.acceptProposedAction()

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
        if not self.editor_stack.confirm_discard_all("Quit"):
            event.ignore()
            return
        self._closing = self.editor_stack.closing = True
        self._save_session()
        self.settings.save_window_state(self.saveGeometry(), self.saveState())
        self.settings.sync()
        self.shutdown()
        self.recovery.discard_all_own()
        event.accept()

    def shutdown(self) -> None:
        """Stop the timers, threads and the controller (also for tests)."""
        self._closing = self.editor_stack.closing = True
        self.recovery.stop()
        self.lint.worker.shutdown()
        self.run_actions.build_runner.wait(10)
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


def _unique_folder(parent: Path, base: str) -> Path:
    cand = parent / base
    i = 2
    while cand.exists():
        cand = parent / f"{base}-{i}"
        i += 1
    return cand
