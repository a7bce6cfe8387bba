"""The run panels show the softMC virtual outputs, and the outputs of
programmable limit switches, as lanes like the physical outputs (SPEC §9)."""

from __future__ import annotations

import pytest

pytest.importorskip("PySide6")

from plcbuilder.controller.controller import Controller  # noqa: E402
from plcbuilder.controller.machine_config import parse_machine  # noqa: E402

from tests.controller._sim import compile_proc  # noqa: E402
from tests.ide._workbench import docked_run_panels  # noqa: E402
from tests.ide.test_panels import FakeConnection  # noqa: E402

MACHINE = """
[axes.X]
rapid = 60000.0
accel = 20000.0
start = 0.0
[[pls]]
axis = "X"
vout = 3
positions = [10.0, 20.0]
polarity = 1
enabled = true
[[pls]]
axis = "X"
output = 6
positions = [15.0]
polarity = 1
enabled = true
"""

#: X to 30 mm and back to 0 (through both PLSs' points), VOUT.32 set by hand
TOUR = """go()
{
  g0moveA(0x3, 1, d);
  timer = 3;
  do { timer--; } while (timer > 0);
  do { w = gvarget(GVAR_CURRENT_MOTION_CODE); } while (w != 0x4d);
}

main()
{
  gvarset(VOUT_32, 1);
  d = 3000;
  go();
  d = 0;
  go();
  exit(99);
}
"""


@pytest.fixture
def panels(qtbot):
    fake = FakeConnection()
    _win, p = docked_run_panels(qtbot, fake, (1200, 800), capacity=5000)
    yield p, fake
    p.shutdown()


def _run_samples():
    c = Controller(parse_machine(MACHINE, "m.toml"), record_samples=True)
    c.load([compile_proc(TOUR)])
    c.start("M03")
    c.run_until_idle(5000)
    return c.drain_samples()


def test_virtual_and_pls_outputs_are_lanes(qtbot, panels):
    """Issue 15 (softMC I/O): "The panels show virtual outputs and PLS outputs
    like physical ones": a PLS on VOUT.3, one on output 6 and VOUT.32 written by the
    procedure each get a lane, with the edges the run had."""
    p, fake = panels
    samples = _run_samples()
    assert any(s.vio and s.vio[1] & 0b100 for s in samples)      # the samples carry VOUTs
    fake.sig_samples.emit(samples)
    p.tick()
    lanes = p.lanes
    assert lanes.lanes() == [("outputs", 6), ("vouts", 2), ("vouts", 31)]
    assert lanes.y_labels()[1:] == ["VOUT 3", "VOUT 32"]
    series = p.model.bit_series("vouts", 2)
    rises = int(((series[1:] == 1) & (series[:-1] == 0)).sum())
    assert rises == 2                         # 10..20 mm going out, and again coming back
    assert p.model.pin_state("vouts", 31) == 1 and p.model.pin_state("vouts", 2) == 0
    x, _ = lanes.merged_data("vouts")
    assert len(x) > 0


def test_a_virtual_output_lane_can_be_pinned(qtbot, panels):
    """The lanes' menu offers virtual outputs: a pinned VOUT lane shows before it
    ever changes, and can be removed again."""
    p, fake = panels
    lanes = p.lanes
    menu = lanes.build_menu()
    assert "Add virtual output lane" in [a.text() for a in menu.actions()]
    lanes.pin_lane("vouts", 0)
    p.tick()
    assert lanes.lanes() == [("vouts", 0)] and lanes.y_labels() == ["VOUT 1"]
    lanes.remove_lane("vouts", 0)
    p.tick()
    assert lanes.lanes() == []
