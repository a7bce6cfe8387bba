"""Run › Issue Code…: the CNC issues M/S/B/T codes to the running controller
(as a scenario's ``code M3``), through the link's ``code`` request; each is in
the session recording (so replay and step back do it again), and the
project's last codes come back in the dialog's list."""

from __future__ import annotations

import pytest

pytest.importorskip("PySide6")

from PySide6.QtCore import Qt, QTimer  # noqa: E402
from PySide6.QtWidgets import QApplication  # noqa: E402

from plcbuilder import api  # noqa: E402
from plcbuilder.ide.actions import Act  # noqa: E402
from plcbuilder.ide.dialogs.issue_code import IssueCodeDialog, parse_codes  # noqa: E402

WAIT = 30_000


def test_parse_codes():
    assert parse_codes("S12000 M3") == ([("S", 12000), ("M", 3)], None)
    assert parse_codes("m5, t2") == ([("M", 5), ("T", 2)], None)
    assert parse_codes("X3")[0] == [] and "not a code" in parse_codes("X3")[1]
    assert parse_codes("")[0] == []


def _dialog():
    w = QApplication.activeModalWidget()
    return w if isinstance(w, IssueCodeDialog) else None


@pytest.fixture
def huazhong(qtbot, tmp_path):
    """(a window with its embedded controller, the Huazhong example built and uploaded)."""
    from plcbuilder.ide.main_window import MainWindow
    from plcbuilder.ide.settings import Settings
    project = api.create_project(tmp_path / "hz", target="huazhong")
    win = MainWindow(Settings(str(tmp_path / "s.ini")), start_controller=True)
    qtbot.addWidget(win)
    win.show()
    try:
        assert win.open_project(str(project.root), offer_recovery=False)
        conn = win.connection
        qtbot.waitUntil(lambda: conn.connected, timeout=WAIT)
        win.ensure_run_panels()
        with qtbot.waitSignal(win.sig_build_finished, timeout=60_000):
            win.build_all()
        with qtbot.waitSignal(conn.sig_result, timeout=WAIT,
                              check_params_cb=lambda verb, _r: verb == "upload"):
            win.run_actions.upload_image()
        yield win
    finally:
        win.shutdown()


def test_issue_code_from_the_run_menu_reaches_the_handler_and_is_recorded(huazhong, qtbot,
                                                                          tmp_path):
    win = huazhong
    conn = win.connection
    run_menu = next(a.menu() for a in win.menuBar().actions() if a.text() == "&Run")
    act = win.action(Act.ISSUE_CODE)
    assert act in run_menu.actions() and act.isEnabled()
    seen = []

    def type_and_issue(text):
        dlg = _dialog()
        seen.append(dlg)
        if dlg is None:
            return
        seen.append([dlg.combo.itemText(i) for i in range(dlg.combo.count())])
        dlg.combo.lineEdit().selectAll()
        qtbot.keyClicks(dlg.combo.lineEdit(), text)
        seen.append(dlg.hint.text())
        qtbot.mouseClick(dlg.issue_button, Qt.MouseButton.LeftButton)

    QTimer.singleShot(100, lambda: type_and_issue("S12000 M3"))
    act.trigger()
    assert seen[0] is not None and seen[1] == []
    assert "set_m_func" in seen[2]                       # what a code does on Huazhong
    # on_m() switches the spindle (Y0.0, output 0) on; on_s() puts S in G[1]
    qtbot.waitUntil(lambda: 0 in (conn.last_state.outputs or ()), timeout=WAIT)
    qtbot.waitUntil(lambda: "M3 issued at t = " in win.statusBar().currentMessage(),
                    timeout=WAIT)

    # the dialog offers the project's last codes, newest first
    QTimer.singleShot(100, lambda: type_and_issue("M5"))
    act.trigger()
    assert seen[4] == ["S12000 M3"]
    qtbot.waitUntil(lambda: 0 not in (conn.last_state.outputs or ()), timeout=WAIT)
    assert win.run_actions.code_history() == ["M5", "S12000 M3"]

    # recorded as every action that changes the run: in the session recording
    path = tmp_path / "session.txt"
    from plcbuilder.ide import trace_actions as ta
    with qtbot.waitSignal(win.sig_recording_saved, timeout=WAIT):
        assert ta.save_recording(win, str(path))
    lines = [ln.split(" @ ")[0] for ln in path.read_text().splitlines()
             if ln.startswith("code ")]
    assert lines == ["code S12000", "code M3", "code M5"]

    # a bad code never reaches the controller
    QTimer.singleShot(100, lambda: _check_refused(qtbot, seen))
    assert not win.run_actions.issue_code() and seen[-1] == (False, True)


def _check_refused(qtbot, seen):
    dlg = _dialog()
    dlg.combo.lineEdit().selectAll()
    qtbot.keyClicks(dlg.combo.lineEdit(), "X3")
    seen.append((dlg.issue_button.isEnabled(), "not a code" in dlg.error.text()))
    dlg.reject()
