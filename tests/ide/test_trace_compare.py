"""File › Compare with Trace… draws the second trace over the first (issue 11:
'compare two traces (first differing tick and signal, and the two overlaid)'):
dashed lanes, analog curves and proc in the run panels, a key saying which is
which, a line at the first difference, the cursors reading both; File › Clear
Comparison (or Back to Live) removes it."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from PySide6.QtCore import Qt

from plcbuilder import api
from plcbuilder.ide import trace_actions
from plcbuilder.ide.actions import Act
from plcbuilder.ide.panels import style
from tests.ide.test_docks_fit import prompts_off, runwin  # noqa: F401 - fixtures

T_END = 300
DIFF = 140


def _trace(other: bool) -> api.Trace:
    """out 3 toggles every 10 ms and pwm 0 steps with it; in the other trace,
    from 140 ms out 3 stays on, pwm 0 reads 7 and out 5 comes on."""
    out3, pwm0, proc = [], [], []
    for t in range(0, T_END, 10):
        on = (t // 10) % 2
        if other and t >= DIFF:
            out3.append((t, 1))
            pwm0.append((t, 7))
            proc.append((t, 33))
            continue
        out3.append((t, on))
        pwm0.append((t, 100 * on))
        proc.append((t, 33 if on else 0))
    signals = {"out 3": ("bit", out3), "out 5": ("bit", [(0, 0)] + ([(DIFF, 1)] if other else [])),
               "pwm 0": ("int", pwm0), "proc": ("int", proc), "message": ("int", [(0, 0)]),
               "running": ("text", [(0, 1)])}
    return api.Trace(0, T_END - 1, signals, ["", "M03"], [], {})


@pytest.fixture
def files(tmp_path):
    a, b = tmp_path / "before.plctrace", tmp_path / "after.plctrace"
    api.save_trace(_trace(False), a)
    api.save_trace(_trace(True), b)
    return a, b


def _drawn(qtbot, w):
    panels = w.run_panels
    # the three share a tab group: each draws when its tab is the one shown
    drawn = {"outputs": lambda: panels.lanes.other_data("outputs")[0].size > 0,
             "analog": lambda: bool(panels.analog.other_curves),
             "proc": lambda: panels.proc.other_curve is not None
             and panels.proc.other_curve.getData()[0] is not None}
    for key, done in drawn.items():
        panels.dock(key).show()
        panels.dock(key).raise_()
        qtbot.waitUntil(done, timeout=10000)
    return panels


def _key_texts(legend) -> list[str]:
    return [label.text for _sample, label in legend.items]


def test_compare_draws_the_other_trace_over_the_first_and_clears(runwin, qtbot, files):
    w, _conn = runwin
    a, b = files
    assert trace_actions.open_trace(w, str(a))
    assert not w.action(Act.CLEAR_COMPARISON).isEnabled()
    diff = trace_actions.compare_trace(w, str(b))
    assert diff.t_ms == DIFF and ("out 3", "0", "1") in diff.signals
    panels = _drawn(qtbot, w)
    comp = panels.comparison
    assert comp is not None and comp.name == "after.plctrace"
    assert comp.base == "trace before.plctrace"
    assert panels.failing_ms == DIFF                       # the line at the first difference
    assert any(line.label is not None and line.label.textItem.toPlainText() == "first difference"
               for _p, _plot, line in panels._markers)
    assert w.action(Act.CLEAR_COMPARISON).isEnabled()
    banner = panels.banners[0].text()
    assert "after.plctrace (dashed)" in banner and "first difference at 0.140 s" in banner

    # the lanes: the other trace's path, dashed in the overlay colour, inside
    # each lane; OUT 5 (on only in the other trace) has a lane
    lanes = panels.lanes
    assert ("outputs", 5) in lanes.lanes()
    item = lanes.other_items["outputs"]
    pen = item.opts["pen"]
    assert pen.style() == Qt.PenStyle.DashLine
    assert pen.color().name() == style.plot_colours().overlay
    x, y = lanes.other_data("outputs")
    y3, y5 = lanes._lane_y[("outputs", 3)], lanes._lane_y[("outputs", 5)]
    hi3, lo3 = y3 + lanes.OTHER_HIGH, y3 + lanes.OTHER_LOW
    in3 = np.isclose(y, hi3) | np.isclose(y, lo3)
    assert np.all(np.isclose(y[in3 & (x > DIFF / 1000 + 1e-6)], hi3))   # on from 140 ms
    assert np.any(np.isclose(y[in3 & (x < DIFF / 1000)], lo3))          # toggling before
    assert np.any(np.isclose(y, y5 + lanes.OTHER_HIGH))
    # the first trace's own lanes are drawn as before
    fx, fy = lanes.merged_data("outputs")
    assert np.any(np.isclose(fy[fx > DIFF / 1000 + 0.01], y3))          # still toggling
    assert _key_texts(lanes.other_key) == ["trace before.plctrace", "after.plctrace"]

    # the analog curves: PWM0 of the other trace, dashed in the channel's colour
    curve = panels.analog.other_curves[0]
    assert curve.opts["pen"].style() == Qt.PenStyle.DashLine
    cx, cy = curve.getData()
    assert set(np.asarray(cy)[np.asarray(cx) > DIFF / 1000]) == {7}
    assert any("dashed: after.plctrace" in t for t in _key_texts(panels.analog.out_legend))
    # proc, dashed
    px, py = panels.proc.other_curve.getData()
    assert set(np.asarray(py)[np.asarray(px) > DIFF / 1000]) == {33}

    # the cursors read both traces
    panels.dock("cursors").show()
    panels.cursor_table.toggle.setChecked(True)
    panels.cursors.set_times(0.135, 0.165)
    rows = {r[0]: r for r in panels.cursor_table.rows()}
    out3 = next(k for k in rows if k.startswith("OUT 3"))
    assert rows[out3] == (out3, "1", "0", "-1", "1", "1")
    assert rows["PWM0"][1:3] == ("100", "0") and rows["PWM0"][4:] == ("100", "7")
    assert panels.cursor_table.table.columnCount() == 6
    head = panels.cursor_table.table.horizontalHeaderItem(5).text()
    assert "after.plctrace" in head

    # File › Clear Comparison: every item of the other trace goes
    plots = [lanes.plot, panels.analog.out_plot, panels.proc.plot]
    overlay_items = [*lanes.other_items.values(), curve, panels.proc.other_curve]
    keys = [lanes.other_key, panels.proc.other_key]
    assert all(k.scene() is not None for k in keys)
    w.action(Act.CLEAR_COMPARISON).trigger()
    assert panels.comparison is None
    assert lanes.other_items == {} and lanes.other_key is None
    assert all(k.scene() is None for k in keys)
    assert panels.analog.other_curves == {} and panels.proc.other_curve is None
    for it in overlay_items:
        assert all(it not in p.items for p in plots)
    assert not any("after.plctrace" in t for t in _key_texts(panels.analog.out_legend))
    assert ("outputs", 5) not in lanes.lanes()
    assert panels.recorded == "trace before.plctrace"            # the first trace stays
    assert panels.cursor_table.table.columnCount() == 4
    assert not w.action(Act.CLEAR_COMPARISON).isEnabled()


def _opened_and_compared(qtbot, w, files):
    """The first trace opened, the second compared with it, both drawn: the panels."""
    a, b = files
    trace_actions.open_trace(w, str(a))
    trace_actions.compare_trace(w, str(b))
    return _drawn(qtbot, w)


def test_back_to_live_ends_the_comparison(runwin, qtbot, files):
    w, _conn = runwin
    panels = _opened_and_compared(qtbot, w, files)
    panels.back_to_live()
    assert panels.comparison is None and panels.lanes.other_items == {}
    assert not w.action(Act.CLEAR_COMPARISON).isEnabled()


def test_the_overlay_follows_the_theme(runwin, qtbot, files):
    w, _conn = runwin
    panels = _opened_and_compared(qtbot, w, files)
    try:
        w.apply_preferences(dataclasses.replace(w.prefs, theme="dark"))
        qtbot.waitUntil(lambda: panels.lanes.other_items["outputs"].opts["pen"].color().name()
                        == style.DARK_PLOTS.overlay, timeout=5000)
        assert panels.proc.other_curve.opts["pen"].color().name() == style.DARK_PLOTS.overlay
        assert panels.comparison is not None
    finally:
        w.apply_preferences(dataclasses.replace(w.prefs, theme="light"))
    qtbot.waitUntil(lambda: panels.lanes.other_items["outputs"].opts["pen"].color().name()
                    == style.LIGHT_PLOTS.overlay, timeout=5000)


def test_comparing_with_the_live_session(runwin, qtbot, files):
    """With no trace on show, the session is compared, and the key says so."""
    w, conn = runwin
    from tests.ide.test_panels import sample
    conn.sig_samples.emit([sample(t, outputs=(1 << 3) if (t // 10) % 2 else 0)
                           for t in range(0, 200)])
    _a, b = files
    trace_actions.compare_trace(w, str(b))
    panels = _drawn(qtbot, w)
    assert panels.comparison.base == "the session"
    assert _key_texts(panels.lanes.other_key)[0] == "the session"
