"""The Tests dock: the project's scenario tests (``tests/*.toml``) with their
results.

Run All or the selected test (Run › Run Tests, Ctrl+T, runs them all); each
row shows pass, fail or "not run", a failing test's first failing condition,
and its file and line. Selecting a row shows every failing condition below;
a double-click opens the test file at the failing expectation (or at the
test). With "Coverage" checked, the run records which lines ran, and the
editors mark them in the margin (``CodeEditor.set_coverage``).

The tests run in a worker thread (building the project and running the tests
is what ``plcbuilder test`` does; the example project's take about a second),
so the window keeps painting; results arrive by signal.
"""

from __future__ import annotations

from pathlib import Path
from typing import Callable, Optional

from PySide6 import QtCore, QtWidgets

from plcbuilder.ide.docks import dock_of, on_screen
from plcbuilder.ide.elided_label import ElidedLabel
# plcbuilder.testing (and through it the compiler) loads when the panel first
# needs it, not with the main window: the IDE's first paint does not wait for it
TESTS_DIR = "tests"           # plcbuilder.testing.spec.TESTS_DIR (checked by a test)

Qt = QtCore.Qt
Signal = QtCore.Signal

NAME, STATUS, WHERE = range(3)
ROLE_FILE = Qt.ItemDataRole.UserRole
ROLE_LINE = Qt.ItemDataRole.UserRole + 1
ROLE_DETAIL = Qt.ItemDataRole.UserRole + 2
ROLE_KIND = Qt.ItemDataRole.UserRole + 3       # "test", or "error" for a file with a mistake
PASS_COLOUR, FAIL_COLOUR, ERROR_COLOUR = "#1e7a1e", "#b3261e", "#b35c00"


class _Worker(QtCore.QObject):
    """Builds the project and runs tests in a thread; one run per object."""

    sig_done = Signal(object)
    """(results, coverage, errors, message): the run's outcome."""

    def __init__(self, root: Path, names: Optional[set], coverage: bool):
        super().__init__()
        self.root, self.names, self.coverage = root, names, coverage

    def run(self) -> None:
        from plcbuilder.testing.runner import SuiteError, prepare, run_suite
        try:
            suite = prepare(self.root)
            if not suite.built:
                bad = ", ".join(pb.name for pb in suite.compiled if not pb.ok)
                self.sig_done.emit(([], None, suite.errors, f"not run: {bad} did not compile"))
                return
            tests = [t for t in suite.tests if self.names is None or t.name in self.names]
            run = run_suite(suite, tests=tests, coverage=self.coverage, jobs=1)
            self.sig_done.emit((run.results, run.coverage, suite.errors,
                                f"{run.passed} passed, {run.failed} failed "
                                f"in {run.seconds:.2f} s"))
        except SuiteError as exc:
            self.sig_done.emit(([], None, [], f"not run: {exc}"))
        except Exception as exc:  # noqa: BLE001 - shown in the panel, never a crash
            self.sig_done.emit(([], None, [], f"not run: internal error: "
                                              f"{type(exc).__name__}: {exc}"))


class _RecordWorker(QtCore.QObject):
    """Builds the project and reruns one test, recording it (``record_run``)."""

    sig_done = Signal(object)
    """(RecordedRun or None, message)."""

    def __init__(self, root: Path, name: str, keep: Optional[int]):
        super().__init__()
        self.root, self.name, self.keep = root, name, keep

    def run(self) -> None:
        from plcbuilder.testing.runner import SuiteError, prepare, record_run
        try:
            suite = prepare(self.root)
            if not suite.built:
                bad = ", ".join(pb.name for pb in suite.compiled if not pb.ok)
                self.sig_done.emit((None, f"not run: {bad} did not compile"))
                return
            rec = record_run(suite, self.name, keep=self.keep)
            self.sig_done.emit((rec, f"recorded '{rec.name}': {rec.end_ms} ms"))
        except SuiteError as exc:
            self.sig_done.emit((None, f"not run: {exc}"))
        except Exception as exc:  # noqa: BLE001 - shown in the panel, never a crash
            self.sig_done.emit((None, f"not run: internal error: {type(exc).__name__}: {exc}"))


class TestsPanel(QtWidgets.QWidget):
    """The list of tests and their results."""

    __test__ = False

    sig_open_location = Signal(str, int)
    """Open a file at a line (a double-click on a test or a failure)."""

    sig_coverage = Signal(object)
    """A run with coverage finished: the list of ProcedureCoverage."""

    sig_finished = Signal(str)
    """A run finished (its summary line)."""

    sig_open_run = Signal(object)
    """Open Failing Run recorded a test's run: the RecordedRun, for the run panels."""

    sig_back_to_live = Signal()
    """Back to Live: the run panels should show the live controller again."""

    #: the newest samples a recorded run keeps (the run panels' capacity)
    RECORD_KEEP = 30000

    def __init__(self, parent=None):
        super().__init__(parent)
        self.root: Optional[Path] = None
        self._thread: Optional[QtCore.QThread] = None
        self._worker: Optional[_Worker] = None
        self.results: dict[str, object] = {}
        self.coverage = None
        self.showing: Optional[str] = None    # the recorded test run the run panels show
        #: asked before a run reads the project's files (``what`` -> go on): the
        #: window saves the editors first (RunActions.ensure_saved)
        self.before_run: Optional[Callable[[str], bool]] = None
        self._stale = False                   # the project's tests are not read yet

        self.run_all_button = QtWidgets.QPushButton("Run All")
        self.run_all_button.setToolTip("Build the project and run every test (Ctrl+T)")
        self.run_one_button = QtWidgets.QPushButton("Run Selected")
        self.coverage_box = QtWidgets.QCheckBox("Coverage")
        self.coverage_box.setToolTip("Record which lines ran and mark them in the editors "
                                     "(runs on the reference interpreter)")
        self.open_run_button = QtWidgets.QPushButton("Open Failing Run")
        self.open_run_button.setToolTip("Run the selected failing test again and show its "
                                        "run in the run panels, at the failing tick")
        self.summary = ElidedLabel("")                  # never widens the dock: it elides
        bar = QtWidgets.QHBoxLayout()
        for w in (self.run_all_button, self.run_one_button, self.open_run_button,
                  self.coverage_box):
            bar.addWidget(w)
        bar.addWidget(self.summary, 1)

        self.tree = QtWidgets.QTreeWidget()
        self.tree.setColumnCount(3)
        self.tree.setHeaderLabels(["Test", "Result", "File"])
        self.tree.setRootIsDecorated(False)
        self.tree.setUniformRowHeights(True)
        self.tree.setAlternatingRowColors(True)
        self.tree.header().setStretchLastSection(True)
        self.tree.setColumnWidth(NAME, 360)
        self.tree.setColumnWidth(STATUS, 160)
        self.detail = QtWidgets.QPlainTextEdit()
        self.detail.setReadOnly(True)
        self.detail.setPlaceholderText("Select a failing test to see its failing conditions")
        self.detail.setMaximumBlockCount(2000)
        # the details beside the list, not under it: in a bottom dock a few rows
        # high, the list keeps every row the dock has
        split = QtWidgets.QSplitter(Qt.Orientation.Horizontal)
        split.addWidget(self.tree)
        split.addWidget(self.detail)
        split.setStretchFactor(0, 3)
        split.setStretchFactor(1, 2)
        split.setSizes([600, 400])
        self.split = split

        lay = QtWidgets.QVBoxLayout(self)
        lay.setContentsMargins(2, 2, 2, 2)
        lay.addLayout(bar)
        lay.addWidget(split, 1)

        self.run_all_button.clicked.connect(lambda: self.run_tests())
        self.run_one_button.clicked.connect(self.run_selected)
        self.open_run_button.clicked.connect(self._open_run_clicked)
        self.tree.itemDoubleClicked.connect(self._open_item)
        self.tree.currentItemChanged.connect(lambda cur, _prev: self._show_detail(cur))
        self.tree.currentItemChanged.connect(lambda *_a: self._update_buttons())
        self.tree.setContextMenuPolicy(Qt.ContextMenuPolicy.CustomContextMenu)
        self.tree.customContextMenuRequested.connect(self._context_menu)
        self._update_buttons()

    # ============================================================== public
    def set_project(self, root) -> None:
        """Show the tests of the project at ``root`` (None: no project). In a
        dock tabbed away or hidden, the files are read when it shows or its
        tests are asked for: a project opens (and the window first paints)
        without reading them."""
        self.root = Path(root) if root is not None else None
        self.results.clear()
        self.coverage = None
        self._stale = True
        self.summary.setText("")              # not the last project's totals
        if dock_of(self) is None or on_screen(self):
            self.reload()

    def ensure_loaded(self) -> None:
        """List the project's tests now, if they were not read since it opened."""
        if self._stale:
            self.reload()

    def reload(self) -> None:
        """Read tests/*.toml again and list the tests (results are kept by name)."""
        self._stale = False
        self.tree.clear()
        self.detail.clear()
        if self.root is None:
            self.summary.setText("")
            self._update_buttons()
            return
        from plcbuilder.testing.spec import load_dir
        tests, errors = load_dir(self.root / TESTS_DIR)
        for e in errors:
            item = QtWidgets.QTreeWidgetItem([Path(e.file).name, e.message,
                                              self._where(e.file, e.line)])
            self._mark(item, "error", e.file, e.line, str(e))
            self.tree.addTopLevelItem(item)
        for t in tests:
            item = QtWidgets.QTreeWidgetItem([t.name, "not run", self._where(t.file, t.line)])
            item.setData(NAME, ROLE_FILE, t.file)
            item.setData(NAME, ROLE_LINE, t.line or 1)
            item.setData(NAME, ROLE_KIND, "test")
            self.tree.addTopLevelItem(item)
            r = self.results.get(t.name)
            if r is not None:
                self._show_result(item, r)
        if not tests and not errors:
            self.summary.setText(f"no tests in {TESTS_DIR}/ (add a .toml file: see the "
                                 f"manual, Scenario tests)")
        self._update_buttons()

    def test_names(self) -> list[str]:
        """The tests listed, in order."""
        self.ensure_loaded()
        items = (self.tree.topLevelItem(i) for i in range(self.tree.topLevelItemCount()))
        return [it.text(NAME) for it in items if it.data(NAME, ROLE_KIND) == "test"]

    def status_of(self, name: str) -> Optional[str]:
        """The Result column of the test ``name`` (None: no such row)."""
        item = self._item(name)
        return item.text(STATUS) if item is not None else None

    def running(self) -> bool:
        return self._thread is not None

    def run_tests(self, names: Optional[list] = None) -> bool:
        """Build the project and run the tests ``names`` (None: all) in the
        background. False when nothing can run (no project, a run going on)."""
        if self.root is None or self.running():
            return False
        if self.before_run is not None and not self.before_run("Run Tests"):
            return False
        self.reload()
        self.summary.setText("building and running…")
        for i in range(self.tree.topLevelItemCount()):
            item = self.tree.topLevelItem(i)
            if item.data(NAME, ROLE_KIND) == "test" and (names is None or item.text(NAME) in names):
                item.setText(STATUS, "running…")
        self._start(_Worker(self.root, set(names) if names is not None else None,
                            self.coverage_box.isChecked()), self._on_done)
        return True

    def _start(self, worker, done) -> None:
        thread = QtCore.QThread(self)
        worker.moveToThread(thread)
        thread.started.connect(worker.run)
        worker.sig_done.connect(done)
        self._thread, self._worker = thread, worker
        self._update_buttons()
        thread.start()

    def _end_thread(self) -> None:
        thread, self._thread, self._worker = self._thread, None, None
        if thread is not None:
            thread.quit()
            thread.wait()
            thread.deleteLater()

    def failing_selected(self) -> Optional[str]:
        """The selected test's name when its last run failed (else None)."""
        item = self.tree.currentItem()
        if item is None or item.data(NAME, ROLE_KIND) != "test":
            return None
        r = self.results.get(item.text(NAME))
        return r.name if r is not None and r.failures else None

    def open_failing_run(self, name: Optional[str] = None) -> bool:
        """Run the failing test ``name`` (None: the selected one) again in the
        background, recording it; ``sig_open_run`` brings its RecordedRun.
        False when nothing can run."""
        name = name if name is not None else self.failing_selected()
        if name is None or self.root is None or self.running():
            return False
        if self.before_run is not None and not self.before_run("Open Failing Run"):
            return False
        self.summary.setText(f"recording '{name}'…")
        self._start(_RecordWorker(self.root, name, self.RECORD_KEEP), self._on_recorded)
        return True

    def set_showing(self, name: Optional[str]) -> None:
        """The run panels show the recorded run ``name`` (None: live again)."""
        self.showing = name
        self._update_buttons()

    def menu_for(self, item) -> QtWidgets.QMenu:
        """The context menu of a row."""
        menu = QtWidgets.QMenu(self)
        act = menu.addAction("Open Failing Run")
        r = self.results.get(item.text(NAME)) if item is not None else None
        act.setEnabled(bool(r is not None and r.failures and not self.running()
                            and item.data(NAME, ROLE_KIND) == "test"))
        act.triggered.connect(lambda: self.open_failing_run(item.text(NAME)))
        if self.showing is not None:
            menu.addAction("Back to Live", self.sig_back_to_live.emit)
        return menu

    def run_selected(self) -> bool:
        self.ensure_loaded()
        item = self.tree.currentItem()
        if item is None or item.data(NAME, ROLE_KIND) != "test":
            return False
        return self.run_tests([item.text(NAME)])

    # ============================================================= private
    def _on_done(self, outcome) -> None:
        results, coverage, errors, message = outcome
        self._end_thread()
        for r in results:
            self.results[r.name] = r
        self.reload()
        if errors:
            message = f"{message}; {len(errors)} test file(s) with mistakes"
        self.summary.setText(message)
        self._update_buttons()
        if coverage is not None:
            self.coverage = coverage
            self.sig_coverage.emit(coverage)
        self.sig_finished.emit(message)

    def _on_recorded(self, outcome) -> None:
        rec, message = outcome
        self._end_thread()
        self.summary.setText(message)
        self._update_buttons()
        if rec is not None:
            self.sig_open_run.emit(rec)

    def _open_run_clicked(self) -> None:
        if self.showing is not None:
            self.sig_back_to_live.emit()
        else:
            self.open_failing_run()

    def _context_menu(self, pos) -> None:
        item = self.tree.itemAt(pos)
        if item is not None:
            self.menu_for(item).exec(self.tree.viewport().mapToGlobal(pos))

    def _show_result(self, item, r) -> None:
        if r.passed:
            item.setText(STATUS, "pass")
            item.setForeground(STATUS, _brush(PASS_COLOUR))
            item.setData(NAME, ROLE_LINE, r.line or 1)
            item.setToolTip(STATUS, f"passed in {r.seconds * 1000:.0f} ms")
            return
        if r.error is not None:
            item.setText(STATUS, f"error: {r.error}")
            item.setForeground(STATUS, _brush(ERROR_COLOUR))
            item.setData(NAME, ROLE_DETAIL, f"could not run: {r.error}")
            return
        first = r.failures[0]
        item.setText(STATUS, f"FAIL: {first.condition}: expected {first.expected}, "
                             f"actual {first.actual} at tick {first.tick}")
        item.setForeground(STATUS, _brush(FAIL_COLOUR))
        item.setData(NAME, ROLE_LINE, first.line or r.line or 1)
        item.setData(NAME, ROLE_DETAIL, "\n".join(f.text() for f in r.failures))
        item.setToolTip(STATUS, item.data(NAME, ROLE_DETAIL))
        item.setText(WHERE, self._where(first.file, first.line))

    def _mark(self, item, kind: str, file: str, line: Optional[int], detail: str) -> None:
        item.setForeground(STATUS, _brush(ERROR_COLOUR))
        item.setData(NAME, ROLE_KIND, kind)
        item.setData(NAME, ROLE_FILE, file)
        item.setData(NAME, ROLE_LINE, line or 1)
        item.setData(NAME, ROLE_DETAIL, detail)

    def _where(self, file: str, line: Optional[int]) -> str:
        p = Path(file)
        try:
            p = p.relative_to(self.root) if self.root is not None else p
        except ValueError:
            pass
        return f"{p.as_posix()}:{line}" if line else p.as_posix()

    def _item(self, name: str):
        self.ensure_loaded()
        for i in range(self.tree.topLevelItemCount()):
            item = self.tree.topLevelItem(i)
            if item.text(NAME) == name:
                return item
        return None

    def _show_detail(self, item) -> None:
        self.detail.setPlainText((item.data(NAME, ROLE_DETAIL) or "") if item is not None else "")

    def _open_item(self, item, _column: int = 0) -> None:
        file = item.data(NAME, ROLE_FILE)
        if file:
            self.sig_open_location.emit(str(file), int(item.data(NAME, ROLE_LINE) or 1))

    def _update_buttons(self) -> None:
        idle = self.root is not None and not self.running()
        self.run_all_button.setEnabled(idle)
        self.run_one_button.setEnabled(idle)
        if self.showing is not None:
            self.open_run_button.setText("Back to Live")
            self.open_run_button.setEnabled(True)
        else:
            self.open_run_button.setText("Open Failing Run")
            self.open_run_button.setEnabled(idle and self.failing_selected() is not None)


def wire(win) -> None:
    """Connect the window's Tests panel: opening locations, the project, and
    coverage in the editors (those open now and those opened later)."""
    panel, es = win.tests_panel, win.editor_stack
    panel.before_run = win.run_actions.ensure_saved
    panel.sig_open_location.connect(lambda f, line: win.open_location(f, line))
    panel.sig_coverage.connect(lambda cov: show_coverage(es, cov))
    panel.sig_open_run.connect(lambda rec: show_recorded_run(win, rec))
    panel.sig_back_to_live.connect(lambda: win.run_panels is not None
                                   and win.run_panels.back_to_live())
    es.sig_editor_created.connect(lambda *_a: show_coverage(es, panel.coverage))


def show_recorded_run(win, rec) -> bool:
    """Show a RecordedRun in the window's run panels (made now if they are
    not yet); False when the window has none."""
    panels = win.ensure_run_panels()
    if panels is None:
        win.tests_panel.summary.setText("no run panels to show the run in")
        return False
    if not getattr(panels, "_tests_wired", False):
        panels._tests_wired = True
        panels.sig_recorded.connect(win.tests_panel.set_showing)
    panels.show_recorded(rec.name, rec.samples, rec.events, rec.failing_tick)
    at = f", failing at t = {rec.failing_tick} ms" if rec.failing_tick is not None else ""
    win.statusBar().showMessage(f"Showing test run '{rec.name}' (recorded){at}", 8000)
    return True


def _brush(colour: str):
    from PySide6.QtGui import QBrush, QColor
    return QBrush(QColor(colour))


def show_coverage(editor_stack, coverage) -> int:
    """Mark covered and uncovered lines in the open editors of the files the
    coverage names; returns how many editors were marked."""
    marked = 0
    for proc in coverage or ():
        for f in proc.files:
            if not f.path:
                continue
            ed = editor_stack.editor_for(f.path)
            if ed is not None:
                ed.set_coverage(f.covered, f.uncovered)
                marked += 1
    return marked
