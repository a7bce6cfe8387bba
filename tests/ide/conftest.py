"""Fixtures several IDE test files share. Qt is imported inside them, so that
collecting a folder never needs it before a test module asks for it."""

from __future__ import annotations

import os

import pytest

WAIT = 15_000      # ms: generous bounds for a loaded machine; passing runs take far less


def _gone(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return True
    return False


@pytest.fixture
def live_run_panels(qtbot):
    """(a plain main window, a ControllerConnection to a real embedded
    controller, connected and empty, the RunPanels docked on it); at the end the
    controller's child process is waited for until it is gone."""
    from plcbuilder.ide.connection import ControllerConnection
    from tests.ide._workbench import docked_run_panels

    conn = ControllerConnection()
    win, panels = docked_run_panels(qtbot, conn, (1400, 900))
    conn.start_embedded()
    try:
        qtbot.waitUntil(lambda: conn.connected, timeout=WAIT)
        yield win, conn, panels
    finally:
        pid = conn.child_pid
        conn.shutdown()
        panels.shutdown()
        if pid:
            qtbot.waitUntil(lambda: _gone(pid), timeout=5000)


@pytest.fixture
def live_example(qtbot, tmp_path, monkeypatch):
    """(a main window that starts the embedded controller, the root of a fresh
    example project, not opened yet); every message box answers No."""
    from plcbuilder.ide.main_window import MainWindow
    from plcbuilder.ide.settings import Settings
    from plcbuilder.project.new import create_project
    from tests.ide._workbench import answer_no

    answer_no(monkeypatch)
    root = create_project(tmp_path / "example", name="example").root
    w = MainWindow(Settings(str(tmp_path / "settings.ini")), start_controller=True,
                   debounce_ms=20)
    qtbot.addWidget(w)
    w.resize(1400, 900)
    w.show()
    yield w, root
    w.shutdown()


@pytest.fixture
def live_uploaded(qtbot, tmp_path):
    """(a main window with its embedded controller, the example project open,
    built and uploaded, the run panels made); the window is closed at the end."""
    from plcbuilder.ide.main_window import MainWindow
    from plcbuilder.ide.settings import Settings
    from plcbuilder.project.new import create_project
    create_project(tmp_path / "p")
    win = MainWindow(Settings(str(tmp_path / "s.ini")), start_controller=True)
    qtbot.addWidget(win)
    win.show()
    try:
        win.open_project(str(tmp_path / "p"))
        conn = win.connection
        qtbot.waitUntil(lambda: conn.connected, timeout=30000)
        panels = win.ensure_run_panels()
        with qtbot.waitSignal(win.sig_build_finished, timeout=60000):
            win.build_all()
        with qtbot.waitSignal(conn.sig_result, timeout=30000,
                              check_params_cb=lambda verb, _r: verb == "upload"):
            win.run_actions.upload_image()
        yield win, panels
    finally:
        win.close()
