"""Docks never grow by themselves (issue 13, defect 2): status text in a dock's
toolbar elides instead of setting the dock's minimum width, and the recorded-run
banner keeps some room when the dock is narrow."""

import pytest
from PySide6.QtCore import Qt
from PySide6.QtWidgets import QApplication

from plcbuilder.ide.settings import Settings
from plcbuilder.link.client import ControllerStatus
from tests.ide._workbench import RecordingConnection, answer_no, windows
from tests.ide.test_main_window import make_project


@pytest.fixture
def runwin(qtbot, tmp_path, prompts_off):
    conn = RecordingConnection()
    with windows(qtbot, Settings(str(tmp_path / "cfg" / "settings.ini")), (1200, 800)) as make:
        w = make(connection=conn, start_controller=True)
        qtbot.waitUntil(lambda: w.run_panels is not None, timeout=10000)
        w.open_project(make_project(tmp_path / "proj"))
        yield w, conn


@pytest.fixture
def prompts_off(monkeypatch):
    answer_no(monkeypatch)


def _settle(qtbot):
    for _ in range(5):
        QApplication.processEvents()
    qtbot.wait(20)


def _in_front(w, key: str, qtbot):
    """A run dock shown and in front of its tabs, laid out."""
    dock = w.run_docks[key]
    dock.show()
    dock.raise_()
    _settle(qtbot)
    return dock


def test_a_long_status_never_widens_the_proc_dock(runwin, qtbot):
    w, conn = runwin
    rp = w.run_panels
    proc_dock = _in_front(w, "proc", qtbot)
    before = (proc_dock.width(), w.width(), w.centralWidget().width())
    conn.connected = True
    conn.sig_connected.emit("127.0.0.1:5555")
    # upload, start M03, a looping software procedure, Max speed: the longest status
    conn.sig_state.emit(ControllerStatus(t_ms=123456789, running="M03_WITH_A_LONG_NAME",
                                         proc=70, proc_name="plc_proc_spindle",
                                         software=["LUBE", "__HANDLER_INIT", "LOOP", "WATCHDOG",
                                                   "MORE"],
                                         speed={"mode": "max"}), 1234)
    _settle(qtbot)
    assert "max" in rp.proc.status.plain_text()
    assert "telemetry behind: 1234 samples dropped" in rp.proc.status.plain_text()
    assert (proc_dock.width(), w.width(), w.centralWidget().width()) == before
    assert proc_dock.minimumSizeHint().width() < proc_dock.width()
    # every fact shows, on more lines: nothing is elided into the tooltip
    assert not rp.proc.status.is_elided() and rp.proc.status.height() > \
        rp.proc.status.fontMetrics().height() * 2
    # then kill the controller: the reason is long too
    conn.connected = False
    conn.sig_disconnected.emit("the controller process ended (killed by SIGKILL) while "
                               "running M03_WITH_A_LONG_NAME at t = 123456.789 s " * 3)
    _settle(qtbot)
    assert (proc_dock.width(), w.width(), w.centralWidget().width()) == before
    assert proc_dock.minimumSizeHint().width() < 400


def test_the_recorded_run_banner_keeps_room_in_a_narrow_dock(runwin, qtbot):
    w, _conn = runwin
    rp = w.run_panels
    outputs = w.run_docks["outputs"]
    outputs.show()
    outputs.raise_()
    w.resizeDocks([outputs], [300], Qt.Orientation.Horizontal)     # as narrow as it goes
    _settle(qtbot)
    narrow = outputs.width()
    rp.show_recorded("pulse too long", [], [], 8)
    _settle(qtbot)
    link, banner = rp.banner_links[1], rp.banners[1]
    assert link.isVisible() and link.width() >= link.sizeHint().width()    # Back to Live
    assert banner.isVisible() and banner.width() > 30                      # not 0 px
    assert outputs.width() == narrow                                  # not widened
    rp.back_to_live()
    assert banner.isHidden() and link.isHidden()


def test_the_tests_list_keeps_the_docks_height(runwin, qtbot):
    """The Tests dock's list is not squeezed under its details: they sit beside it."""
    w, _conn = runwin
    w.tests_dock.show()
    w.tests_dock.raise_()
    _settle(qtbot)
    panel = w.tests_panel
    assert panel.tree.height() >= panel.height() - 60
    assert panel.detail.height() >= panel.height() - 60


def _right_widths(w) -> tuple:
    return tuple(w.run_docks[k].width() for k in ("outputs", "inputs"))


def test_the_right_docks_keep_their_width_when_the_panels_load_and_a_trace_is_compared(
        qtbot, tmp_path, prompts_off):
    """Issue 23 point 6: at first start the right-hand docks widened by ~54 px
    when the run panels loaded (the Watch's bar was wider than them), and by
    ~70 px when a comparison was shown (Back to Live, Clear Comparison and the
    banner beside the plot's buttons), and stayed so until Reset Layout."""
    from tests.ide.test_panels import sample
    from plcbuilder import api
    conn = RecordingConnection()
    with windows(qtbot, Settings(str(tmp_path / "cfg" / "s.ini")), None) as make:
        w = make(connection=conn, start_controller=True)      # the default size
        qtbot.waitUntil(lambda: w.run_panels is not None, timeout=10000)
        w.open_project(make_project(tmp_path / "proj"))
        _settle(qtbot)
        want = int(w.width() * 0.30)                          # docks.default_dock_sizes
        outputs, inputs = _right_widths(w)
        assert abs(outputs - want) <= 8 and abs(inputs - want) <= 8, (outputs, inputs, want)
        for key in ("watch", "cursors", "inputs", "proc", "analog", "axes", "outputs"):
            w.run_docks[key].show()
            w.run_docks[key].raise_()
            _settle(qtbot)
            assert abs(_right_widths(w)[0] - want) <= 8, key
        rp = w.run_panels
        conn.sig_samples.emit([sample(t, outputs=(t // 10) % 2 << 3) for t in range(0, 300)])
        rp.traces.save(tmp_path / "a.plctrace")
        other = api.load_trace(tmp_path / "a.plctrace")
        kind, ch = other.signals["out 3"]
        other.signals["out 3"] = (kind, [c for c in ch if c[0] < 140] + [(140, 1)])
        api.save_trace(other, tmp_path / "b.plctrace")
        before = _right_widths(w)
        rp.traces.compare_with(tmp_path / "b.plctrace")
        _settle(qtbot)
        assert rp.comparison is not None
        assert all(link.isVisible() for link in rp.compare_links[1:2])
        assert _right_widths(w) == before
        rp.back_to_live()
        _settle(qtbot)
        assert _right_widths(w) == before


def test_dock_tabs_show_their_whole_titles(qtbot, tmp_path, prompts_off):
    """Issue 23 point 15: with Disassembly and Registers open beside the plots,
    the right-hand tabs read "Ou…", "Ax…", "Disasse…": a tab says its whole
    title (the bar scrolls when they do not all fit)."""
    from PySide6.QtWidgets import QTabBar
    conn = RecordingConnection()
    with windows(qtbot, Settings(str(tmp_path / "cfg" / "s.ini")), None) as make:
        w = make(connection=conn, start_controller=True)
        qtbot.waitUntil(lambda: w.run_panels is not None, timeout=10000)
        w.open_project(make_project(tmp_path / "proj"))
        w.open_file(w.project.root / "hardware" / "M03.plc")
        w.disasm_dock.show()
        w.registers_dock.show()
        w.registers_dock.raise_()
        _settle(qtbot)
        bars = [b for b in w.findChildren(QTabBar) if b.isVisible() and b.count() > 1]
        assert bars
        titles = set()
        for bar in bars:
            for i in range(bar.count()):
                text = bar.tabText(i)
                titles.add(text)
                need = bar.fontMetrics().horizontalAdvance(text)
                assert bar.tabRect(i).width() >= need, (text, bar.tabRect(i).width(), need)
        assert {"Disassembly", "Registers", "Outputs", "Axes", "PWM / DAC / ADC"} <= titles


def test_the_proc_status_shows_every_fact_at_the_default_dock_width(runwin, qtbot):
    """The Proc & messages status was elided at the default dock width (the
    facts only in its tooltip): it wraps under the dock's tools, each fact whole."""
    w, conn = runwin
    rp = w.run_panels
    _in_front(w, "proc", qtbot)
    conn.connected = True
    conn.sig_connected.emit("127.0.0.1:5555")
    conn.sig_state.emit(ControllerStatus(t_ms=5000, running="M03", proc=70,
                                         proc_name="plc_proc_spindle", software=["LUBE"],
                                         speed={"mode": "realtime", "factor": 1.0},
                                         job={"file": "job.nc", "line": 3, "lines": 13,
                                              "state": "running"}), 0)
    _settle(qtbot)
    status = rp.proc.status
    facts = ["Running M03", "G-code job.nc line 3/13 running", "software: LUBE",
             "proc plc_proc_spindle (70)", "realtime"]
    assert status.plain_text() == " · ".join(facts)      # (as rich text shows it)
    assert status.isVisible() and not status.is_elided()
    assert status.toolTip() == ""
    # each fact on one line of the label as drawn (a line breaks between facts)
    fm = status.fontMetrics()
    room = status.contentsRect().width()
    assert all(fm.horizontalAdvance(f) <= room for f in facts)
    assert status.heightForWidth(status.width()) <= status.height()
    assert not rp.proc.status_beside          # (too long for the tools' row: under it)
    # a short status takes no row from the plot: it sits beside the tools
    rp.proc.set_status("Idle")
    _settle(qtbot)
    assert rp.proc.status_beside and rp.proc.status.parentWidget() is rp.proc.toolbar
    assert not status.is_elided()


def test_the_axes_panel_made_late_never_widens_its_dock(runwin, qtbot):
    """The run panels are made when their dock first shows: the Axes panel
    (two time plots and the XY path side by side) asked for 324 px, so the
    first look at it widened a right-hand dock the user had made narrower."""
    w, _conn = runwin
    rp = w.run_panels
    outputs, axes = w.run_docks["outputs"], w.run_docks["axes"]
    outputs.show()
    outputs.raise_()
    w.resizeDocks([outputs], [120], Qt.Orientation.Horizontal)     # as narrow as it goes
    _settle(qtbot)
    narrow = outputs.width()
    assert "axes" not in rp._made                                     # not made yet
    axes.show()
    axes.raise_()
    _settle(qtbot)
    assert "axes" in rp._made and axes.widget() is not None
    assert axes.width() == narrow                                     # not widened
    # too narrow for both plots side by side: the XY path folds away and the
    # time plots keep the width their axes and titles need (never cut)
    panel = rp.axes
    assert panel.xy_folded()
    assert panel.widget.width() >= panel.widget.ci.minimumWidth()
    w.resizeDocks([axes], [panel.side_by_side_width() + 40], Qt.Orientation.Horizontal)
    _settle(qtbot)
    assert not panel.xy_folded() and panel.xy_widget.width() > 60
