"""The run panels driven by a real embedded controller: a procedure's outputs,
proc and messages reach the docks; an input toggle ends a procedure waiting
for it; a click on a fault opens its source line."""

from __future__ import annotations

import pytest

pytest.importorskip("PySide6")

from PySide6 import QtCore  # noqa: E402

from plcbuilder.api import image_of as build_image  # noqa: E402
from tests.ide._demo import DEMO_SOURCE  # noqa: E402
from plcbuilder.ide.panels.log import CATEGORY, LINE, TEXT  # noqa: E402

Qt = QtCore.Qt
WAIT = 15_000

SPINDLE = """\
#include pins.h
main() {
  proc = plc_proc_spindle;
  portset(OUTPUT_SPINDLE);
  pwm01 = 640;
  timer = 40; do { timer--; } while (timer > 0);
  message = PLC_MESSAGE_SPINDLE_TURNING;
  speed = 1200;
  timer = 40; do { timer--; } while (timer > 0);
  exit(99);
}
"""

WAIT_BUTTON = """\
#include pins.h
main() {
  portset(OUTPUT_ALARM_LAMP);
  do { b = portget(INPUT_CYCLE_START); } while (b == 0);
  portclear(OUTPUT_ALARM_LAMP);
  exit(99);
}
"""

DIVIDE = """\
main() {
  a = 10;
  timer = 3; do { timer--; } while (timer > 0);
  b = a / timer;
  exit(99);
}
"""


@pytest.fixture
def live(live_run_panels):
    """The live run panels with SPINDLE, WAITB, DIVIDE and DEMO uploaded."""
    win, conn, panels = live_run_panels
    conn.upload(build_image({"SPINDLE": SPINDLE, "WAITB": WAIT_BUTTON,
                             "DIVIDE": DIVIDE, "DEMO": DEMO_SOURCE}))
    return win, conn, panels


def _log_texts(panels) -> list[str]:
    return [r[TEXT] for r in panels.log.rows.rows()]


def _ended(panels, name: str) -> bool:
    return any(t.startswith(f"{name} ended") for t in _log_texts(panels))


def test_procedure_reaches_the_panels(qtbot, live):
    win, conn, panels = live
    conn.start("SPINDLE", 0)
    qtbot.waitUntil(lambda: _ended(panels, "SPINDLE"), timeout=WAIT)
    m = panels.model
    qtbot.waitUntil(lambda: 0 in m.active_outputs and 70 in m.proc_values, timeout=WAIT)
    # outputs: a named lane for the spindle
    panels.lanes.refresh(force=True)
    assert ("outputs", 0) in panels.lanes.lanes()
    assert panels.lanes.lane_label("outputs", 0) == "OUT 0  OUTPUT_SPINDLE"
    assert "OUT 0  OUTPUT_SPINDLE" in panels.lanes.y_labels()
    # proc: a step to 70 and the y axis names the state
    panels.proc.refresh(force=True)
    labels = panels.proc.y_labels()
    assert "plc_proc_spindle (70)" in labels and "plc_proc_idle (0)" in labels
    x, y = panels.proc.curve.getOriginalDataset()
    assert 70 in set(y.tolist())
    # the message: a marker, a decoded row, a log line
    assert [r.name for r in m.messages] == ["PLC_MESSAGE_SPINDLE_TURNING"]
    panels.tick()
    assert panels.proc.messages.rowCount() == 1
    assert panels.proc.messages.row(0)[2] == "PLC_MESSAGE_SPINDLE_TURNING"
    assert len(panels.proc.markers.data) == 1
    assert any("PLC_MESSAGE_SPINDLE_TURNING (131)" in t for t in _log_texts(panels))
    assert any("exit plc_exit_normal (99)" in t for t in _log_texts(panels))
    # PWM0 plotted with its value
    panels.analog.refresh(force=True)
    assert 0 in panels.analog._curves
    _, pwm = panels.analog._curves[0].getOriginalDataset()
    assert 640 in set(pwm.tolist())
    # watch: the final values of its variables
    qtbot.waitUntil(lambda: panels.watch.value("speed", "SPINDLE") == 1200, timeout=WAIT)
    assert panels.watch.table.item(0, 0).text() == "speed"


def test_input_toggle_ends_a_waiting_procedure(qtbot, live):
    win, conn, panels = live
    panels.dock("inputs").raise_()
    conn.start("WAITB", 0)
    qtbot.waitUntil(lambda: panels.model.running == "WAITB", timeout=WAIT)
    qtbot.waitUntil(lambda: 7 in panels.model.active_outputs, timeout=WAIT)
    assert not _ended(panels, "WAITB")
    button = panels.inputs.button(9)
    assert "INPUT_CYCLE_START" in button.text() and button.isEnabled()
    qtbot.mouseClick(button, Qt.MouseButton.LeftButton)
    qtbot.waitUntil(lambda: _ended(panels, "WAITB"), timeout=WAIT)
    assert any("WAITB ended: exit plc_exit_normal (99)" in t for t in _log_texts(panels))
    qtbot.waitUntil(lambda: panels.model.pin_state("inputs", 9) == 1, timeout=WAIT)
    panels.inputs.refresh()
    assert button.isChecked()
    assert 9 in panels.model.active_inputs
    # and back off by hand
    qtbot.mouseClick(button, Qt.MouseButton.LeftButton)
    qtbot.waitUntil(lambda: panels.model.pin_state("inputs", 9) == 0, timeout=WAIT)


def test_adc_spin_sets_the_channel(qtbot, live):
    win, conn, panels = live
    panels.inputs.spins[3].setValue(777)
    qtbot.waitUntil(lambda: panels.model.last_sample is not None
                    and panels.model.last_sample.adc[3] == 777, timeout=WAIT)
    panels.inputs.refresh()
    assert panels.inputs.readings[3].text() == "777"
    assert panels.inputs.sliders[3].value() == 777


def test_fault_click_opens_its_line(qtbot, live):
    win, conn, panels = live
    conn.start("DIVIDE", 0)
    qtbot.waitUntil(lambda: any(r[CATEGORY] == "fault" for r in panels.log.rows.rows()),
                    timeout=WAIT)
    panels.log.flush()
    fault = [r for r in panels.log.rows.rows() if r[CATEGORY] == "fault"][0]
    assert fault[LINE] == 4 and "division by zero" in fault[TEXT]
    rows = panels.log.fault_rows()
    assert len(rows) == 1
    view = panels.log.view
    rect = view.visualRect(panels.log.proxy.index(rows[0], 3))
    with qtbot.waitSignal(panels.sig_open_location, timeout=WAIT) as blocker:
        qtbot.mouseClick(view.viewport(), Qt.MouseButton.LeftButton, pos=rect.center())
    assert blocker.args == ["DIVIDE.plc", 4]
    # the fault's message reached the proc dock too
    qtbot.waitUntil(lambda: any(r.code == -1 for r in panels.model.messages), timeout=WAIT)


def test_demo_motion_reaches_the_axes(qtbot, live):
    win, conn, panels = live
    conn.set_speed("10")
    conn.start("DEMO", 0)
    qtbot.waitUntil(lambda: panels.model.proc_values >= {65, 70, 10}, timeout=WAIT)
    panels.axes.refresh(force=True)
    assert set(panels.axes._pos) >= {0, 1}          # X and Y moved
    x, y = panels.axes.xy_path.getData()
    assert x is not None and max(x) > 150 and max(y) > 120
    conn.set_input(9, 1)
    qtbot.waitUntil(lambda: _ended(panels, "DEMO"), timeout=WAIT)


def test_a_controller_reset_starts_the_plots_over(qtbot, live):
    win, conn, panels = live
    qtbot.waitUntil(lambda: panels.model.t_end > 0.3, timeout=WAIT)
    epoch = panels.model.epoch
    conn.reset()
    qtbot.waitUntil(lambda: panels.model.epoch > epoch, timeout=WAIT)
    panels.tick()
    assert panels.model.t_end < 0.3
