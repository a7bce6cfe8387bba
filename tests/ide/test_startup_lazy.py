"""Issue 14 point 5: what the main window does not do before its first paint.

The window shows with the project open; the hidden or tabbed-away docks get
their panel when they first show (or are used), the project's check starts
after the paint, and neither the editor (Scintilla, pygments) nor the link
nor the compiler is loaded by then. Each cause of a slow start found by
profiling, pinned down without timing.
"""

from __future__ import annotations

import subprocess
import sys

import pytest
from PySide6.QtWidgets import QApplication, QWidget

from plcbuilder.project.new import create_project
from tests.ide import _workbench

make_window, prompts = _workbench.make_window, _workbench.prompts

#: Not loaded when the window first paints (they come with the first editor,
#: the first connection, the first check, the run panels).
NOT_AT_FIRST_PAINT = ("lark", "plcbuilder.lang.pipeline", "pyside6_scintilla", "pygments",
                      "plcbuilder.ide.editor.widget", "plcbuilder.link.client",
                      "plcbuilder.link.process", "plcbuilder.controller.events", "pyqtgraph",
                      "numpy", "plcbuilder.ide.help", "plcbuilder.ide.build_panel",
                      "plcbuilder.ide.panels.tests", "plcbuilder.ide.panels.register_browser",
                      "plcbuilder.testing.spec", "plcbuilder.lang.preprocess",
                      "plcbuilder.lang.symbols", "plcbuilder.ide.completion",
                      "plcbuilder.image.manifest", "plcbuilder.image.romfs", "hashlib",
                      "plcbuilder.ide.debug.callstack", "plcbuilder.ide.debug.inline",
                      "plcbuilder.bytecode.program", "plcbuilder.bytecode.opcodes",
                      "importlib.resources")

#: A window opening the project (argv 1; with argv 4, a file the last session
#: had open in it), its settings in argv 2; at the first paint it notes which of
#: the modules of argv 3 (JSON) are loaded, whether QStyle was used from Python,
#: whether the tree's descriptions are still to be read and whether an editor
#: is open. Prints that (and the application's style sheet) as JSON.
_PROBE = r"""
import json, sys
from PySide6.QtCore import QEvent, QObject, QTimer
from plcbuilder.ide.app import create_application
from plcbuilder.ide.main_window import MainWindow
from plcbuilder.ide.settings import Settings
app = create_application()
st = Settings(sys.argv[2])
if len(sys.argv) > 4:
    st.save_session(sys.argv[1], [sys.argv[4]], sys.argv[4])
    st.sync()
win = MainWindow(st, start_controller=False)
modules = json.loads(sys.argv[3])
class FirstPaint(QObject):
    def eventFilter(self, obj, ev):
        if ev.type() == QEvent.Type.Paint and not hasattr(self, "seen"):
            self.seen = sorted(m for m in modules if m in sys.modules)
            import PySide6.QtWidgets as widgets
            # resolved from Python, a Qt class builds all its enums: QStyle's take 5 ms
            self.qstyle = "QStyle" in widgets.__dict__
            self.described = win.tree.describing()
            self.editor = win.current_editor() is not None
            QTimer.singleShot(0, app.quit)
        return False
f = FirstPaint()
win.installEventFilter(f)
win.show()
win.open_project(sys.argv[1])
app.exec()
print(json.dumps({"seen": f.seen, "style_sheet": app.styleSheet(), "qstyle": f.qstyle,
                  "described": f.described, "editor": f.editor}))
win.shutdown()
"""


def _first_paint(project, settings, modules, reopen=None) -> dict:
    """What :data:`_PROBE` saw at the first paint of a window opening ``project``."""
    import json
    import os
    args = [sys.executable, "-c", _PROBE, str(project), str(settings), json.dumps(list(modules))]
    r = subprocess.run(args + ([str(reopen)] if reopen else []), capture_output=True, text=True,
                       timeout=120, env={**os.environ, "QT_QPA_PLATFORM": "offscreen"})
    assert r.returncode == 0, r.stderr
    return json.loads(r.stdout.splitlines()[-1])


def test_the_first_paint_waits_for_no_editor_link_or_compiler(tmp_path):
    project = create_project(tmp_path / "example").root
    seen = _first_paint(project, tmp_path / "s.ini", NOT_AT_FIRST_PAINT)
    assert seen["seen"] == [], seen
    # no application-wide style sheet: it makes every widget slower to build and paint
    assert seen["style_sheet"] == "", seen
    # QStyle is not used from Python before the first paint, and the tree's
    # descriptions (which need it to be drawn) are still to be read then
    assert seen["qstyle"] is False and seen["described"] is True, seen


def test_the_trees_descriptions_come_after_the_first_paint_a_batch_at_a_time(
        qtbot, make_window, tmp_path):
    from plcbuilder.ide.project_tree import DESCRIBE_BATCH, ROLE_DESCRIPTION
    project = create_project(tmp_path / "example").root
    for i in range(DESCRIBE_BATCH + 20):
        (project / "software" / f"S{i:03}.plc").write_text(
            f"// S{i:03}: job number {i}. More words.\nmain()\n{{\n  exit(99);\n}};\n")
    w = make_window()
    assert not w._painted
    w.open_project(project)
    tree = w.tree

    def described():
        return [it.text(0) for it in tree._all_items() if it.data(0, ROLE_DESCRIPTION)]

    assert described() == [] and tree.describing() and w.busy()
    # counted after each turn that reads some (polling would see several turns
    # at once on a busy machine)
    counts, painted_then = [], []
    describe_some = tree._describe_some

    def counted(batch):
        painted_then.append(w._painted)
        describe_some(batch)
        counts.append(len(described()))
    tree._describe_some = counted
    qtbot.waitUntil(lambda: w._painted)
    _workbench.settle(qtbot, w)
    assert not tree.describing() and len(counts) >= 2 and all(painted_then)
    assert counts[0] <= DESCRIBE_BATCH                   # the rest on later turns
    assert all(b - a <= DESCRIBE_BATCH for a, b in zip(counts, counts[1:]))
    assert counts[-1] > counts[0]
    assert tree.find_item("S007").data(0, ROLE_DESCRIPTION) == "job number 7"
    assert tree.find_item("M03").data(0, ROLE_DESCRIPTION) == "spindle on, clockwise"
    # once painted, a refresh reads them on the next turns, not before returning
    (project / "software" / "NEW.plc").write_text("// NEW: a new one\nmain()\n{\n};\n")
    tree.refresh()
    assert tree.find_item("NEW").data(0, ROLE_DESCRIPTION) is None and tree.describing()
    qtbot.waitUntil(lambda: not tree.describing())
    assert tree.find_item("NEW").data(0, ROLE_DESCRIPTION) == "a new one"


def test_hidden_and_tabbed_docks_get_their_panel_when_shown(qtbot, make_window, tmp_path):
    conn = _workbench.FakeConnection()
    w = make_window(connection=conn, start_controller=True)
    project = create_project(tmp_path / "example").root
    w.open_project(project)
    # before the first paint the project's check is only due: nothing compiles yet
    assert w.busy() and not w.lint.worker.pending()
    qtbot.waitUntil(lambda: w._painted and w.run_panels is not None, timeout=10000)
    _workbench.settle(qtbot, w)                        # ... then it runs
    assert w.lint.results
    wb, dbg = w.workbench, w.debug
    assert wb.panels.made == {} and dbg.panels.made == {}
    assert w._build_panel is None and w._tests_panel is None
    for dock in (w.find_dock, w.references_dock, w.disasm_dock, w.registers_dock,
                 w.callstack_dock, w.breakpoints_dock, w.forces_dock, w.build_dock,
                 w.tests_dock):
        assert dock.widget() is None, dock.objectName()
    # shown: made, in its dock, up to date
    w.registers_dock.show()
    w.registers_dock.raise_()
    qtbot.waitUntil(lambda: "registers" in wb.panels.made)
    assert w.registers_dock.widget() is wb.registers and wb.registers.connection is conn
    w.callstack_dock.raise_()
    qtbot.waitUntil(lambda: "callstack" in dbg.panels.made)
    assert w.callstack_dock.widget() is dbg.call_stack
    w.tests_dock.raise_()
    qtbot.waitUntil(lambda: w._tests_panel is not None)
    assert w.tests_dock.widget() is w.tests_panel
    assert w.tests_panel.test_names()                  # the example's tests, read on show
    # used: made (a build needs Build Output)
    done = []
    w.sig_build_finished.connect(done.append)
    assert w.build_all()
    assert w.build_dock.widget() is w.build_panel
    qtbot.waitUntil(lambda: bool(done), timeout=30000)
    assert "0 errors" in w.build_panel.text.toPlainText()


def test_no_style_sheet_before_the_first_paint_and_the_editor_tabs_keep_their_look(
        qtbot, make_window, tmp_path):
    """A style sheet, even one widget's, is parsed and makes that widget draw
    through the style-sheet style: none is set before the window first shows.
    The editor tabs get theirs with the first tab, the find bar when made, the
    speed list when it first drops down."""
    w = make_window()
    assert QApplication.instance().styleSheet() == ""
    assert [x.objectName() or type(x).__name__ for x in w.findChildren(QWidget)
            if x.styleSheet()] == []
    assert w.editor_stack._find_bar is None                # made when first opened
    project = create_project(tmp_path / "example").root
    w.open_project(project)
    w.open_file(project / "hardware" / "M03.plc")
    bar = w.tabs.tabBar()
    assert "padding: 5px 10px" in bar.styleSheet() and "close.svg" in bar.styleSheet()
    assert "border-top" in w.find_bar.styleSheet()


@pytest.mark.parametrize("name", ["CodeEditor", "file_key", "MK_ERROR", "EditorPrefs"])
def test_the_editor_package_still_gives_every_name(name):
    from plcbuilder.ide import editor
    assert getattr(editor, name) is not None


def test_pysides_source_check_answers_as_its_own_without_inspect(monkeypatch):
    """PySide's import hook read every later module's source through
    inspect.getsource (20 ms of the IDE's start-up); the IDE's check reads the
    file's bytes and gives the same answer for every module loaded."""
    import inspect

    import plcbuilder.ide  # noqa: F401 - puts the quicker check in place
    feature = sys.modules.get("shibokensupport.feature")
    if feature is None or not hasattr(feature, "_mod_uses_pyside"):
        pytest.skip("this PySide has no such import hook")
    quick = feature._mod_uses_pyside
    original = getattr(quick, "original", None)
    assert original is not None, "the IDE's check is not in place"
    import os
    mods = [m for m in list(sys.modules.values())
            if str(getattr(m, "__file__", None)).endswith(".py") and os.path.isfile(m.__file__)]
    assert len(mods) > 100
    theirs = [original(m) for m in mods]
    assert any(theirs) and not all(theirs)

    def no_getsource(obj):
        raise AssertionError(f"inspect.getsource({obj!r})")
    monkeypatch.setattr(inspect, "getsource", no_getsource)
    assert [quick(m) for m in mods] == theirs


def test_the_last_session_shows_its_current_editor_first_and_compiles_after_the_paint(
        qtbot, make_window, tmp_path):
    """Issue 26.5: until the window's first paint only the current editor of
    the last session is made, nothing is compiled in the background (the
    diagnostics thread held the interpreter, and the main thread waited for
    its lock while it loaded the compiler) and the outline waits; then the
    other editors come in their places, with every check."""
    project, files, st = _last_session(tmp_path)
    w = make_window()
    compiled = []
    w.lint.worker.sig_result.connect(lambda key, result: compiled.append(key))
    assert not w._painted and w.isVisible()
    w.open_project(project)
    assert [e.path for e in w.editors()] == [files[1]] and w.busy()
    worker = w.lint.worker
    assert worker._held and list(worker._queue) and compiled == []   # queued, not compiled
    assert w.workbench.outline.items == []
    qtbot.waitUntil(lambda: w._painted and not w.busy(), timeout=20000)
    assert not worker._held and len(set(compiled)) >= 3
    assert [e.path for e in w.editors()] == files            # in their places
    assert w.current_editor().path == files[1]
    assert w.workbench.outline.items                         # outlined once painted


def test_closing_before_the_last_sessions_other_editors_open_keeps_them(
        qtbot, make_window, tmp_path):
    """Issue 26.5: the last session's other editors open after the first
    paint (and the run panels); a window closed before then saves them in
    the session all the same, in their order."""
    project, files, st = _last_session(tmp_path)
    w = make_window(settings=st)
    w.open_project(project)
    assert [e.path for e in w.editors()] == [files[1]] and w._editors_due is not None
    w.close()
    from plcbuilder.ide.settings import Settings
    again = Settings(str(tmp_path / "config" / "settings.ini"))
    assert again.open_files(project) == files and again.current_file(project) == files[1]


def test_the_embedded_controller_process_starts_before_the_first_paint(
        qtbot, make_window, tmp_path):
    """Issue 26.5: the controller's own Python start is the longest part of
    the run panels coming live: its process starts when the project opens
    (before the paint, on the other core); the connection made after the
    paint uses that process, not another."""
    project = create_project(tmp_path / "example").root
    w = make_window(start_controller=True)
    assert not w._painted
    w.open_project(project)
    conn = w.connection
    pre = conn._prestarted
    assert pre is not None and pre[1].alive() and conn._worker is None   # not connected yet
    pid = pre[1].pid
    qtbot.waitUntil(lambda: w.connected(), timeout=30000)
    assert conn.child_pid == pid and conn._prestarted is None
    # another project before the paint would have dropped it; after: a new one
    w.shutdown()
    qtbot.waitUntil(lambda: not pre[1].alive(), timeout=10000)


#: the compiler's symbols (what the editor's defines need)
SYMBOLS = ("plcbuilder.ide.completion", "plcbuilder.lang.symbols", "plcbuilder.lang.preprocess")


def test_the_first_editor_paints_without_the_compilers_symbols(qtbot, make_window, tmp_path):
    """Issue 26.5: the last session's editor is in the first frame, but the
    defines it colours (found with the compiler's symbols, 60 ms to load) come
    after the paint, with the headers' defines."""
    project = create_project(tmp_path / "example").root
    seen = _first_paint(project, tmp_path / "s.ini", SYMBOLS,
                        reopen=project / "hardware" / "M71.plc")
    assert seen["seen"] == [] and seen["editor"] is True, seen
    # in a window: the editor made before the paint gets its defines after it
    w = make_window()
    w.open_project(project)
    ed = w.open_file(project / "hardware" / "M71.plc")
    assert not w._painted and "ARC_TIMEOUT" not in ed.highlighter.defines
    qtbot.waitUntil(lambda: "ARC_TIMEOUT" in ed.highlighter.defines, timeout=20000)
    assert w._painted


def test_the_checks_and_the_other_editors_wait_until_the_run_panels_are_live(
        qtbot, make_window, tmp_path):
    """Issue 26.5: once the run panels are made, the project's check (on the
    diagnostics thread, which takes the interpreter from the window) and the
    session's other editors wait until the panels have drawn the controller's
    first telemetry, the last thing the start is waited for; at most
    LIVE_WAIT_MS when none comes."""
    from plcbuilder.controller import events as ev
    from plcbuilder.ide.main_window import LIVE_WAIT_MS
    conn = _workbench.FakeConnection()             # (an embedded controller's)
    w = make_window(connection=conn, start_controller=True)
    rest = w._after_panels
    rested = []
    w._after_panels = lambda: (rested.append(w.run_panels.live), rest())
    w.open_project(create_project(tmp_path / "example").root)
    qtbot.waitUntil(lambda: w.run_panels is not None and not w.dock_table.held, timeout=10000)
    qtbot.wait(LIVE_WAIT_MS // 2)
    assert rested == [] and w._lint_due
    zeros = (0,) * 8
    conn.sig_samples.emit([ev.Sample(t_ms=1, running="", proc=0, message=0, inputs=zeros,
                                     outputs=zeros, pwm=zeros, dac=zeros, adc=zeros,
                                     axes=(0,) * 9, velocities=(0,) * 9)])
    qtbot.waitUntil(lambda: rested == [True], timeout=LIVE_WAIT_MS // 2)
    qtbot.waitUntil(lambda: not w._lint_due, timeout=5000)
    # no telemetry: the rest comes LIVE_WAIT_MS after the panels
    w2 = make_window(connection=_workbench.FakeConnection(), start_controller=True)
    rest2 = w2._after_panels
    rested2 = []
    w2._after_panels = lambda: (rested2.append(w2.run_panels.live), rest2())
    w2.open_project(create_project(tmp_path / "other").root)
    qtbot.waitUntil(lambda: w2.run_panels is not None and not w2.dock_table.held,
                    timeout=10000)
    qtbot.waitUntil(lambda: rested2 == [False], timeout=LIVE_WAIT_MS * 3)


@pytest.mark.parametrize("turn_ms", [0, 60_000])
def test_the_run_panels_make_the_docks_on_screen_a_turn_at_a_time_and_the_others_when_shown(
        qtbot, make_window, tmp_path, monkeypatch, turn_ms):
    """Issue 26.5: after the paint only the run docks on screen get their
    panel (and the log, which keeps every message), as many a turn of the
    event loop as fit in docks.TURN_MS (the window answers between turns;
    with 0, one a turn; with a minute, all in one); a dock hidden or
    tabbed away gets its panel when it first shows, and that panel shows what
    the others do (here a recorded run on show: its banner, link and marker)."""
    from PySide6.QtCore import QTimer

    from plcbuilder.ide import docks
    from plcbuilder.ide.docks import on_screen
    monkeypatch.setattr(docks, "TURN_MS", turn_ms)
    turn = [0]
    ticker = QTimer()
    ticker.timeout.connect(lambda: turn.__setitem__(0, turn[0] + 1))
    ticker.start(0)                                   # one tick a turn of the event loop
    conn = _workbench.FakeConnection()
    w = make_window(connection=conn, start_controller=True)
    made_on: dict = {}
    panel = w.dock_table.panel

    def noted(key):
        made_on.setdefault(key, turn[0])
        return panel(key)
    w.dock_table.panel = noted
    rest = w._after_panels                  # the checks, the other editors: after the panels
    rested = []
    w._after_panels = lambda: (rested.append(set(w.run_panels.made)), rest())
    w.open_project(create_project(tmp_path / "example").root)
    qtbot.waitUntil(lambda: w._painted and w.run_panels is not None, timeout=10000)
    _workbench.settle(qtbot, w)
    qtbot.wait(700)                         # (past the fallback for a window never painted)
    # (no telemetry: the rest comes at most LIVE_WAIT_MS after the panels)
    qtbot.waitUntil(lambda: bool(rested), timeout=5000)
    ticker.stop()
    panels = w.run_panels
    shown = {k for k, d in w.run_docks.items() if on_screen(d)}
    assert shown and "outputs" in shown and "axes" not in shown
    assert set(panels.made) == shown | {"log"}, (panels.made, shown)
    for key, dock in w.run_docks.items():
        assert (dock.widget() is not None) == (key in panels.made), key
    turns = [made_on[k] for k in shown if k != "log"]
    assert len(turns) > 1
    if turn_ms == 0:
        assert len(set(turns)) == len(turns), made_on         # one a turn
    else:
        assert len(set(turns)) == 1, made_on                  # all in one
    assert rested == [shown | {"log"}]                        # once, after them
    # a recorded run on show; then the Axes dock shows: its panel shows it too
    panels.show_recorded("a test", [], [], failing_ms=100)
    assert "axes" not in panels.made
    w.run_docks["axes"].raise_()
    qtbot.waitUntil(lambda: "axes" in panels.made)
    axes = panels.axes
    assert w.run_docks["axes"].widget() is axes
    banner = [b for b in panels.banners if axes.isAncestorOf(b)]
    assert banner and "showing test run 'a test'" in banner[0].plain_text()
    assert any(p is axes for p, _plot, _line in panels._markers)
    back = [b for b in panels.banner_links if axes.isAncestorOf(b)]
    assert back and back[0].isVisibleTo(axes)


def test_a_window_on_screen_whose_paint_is_late_is_waited_for(qtbot, make_window, tmp_path,
                                                              monkeypatch):
    """Issue 26.5: the start's rest (the run panels' modules among it) waits
    for the first paint; the fallback for a window that never paints (500 ms
    after the first turn) ran it before a paint that was only late (a loaded
    machine), which then waited for pyqtgraph. A window on screen is waited
    for; one that cannot be seen starts the rest at once."""
    w = make_window(connection=_workbench.FakeConnection(), start_controller=True)
    qtbot.waitUntil(lambda: w.windowHandle() is not None and w.windowHandle().isExposed())
    w._after_paint_done, w._painted = False, False      # as if no paint had come yet
    w._paint_overdue()
    assert not w._after_paint_done and w._overdue_waits == 1
    monkeypatch.setattr(type(w.windowHandle()), "isExposed", lambda self: False)
    w._paint_overdue()                                  # minimised, unmapped: now
    assert w._after_paint_done


def test_telemetry_before_the_run_panels_are_made_is_shown_by_them(qtbot, make_window, tmp_path):
    """Issue 26.5: the connection starts right after the first paint and the
    run panels are made once their modules load: the telemetry that came
    meanwhile (the inputs that changed as the controller started, its first
    messages) is theirs too, not lost: the Outputs dock showed no lane for
    an input that had changed before."""
    from tests.ide.test_panels import sample
    from plcbuilder.api import events as ev
    conn = _workbench.FakeConnection()
    w = make_window(connection=conn, start_controller=True)
    assert w.run_panels is None
    conn.sig_samples.emit([sample(10, inputs=0), sample(20, inputs=1 << 4, outputs=1 << 5)])
    conn.sig_events.emit([ev.Message(t_ms=20, message=7, name=None, command=0, parameter=0,
                                     source="M03")])
    qtbot.waitUntil(lambda: w.run_panels is not None, timeout=10000)
    panels = w.run_panels
    assert len(panels.model) == 2
    assert panels.model.active_inputs == {4} and panels.model.active_outputs == {5}
    assert [m.code for m in panels.model.messages] == [7]
    conn.sig_samples.emit([sample(30, inputs=0)])
    assert len(panels.model) == 3 and w._early_samples == []    # once, then no more kept


def _last_session(tmp_path):
    """The example project with three editors saved as its last session (the
    second one current): (its folder, the files, the settings)."""
    from plcbuilder.ide.settings import Settings
    project = create_project(tmp_path / "example").root
    files = [str(project / "hardware" / n) for n in ("M03.plc", "M05.plc")] + \
        [str(project / "software" / "LUBE.plc")]
    st = Settings(str(tmp_path / "config" / "settings.ini"))
    st.save_session(project, files, files[1])
    st.sync()
    return project, files, st


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="counts threads in /proc")
@pytest.mark.parametrize("setting", [None, "2"])
def test_numpy_in_the_ide_starts_no_threads_of_its_own_unless_the_user_asks(setting):
    """OpenBLAS (numpy's) started a spinning thread a core at numpy's import,
    taking the other core from the controller and the X server as the IDE
    started; the IDE does no linear algebra. A user's own setting wins."""
    import os
    code = ("import os, plcbuilder.ide, numpy\n"
            "print(os.environ['OPENBLAS_NUM_THREADS'], len(os.listdir('/proc/self/task')))")
    env = {k: v for k, v in os.environ.items() if k != "OPENBLAS_NUM_THREADS"}
    if setting is not None:
        env["OPENBLAS_NUM_THREADS"] = setting
    env["QT_QPA_PLATFORM"] = "offscreen"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         env=env, timeout=60, check=True).stdout.split()
    if setting is None:
        assert out == ["1", "1"]
    else:
        assert out[0] == setting            # (its threads: as many as OpenBLAS then makes)


def test_the_collector_keeps_its_start_up_pace_until_the_run_panels_are_live(
        qtbot, make_window, tmp_path):
    """Issue 26.5: loading numpy and pyqtgraph for the run panels, after the
    window's paint, allocates as much as the start before it: at the usual
    thresholds the collector ran 64 times (30 ms) in between. The start-up
    thresholds stay until the panels are live, then the usual ones come back."""
    import gc

    import plcbuilder.ide as ide
    from plcbuilder.controller import events as ev
    usual = gc.get_threshold()
    gc.set_threshold(*ide._STARTUP_THRESHOLDS)           # as the IDE's import leaves them
    try:
        conn = _workbench.FakeConnection()
        w = make_window(connection=conn, start_controller=True)
        w.open_project(create_project(tmp_path / "example").root)
        qtbot.waitUntil(lambda: w.run_panels is not None and not w.dock_table.held,
                        timeout=10000)
        assert w._painted and gc.get_threshold() == ide._STARTUP_THRESHOLDS
        zeros = (0,) * 8
        conn.sig_samples.emit([ev.Sample(t_ms=1, running="", proc=0, message=0, inputs=zeros,
                                         outputs=zeros, pwm=zeros, dac=zeros, adc=zeros,
                                         axes=(0,) * 9, velocities=(0,) * 9)])
        qtbot.waitUntil(lambda: w.run_panels.live, timeout=5000)
        qtbot.waitUntil(lambda: gc.get_threshold() == ide._THRESHOLDS, timeout=5000)
        assert ide._THRESHOLDS[0] < ide._STARTUP_THRESHOLDS[0]
    finally:
        gc.set_threshold(*usual)
