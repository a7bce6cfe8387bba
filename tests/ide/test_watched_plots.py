"""Watched variables in the run panels (SPEC §7: the history holds "watched
variables", and "A capture holds every signal over [trigger − pre, trigger +
post]"): a variable's bit as a lane in the Outputs plot, a number as a step
curve under PWM/DAC/ADC, live, in a capture, in a trace file, in the session
and in a comparison, and in the cursor table."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("PySide6")

from PySide6 import QtCore, QtGui, QtWidgets  # noqa: E402

from plcbuilder import api  # noqa: E402
from plcbuilder.api import events as ev  # noqa: E402
from plcbuilder.ide.docks import on_screen  # noqa: E402
from plcbuilder.ide.panels import RunPanels, style  # noqa: E402
from tests.ide.test_panels import FakeConnection, sample  # noqa: E402
from tests.ide.test_panels_idle import tabbed  # noqa: E402,F401 - fixture
from tests.ide._workbench import docked_run_panels  # noqa: E402
from tests.ide.test_traces_ide import WatchingConnection, arm  # noqa: E402

Qt = QtCore.Qt
SENS = ("vars", ("M80.sens", 0))


def _panels(qtbot, fake) -> RunPanels:
    win, p = docked_run_panels(qtbot, fake, (1600, 1000), capacity=2000)
    qtbot.waitExposed(win)
    p.window = win                    # (qtbot does not keep the window alive)
    return p


@pytest.fixture
def fake():
    return FakeConnection()


@pytest.fixture
def panels(qtbot, fake):
    p = _panels(qtbot, fake)
    yield p
    p.shutdown()


def _feed(fake, t0: int = 0, t1: int = 1000) -> None:
    """A sample every 10 ms; M80.sens 0, 1 at 300, 0 at 600, 1 at 800;
    M80.timer 50 counting down one each 20 ms."""
    fake.sig_samples.emit([sample(t, outputs=1 if t >= 500 else 0) for t in range(t0, t1, 10)])
    sens = {0: 0, 300: 1, 600: 0, 800: 1}
    fake.sig_events.emit([ev.Watched(t, "M80.sens", v) for t, v in sens.items() if t0 <= t < t1]
                         + [ev.Watched(t, "M80.timer", 50 - t // 20)
                            for t in range(t0, t1, 20)])


def _lane(lanes, key) -> tuple[np.ndarray, np.ndarray]:
    """The variables' merged path inside one lane: absolute x, level 0/1."""
    x, y = lanes.merged_data("vars")
    base = lanes._lane_y[key]
    mine = (y >= base - 0.01) & (y <= base + 1.01)
    return x[mine] + lanes.offset, np.round(y[mine] - base, 6)


def _rising_at(x: np.ndarray, y: np.ndarray) -> list[float]:
    """Where a lane's path goes from 0 to 1 (two points at one x)."""
    return [float(x[i]) for i in range(len(x) - 1)
            if x[i] == x[i + 1] and y[i] == 0 and y[i + 1] == 1]


def _legend_texts(legend) -> list[str]:
    return [label.text for _sample, label in legend.items]


def _rows(panels) -> dict:
    return {r[0]: r for r in panels.cursor_table.rows()}


# ------------------------------------------------------------------ live
def test_watched_events_draw_a_lane_and_a_step_curve(qtbot, panels, fake):
    """SPEC §7: the history includes "watched variables" — live, a 0/1 variable
    is a lane of its own in the Outputs plot, named PROC.var, in its own colour;
    any other is a step curve named in the legend of the Watched variables plot."""
    assert not panels.analog.var_plot.isVisible()          # nothing watched: no room taken
    _feed(fake)
    panels.tick()
    lanes = panels.lanes
    assert lanes.lanes() == [SENS, ("outputs", 0)]          # variables above the pins
    assert lanes.y_labels()[0] == "M80.sens"
    x, y = _lane(lanes, SENS)
    assert np.allclose(x[:-1], [0.0, 0.3, 0.3, 0.6, 0.6, 0.8, 0.8])
    assert y.tolist() == [0, 0, 1, 1, 0, 0, 1, 1]
    assert x[-1] >= 0.99                                    # held to the newest tick
    pen = lanes._items["vars"].opts["pen"].color().name()
    assert pen == style.plot_colours().variable
    assert pen not in (style.OUTPUT_COLOUR, style.INPUT_COLOUR)

    analog = panels.analog
    assert list(analog.var_curves) == ["M80.timer"] and analog.var_plot.isVisible()
    assert "M80.timer" in _legend_texts(analog.var_legend)
    cx, cy = analog.var_curves["M80.timer"].getOriginalDataset()
    times = np.arange(0, 1000, 20) / 1000
    assert np.allclose(cx[:len(times)] + analog.offset, times)
    assert cy[:len(times)].tolist() == [50 - t // 20 for t in range(0, 1000, 20)]
    assert cy[-1] == cy[len(times) - 1] and cx[-1] + analog.offset >= 0.99   # held
    assert analog.var_curves["M80.timer"].opts["stepMode"] == "right"

    # a new value alone (no new sample) redraws the lane
    frames = lanes.frames
    fake.sig_events.emit([ev.Watched(995, "M80.sens", 0)])
    panels.tick()
    assert lanes.frames == frames + 1
    x, y = _lane(lanes, SENS)
    assert y.tolist()[-3:] == [1, 0, 0] and x[-2] == pytest.approx(0.995)

    # a variable's lane has the lane menu's Remove (no force: it is not a pin)
    lanes.force_menu = lambda menu, lane: menu.addAction(f"Force {lane}")
    texts = [a.text() for a in lanes.build_menu(SENS).actions()]
    assert "Remove lane M80.sens" in texts and not any("Force" in t for t in texts)
    lanes.remove_lane(*SENS)
    assert SENS not in lanes.lanes()
    lanes.reset_lanes()
    assert SENS in lanes.lanes()

    # Clear forgets them, and the variables' plot gives its room back
    panels.clear()
    panels.tick()
    assert lanes.lanes() == [] and not analog.var_plot.isVisible()
    assert analog.var_plot.height() == 0


def test_the_cursor_table_lists_each_watched_variable(qtbot, panels, fake):
    """SPEC §7: 'two time cursors on the plots show Δt and every signal's value at each'."""
    _feed(fake)
    panels.dock("cursors").show()
    panels.cursor_table.toggle.setChecked(True)
    panels.cursors.set_times(0.35, 0.65)
    rows = _rows(panels)
    assert rows["M80.sens"][1:] == ("1", "0", "-1")
    assert rows["M80.timer"][1:] == ("33", "18", "-15")
    names = [r[0] for r in panels.cursor_table.rows()]
    assert names.index("M80.sens") < names.index("OUT 0  OUTPUT_SPINDLE")
    # before a variable's first value: nothing to show
    fake.sig_events.emit([ev.Watched(900, "LUBE.timer", 7)])
    panels.cursors.set_times(0.35, 0.95)
    assert _rows(panels)["LUBE.timer"][1:] == ("", "7", "")


def test_a_variable_trigger_draws_its_bit_live_and_in_the_capture(qtbot):
    """A trigger on a variable's bit (M80.var03 bit 2 rise): live, the bit has its
    lane ("M80.var03 bit 2") and the number its curve; the capture shown when
    the trigger came draws both, the lane rising at the trigger's red line."""
    fake = WatchingConnection()
    panels = _panels(qtbot, fake)
    try:
        bar = panels.traces.bar
        arm(qtbot, bar, "M80.var03 bit 2 rise", 50, 60)
        assert fake.watches == [["M80.var03"]]

        def var03(t0, t1):            # counts up one each 10 ms from t = 100
            fake.sig_samples.emit([sample(t) for t in range(t0, t1)])
            fake.sig_events.emit([ev.Watched(t, "M80.var03", (t - 100) // 10)
                                  for t in range(100, t1, 10) if t >= t0])

        var03(0, 135)                 # 0, 1, 2, 3: bit 2 not yet set
        panels.tick()
        key = ("vars", ("M80.var03", 2))
        lanes = panels.lanes
        assert panels.recorded is None and lanes.lanes()[0] == key
        assert lanes.y_labels()[0] == "M80.var03 bit 2"
        x, y = _lane(lanes, key)
        assert set(y.tolist()) == {0}
        assert list(panels.analog.var_curves) == ["M80.var03"]

        var03(135, 400)               # 4 at t = 140: bit 2 rises
        assert panels.recorded is not None and panels.failing_ms == 140
        panels.tick()
        assert lanes.lanes()[0] == key and lanes.y_labels()[0] == "M80.var03 bit 2"
        x, y = _lane(lanes, key)
        assert _rising_at(x, y) == [pytest.approx(0.14)]
        # from its first value (watching began at 100 ms; the capture at 90) to the post
        assert x[0] == pytest.approx(0.1) and x[-1] == pytest.approx(0.2)
        cx, cy = panels.analog.var_curves["M80.var03"].getOriginalDataset()
        assert cy.tolist()[:3] == [0, 1, 2] and 4 in cy.tolist()
        panels.dock("cursors").show()
        panels.cursor_table.toggle.setChecked(True)
        panels.cursors.set_times(0.135, 0.145)
        rows = _rows(panels)
        assert rows["M80.var03"][1:3] == ("3", "4")
        assert rows["M80.var03 bit 2"][1:] == ("0", "1", "+1")
        panels.back_to_live()
        assert panels.model.watched.bits == {"M80.var03": 2}     # the bar's trigger still
    finally:
        panels.shutdown()


# ------------------------------------------------------------- trace files
@pytest.fixture(scope="module")
def m80_traces(tmp_path_factory):
    """The example's M80 (homing Z) run headless with --watch and a trigger on
    M80.sens: the whole history and the capture, as .plctrace files."""
    from plcbuilder.project.new import create_project
    tmp = tmp_path_factory.mktemp("m80")
    project = create_project(tmp / "p")
    history, capture = tmp / "history.plctrace", tmp / "capture.plctrace"
    res = api.run(project.root, api.RunOptions(
        ms=3500, starts=["M80@0"], watch=["M80.sens", "M80.statez"], history=history,
        trigger="M80.sens bit 0 rise", pre_ms=200, post_ms=300, capture=capture))
    assert res.report["capture"]["t_ms"] > 0
    return history, capture


def test_an_opened_trace_draws_its_variables_and_the_cursors_read_them(qtbot, panels,
                                                                         m80_traces):
    """File › Open Trace… of a `run --watch` history: its PROC.var signals are
    drawn (M80.sens a lane, M80.statez 0/1/2 a curve), and the cursor table
    gives their values at A and B."""
    history, _capture = m80_traces
    trace = api.load_trace(history)
    panels.traces.open(history)
    panels.tick()
    lanes = panels.lanes
    assert lanes.lanes()[0] == SENS and "M80.statez" not in str(lanes.lanes())
    x, y = _lane(lanes, SENS)
    _kind, ch = trace.signals["M80.sens"]
    rises = [t / 1000 for (t, v), (_t0, v0) in zip(ch[1:], ch) if v == 1 and v0 == 0]
    assert rises and _rising_at(x, y) == pytest.approx(rises)
    statez = panels.analog.var_curves["M80.statez"]
    cx, cy = statez.getOriginalDataset()
    _kind, ch = trace.signals["M80.statez"]
    assert cy.tolist()[:len(ch)] == [v for _t, v in ch] == [0, 1, 2]
    assert np.allclose(cx[:len(ch)] + panels.analog.offset, [t / 1000 for t, _v in ch])

    panels.dock("cursors").show()
    panels.cursor_table.toggle.setChecked(True)
    a, b = ch[1][0] - 5, ch[2][0] + 5            # around M80 backing off the switch
    panels.cursors.set_times(a / 1000, b / 1000)
    rows = _rows(panels)
    for name in ("M80.sens", "M80.statez"):
        assert rows[name][1:3] == (str(trace.value_at(name, a)), str(trace.value_at(name, b)))
    assert rows["M80.statez"][1:] == ("0", "2", "+2")


def test_an_opened_capture_draws_the_trigger_variable_rising_at_the_trigger(qtbot, panels,
                                                                            m80_traces):
    _history, capture = m80_traces
    trace = api.load_trace(capture)
    t = trace.meta["trigger"]["t_ms"]
    panels.traces.open(capture)
    panels.tick()
    assert panels.failing_ms == t and panels.lanes.y_labels()[0] == "M80.sens"
    x, y = _lane(panels.lanes, SENS)
    assert _rising_at(x, y) == [pytest.approx(t / 1000)]


def test_a_compared_trace_draws_its_variables_dashed(qtbot, panels, m80_traces, tmp_path):
    """Compare with Trace…: the other trace's variables over the first's, dashed,
    and in the cursor table's two more columns."""
    history, _capture = m80_traces
    other = api.load_trace(history)
    kind, ch = other.signals["M80.statez"]
    other.signals["M80.statez"] = (kind, [(t + 100, v) for t, v in ch])
    path = tmp_path / "later.plctrace"
    api.save_trace(other, path)
    panels.traces.open(history)
    diff = panels.traces.compare_with(path)
    assert diff.t_ms is not None
    panels.tick()
    lanes, analog = panels.lanes, panels.analog
    ox, _oy = lanes.other_data("vars")
    assert ox.size > 0
    dashed = analog.other_var_curves["M80.statez"]
    assert dashed.opts["pen"].style() == Qt.PenStyle.DashLine
    dx, dy = dashed.getOriginalDataset()
    assert np.allclose(dx[:len(ch)] + analog.offset, [(t + 100) / 1000 for t, _v in ch])
    assert f"dashed: {path.name}" in _legend_texts(analog.var_legend)
    panels.dock("cursors").show()
    panels.cursor_table.toggle.setChecked(True)
    t1 = ch[1][0]
    panels.cursors.set_times((t1 + 10) / 1000, (t1 + 150) / 1000)
    assert _rows(panels)["M80.statez"][1:] == ("1", "1", "", "0", "1")
    panels.clear_comparison()
    panels.tick()
    assert analog.other_var_curves == {} and lanes.other_items == {}


def test_the_session_view_draws_the_watched_variables(qtbot, panels, fake):
    _feed(fake)
    fake.sig_events.emit([ev.Watched(999, "M80.zero", 0)])     # 0 all along: kept too
    qtbot.mouseClick(panels.traces.bar.session, Qt.MouseButton.LeftButton)
    assert panels.recorded is not None and "whole session" in panels.recorded
    panels.tick()
    assert ("vars", ("M80.zero", 0)) in panels.lanes.lanes()
    x, y = _lane(panels.lanes, SENS)
    assert _rising_at(x, y) == [pytest.approx(0.3), pytest.approx(0.8)]
    assert list(panels.analog.var_curves) == ["M80.timer"]


# ------------------------------------------------------------ performance
def test_watched_values_leave_tabbed_away_docks_and_time_only_moves_alone(qtbot, tabbed,
                                                                          monkeypatch):
    """The panels' performance work holds with variables: the PWM/DAC/ADC dock
    behind a tab does not redraw for them (it catches up when shown), and a
    time-only move sets no curve's data, the variables' included."""
    import pyqtgraph as pg
    p, fake = tabbed
    p.timebase.set_window(1.0)
    analog, lanes = p.analog, p.lanes
    assert on_screen(lanes) and not on_screen(analog)
    frames = analog.frames
    _feed(fake, 0, 2000)
    p.tick()
    assert analog.frames == frames and lanes.frames >= 1
    assert _lane(lanes, SENS)[0].size > 0
    p.dock("analog").raise_()
    qtbot.waitUntil(lambda: on_screen(analog))
    p.tick()
    assert analog.frames == frames + 1 and "M80.timer" in analog.var_curves

    p._on_state(api.ControllerStatus(t_ms=0, running=None, software=("LUBE",), proc=0))
    curve_data = []
    orig = pg.PlotCurveItem.setData
    monkeypatch.setattr(pg.PlotCurveItem, "setData",
                        lambda self, *a, **k: (curve_data.append(self), orig(self, *a, **k)))
    frames, moves = analog.frames, analog.moves
    fake.sig_samples.emit([sample(t, outputs=1) for t in range(2000, 2100, 10)])
    analog._last_move = 0.0
    p.tick()
    assert analog.frames == frames and analog.moves == moves + 1
    assert curve_data == []


# ----------------------------------------------------------------- themes
def _contrast(a: str, b: str) -> float:
    def lum(c: str) -> float:
        q = QtGui.QColor(c)
        ch = [v / 255 for v in (q.red(), q.green(), q.blue())]
        ch = [v / 12.92 if v <= 0.03928 else ((v + 0.055) / 1.055) ** 2.4 for v in ch]
        return 0.2126 * ch[0] + 0.7152 * ch[1] + 0.0722 * ch[2]
    hi, lo = sorted((lum(a), lum(b)), reverse=True)
    return (hi + 0.05) / (lo + 0.05)


def _hue_apart(a: str, b: str) -> int:
    d = abs(QtGui.QColor(a).hue() - QtGui.QColor(b).hue())
    return min(d, 360 - d)


def test_the_variables_read_in_the_light_and_the_dark_theme(qtbot, panels, fake):
    from plcbuilder.ide.app import apply_theme
    app = QtWidgets.QApplication.instance()
    _feed(fake)
    panels.tick()
    try:
        for theme, colours in (("dark", style.DARK_PLOTS), ("light", style.LIGHT_PLOTS)):
            apply_theme(app, theme)
            qtbot.waitUntil(lambda c=colours: panels.lanes._items["vars"].opts["pen"].color()
                            .name() == c.variable)
            assert _contrast(colours.variable, colours.background) >= 4.5
            for band in colours.lane_bands:
                assert _contrast(colours.variable, band) >= 4.5
            # a hue of its own: not the pins', nor the compared trace's
            for other in (style.OUTPUT_COLOUR, style.INPUT_COLOUR, colours.overlay):
                assert _hue_apart(colours.variable, other) >= 40
            plot = panels.analog.var_plot
            assert plot.getAxis("left").textPen().color().name() == colours.text
            assert plot.titleLabel.opts["color"] == colours.text
    finally:
        apply_theme(app, "light")


# ---------------------------------------------------------- a live controller
def test_a_capture_on_m80_sens_shows_it_rising_at_the_trigger(qtbot, live_uploaded):
    """With the IDE's embedded controller: arm `M80.sens bit 0 rise`, start M80
    (homing Z): live, M80.sens has its lane while the controller records it;
    the capture shows it rising at the red trigger line, and the cursors read
    it 0 before and 1 after."""
    win, panels = live_uploaded
    conn = win.connection
    bar = panels.traces.bar
    arm(qtbot, bar, "M80.sens bit 0 rise", 200, 300)
    assert bar.arm.isChecked(), bar.state.text()
    conn.start("M80", 0)
    # live: the controller sends M80.sens (0 until Z reaches its home switch)
    qtbot.waitUntil(lambda: panels.recorded is not None
                    or SENS in panels.lanes.lanes(), timeout=30000)
    assert panels.recorded is None
    qtbot.waitUntil(lambda: panels.recorded is not None, timeout=60000)
    t = panels.failing_ms
    assert t is not None and panels.traces.shown.meta["trigger"]["spec"] == \
        "M80.sens bit 0 rise"
    panels.dock("outputs").raise_()
    qtbot.waitUntil(lambda: on_screen(panels.lanes))
    panels.tick()
    lanes = panels.lanes
    assert lanes.lanes()[0] == SENS and lanes.y_labels()[0] == "M80.sens"
    x, y = _lane(lanes, SENS)
    assert _rising_at(x, y) == [pytest.approx(t / 1000)]
    assert ("inputs", 2) in lanes.lanes()          # INPUT_HOME_Z, which it reads
    panels.dock("cursors").show()
    panels.cursor_table.toggle.setChecked(True)
    panels.cursors.set_times((t - 50) / 1000, (t + 10) / 1000)
    assert _rows(panels)["M80.sens"][1:] == ("0", "1", "+1")
