"""Frame rate of the run panels, and a demo program that exercises them.

:func:`measure_fps` is what ``scripts/bench.py``'s ``gui`` section calls: the
outputs (8 lanes) and PWM/DAC (8 curves) docks, 16 signals of 10 000 points
each, redrawn as fast as they can be while an embedded controller runs a
procedure in real time and streams its telemetry. The goal is at least 30 fps.
"""

from __future__ import annotations

import os
import time
from typing import Optional

DEMO_SOURCE = """\
#include pins.h
// A demo for the run panels: a move, outputs, PWM and DAC ramps,
// messages, prints, and a wait on the cycle start button.
main() {
  proc = plc_proc_moveup;
  portset(OUTPUT_CHARGE_PUMP);
  g0moveA(0x81, 1, 20000);          // X to 200 mm ...
  g0moveA(0x81, 2, 15000);          // ... and Y to 150 mm, together
  g0moveA(1, 3, 0);
  timer = 5; do { timer--; } while (timer > 0);
  do { motion = gvarget(6060); } while (motion != 0x4d);
  proc = plc_proc_spindle;
  portset(OUTPUT_SPINDLE);
  i = 0;
  do { i++; pwm01 = i * 4; dac01 = 3000 - i * 8; } while (i < 250);
  command = PLC_MESSAGE_SPINDLE_SPEED_CHANGED;   // tell myCNC the speed
  parameter = pwm01;
  message = PLCCMD_REPLY_TO_MYCNC;
  gvarset(20000, pwm01);
  portset(OUTPUT_MIST);
  g0moveA(1, 1, 5000);              // X back to 50 mm
  timer = 5; do { timer--; } while (timer > 0);
  do { motion = gvarget(6060); } while (motion != 0x4d);
  proc = plc_proc_check_plasma;
  portset(OUTPUT_ALARM_LAMP);
  do { button = portget(INPUT_CYCLE_START); } while (button == 0);
  portclear(OUTPUT_ALARM_LAMP);
  message = PLC_MESSAGE_PLASMA_OK;
  portclear(OUTPUT_MIST);
  i = 250;
  do { i--; pwm01 = i * 4; } while (i > 0);
  portclear(OUTPUT_SPINDLE);
  proc = plc_proc_idle;
  gvarset(20001, 7);
  exit(99);
}
"""

#: Runs until stopped: toggles 8 outputs and moves 8 PWM/DAC channels every tick.
BUSY_SOURCE = """\
main() {
  n = 0;
  do {
    n++;
    if (n & 1) portset(0); else portclear(0);
    if (n & 2) portset(1); else portclear(1);
    if (n & 4) portset(2); else portclear(2);
    if (n & 8) portset(3); else portclear(3);
    if (n & 16) portset(4); else portclear(4);
    if (n & 64) portset(5); else portclear(5);
    if (n & 256) portset(6); else portclear(6);
    if (n & 1024) portset(7); else portclear(7);
    pwm01 = n & 1023; pwm02 = (n * 3) & 1023; pwm03 = (n * 7) & 1023; pwm04 = (n >> 2) & 1023;
    dac01 = (n * 5) & 4095; dac02 = (n * 11) & 4095;
    gvarset(7282, (n * 13) & 1023); gvarset(7272, (n * 17) & 4095);   // PWM4, DAC2
  } while (1);
}
"""


def build_image(sources: dict[str, str]) -> bytes:
    """An eeprom.rom of hardware procedures {name: source} (raises on compile errors)."""
    from plcbuilder.api import compile_source
    from plcbuilder.image.manifest import write_image
    items = []
    for name, text in sources.items():
        r = compile_source(text, f"{name}.plc")
        if not r.ok:
            raise ValueError(f"{name}: " + "; ".join(str(d) for d in r.diagnostics))
        items.append((name, r.kind, r.program.to_bytes()))
    return write_image(items)


class _PaintCounter:
    """Counts the paint events of the viewports it filters."""

    def __new__(cls):
        from PySide6 import QtCore

        class Counter(QtCore.QObject):
            def __init__(self):
                super().__init__()
                self.counts: dict[int, int] = {}

            def eventFilter(self, obj, event):  # noqa: N802
                if event.type() == QtCore.QEvent.Type.Paint:
                    self.counts[id(obj)] = self.counts.get(id(obj), 0) + 1
                return False
        return Counter()


def measure_fps(seconds: float = 5.0, points: int = 10000, show: bool = True) -> float:
    """Frames a second of the outputs + PWM/DAC docks (16 signals × ``points``)
    redrawn back to back for ``seconds`` while an embedded controller runs a
    busy procedure in real time. Each frame feeds the telemetry that arrived,
    redraws both docks and paints them (synchronously)."""
    os.environ.setdefault("PYQTGRAPH_QT_LIB", "PySide6")
    from PySide6 import QtCore, QtWidgets

    from plcbuilder.ide.connection import ControllerConnection
    from plcbuilder.ide.panels.runpanels import RunPanels

    app = QtWidgets.QApplication.instance() or QtWidgets.QApplication([])
    win = QtWidgets.QMainWindow()
    conn = ControllerConnection()
    panels = RunPanels(win, conn, capacity=points)
    panels.timer.stop()                 # frames are driven here, as fast as they go
    panels.var_timer.stop()
    panels.timebase.set_window(points / 1000.0)   # the whole buffer in view
    for key in ("outputs", "analog"):
        win.addDockWidget(QtCore.Qt.DockWidgetArea.TopDockWidgetArea, panels.dock(key))
    for key in ("proc", "axes", "inputs", "watch", "log"):
        d = panels.dock(key)
        win.addDockWidget(QtCore.Qt.DockWidgetArea.BottomDockWidgetArea, d)
        d.hide()
    win.resize(1600, 700)
    if show:
        win.show()
    conn.start_embedded()

    def pump(until: float, cond=lambda: False) -> bool:
        while time.monotonic() < until and not cond():
            app.processEvents()
            time.sleep(0.002)
        return cond()

    try:
        if not pump(time.monotonic() + 20, lambda: conn.connected):
            raise RuntimeError("the embedded controller did not come up")
        conn.upload(build_image({"BUSY": BUSY_SOURCE}))
        conn.start("BUSY", 0)
        # fill the buffers quickly (10x real time: still every tick), then
        # measure in real time
        conn.set_speed("10")
        if not pump(time.monotonic() + 20, lambda: len(panels.model) >= points):
            raise RuntimeError(f"only {len(panels.model)} samples arrived")
        conn.set_speed("realtime")
        pump(time.monotonic() + 0.3)
        a, b = panels.model.window(*panels.lanes.visible_span())
        if b - a < points * 0.95:
            raise RuntimeError(f"only {b - a} samples in view")
        lanes, analog = panels.lanes, panels.analog
        for pin in range(8):
            lanes.pin_lane("outputs", pin)
        painted = _PaintCounter()
        for w in (lanes.widget, analog.widget):
            w.viewport().installEventFilter(painted)
        app.processEvents()
        painted.counts.clear()
        start = time.monotonic()
        end = start + seconds
        while time.monotonic() < end:
            lanes.refresh(force=True)       # the telemetry that came is in the model
            analog.refresh(force=True)
            app.processEvents()             # receives telemetry, paints both docks
        elapsed = time.monotonic() - start
        frames = min(painted.counts.values()) if len(painted.counts) == 2 else 0
        return frames / elapsed if elapsed > 0 else 0.0
    finally:
        conn.shutdown()
        panels.shutdown()
        win.close()
        win.deleteLater()
        app.processEvents()


def main(argv: Optional[list[str]] = None) -> int:
    import argparse
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--seconds", type=float, default=5.0)
    p.add_argument("--points", type=int, default=10000)
    args = p.parse_args(argv)
    fps = measure_fps(args.seconds, args.points)
    print(f"run panels: {fps:.1f} fps (16 signals x {args.points} points, controller in "
          "real time; goal >= 30)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
