"""File › Compare with Trace… lines the file's trace up with the one on show
(issue 23 item 5: two captures of one session said "no tick in common"): the
dialog offers the same times, the starts together or the triggers together,
and an offset; the overlay draws the file's trace moved so. And File › Export
Trace… writes one-bit lanes for PulseView (issue 25 item 9). Driven through
the real menu actions, dialog and widgets."""

from __future__ import annotations

import shutil
import subprocess

import numpy as np
import pytest
from PySide6.QtCore import Qt, QTimer
from PySide6.QtWidgets import QApplication, QFileDialog

from plcbuilder import api
from plcbuilder.ide import trace_actions
from plcbuilder.ide.actions import Act
from plcbuilder.ide.dialogs.compare_trace import CompareDialog
from tests.ide.test_docks_fit import prompts_off, runwin  # noqa: F401 - fixtures

PRE, POST = 100, 200


def _capture(t0: int, longer: bool = False) -> api.Trace:
    """A capture of ``out 3 rise`` at t0: out 3 on for 30 ms from the trigger
    (50 ms when ``longer``), pwm 0 = 500 meanwhile, proc 33."""
    off = t0 + (50 if longer else 30)
    trig = {"spec": "out 3 rise", "t_ms": t0, "pre_ms": PRE, "post_ms": POST, "mode": "single"}
    signals = {"out 3": ("bit", [(t0 - PRE, 0), (t0, 1), (off, 0)]),
               "pwm 0": ("int", [(t0 - PRE, 0), (t0, 500), (off, 0)]),
               "proc": ("int", [(t0 - PRE, 0), (t0, 33), (off, 0)]),
               "message": ("int", [(t0 - PRE, 0)]), "running": ("text", [(t0 - PRE, 1)])}
    return api.Trace(t0 - PRE, t0 + POST, signals, ["", "M90"], [], {"trigger": trig})


@pytest.fixture
def captures(tmp_path):
    """The before (trigger at 1.020 s) and after (5.020 s) captures of one session,
    and a whole session with no trigger."""
    a, b, plain = (tmp_path / n for n in ("before.plctrace", "after.plctrace",
                                          "session.plctrace"))
    api.save_trace(_capture(1020), a)
    api.save_trace(_capture(5020, longer=True), b)
    whole = _capture(1020)
    api.save_trace(api.Trace(0, 6000, whole.signals, whole.strings, [], {}), plain)
    return a, b, plain


def _drive_dialog(qtbot, act, path, *, expect_align: str, offset: int = 0, cancel=False):
    """Trigger ``act`` (a menu action opening the dialog) and, once the modal
    dialog is up, type the file name, check the alignment it proposes, set the
    offset and press Compare (or Cancel). Returns what the dialog showed."""
    seen = {}

    def drive():
        d = QApplication.activeModalWidget()
        if not isinstance(d, CompareDialog):
            QTimer.singleShot(20, drive)
            return
        try:
            seen["on_show"] = d.on_show.text()
            qtbot.keyClicks(d.path, str(path))              # read once the typing stops
            qtbot.waitUntil(lambda: d.info.text() != "", timeout=5000)
            seen["info"] = d.info.text()
            seen["align"] = d.align()
            seen["trigger_enabled"] = d.buttons["trigger"].isEnabled()
            d.offset.setValue(offset)
            seen["ok_enabled"] = d.box.button(d.box.StandardButton.Ok).isEnabled()
            button = d.box.button(d.box.StandardButton.Cancel if cancel else
                                  d.box.StandardButton.Ok)
            qtbot.mouseClick(button, Qt.MouseButton.LeftButton)
        finally:
            if d.isVisible():                               # something failed: never hang
                d.reject()

    QTimer.singleShot(0, drive)
    act.trigger()
    assert seen.get("align") == expect_align, seen
    return seen


def _drawn(qtbot, panels):
    for key, done in (("outputs", lambda: panels.lanes.other_data("outputs")[0].size > 0),
                      ("analog", lambda: bool(panels.analog.other_curves))):
        panels.dock(key).show()
        panels.dock(key).raise_()
        qtbot.waitUntil(done, timeout=10000)


def _rises(x, y, lane_y, high, low):
    """The times (s) where a dashed lane steps from its low to its high level."""
    inside = np.isclose(y, lane_y + high) | np.isclose(y, lane_y + low)
    xs, ys = x[inside], y[inside]
    up = np.isclose(ys[1:], lane_y + high) & np.isclose(ys[:-1], lane_y + low)
    return [round(float(t), 4) for t in xs[1:][up]]


def test_two_captures_overlay_with_their_triggers_together(runwin, qtbot, captures):
    w, _conn = runwin
    a, b, _plain = captures
    assert trace_actions.open_trace(w, str(a))
    seen = _drive_dialog(qtbot, w.action(Act.COMPARE_TRACE), b, expect_align="trigger")
    assert "trigger out 3 rise at 1.020 s" in seen["on_show"]
    assert seen["info"] == "4.920 .. 5.220 s, trigger out 3 rise at 5.020 s"
    assert seen["ok_enabled"]
    assert w.settings.last_folder("traces") == b.parent.resolve()     # remembered
    panels = w.run_panels
    _drawn(qtbot, panels)
    comp = panels.comparison
    assert comp is not None and comp.name == "after.plctrace (moved -4.000 s)"
    assert "triggers together" in comp.where and "first difference at 1.050 s" in comp.where
    banner = panels.banners[0].text()
    assert "after.plctrace (moved -4.000 s) (dashed)" in banner
    assert panels.failing_ms == 1050                  # out 3 falls at 1.050 s, not 1.070 s
    # the file's out 3 is drawn rising under the trigger on show (1.020 s), not at 5.020 s
    lanes = panels.lanes
    x, y = lanes.other_data("outputs")
    assert _rises(x, y, lanes._lane_y[("outputs", 3)], lanes.OTHER_HIGH,
                  lanes.OTHER_LOW) == [1.02]
    assert x.max() < 1.3                              # nothing drawn out at 5 s
    cx, cy = panels.analog.other_curves[0].getData()
    on = np.asarray(cx)[np.asarray(cy) == 500]
    assert on.min() == pytest.approx(1.02) and on.max() == pytest.approx(1.069, abs=0.002)
    # the cursors read both at the same moment of each capture
    panels.dock("cursors").show()
    panels.cursor_table.toggle.setChecked(True)
    panels.cursors.set_times(1.030, 1.060)
    rows = {r[0]: r for r in panels.cursor_table.rows()}
    assert rows["PWM0"][1:3] == ("500", "0") and rows["PWM0"][4:] == ("500", "500")


def test_an_offset_moves_the_overlay_further(runwin, qtbot, captures):
    w, _conn = runwin
    a, b, _plain = captures
    trace_actions.open_trace(w, str(a))
    _drive_dialog(qtbot, w.action(Act.COMPARE_TRACE), b, expect_align="trigger", offset=10)
    panels = w.run_panels
    _drawn(qtbot, panels)
    assert panels.comparison.name == "after.plctrace (moved -3.990 s)"
    lanes = panels.lanes
    x, y = lanes.other_data("outputs")
    assert _rises(x, y, lanes._lane_y[("outputs", 3)], lanes.OTHER_HIGH,
                  lanes.OTHER_LOW) == [1.03]
    assert panels.failing_ms == 1020                  # on show it rises at 1.020 s, 1.030 s here


def test_a_file_without_a_trigger_cannot_be_lined_up_on_one(runwin, qtbot, captures):
    w, _conn = runwin
    a, _b, plain = captures
    trace_actions.open_trace(w, str(a))
    seen = _drive_dialog(qtbot, w.action(Act.COMPARE_TRACE), plain, expect_align="none",
                         cancel=True)
    assert seen["info"] == "0.000 .. 6.000 s, no trigger" and not seen["trigger_enabled"]
    assert w.run_panels.comparison is None             # cancelled: nothing compared


def test_same_times_keeps_the_old_comparison(runwin, qtbot, captures):
    """Without alignment the two captures have no tick in common, as before."""
    w, _conn = runwin
    a, b, _plain = captures
    trace_actions.open_trace(w, str(a))
    diff = trace_actions.compare_trace(w, str(b))
    assert diff is not None and not diff.overlap and diff.shift_ms == 0
    assert w.run_panels.comparison.name == "after.plctrace"
    diff = trace_actions.compare_trace(w, str(b), align="start")
    assert diff.shift_ms == -4000 and w.run_panels.comparison.where.startswith(
        "starts together, after.plctrace moved -4.000 s")


def test_export_trace_one_bit_lanes_for_pulseview(runwin, qtbot, captures, tmp_path,
                                                  monkeypatch):
    """File › Export Trace…, the filter 'VCD, one-bit lanes for PulseView and sigrok'."""
    w, _conn = runwin
    a, _b, _plain = captures
    trace_actions.open_trace(w, str(a))
    out = tmp_path / "lanes"
    chosen = [f for f in trace_actions.export_filter().split(";;") if "one-bit" in f][0]
    monkeypatch.setattr(QFileDialog, "getSaveFileName", lambda *a, **k: (str(out), chosen))
    w.action(Act.EXPORT_TRACE).trigger()
    vcd = tmp_path / "lanes.vcd"
    text = vcd.read_text()
    assert "$var wire 1" in text and "pwm0[8]" in text and "$var integer" not in text
    if shutil.which("sigrok-cli"):
        r = subprocess.run(["sigrok-cli", "-I", "vcd", "-i", str(vcd), "-O", "csv"],
                           capture_output=True, text=True, timeout=120, check=True)
        rows = [ln for ln in r.stdout.splitlines() if ln[:1] in ("0", "1")]
        assert len(rows) == PRE + POST
    plain_filter = [f for f in trace_actions.export_filter().split(";;") if "GTKWave" in f][0]
    monkeypatch.setattr(QFileDialog, "getSaveFileName",
                        lambda *a, **k: (str(tmp_path / "whole"), plain_filter))
    w.action(Act.EXPORT_TRACE).trigger()
    assert "$var integer 9 " in (tmp_path / "whole.vcd").read_text()      # pwm 0: 0..500
