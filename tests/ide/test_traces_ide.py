"""Traces in the IDE: the session history, the trigger bar, cursors, and
File › Open/Save/Export Trace, Export Plot Image and Compare with Trace."""

from __future__ import annotations

from pathlib import Path

import pytest

pytest.importorskip("PySide6")

from PySide6 import QtCore, QtWidgets  # noqa: E402
from tests.vcd_reader import VCDVCD  # noqa: E402

from plcbuilder import api  # noqa: E402
from plcbuilder.ide.panels import RunPanels  # noqa: E402
from tests.ide._workbench import docked_run_panels  # noqa: E402
from tests.ide.test_panels import FakeConnection, sample  # noqa: E402

Qt = QtCore.Qt


@pytest.fixture
def fake():
    return FakeConnection()


@pytest.fixture
def panels(qtbot, fake):
    _win, p = docked_run_panels(qtbot, fake, (1400, 900), capacity=500)
    yield p
    p.shutdown()


def arm(qtbot, bar, spec: str, pre=None, post=None) -> None:
    """Type a trigger spec (and pre/post ms) in the trigger bar and press Arm."""
    bar.spec.setText(spec)
    if pre is not None:
        bar.pre.setValue(pre)
    if post is not None:
        bar.post.setValue(post)
    qtbot.mouseClick(bar.arm, Qt.MouseButton.LeftButton)


def _toggle(fake, t0: int, t1: int, pin: int = 3, period: int = 10) -> None:
    """Output ``pin`` on for ``period`` ms, off for ``period`` ms, from t0 to t1."""
    batch = []
    for t in range(t0, t1, period):
        on = (t // period) % 2
        batch.append(sample(t, outputs=(1 << pin) if on else 0, proc=33 if on else 0,
                            pwm=(t,)))
    fake.sig_samples.emit(batch)


def test_the_session_keeps_every_change_beyond_the_panels_window(panels, fake):
    """SPEC §7: 'A session keeps the whole history of what changed …, not a fixed window'."""
    _toggle(fake, 0, 20_000)                      # 2,000 changes, more than the 500 kept
    assert len(panels.model) <= 500
    ch = panels.traces.session.signals["out 3"].changes()
    assert len(ch) == 2000 and ch[0] == (0, 0) and ch[1] == (10, 1)
    tr = panels.traces.session_trace()
    assert "out 3" in tr.signals and "out 4" not in tr.signals     # never changed: left out


def test_the_trigger_bar_captures_and_shows_the_capture(qtbot, panels, fake):
    """SPEC §7: 'Trigger … with a pre-trigger and a post-trigger duration' — in the
    IDE: a trigger bar on the run panels, the capture shown when it completes."""
    _toggle(fake, 900, 1005)                       # before arming: rises that do not count
    bar = panels.traces.bar
    arm(qtbot, bar, "out 3 rise", 15, 25)
    assert bar.arm.isChecked() and "armed" in bar.state.text()
    assert panels.recorded is None
    _toggle(fake, 1010, 1100)                      # rises at 1010; complete by 1035
    assert panels.recorded is not None and "capture at 1.010 s" in panels.recorded
    cap = panels.traces.shown
    assert (cap.t_start, cap.t_end) == (995, 1035)
    assert panels.failing_ms == 1010               # the line at the trigger
    assert not bar.arm.isChecked()                 # single: done
    assert "captured at t = 1.010 s" in bar.state.text()


def test_a_bad_trigger_spec_says_why_and_stays_disarmed(qtbot, panels):
    bar = panels.traces.bar
    arm(qtbot, bar, "out 3 wobble")
    assert not bar.arm.isChecked()
    assert "unknown condition" in bar.state.text()


def test_cursors_show_values_and_delta(qtbot, panels, fake):
    """SPEC §7: 'two time cursors on the plots show Δt and every signal's value at each'."""
    _toggle(fake, 0, 200)
    panels.dock("cursors").show()
    panels.cursor_table.toggle.setChecked(True)
    assert panels.cursors.enabled
    lines = [ln for _p, _plot, _w, ln in panels.cursors._lines]
    assert len(lines) == 2 * sum(len(p._time_plots) for p in panels.time_panels)
    panels.cursors.set_times(0.015, 0.025)          # out 3 on at 10..19, off at 20..29
    rows = {r[0]: r for r in panels.cursor_table.rows()}
    assert rows["t"][3] == "10 ms"
    out3 = next(k for k in rows if k.startswith("OUT 3"))
    assert rows[out3][1:3] == ("1", "0")
    assert rows["PWM0"][1:] == ("10", "20", "+10")
    assert "plc_proc_probing" in rows["proc"][1]
    # dragging a line on one plot moves that cursor on every plot
    p, _plot, which, line = panels.cursors._lines[0]
    line.setValue(0.05 - p.offset)
    assert panels.cursors.a == pytest.approx(0.05)
    panels.cursor_table.toggle.setChecked(False)
    assert panels.cursors._lines == []


def test_save_open_export_and_compare(qtbot, panels, fake, tmp_path):
    """SPEC §7: saved traces reopen in the same panels; export to CSV and VCD; compare."""
    _toggle(fake, 0, 300)
    tools = panels.traces
    saved = tmp_path / "session.plctrace"
    tools.save(saved)
    tools.export(tmp_path / "session.vcd")
    v = VCDVCD(str(tmp_path / "session.vcd"))
    assert [(t, x) for t, x in v["outputs.out3"].tv][:3] == [(0, "0"), (10, "1"), (20, "0")]
    tools.export(tmp_path / "ticks.csv", per_tick=True)
    assert (tmp_path / "ticks.csv").read_text().count("\n") == 1 + 291
    tools.export_image(tmp_path / "plot.png", panels.lanes)
    tools.export_image(tmp_path / "plot.svg", panels.lanes)
    assert (tmp_path / "plot.png").stat().st_size > 1000
    assert (tmp_path / "plot.svg").read_text().lstrip().startswith("<?xml")
    with pytest.raises(api.ExportError):
        tools.export_image(tmp_path / "plot.bmp", panels.lanes)

    tools.open(saved)
    assert panels.recorded == "trace session.plctrace"
    assert panels.model.t_end == pytest.approx(0.29)
    assert panels.model.pin_state("outputs", 3) == 1          # on from 290 ms

    # a second run that differs from 140 ms on (out 3 stays on)
    other = api.load_trace(saved)
    kind, ch = other.signals["out 3"]
    other.signals["out 3"] = (kind, [c for c in ch if c[0] < 140] + [(140, 1)])
    api.save_trace(other, tmp_path / "other.plctrace")
    diff = tools.compare_with(tmp_path / "other.plctrace")
    assert diff.t_ms == 140 and ("out 3", "0", "1") in diff.signals
    assert panels.failing_ms == 140


def test_comparing_with_a_trace_of_other_ticks_says_so(qtbot, panels, fake, tmp_path):
    """Two traces with no tick in common: the note and the panels' banner said
    'no difference'."""
    _toggle(fake, 0, 300)
    late = panels.traces.session.snapshot(200, 290)
    api.save_trace(late, tmp_path / "late.plctrace")
    panels.traces.open(tmp_path / "late.plctrace")
    early = api.Trace(0, 100, {}, {}, [], {})
    api.save_trace(early, tmp_path / "early.plctrace")
    with qtbot.waitSignal(panels.traces.sig_note) as note:
        diff = panels.traces.compare_with(tmp_path / "early.plctrace")
    assert not diff.overlap and not diff.same
    assert "no tick in common" in note.args[0] and "no difference" not in note.args[0]
    banner = panels.banners[0].toolTip()               # "comparing … (dashed): …"
    assert banner.startswith("comparing") and "no tick in common" in banner


def test_a_bad_trace_file_is_refused_and_the_panels_stay(panels, fake, tmp_path):
    _toggle(fake, 0, 100)
    bad = tmp_path / "bad.plctrace"
    bad.write_text("not a trace")
    with pytest.raises(api.TraceFileError, match="not a trace file"):
        panels.traces.open(bad)
    assert panels.recorded is None and len(panels.model) > 0


def test_file_menu_has_the_trace_actions(qtbot, tmp_path, monkeypatch):
    from plcbuilder.ide.actions import Act
    from plcbuilder.ide.main_window import MainWindow
    from plcbuilder.ide.settings import Settings
    win = MainWindow(Settings(str(tmp_path / "s.ini")), start_controller=False)
    qtbot.addWidget(win)
    names = [a.objectName() for a in win.menuBar().actions()[0].menu().actions()]
    for act in (Act.OPEN_TRACE, Act.SAVE_TRACE, Act.EXPORT_TRACE, Act.EXPORT_PLOT,
                Act.COMPARE_TRACE):
        assert act in names
    win.close()


def test_record_and_replay_a_session_in_the_ide(qtbot, tmp_path, live_uploaded):
    """SPEC §7: 'a session records everything done to the controller from outside
    … Replaying it with the same image and machine gives the identical trace' —
    Run › Save Session Recording and Run › Replay Session with the embedded
    controller: the replay's trace equals the session's, tick for tick."""
    from plcbuilder.ide import trace_actions
    win, panels = live_uploaded
    conn = win.connection
    conn.start("M03", 12000)
    qtbot.wait(400)
    conn.set_input(4, 1)
    conn.force("out 9", 1)
    qtbot.wait(300)
    conn.start("M05", 0)
    qtbot.wait(500)
    rec = tmp_path / "session.txt"
    with qtbot.waitSignal(win.sig_recording_saved, timeout=30000):
        assert trace_actions.save_recording(win, str(rec))
    text = rec.read_text()
    assert "start M03:12000 @" in text and "force out 9=1 @" in text and "upload " in text
    live = panels.traces.session_trace()
    with qtbot.waitSignal(win.sig_replayed, timeout=120000) as sig:
        assert trace_actions.replay_session(win, str(rec))
    replay = sig.args[0]
    assert panels.recorded == "replay of session.txt"
    diff = api.compare_traces(live, replay)
    # the live history holds every change the controller sent up to the moment the
    # recording was taken, the replay runs to the recorded end: over the time both
    # cover they are the same, tick for tick
    assert diff.same, diff.text()
    assert replay.t_end >= live.t_end - 50


def test_the_whole_session_shows_from_the_start(qtbot, panels, fake):
    """Issue 11: the panels can scroll back to t = 0 — the Session button shows
    every change since the controller started, not only the live window."""
    _toggle(fake, 0, 60_000)                       # 6,000 changes; the live view keeps 500
    assert panels.model.time.view()[0] > 1.0
    qtbot.mouseClick(panels.traces.bar.session, Qt.MouseButton.LeftButton)
    assert panels.recorded is not None and "whole session" in panels.recorded
    t = panels.model.time.view()
    assert t[0] == 0.0 and t[-1] == pytest.approx(59.99)
    t0, t1 = panels.lanes.visible_span()
    assert t0 == pytest.approx(0.0, abs=1e-6) and t1 == pytest.approx(59.99, abs=0.02)
    panels.back_to_live()
    assert panels.recorded is None


class WatchingConnection(FakeConnection):
    """A connection whose controller records watched variables (the ``watch`` request)."""
    sig_refused = QtCore.Signal(str, str)
    sig_result = QtCore.Signal(str, dict)

    def __init__(self):
        super().__init__()
        self.connected = True
        self.watches: list[list[str]] = []

    def watch_variables(self, names):
        self.watches.append(list(names))


def _timer(fake, t0: int, t1: int, start: int = 60, name: str = "M80.timer"):
    """``name`` counts down from ``start`` one a tick over [t0, t1), as the controller
    sends a watched variable (one event a change), with a sample each tick."""
    fake.sig_samples.emit([sample(t) for t in range(t0, t1)])
    fake.sig_events.emit([api.events.Watched(t, name, start - (t - t0)) for t in range(t0, t1)])


def test_a_trigger_on_a_variable_has_the_controller_record_it(qtbot):
    """SPEC §7: a trigger on 'a variable's bit' and 'a numeric signal crossing a
    level' — in the IDE too: arming asks the controller to record the variable
    each tick (``watch``), the capture comes from what it sends, and the watch
    stops when the trigger is done."""
    fake = WatchingConnection()
    win = QtWidgets.QMainWindow()
    qtbot.addWidget(win)
    panels = RunPanels(win, fake, capacity=500)
    try:
        _toggle(fake, 0, 100)
        bar = panels.traces.bar
        arm(qtbot, bar, "M80.timer bit 1 rise", 10, 20)
        assert bar.arm.isChecked() and "armed" in bar.state.text()
        assert fake.watches == [["M80.timer"]]
        _timer(fake, 100, 200)                # 60, 59, 58, …
        values = {t: 60 - (t - 100) for t in range(100, 200)}
        rise = next(t for t in range(101, 200)
                    if (values[t] >> 1) & 1 and not (values[t - 1] >> 1) & 1)
        assert panels.recorded is not None and panels.failing_ms == rise
        cap = panels.traces.shown
        assert cap.value_at("M80.timer", rise) == values[rise]
        assert (cap.t_start, cap.t_end) == (rise - 10, rise + 20)
        assert not bar.arm.isChecked() and fake.watches[-1] == []    # single: done, watch off
        panels.back_to_live()

        # a level crossed, in Normal mode: each crossing down through 15 captures
        bar.spec.setText("M80.timer down 15")
        bar.mode.setCurrentIndex(bar.mode.findData("normal"))
        qtbot.mouseClick(bar.arm, Qt.MouseButton.LeftButton)
        assert fake.watches[-1] == ["M80.timer"]
        _timer(fake, 200, 300, start=40)      # 15 -> 14 at t = 226
        assert panels.failing_ms == 226 and bar.arm.isChecked()
        qtbot.mouseClick(bar.arm, Qt.MouseButton.LeftButton)       # disarm: watch off
        assert fake.watches[-1] == [] and "not armed" in bar.state.text()

        # the controller refuses a variable it does not have: the bar says why
        arm(qtbot, bar, "M80.nope bit 0 rise")
        fake.sig_refused.emit("watch", "M80.nope: M80 has no variable named nope")
        assert not bar.arm.isChecked() and "no variable named nope" in bar.state.text()
        assert panels.traces.capturer is None
    finally:
        panels.shutdown()


def test_a_variable_trigger_needs_a_controller_that_records_variables(qtbot, panels, fake):
    bar = panels.traces.bar
    arm(qtbot, bar, "M80.timer up 3")
    assert not bar.arm.isChecked() and "not connected" in bar.state.text()


def test_a_variable_trigger_against_the_embedded_controller(qtbot, live_uploaded):
    """SPEC §7: 'rising, falling or either edge of … a variable's bit' — with the
    IDE's embedded controller (a child process): the trigger bar arms on LUBE's
    timer, the controller records it, and the capture shows when it completes."""
    _win, panels = live_uploaded
    bar = panels.traces.bar
    arm(qtbot, bar, "LUBE.timer bit 2 rise", 300, 200)       # LUBE counts its timer down each 100 ms
    assert bar.arm.isChecked(), bar.state.text()
    qtbot.waitUntil(lambda: panels.recorded is not None, timeout=30000)
    cap = panels.traces.shown
    t = cap.meta["trigger"]["t_ms"]
    assert panels.failing_ms == t and cap.meta["trigger"]["spec"] == "LUBE.timer bit 2 rise"
    assert (cap.value_at("LUBE.timer", t) >> 2) & 1 == 1
    assert (cap.value_at("LUBE.timer", t - 1) >> 2) & 1 == 0
    # post in full; pre as far back as the session goes
    assert cap.t_end == t + 200 and cap.t_start == max(t - 300, panels.traces.session.t_start)
    assert not bar.arm.isChecked() and panels.traces.watching == []


@pytest.mark.parametrize("width, rows", [(460, 2), (1400, 1)])
def test_the_trigger_bar_flows_onto_two_rows_rather_than_squeeze_its_boxes(qtbot, width,
                                                                           rows):
    """In a narrow dock the spec, pre/post boxes and mode were squeezed to a few
    letters each ('pre 10', 'Singl'); the bar now takes a second row instead, and
    every box keeps the width its text needs."""
    from plcbuilder.ide.panels.traces import TriggerBar

    bar = TriggerBar()
    qtbot.addWidget(bar)
    bar.resize(width, 60)
    bar.show()
    qtbot.waitUntil(lambda: bar.two_rows is (rows == 2))
    QtWidgets.QApplication.processEvents()
    for box in (bar.pre, bar.post, bar.mode):
        assert box.width() >= box.minimumSizeHint().width(), box
        assert box.geometry().right() <= bar.width()
    assert bar.spec.width() >= (150 if rows == 2 else bar.SPEC_ROOM - 10)
    below = bar.pre.geometry().top() > bar.spec.geometry().bottom()
    assert below is (rows == 2)
    assert bar.sizeHint().height() > bar.spec.sizeHint().height() * (rows - 0.5)


# ---------------------------------------------- the log and the bar follow what is shown

def _log_texts(panels) -> list[str]:
    panels.log.flush()
    return [r[3] for r in panels.log.rows.rows()]


def _print(t, value):
    from plcbuilder.controller import events as ev
    return ev.Print(t_ms=t, source="M03", register=20000, value=value)


def test_a_capture_on_show_does_not_double_the_run_log(qtbot, panels, fake):
    """Issue 23 point 10: with a capture shown, the Run log had its events
    again below the live rows (the same prints twice). The log shows what the
    panels show: the capture's rows while it is shown, the live rows (with
    those that came meanwhile) after Back to Live."""
    _toggle(fake, 900, 1005)
    bar = panels.traces.bar
    arm(qtbot, bar, "out 3 rise", 15, 25)
    fake.sig_events.emit([_print(1008, 7)])
    _toggle(fake, 1010, 1100)                          # captured: 995..1035
    assert panels.recorded is not None
    texts = _log_texts(panels)
    assert sum("register 20000 = 7" in t for t in texts) == 1, texts
    fake.sig_events.emit([_print(1200, 8)])             # live, while the capture is shown
    assert not any("= 8" in t for t in _log_texts(panels))
    panels.back_to_live()
    texts = _log_texts(panels)
    assert sum("register 20000 = 7" in t for t in texts) == 1, texts
    assert sum("register 20000 = 8" in t for t in texts) == 1, texts
    # issue 23 point 8: the bar no longer says what was captured
    assert "captured at" not in bar.state.text() and "not armed" in bar.state.text()


def test_open_trace_shows_the_files_rows_not_below_the_live_ones(qtbot, panels, fake, tmp_path):
    """Issue 23 point 10: Open Trace appended the file's old events below the
    live rows; point 8: the trigger bar kept "captured at t = …"."""
    _toggle(fake, 0, 300)
    fake.sig_events.emit([_print(299, 1)])
    saved = tmp_path / "old.plctrace"
    panels.traces.save(saved)
    arm(qtbot, panels.traces.bar, "out 3 rise", 15, 25)
    _toggle(fake, 300, 400)                             # a capture: "captured at t = 0.310 s"
    assert "captured at" in panels.traces.bar.state.text()
    panels.back_to_live()
    fake.sig_events.emit([_print(500, 2)])
    panels.traces.open(saved)
    texts = _log_texts(panels)
    assert sum("register 20000 = 1" in t for t in texts) == 1, texts     # the file's
    assert not any("register 20000 = 2" in t for t in texts), texts      # not the live one
    assert "captured at" not in panels.traces.bar.state.text()
    panels.back_to_live()
    texts = _log_texts(panels)
    assert [t for t in texts if "register 20000" in t] == ["register 20000 = 1",
                                                           "register 20000 = 2"]


@pytest.mark.parametrize("width", [410, 300, 1400])
def test_the_trigger_bars_state_is_never_cut_off(qtbot, width):
    """Issue 23 point 15: in the right-hand dock the state read "armed: waitin"
    (cut off at the dock's edge): it ends in "…" where it does not fit, and says
    it whole in its tooltip."""
    from plcbuilder.ide.panels.traces import TriggerBar

    bar = TriggerBar()
    qtbot.addWidget(bar)
    bar.resize(width, 60)
    bar.show()
    text = "armed: waiting for M80.statez bit 0 rise (single; the controller records M80.statez)"
    bar.set_state(text, armed=True)
    QtWidgets.QApplication.processEvents()
    st = bar.state
    assert st.geometry().right() <= bar.width()
    assert st.plain_text() == text
    if st.is_elided():
        assert st.toolTip() == text
    else:
        assert st.fontMetrics().horizontalAdvance(text) <= st.contentsRect().width()
    bar.set_state("unknown condition 'x'", error=True)
    assert st.plain_text() == "unknown condition 'x'"


def test_trace_file_dialogs_propose_a_name_and_remember_the_folder(qtbot, tmp_path,
                                                                 monkeypatch):
    """Issue 23, what users expect: Save Trace and Export Trace proposed no name
    and always started in the project's folder."""
    from tests.ide._workbench import RecordingConnection, answer_no, make_project
    from plcbuilder.ide import trace_actions as ta
    from plcbuilder.ide.main_window import MainWindow
    from plcbuilder.ide.settings import Settings
    answer_no(monkeypatch)
    conn = RecordingConnection()
    win = MainWindow(Settings(str(tmp_path / "s.ini")), connection=conn, start_controller=True)
    qtbot.addWidget(win)
    win.show()
    qtbot.waitUntil(lambda: win.run_panels is not None, timeout=10000)
    root = make_project(tmp_path / "table")
    win.open_project(root)
    rp = win.run_panels
    conn.sig_samples.emit([sample(t, outputs=((t // 10) % 2) << 3) for t in range(0, 300)])
    asked = []
    saves = tmp_path / "my traces"
    saves.mkdir()

    def save_dialog(_parent, _title, start, filters, *a, **k):
        asked.append(start)
        name = Path(start).name
        return str(saves / name), filters.split(";;")[0]
    monkeypatch.setattr(QtWidgets.QFileDialog, "getSaveFileName", save_dialog)
    assert ta.save_trace(win)
    first = Path(asked[-1])
    assert first.parent == root and first.suffix == ".plctrace"
    assert first.stem.startswith("table-session-"), first
    assert (saves / first.name).is_file()
    # a capture on show: its name says so; and the folder is the one saved in last
    arm(qtbot, rp.traces.bar, "out 3 rise", 15, 25)
    conn.sig_samples.emit([sample(t, outputs=((t // 10) % 2) << 3) for t in range(300, 400)])
    assert rp.recorded is not None
    assert ta.export_trace(win)
    second = Path(asked[-1])
    assert second.parent == saves and second.suffix == ".vcd"
    assert "capture-0.310s" in second.stem, second
    assert ta.export_plot(win)
    assert Path(asked[-1]).parent == saves and Path(asked[-1]).suffix == ".png"
    win.shutdown()
