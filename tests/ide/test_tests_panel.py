"""The Tests dock driven like a user would: list the project's tests, Run All
and Run Selected, pass/fail with the failing condition, double-click to the
failing expectation, coverage marks in the editors' margin (Ctrl+T in the
main window)."""

from __future__ import annotations

import pytest
from PySide6 import QtWidgets
from PySide6.QtCore import Qt

from plcbuilder.controller import events as ev

from plcbuilder.ide.editor import MK_COVERED, MK_UNCOVERED
from plcbuilder.ide.main_window import Act
from plcbuilder.ide.panels.tests import STATUS, TestsPanel

from tests.ide._workbench import RecordingConnection, answer_no, settings_in, windows
from tests.testing._proj import FAILING, LONG_FAILING, PASSING, make_project

@pytest.fixture
def proj(tmp_path):
    return make_project(tmp_path / "proj", {"a": PASSING, "b": FAILING,
                                            "c": "[[test]]\nname = 1\n"})


@pytest.fixture
def panel(qtbot, proj):
    p = TestsPanel()
    qtbot.addWidget(p)
    p.set_project(proj)
    return p


def run_and_wait(qtbot, panel, names=None):
    with qtbot.waitSignal(panel.sig_finished, timeout=30000) as blocker:
        assert panel.run_tests(names)
    return blocker.args[0]


def test_lists_tests_and_files_with_mistakes(panel, proj):
    assert panel.test_names() == ["pulse on in ticks 5..7", "branch two"]
    assert panel.status_of("pulse on in ticks 5..7") == "not run"
    assert panel.status_of("c.toml").startswith("name must be a non-empty string")
    assert panel.tree.topLevelItem(0).text(2) == "tests/c.toml:2"


def test_run_all_shows_pass_and_the_failing_condition(qtbot, panel):
    summary = run_and_wait(qtbot, panel)
    assert summary.startswith("1 passed, 1 failed")
    assert panel.status_of("pulse on in ticks 5..7") == "pass"
    assert panel.status_of("branch two") == ("FAIL: pwm = { 0 = 10 }: expected pwm 0 = 10, "
                                             "actual pwm 0 = 20 at tick 1")
    assert panel.summary.text().startswith("1 passed, 1 failed")
    assert panel.run_all_button.isEnabled()


def test_selecting_a_failure_shows_it_and_double_click_opens_the_expectation(qtbot, panel, proj):
    run_and_wait(qtbot, panel)
    item = next(panel.tree.topLevelItem(i) for i in range(panel.tree.topLevelItemCount())
                if panel.tree.topLevelItem(i).text(0) == "branch two")
    panel.tree.setCurrentItem(item)
    assert "b.toml:10: at_ms = 1: pwm = { 0 = 10 }" in panel.detail.toPlainText()
    with qtbot.waitSignal(panel.sig_open_location) as blocker:
        panel.tree.itemDoubleClicked.emit(item, 0)
    assert blocker.args == [str(proj / "tests" / "b.toml"), 10]


def test_run_selected_runs_only_that_test(qtbot, panel):
    item = next(panel.tree.topLevelItem(i) for i in range(panel.tree.topLevelItemCount())
                if panel.tree.topLevelItem(i).text(0) == "pulse on in ticks 5..7")
    panel.tree.setCurrentItem(item)
    with qtbot.waitSignal(panel.sig_finished, timeout=30000) as blocker:
        assert panel.run_selected()
    assert blocker.args[0].startswith("1 passed, 0 failed")
    assert panel.status_of("branch two") == "not run"


def test_a_project_that_does_not_build_says_so(qtbot, panel, proj):
    (proj / "hardware" / "BAD.plc").write_text("main(){ x = ; };\n")
    assert run_and_wait(qtbot, panel).startswith("not run: BAD did not compile")


def test_without_a_project_nothing_runs(qtbot):
    p = TestsPanel()
    qtbot.addWidget(p)
    assert not p.run_tests() and not p.run_all_button.isEnabled()


# --------------------------------------------------------------- in the window

@pytest.fixture
def win(qtbot, tmp_path, monkeypatch):
    answer_no(monkeypatch)
    with windows(qtbot, settings_in(tmp_path), None) as make:
        yield make()


def marks(ed, marker):
    return [n + 1 for n in range(ed.lineCount()) if ed.markerGet(n) & (1 << marker)]


def test_ctrl_t_runs_the_tests_and_coverage_marks_the_editors(qtbot, win, proj):
    assert win.open_project(proj)
    assert win.action(Act.RUN_TESTS).isEnabled()
    assert win.action(Act.RUN_TESTS).shortcut().toString() == "Ctrl+T"
    before = win.open_file(proj / "hardware" / "BRANCH.plc")
    win.tests_panel.coverage_box.setChecked(True)
    with qtbot.waitSignal(win.tests_panel.sig_finished, timeout=30000):
        win.action(Act.RUN_TESTS).trigger()
    assert win.tests_dock.isVisible()
    assert win.tests_panel.status_of("pulse on in ticks 5..7") == "pass"
    # BRANCH ran with eparam 2: the eparam-1 branch (lines 6-7) did not run
    assert marks(before, MK_UNCOVERED) == [6, 7]
    assert marks(before, MK_COVERED) == [3, 4, 9, 11, 12, 14, 15, 16]
    after = win.open_file(proj / "hardware" / "PULSE.plc")     # opened after the run
    assert marks(after, MK_COVERED) == [3, 4, 5, 6, 7, 8, 9] and marks(after, MK_UNCOVERED) == []


def test_double_click_in_the_window_opens_the_test_file(qtbot, win, proj):
    win.open_project(proj)
    with qtbot.waitSignal(win.tests_panel.sig_finished, timeout=30000):
        win.tests_panel.run_tests()
    item = next(win.tests_panel.tree.topLevelItem(i)
                for i in range(win.tests_panel.tree.topLevelItemCount())
                if win.tests_panel.tree.topLevelItem(i).text(0) == "branch two")
    win.tests_panel.tree.itemDoubleClicked.emit(item, 0)
    ed = win.current_editor()
    assert ed is not None and ed.path.endswith("b.toml")
    assert ed.cursor_line_col()[0] == 10


# ---------------------------------------------------------- open the failing run

def item_named(panel, name):
    return next(panel.tree.topLevelItem(i) for i in range(panel.tree.topLevelItemCount())
                if panel.tree.topLevelItem(i).text(0) == name)


def test_open_failing_run_is_for_a_selected_failing_test(qtbot, panel):
    assert not panel.open_run_button.isEnabled()
    run_and_wait(qtbot, panel)
    panel.tree.setCurrentItem(item_named(panel, "pulse on in ticks 5..7"))
    assert not panel.open_run_button.isEnabled()            # it passed
    assert not panel.menu_for(panel.tree.currentItem()).actions()[0].isEnabled()
    panel.tree.setCurrentItem(item_named(panel, "branch two"))
    assert panel.open_run_button.isEnabled()
    act = panel.menu_for(panel.tree.currentItem()).actions()[0]
    assert act.text() == "Open Failing Run" and act.isEnabled()
    with qtbot.waitSignal(panel.sig_open_run, timeout=30000) as blocker:
        act.trigger()                                          # the context menu's
    rec = blocker.args[0]
    assert rec.name == "branch two" and rec.failing_tick == 1
    assert [s.t_ms for s in rec.samples] == list(range(40))   # ms = 40: the whole run
    assert not panel.running()


def live_sample(t):
    z = (0,) * 8
    return ev.Sample(t_ms=t, running="M03", proc=0, message=0, inputs=z, outputs=(1,) + z[1:],
                     pwm=z, dac=z, adc=z, axes=(0,) * 9, velocities=(0,) * 9)


@pytest.fixture
def live_win(qtbot, tmp_path, monkeypatch):
    """A window whose connection only sends what the test emits."""
    answer_no(monkeypatch)
    conn = RecordingConnection()
    with windows(qtbot, settings_in(tmp_path), (1200, 800)) as make:
        w = make(connection=conn, start_controller=True)
        qtbot.waitUntil(lambda: w.run_panels is not None, timeout=10000)
        yield w, conn


def test_open_failing_run_shows_it_in_the_run_panels_until_back_to_live(qtbot, live_win, tmp_path):
    win, conn = live_win
    proj = make_project(tmp_path / "p2", {"long": LONG_FAILING})
    assert win.open_project(proj)
    rp, panel = win.run_panels, win.tests_panel
    conn.sig_samples.emit([live_sample(t) for t in range(5000, 5100)])   # live telemetry
    assert len(rp.model) == 100
    with qtbot.waitSignal(panel.sig_finished, timeout=30000):
        panel.run_tests()
    panel.tree.setCurrentItem(item_named(panel, "pulse too long"))
    assert panel.open_run_button.text() == "Open Failing Run"
    with qtbot.waitSignal(rp.sig_recorded, timeout=30000):
        qtbot.mouseClick(panel.open_run_button, Qt.MouseButton.LeftButton)
    # the recorded run: ticks 0 … 8 + 100 (a little past the failing tick 8)
    assert rp.recorded == "pulse too long" and rp.failing_ms == 8
    assert len(rp.model) == 109 and rp.model.t_end == pytest.approx(0.108)
    assert rp.model.t_end >= 0.008
    assert rp.model.pin_state("outputs", 3) == 0 and 3 in rp.model.active_outputs
    assert win.run_docks["outputs"].isVisible()
    assert not rp.timebase.follow
    rp.tick()
    for p in rp.time_panels:
        t0, t1 = p.visible_span()
        assert t0 <= 0.008 <= t1
    assert rp._markers
    for p, _plot, line in rp._markers:
        assert line.value() + p.offset == pytest.approx(0.008)
    banner = rp.banners[1]                                   # the Outputs dock's toolbar
    assert not banner.isHidden()
    assert "showing test run 'pulse too long' (recorded), failing at t = 8 ms" in banner.text()
    assert panel.open_run_button.text() == "Back to Live" and panel.open_run_button.isEnabled()
    assert "failing at t = 8 ms" in win.statusBar().currentMessage()

    # live telemetry does not overwrite it
    conn.sig_samples.emit([live_sample(t) for t in range(5100, 5200)])
    conn.sig_events.emit([ev.Message(5150, 101, None, 0, 0, "M03")])
    rp.tick()
    assert len(rp.model) == 109 and rp.model.t_end == pytest.approx(0.108)
    assert rp.recorded == "pulse too long" and rp.held == 100

    # until the user goes back to live (the same button)
    qtbot.mouseClick(panel.open_run_button, Qt.MouseButton.LeftButton)
    assert rp.recorded is None and len(rp.model) == 0 and rp.timebase.follow
    assert not rp._markers and banner.isHidden()
    assert panel.open_run_button.text() == "Open Failing Run"
    conn.sig_samples.emit([live_sample(t) for t in range(5200, 5300)])
    assert len(rp.model) == 100 and rp.model.t_end == pytest.approx(5.299)


def test_clear_in_the_run_panels_also_goes_back_to_live(qtbot, live_win, tmp_path):
    win, conn = live_win
    assert win.open_project(make_project(tmp_path / "p3", {"long": LONG_FAILING}))
    rp, panel = win.run_panels, win.tests_panel
    with qtbot.waitSignal(panel.sig_finished, timeout=30000):
        panel.run_tests()
    with qtbot.waitSignal(rp.sig_recorded, timeout=30000):
        assert panel.open_failing_run("pulse too long")
    rp.lanes.toolbar.findChildren(QtWidgets.QToolButton)[-1].click()   # Clear
    assert rp.recorded is None and panel.showing is None


def test_a_long_recorded_run_name_never_widens_the_docks(qtbot, live_win):
    """Docks never grow by themselves: the banner over the plots and the Tests
    dock's summary take the room there is, whatever the test's name."""
    win, _conn = live_win
    rp, panel = win.run_panels, win.tests_panel
    outputs = win.run_docks["outputs"]

    def widths(name: str) -> tuple:
        rp.show_recorded(name, [], [], 8)
        panel.summary.setText(f"recorded '{name}': 151 ms")
        return (outputs.minimumSizeHint().width(), panel.minimumSizeHint().width(),
                win.minimumSizeHint().width())

    window_before = win.minimumSizeHint().width()
    short = widths("t")
    long_name = "a test whose name goes on and on " * 8
    assert widths(long_name) == short
    assert short[2] == window_before
    assert long_name.strip() in rp.banners[1].toolTip()
    rp.back_to_live()


def test_the_panel_looks_for_tests_where_the_runner_does():
    """The panel names the tests folder without loading the runner at start-up."""
    from plcbuilder.ide.panels import tests as panel_module
    from plcbuilder.testing.spec import TESTS_DIR
    assert panel_module.TESTS_DIR == TESTS_DIR


# ------------------------------------------------- what the editors show (23.2)

def _halve_the_spindle_speed(qtbot, win, root):
    """Open M03 and type ``/2`` after ``pwm01=speed`` (not saved)."""
    ed = win.open_file(root / "hardware" / "M03.plc")
    line = next(i for i, t in enumerate(ed.text().splitlines()) if "pwm01=speed;" in t)
    col = ed.text().splitlines()[line].index(";")
    ed.goto_line(line + 1, col + 1)
    qtbot.keyClicks(ed, "/2")
    assert "pwm01=speed/2;" in ed.text() and win.is_modified(ed)
    return ed


def test_run_tests_runs_what_the_editors_show_saving_first_as_build_all_does(
        qtbot, win, tmp_path):
    """Issue 23 point 2: with M03 changed and not saved, Ctrl+T said "14 passed"
    (the files on disk); the tests run on the editors' text: saved first, as
    Build All saves (the preference), and they fail."""
    from plcbuilder.project.new import create_project
    root = create_project(tmp_path / "example", name="example").root
    assert win.open_project(root)
    with qtbot.waitSignal(win.tests_panel.sig_finished, timeout=60000) as clean:
        win.action(Act.RUN_TESTS).trigger()
    assert ", 0 failed" in clean.args[0]
    ed = _halve_the_spindle_speed(qtbot, win, root)
    with qtbot.waitSignal(win.tests_panel.sig_finished, timeout=60000) as edited:
        win.action(Act.RUN_TESTS).trigger()
    assert ", 0 failed" not in edited.args[0], edited.args[0]
    assert not win.is_modified(ed)
    assert "pwm01=speed/2;" in (root / "hardware" / "M03.plc").read_text()


def test_without_saving_before_build_run_tests_asks_and_cancel_runs_nothing(
        qtbot, win, tmp_path, monkeypatch):
    from PySide6.QtWidgets import QMessageBox
    from plcbuilder.project.new import create_project
    root = create_project(tmp_path / "example", name="example").root
    win.apply_preferences(win.prefs.with_changes(save_before_build=False))
    assert win.open_project(root)
    ed = _halve_the_spindle_speed(qtbot, win, root)
    asked = []
    answer = [QMessageBox.StandardButton.Cancel]
    monkeypatch.setattr(QMessageBox, "question", lambda _p, title, text, *a, **k: (
        asked.append((title, text)), answer[0])[1])
    win.action(Act.RUN_TESTS).trigger()
    assert asked and asked[0][0] == "Run Tests" and "M03.plc" in asked[0][1]
    assert not win.tests_panel.running() and win.is_modified(ed)
    assert "pwm01=speed;" in (root / "hardware" / "M03.plc").read_text()
    # Build All asks the same (it built the files on disk without a word)
    assert not win.build_all() and len(asked) == 2 and asked[1][0] == "Build All"
    answer[0] = QMessageBox.StandardButton.Save
    with qtbot.waitSignal(win.tests_panel.sig_finished, timeout=60000) as edited:
        win.action(Act.RUN_TESTS).trigger()
    assert ", 0 failed" not in edited.args[0] and not win.is_modified(ed)


def test_another_project_shows_none_of_the_last_ones_test_run(qtbot, live_win, tmp_path):
    """Issue 23 points 9 and 8: after switching project, the Outputs dock still
    said "showing test run 'pulse too long' (recorded)…", the Tests header kept
    the old totals, and the trigger bar its last capture."""
    win, conn = live_win
    assert win.open_project(make_project(tmp_path / "p4", {"long": LONG_FAILING}))
    rp, panel = win.run_panels, win.tests_panel
    with qtbot.waitSignal(panel.sig_finished, timeout=30000):
        panel.run_tests()
    assert "failed" in panel.summary.text()
    with qtbot.waitSignal(rp.sig_recorded, timeout=30000):
        assert panel.open_failing_run("pulse too long")
    assert rp.recorded == "pulse too long"
    rp.traces.bar.set_state("captured at t = 1.000 s")
    rp.traces.bar.spec.setText("out 3 rise")
    rp.traces.bar.arm.setChecked(True)
    assert win.open_project(make_project(tmp_path / "p5", {"other": LONG_FAILING}))
    assert rp.recorded is None and all(b.isHidden() for b in rp.banners)
    assert panel.showing is None and panel.open_run_button.text() == "Open Failing Run"
    assert panel.summary.text() == ""
    assert all(panel.status_of(n) == "not run" for n in panel.test_names())
    assert rp.traces.capturer is None and not rp.traces.bar.arm.isChecked()
    assert "not armed" in rp.traces.bar.state.text()
    # closing the project too
    with qtbot.waitSignal(panel.sig_finished, timeout=30000):
        panel.run_tests()
    assert win.close_project()
    assert panel.summary.text() == ""
