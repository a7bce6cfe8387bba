"""Issue 23 point 1: the mouse wheel never changes the run. A wheel over any
value widget of a dock (a slider, a spin box, a combo box) scrolls what it is
in and changes nothing; values change only by a click, a drag or a typed value.

Before: scrolling the Inputs dock over the pin list moved an ADC slider when it
came under the pointer, and that forced the channel ("937 F")."""

from __future__ import annotations

import pytest
from PySide6.QtCore import QPoint, QPointF, Qt
from PySide6.QtGui import QWheelEvent
from PySide6.QtWidgets import (QAbstractSlider, QAbstractSpinBox, QApplication, QComboBox,
                               QDockWidget, QScrollArea, QScrollBar, QWidget)

from plcbuilder.ide.settings import Settings
from tests.ide.test_debug_ide import DebugConnection
from tests.ide._workbench import answer_no, make_project, windows

VALUE_WIDGETS = (QAbstractSlider, QAbstractSpinBox, QComboBox)


@pytest.fixture
def runwin(qtbot, tmp_path, monkeypatch):
    """A window with its run docks on a connected controller that forces (the
    IDE's debugger): a click or a slider forces an input or ADC channel."""
    answer_no(monkeypatch)
    conn = DebugConnection()
    with windows(qtbot, Settings(str(tmp_path / "cfg" / "s.ini")), (1400, 900)) as make:
        w = make(connection=conn, start_controller=True)
        qtbot.waitUntil(lambda: w.run_panels is not None, timeout=10000)
        w.open_project(make_project(tmp_path / "proj"))
        conn.connect_now()
        yield w, conn


def wheel(widget, notches: int = -3, at: QPoint | None = None) -> None:
    """Turn the wheel over ``widget`` (down: negative), as the window system
    delivers it to the widget under the pointer."""
    pos = QPointF(at if at is not None else widget.rect().center())
    glob = QPointF(widget.mapToGlobal(pos.toPoint()))
    for _ in range(abs(notches)):
        ev = QWheelEvent(pos, glob, QPoint(0, 0), QPoint(0, 120 if notches > 0 else -120),
                         Qt.MouseButton.NoButton, Qt.KeyboardModifier.NoModifier,
                         Qt.ScrollPhase.NoScrollPhase, False)
        QApplication.sendEvent(widget, ev)


def _value(w):
    return w.currentIndex() if isinstance(w, QComboBox) else (
        w.value() if hasattr(w, "value") else w.text())


def value_widgets(win) -> list:
    """Every slider, spin box and combo box in the window's docks (scroll bars
    are what scrolls: not these), with the toolbar's speed box."""
    out = []
    for dock in win.findChildren(QDockWidget):
        for w in dock.findChildren(QWidget):
            if isinstance(w, VALUE_WIDGETS) and not isinstance(w, QScrollBar):
                out.append(w)
    return out + [win.run_actions.speed_combo]


def test_the_wheel_over_an_adc_slider_scrolls_the_inputs_dock_and_forces_nothing(runwin, qtbot):
    w, conn = runwin
    dock = w.run_docks["inputs"]
    dock.show()
    dock.raise_()
    inputs = w.run_panels.inputs
    qtbot.waitUntil(lambda: inputs.sliders[0].isVisible(), timeout=5000)
    area = inputs.findChild(QScrollArea)
    bar = area.verticalScrollBar()
    assert bar.maximum() > 0, "the dock is too tall to scroll: make it shorter"
    bar.setValue(bar.maximum() // 2)
    before_bar = bar.value()
    slider, spin = inputs.sliders[0], inputs.spins[0]
    for x in (slider, spin):               # as a reading of 2000 shows them
        x.blockSignals(True)
        x.setValue(2000)
        x.blockSignals(False)
    before = (slider.value(), spin.value())
    wheel(slider, -3)                       # down over the slider
    wheel(spin, -2)
    qtbot.wait(50)
    assert (slider.value(), spin.value()) == before
    assert not [c for c in conn.calls if c[0] in ("force", "set_adc", "write")], conn.calls
    assert bar.value() > before_bar         # the dock scrolled instead
    wheel(slider, +5)                       # and back up
    assert bar.value() < before_bar and slider.value() == before[0]
    qtbot.wait(50)
    assert not [c for c in conn.calls if c[0] in ("force", "set_adc", "write")], conn.calls


def test_no_value_widget_of_any_dock_changes_with_the_wheel(runwin, qtbot):
    """Every slider, spin box and combo box of the run docks, the debugger's and
    the workbench's (made when their dock first shows), and the speed box."""
    w, conn = runwin
    for dock in w.findChildren(QDockWidget):
        dock.show()
        dock.raise_()
        qtbot.wait(5)
    widgets = value_widgets(w)
    kinds = {type(x).__name__ for x in widgets}
    assert {"QSlider", "QSpinBox", "QComboBox"} <= kinds, kinds
    assert len(widgets) > 20
    for x in widgets:
        if isinstance(x, QComboBox) and x.count() < 2:
            x.addItems(["one", "two", "three"])   # something to move to
        before = _value(x)
        wheel(x, -2)
        wheel(x, +1)
        assert _value(x) == before, f"{type(x).__name__} {x.objectName() or x.toolTip()!r}"
        assert not x.hasFocus() or x.focusPolicy() != Qt.FocusPolicy.WheelFocus
    changing = ("force", "set_adc", "set_input", "write", "set_speed", "start", "stop")
    assert not [c for c in conn.calls if c[0] in changing], conn.calls
