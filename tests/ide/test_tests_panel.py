"""The Tests dock driven like a user would: list the project's tests, Run All
and Run Selected, pass/fail with the failing condition, double-click to the
failing expectation, coverage marks in the editors' margin (Ctrl+T in the
main window)."""

from __future__ import annotations

import pytest
from PySide6.QtCore import Qt
from PySide6.QtWidgets import QMessageBox

from plcbuilder.ide.editor import MK_COVERED, MK_UNCOVERED
from plcbuilder.ide.main_window import Act, MainWindow
from plcbuilder.ide.panels.tests import STATUS, TestsPanel
from plcbuilder.ide.settings import Settings

from tests.testing._proj import FAILING, PASSING, make_project

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
    for name in ("warning", "question", "critical", "information"):
        monkeypatch.setattr(QMessageBox, name, lambda *a, **k: QMessageBox.StandardButton.No)
    w = MainWindow(Settings(str(tmp_path / "config" / "settings.ini")), start_controller=False,
                   debounce_ms=20)
    qtbot.addWidget(w)
    w.show()
    yield w
    w.shutdown()


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
