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
from typing import TYPE_CHECKING, Optional

from PySide6.QtCore import Qt, QTimer, Signal
from PySide6.QtGui import QAction
from PySide6.QtWidgets import QApplication, QFileDialog, QMainWindow, QMessageBox

from plcbuilder.api import Kind
from plcbuilder.ide import actions, debug, dialogs, docks, startup_done, workbench
from plcbuilder.ide.actions import Act
from plcbuilder.ide.debug import actions as debug_actions
from plcbuilder.ide.link_reasons import CLOSED_BY_IDE
from plcbuilder.ide.dialogs.not_a_project import project_or_offer
from plcbuilder.ide.editor import file_key
from plcbuilder.ide.editor_stack import EditorStack
from plcbuilder.ide.first_frame import frame_title, session_files
from plcbuilder.ide.icons import icon
from plcbuilder.ide.lint import Lint
from plcbuilder.ide.problems import ProblemsPanel
from plcbuilder.ide.project_tree import ProjectTree
from plcbuilder.ide.run_actions import SPEEDS, RunActions
from plcbuilder.ide.settings import Preferences, Settings
from plcbuilder.ide.status_bar import StatusBar
from plcbuilder.ide.welcome import APP_NAME
from plcbuilder.project.model import Project, ProjectError

if TYPE_CHECKING:
    from plcbuilder.ide.editor import CodeEditor
    from plcbuilder.link.client import ControllerStatus

__all__ = ["APP_NAME", "Act", "MainWindow", "SPEEDS"]

SOURCE_SUFFIXES = (".plc", ".h")
#: at the start, the checks and the session's other editors wait for the run
#: panels' first telemetry this long at most (MainWindow._once_live)
LIVE_WAIT_MS = 500
#: telemetry kept for the run panels until they are made (samples, events), at most
EARLY_SAMPLES, EARLY_EVENTS = 30000, 5000
TEXT_SUFFIXES = (".plc", ".h", ".toml", ".xml", ".md", ".txt")


class MainWindow(QMainWindow):
    """The IDE's main window."""

    sig_project_opened = Signal(str)
    """A project was opened (its folder)."""

    sig_build_finished = Signal(object)
    """Build All finished (the BuildResult, or the exception it raised)."""

    sig_diagnostics_updated = Signal(str)
    """New diagnostics of a procedure arrived (its file key)."""

    sig_recording_saved = Signal(str)
    """Run › Save Session Recording wrote the session's recording (its path)."""

    sig_replayed = Signal(object)
    """Run › Replay Session finished: the replay's trace (shown in the run panels)."""

    def __init__(self, settings: Optional[Settings] = None, *, start_controller: bool = True,
                 connection=None, debounce_ms: Optional[int] = None):
        super().__init__()
        self.settings = settings or Settings()
        self.prefs: Preferences = self.settings.preferences()
        self._project: Optional[Project] = None
        self._closing = False
        self._last_state: Optional[ControllerStatus] = None   # the controller's last state
        self.run_panels = None               # made after the first paint (see ensure_run_panels)
        self.run_docks: dict = {}            # the run docks by key (empty until then)
        self._early_samples: list = []       # telemetry before the run panels are made
        self._early_events: list = []
        self._pin_defines: Optional[dict] = None
        self._painted = False
        #: the window is shown once made (:meth:`show_when_made`)
        self.first_paint_due = False
        self._after_paint_done = False       # _after_first_paint ran
        self._overdue_waits = 0              # (_paint_overdue)
        self._controller_due = False         # started after the first paint
        self._lint_due = False               # the project's check, after the first paint
        self._editors_due = None             # the last session's other editors, after it too
        self.right_docks: list = []          # the docks the default sizes apply to
        self._shown_once = False
        self.layout_restored = False
        self.wheel_guard = None              # made after the first paint (wheel_guard.py)

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
        self.lint = Lint(self, self.editor_stack, self.problems, debounce_ms)
        self.run_actions = RunActions(self, self.editor_stack, lambda: self.build_panel, self.prefs,
                                      connection=connection, start_controller=start_controller)
        self.run_actions.settings = self.settings
        self.status = StatusBar(self)
        self.setStatusBar(self.status)
        self.debug = debug.DebugSession(self)
        # the parts' widgets, by the names the window always had
        es = self.editor_stack
        self.tabs, self.stack = es.tabs, es.stack
        self.welcome, self.welcome_recent = es.welcome, es.welcome.welcome_recent
        self.recovery, self.store = es.recovery, self.lint.store

        self.workbench = workbench.Workbench(self)   # navigation, outline, disassembly...
        run = self.run_actions
        if run.connection is None and run.start_controller:
            from plcbuilder.ide.connection import ControllerConnection
            run.connection = ControllerConnection(self)
        # every dock, from the one table (docks.DOCKS): the run docks with a controller
        table = docks.build(self, run=self.connection is not None)
        self.run_docks = {k: table.docks[k] for k, s in table.specs.items() if s.run}
        self.workbench.panels = table.view(("references", "find", "disasm", "registers"))
        self.debug.panels = table.view(debug.DOCKS)
        self._actions = actions.build_actions(self)
        debug_actions.build_debug_actions(self, self._actions)
        actions.build_menus(self)
        debug_actions.build_debug_menu(self, self.menuBar().actions()[-1])
        actions.build_toolbar(self)
        debug_actions.build_debug_toolbar(self)
        self._wire()
        self._setup_run_side()
        actions.fill_view_menu(self)        # the docks (the table), toolbars, zoom...
        workbench.install(self)             # navigation, disassembly, registers, help
        self.default_state = self.saveState()
        docks.restore_layout(self)
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
        another = project is None or self._project is None or project.root != self._project.root
        self._project = project
        self.editor_stack.project = self.lint.project = self.run_actions.project = project
        if self._tests_panel is not None:
            self._tests_panel.set_project(project.root if project is not None else None)
        if self.run_panels is not None:
            if another:                      # nothing of the last project's runs stays
                self.run_panels.project_changed()
            self.run_panels.set_target(project.target if project is not None else "mycnc")

    @property
    def find_bar(self):
        """The editors' find/replace bar (made when first used)."""
        return self.editor_stack.find_bar

    @property
    def tests_panel(self):
        """The Tests panel, made the first time its dock shows or the tests
        are run (the window's first paint does not wait for it)."""
        return self.dock_table.panel("tests")

    @property
    def _tests_panel(self):
        """The Tests panel if it was made (None: not yet)."""
        return self.dock_table.made.get("tests")

    @property
    def build_panel(self):
        """The Build Output panel, made the first time its dock shows or a
        build needs it (the window's first paint does not wait for it)."""
        return self.dock_table.panel("build")

    @property
    def _build_panel(self):
        """The Build Output panel if it was made (None: not yet)."""
        return self.dock_table.made.get("build")

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
        return (self._lint_due or self.lint.busy() or self.run_actions.building()
                or self.tree.describing() or self._editors_due is not None)

    def is_modified(self, editor: CodeEditor) -> bool:
        return self.editor_stack.is_modified(editor)

    def modified_editors(self) -> list[CodeEditor]:
        return self.editor_stack.modified_editors()

    def open_file(self, path, line: Optional[int] = None, col: int = 1, *,
                  focus: bool = True) -> Optional[CodeEditor]:
        """Open (or show) a file in an editor tab, optionally at a line."""
        return self.editor_stack.open_file(path, line, col, focus=focus)

    def open_location(self, file: str, line: int, col: int = 1) -> Optional[CodeEditor]:
        self.workbench.nav.record()          # for Back
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
        self.workbench.nav.record()          # for Back
        return self.editor_stack.goto_line_dialog()

    def goto_definition(self, word: str) -> bool:
        self.workbench.nav.record()          # for Back
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

    def start_or_continue(self) -> bool:
        """F5: continue when the controller is halted, else Start…"""
        if self.debug.is_halted():
            self.debug.continue_()
            return True
        return self.start_procedure()

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
        folder = project_or_offer(self, Path(path).expanduser().resolve())
        if folder is None:                       # not a project, and not made one
            return False
        try:
            project = Project.open(folder)
        except ProjectError as exc:
            QMessageBox.critical(self, "Open Project", f"Cannot open the project:\n\n{exc}")
            self.settings.remove_recent_project(str(Path(path).expanduser().resolve()))
            actions.fill_recent_menu(self)
            return False
        self._save_session()                     # the project left: its editors come back
        self.editor_stack.close_all(force=True)
        self.project = project
        self.run_actions.project_opened()        # its own last eparam and speed
        self._start_controller()
        if self._build_panel is not None:
            self._build_panel.forget()           # not the previous project's build
        self.lint.clear()
        self.problems.set_root(project.root)
        # the files' descriptions in the tree come after the window's first paint
        self.tree.descriptions_held = self._before_first_paint()
        self.tree.set_project(project)
        self.settings.add_recent_project(project.root)
        actions.fill_recent_menu(self)
        self._lint_project()
        self._restore_editors(project)
        if offer_recovery:
            self.offer_recovery()
        self._update_title()
        self._update_actions()
        self._show_welcome()
        self.lint.refresh_problems()
        self.statusBar().showMessage(f"Opened {project.name} ({project.root})", 5000)
        self.sig_project_opened.emit(str(project.root))
        return True

    def _restore_editors(self, project: Project) -> None:
        """The project's editors of the last session, its current one in
        front. Before the window's first paint only the current one is made
        (the paint shows it); the others follow the paint, in their places."""
        files, current = session_files(self.settings, project.root)
        if self._before_first_paint() and current and len(files) > 1:
            self.open_file(current)          # (with the keyboard, as below)
            self._editors_due = (project.root, files, current)
            return
        for f in files:
            self.open_file(f, focus=False)
        front = self.editor_for(current) if current else None
        if front is not None:
            self.tabs.setCurrentWidget(front)
            front.take_focus()               # what is typed next goes to it

    def _open_due_editors(self) -> None:
        """The last session's other editors, after the first paint (see
        :meth:`_restore_editors`), in the order they had."""
        due, self._editors_due = self._editors_due, None
        if due is None or self._project is None or self._project.root != due[0]:
            return
        _root, files, current = due
        front = self.current_editor()
        typing = front is not None and self.focusWidget() is front
        for f in files:
            self.open_file(f, focus=False)
        bar = self.tabs.tabBar()
        for i, f in enumerate(files):
            ed = self.editor_for(f)
            at = self.tabs.indexOf(ed) if ed is not None else -1
            if at > i:
                bar.moveTab(at, i)
        if front is not None and self.tabs.indexOf(front) >= 0:
            self.tabs.setCurrentWidget(front)
            if typing:
                front.take_focus()

    def close_project(self) -> bool:
        if not self.editor_stack.confirm_discard_all("Close Project"):
            return False
        self._save_session()
        self.debug.project_closed()
        self.editor_stack.close_all(force=True)
        self.project = None
        if self._build_panel is not None:
            self._build_panel.forget()
        self.lint.clear(sizes=False)
        self.tree.set_project(None)
        self.problems.set_root(None)
        self.lint.refresh_problems()
        self._update_title()
        self._update_actions()
        self._show_welcome()
        return True

    def new_project(self) -> bool:
        """File › New Project…: a project for a target (myCNC, Huazhong, TG
        Motion) from its example, in a folder the user names; then open it."""
        if not self.editor_stack.confirm_discard_all("New Project"):
            return False
        from plcbuilder.project.new import create_project
        start = self.settings.last_folder(
            "projects", self.project.root.parent if self.project is not None else None)
        base = "plc-project"
        name = _unique_folder(start, base).name if start.is_dir() else base
        res = dialogs.NewProjectDialog.get_new(self, start, name)
        if res is None:
            return False
        dest, name, target = res
        try:
            project = create_project(dest, name=name, target=target)
        except (OSError, ProjectError) as exc:
            QMessageBox.critical(self, "New Project", f"Cannot create the project:\n\n{exc}")
            return False
        self.settings.set_last_folder("projects", dest.parent)
        ok = self.open_project(project.root, offer_recovery=False)
        if ok:
            first = next(iter(project.procedures(Kind.HARDWARE)), None)
            if first is not None:
                self.open_file(first.path)
        return ok

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
                                                      str(self.settings.last_folder("projects")))
            if not chosen:
                return False
            parent = Path(chosen)
            self.settings.set_last_folder("projects", parent)
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


    def open_project_dialog(self) -> bool:
        start = self.settings.last_folder(
            "projects", self.project.root.parent if self.project else None)
        folder = QFileDialog.getExistingDirectory(self, "Open Project Folder", str(start))
        if not folder:
            return False
        self.settings.set_last_folder("projects", Path(folder).parent)
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
    def _wire(self) -> None:
        """Connect the parts' signals."""
        msg = self.statusBar().showMessage
        es, lint, run, tree = self.editor_stack, self.lint, self.run_actions, self.tree
        for part in (es, lint, run, self.debug):
            part.sig_message.connect(lambda text, ms: msg(text, ms) if ms else msg(text))
        # the editors
        es.can_reveal = lambda path: tree.find_item(path) is not None
        es.sig_editor_created.connect(lint.attach)
        es.sig_editors_changed.connect(self._update_actions)
        es.sig_current_changed.connect(self._on_current_changed)
        es.sig_title_changed.connect(self._update_title)
        es.sig_cursor_moved.connect(self.status.show_cursor)
        es.sig_goto_definition.connect(self.goto_definition)
        es.sig_file_saved.connect(self._on_file_saved)
        es.sig_changes_discarded.connect(lint.on_changes_discarded)
        es.sig_reveal.connect(self._reveal)
        es.welcome.sig_open_project.connect(self.open_project)
        es.welcome.sig_open_project_dialog.connect(self.open_project_dialog)
        es.welcome.sig_open_example.connect(self.open_example_project)
        es.welcome.sig_new_project.connect(self.new_project)
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
        # the debugger
        self.debug.sig_state_changed.connect(self._update_actions)
        self.sig_project_opened.connect(self.debug.project_opened)

    def _setup_run_side(self) -> None:
        """The controller connection's signals. The run docks are there, empty
        (docks.DOCKS): the run panels (pyqtgraph) fill them after the window's
        first paint, so that the window shows as fast as it does without a
        controller."""
        run = self.run_actions
        if self.connection is not None:
            c = self.connection
            c.sig_connected.connect(self._on_connected)
            c.sig_disconnected.connect(self._on_disconnected)
            c.sig_state.connect(self._on_state)
            c.sig_error.connect(lambda t: self.statusBar().showMessage(t, 6000))
            if hasattr(c, "sig_result"):
                c.sig_result.connect(self._on_request_done)
            if self.run_docks:
                # what comes before the run panels are made is kept for them
                c.sig_samples.connect(self._keep_samples)
                c.sig_events.connect(self._keep_events)
        self.debug.wire_connection()
        run.wire_connection()

    def _keep_samples(self, samples: list) -> None:
        if self.run_panels is None:
            self._early_samples.extend(samples)
            del self._early_samples[:-EARLY_SAMPLES]

    def _keep_events(self, events: list) -> None:
        if self.run_panels is None:
            self._early_events.extend(events)
            del self._early_events[:-EARLY_EVENTS]

    def _stop_keeping(self) -> tuple[list, list]:
        """The telemetry kept until the run panels were made (and no more kept)."""
        c = self.connection
        for sig, slot in ((c.sig_samples, self._keep_samples), (c.sig_events, self._keep_events)):
            try:
                sig.disconnect(slot)
            except (RuntimeError, TypeError):
                pass
        kept = self._early_samples, self._early_events
        self._early_samples, self._early_events = [], []
        return kept

    def ensure_run_panels(self):
        """Make the run panels now, if they are due and not made yet (the
        window makes them after its first paint); returns them (or None).
        Only what receives the controller's telemetry and the log are made
        here: each other panel when its dock first shows or it is asked for
        (the dock table: :func:`run_dock_panel`)."""
        if self.run_panels is not None or not self.run_docks or self._closing:
            return self.run_panels
        try:
            from plcbuilder.ide.panels import RunPanels
            self.run_panels = RunPanels(self, self.connection, docks=self.run_docks, lazy=True)
            self.dock_table.adopt()          # the log's dock
            # the telemetry that came since the connection started (it starts
            # first, while the panels' modules load): the session from its start
            self.run_panels.feed(*self._stop_keeping())
        except Exception as exc:  # noqa: BLE001 - the editor side works without them
            import traceback
            traceback.print_exc()
            self.run_panels = None
            self.run_docks = {}
            self._stop_keeping()
            self.statusBar().showMessage(f"The run panels are not available: {exc}")
            return None
        self.run_panels.sig_open_location.connect(lambda f, ln: self.open_location(f, ln))
        self.run_panels.sig_comparison.connect(
            lambda name: self.action(Act.CLEAR_COMPARISON).setEnabled(name is not None))
        self.run_panels.set_forces(self.debug.forces)
        if self._project is not None:
            self.run_panels.set_target(self._project.target)
        if self._pin_defines is not None:
            self._set_pin_names(self._pin_defines)
        self._guard_wheel()
        return self.run_panels

    def _guard_wheel(self) -> None:
        """The wheel over a slider, spin box or combo box of a dock (or the
        speed box) scrolls the dock and changes nothing (wheel_guard.py)."""
        if self.wheel_guard is None:
            from plcbuilder.ide.wheel_guard import WheelGuard
            self.wheel_guard = WheelGuard(self)
            if self.run_actions.speed_combo is not None:
                self.wheel_guard.guard(self.run_actions.speed_combo)
            docks.follow_tab_bars(self)      # whole tab titles, now and after a move
        self.wheel_guard.watch_docks(self)

    # ============================================================ settings
    def reset_layout(self) -> None:
        docks.reset_layout(self)

    def show_when_made(self) -> None:
        """The window is shown once made (the first frame's hand-over, app.py):
        from now until its first paint, what waits for a visible window's
        paint waits (opening the project before it shows included)."""
        self.first_paint_due = True
        self._hold_until_painted()

    def _hold_until_painted(self) -> None:
        # until the first paint: no compile in the background (the diagnostics
        # thread would take the interpreter from the window), no outline
        if not self._painted:
            self.lint.hold(True)
            self.workbench.outline.held = True

    def showEvent(self, event) -> None:  # noqa: N802 - Qt override
        super().showEvent(event)
        if not self._shown_once:
            self._shown_once = True
            self._hold_until_painted()
            if not self.layout_restored:
                QTimer.singleShot(0, lambda: docks.default_dock_sizes(self))
            # the controller and the run panels come after the first paint;
            # this is in case no paint comes (a minimised window): 500 ms
            # from the event loop's first turn (opening the last project
            # between show() and that turn must not let it come before the paint)
            QTimer.singleShot(0, lambda: QTimer.singleShot(500, self._paint_overdue))

    def _paint_overdue(self) -> None:
        """No paint yet, 500 ms after the event loop's first turn: a window
        that cannot be seen (minimised, not mapped) starts the rest now; one on
        screen whose paint is only slow (a loaded machine, the window manager
        late) is waited for, up to 5 s more: the run panels' modules loaded
        before its paint would hold the paint up."""
        if self._after_paint_done or self._closing:
            return
        handle = self.windowHandle()
        if handle is not None and handle.isExposed() and self._overdue_waits < 10:
            self._overdue_waits += 1
            QTimer.singleShot(500, self._paint_overdue)
            return
        self._after_first_paint()

    def _before_first_paint(self) -> bool:
        """The window is (or is about to be) on screen and has not painted yet."""
        return (self.isVisible() or self.first_paint_due) and not self._painted

    def paintEvent(self, event) -> None:  # noqa: N802 - Qt override
        super().paintEvent(event)
        if not self._painted:
            self._painted = True
            QTimer.singleShot(0, self._after_first_paint)

    def _after_first_paint(self) -> None:
        """The window is up: connect to the embedded controller (its process
        started with the project), then make the run panels of the docks on
        screen while it comes up; the outline, the tree's descriptions, the
        whole dock tab titles, the checks in the background and the last
        session's other editors come once the panels are made (each would
        hold them up). Once: the paint or the fallback, whichever comes first
        (the other would run the rest before the panels are made)."""
        if self._after_paint_done:
            return
        self._after_paint_done = True
        self._painted = True
        if self._controller_due and not self._closing:
            self._controller_due = False
            self.run_actions.start_controller_for_project()
        if self.run_docks and self.run_panels is None:
            QTimer.singleShot(0, self._run_panels_then_the_rest)
        else:
            self._after_run_panels()

    def _run_panels_then_the_rest(self) -> None:
        self.ensure_run_panels()
        self._after_run_panels()

    def _after_run_panels(self) -> None:
        """The rest of the start: the docks shown meanwhile get their panels
        (a few a turn of the event loop: docks.DockTable.release); then, once
        the panels are live, the checks and the other editors."""
        self.dock_table.release(then=lambda: self._once_live(self._after_panels))

    def _once_live(self, then) -> None:
        """``then`` once the run panels have drawn the controller's first
        telemetry (the last thing the start is waited for: nothing else
        competes with it), at most :data:`LIVE_WAIT_MS` from now; at once
        without the panels or a controller of the IDE's own."""
        rp = self.run_panels
        if rp is None or rp.live or not getattr(self.connection, "embedded", False):
            then()
            return
        done = []

        def once() -> None:
            if not done and not self._closing:
                done.append(True)
                QTimer.singleShot(0, self, then)     # after that redraw's paint
        rp.sig_live.connect(once)
        QTimer.singleShot(LIVE_WAIT_MS, self, once)

    def _after_panels(self) -> None:
        startup_done()                           # (the collector's usual pace from now)
        if docks.fit_layout(self):               # (the panels are in their docks now)
            self.statusBar().showMessage("The saved layout needed more room than the screen "
                                         "has: the default layout is back", 15000)
        self.workbench.outline.release()         # (each of these once: then no-ops)
        self._guard_wheel()
        self.tree.release_descriptions()
        self.lint.hold(False)
        self._open_due_editors()
        if self._lint_due and not self._closing:
            self._lint_due = False
            self.lint.refresh_header_defines()
            self.lint.lint_project()

    def _start_controller(self) -> None:
        """Start (or restart) the project's controller; before the window's
        first paint only its process: the connection, which would compete with
        the window for the interpreter, waits for the paint."""
        if self._before_first_paint():
            # its process starts now (its own Python start is the longest part,
            # on the other core); the connection to it after the paint
            self._controller_due = True
            self.run_actions.prestart_controller_for_project()
        else:
            self.run_actions.start_controller_for_project()

    def _lint_project(self) -> None:
        """Read the headers' defines (pin names, completion) and check the
        project's procedures in the background; before the window's first
        paint, only note that it is due (loading the compiler and compiling in
        a thread would compete with the window)."""
        if self._before_first_paint():
            self._lint_due = True
        else:
            self.lint.refresh_header_defines()
            self.lint.lint_project()

    def _save_session(self) -> None:
        if self.project is not None:
            files = [ed.path for ed in self.editors()]
            due = self._editors_due
            if due is not None and due[0] == self.project.root:
                # closed before the last session's other editors opened (they
                # follow the first paint): they stay in the session, in order
                files = list(due[1]) + [f for f in files if f not in due[1]]
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
    def _show_welcome(self) -> None:
        self.editor_stack.show_welcome()

    def _reveal(self, path: str) -> None:
        self.project_dock.show()
        self.project_dock.raise_()
        self.tree.select_path(path)

    def _on_current_changed(self, ed: Optional[CodeEditor]) -> None:
        if ed is not None:
            self.tree.select_path(ed.path)       # the tree follows the active tab
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
        self._pin_defines = header_defines
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
        if self.statusBar().currentMessage().startswith("Controller: "):
            self.statusBar().clearMessage()        # the disconnect it told of is over
        self._update_actions()

    def _on_request_done(self, verb: str, result: dict) -> None:
        """The controller did a request: "Uploading …" becomes what it did."""
        if verb == "upload" and self.statusBar().currentMessage().startswith("Uploading"):
            n = result.get("procedures")
            what = f": {len(n)} procedures" if isinstance(n, (list, tuple)) else ""
            self.statusBar().showMessage(f"Uploaded the image to the controller{what}", 4000)

    def _on_disconnected(self, reason: str) -> None:
        self.status.show_disconnected(reason)
        if reason and reason != CLOSED_BY_IDE and not self._closing:
            self.statusBar().showMessage(f"Controller: {reason}", 6000)
        self._update_actions()

    def _on_state(self, st: ControllerStatus, missed: int = 0) -> None:
        self._last_state = st
        self.status.show_state(st)
        self.tree.set_running(st.running)

    def _on_app_state(self, state) -> None:
        if state == Qt.ApplicationState.ApplicationActive and not self._closing:
            self.editor_stack.check_disk()

    def _update_actions(self) -> None:
        actions.update_actions(self)
        debug_actions.update_debug_actions(self)

    def _update_title(self) -> None:
        ed = self.current_editor()
        self.setWindowModified(ed is not None and self.is_modified(ed))
        self.setWindowTitle(frame_title(ed.path if ed is not None else None,
                                        self.project.name if self.project is not None else None))

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
        self.debug.save()
        self.settings.save_window_state(self.saveGeometry(), self.saveState(),
                                        docks.names(self))
        self.settings.save_frame_sketch(self._frame_sketch())
        self.settings.sync()
        self.shutdown()
        self.recovery.discard_all_own()
        event.accept()

    def _frame_sketch(self) -> Optional[dict]:
        """Where the project's tree and the editors are in the window, for the
        next start's first frame (None: the tree is not docked on screen)."""
        from plcbuilder.ide.docks import on_screen
        dock = self.project_dock
        if not on_screen(dock) or dock.isFloating() or not self.editor_stack.isVisible():
            return None

        def rect(w) -> tuple:
            at = w.mapTo(self, w.rect().topLeft())
            return (at.x(), at.y(), w.width(), w.height())
        ed = self.current_editor()
        # where its text starts (after the line numbers, markers and folding)
        # and the height of its lines
        text = (sum(ed.marginWidthN(i) for i in range(5)) + ed.marginLeft(), ed.textHeight(0)) \
            if ed is not None else (0, 0)
        return {"size": (self.width(), self.height()), "tree": rect(self.tree),
                "editor": rect(self.editor_stack), "text": text}

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


def run_dock_panel(win: MainWindow, key: str):
    """The panel of a run dock (docks.DOCKS), made now: the run panels make
    it (pyqtgraph loads with the first); if they cannot be made, a line that
    says so."""
    panels = win.ensure_run_panels()
    if panels is not None:
        return panels.panel(key)
    from PySide6.QtWidgets import QLabel
    return QLabel("The run panels are not available (see the status bar).")


def tests_dock_panel(win: MainWindow, key: str):
    """The Tests dock's panel (docks.DOCKS)."""
    from plcbuilder.ide.panels.tests import TestsPanel
    return TestsPanel(win)


def tests_dock_wire(win: MainWindow, key: str) -> None:
    """The Tests panel, in its dock: wired, for the open project, its tests
    read now if the dock shows (else when it does)."""
    from plcbuilder.ide.panels.tests import wire
    panel = win.tests_panel
    wire(win)
    panel.set_project(win.project.root if win.project is not None else None)
    dock = win.tests_dock
    dock.visibilityChanged.connect(lambda on: on and panel.ensure_loaded())
    if dock.isVisible():
        panel.ensure_loaded()


def _unique_folder(parent: Path, base: str) -> Path:
    cand = parent / base
    i = 2
    while cand.exists():
        cand = parent / f"{base}-{i}"
        i += 1
    return cand
