"""What the IDE does while little or nothing happens (issue 14 point 4): the
causes of CPU use found by profiling, each pinned down without timing.

- Qt keeps the docks of a tab group that are not current "visible" (it moves
  them out of the window): they must neither redraw nor poll.
- A time-only move shifts the curves; it must not make pyqtgraph re-clip,
  re-downsample and re-set their data.
- A move put off by the scroll rate comes back when it is due (not at every
  frame, and not only when the next telemetry arrives); less than a pixel of
  time does not move the plots at all.
- Nothing runs and nothing changes: no QTimer runs.
"""

from __future__ import annotations

import math
import time

import pytest

pytest.importorskip("PySide6")

from PySide6 import QtCore, QtGui, QtWidgets  # noqa: E402

from plcbuilder.ide.docks import on_screen  # noqa: E402
from plcbuilder.ide.panels import RunPanels  # noqa: E402
from plcbuilder.link.client import ControllerStatus  # noqa: E402
from tests.ide import _workbench  # noqa: E402
from tests.ide.test_panels import FakeConnection, sample  # noqa: E402

# the main window's fixtures
make_window, project, prompts = _workbench.make_window, _workbench.project, _workbench.prompts

Qt = QtCore.Qt


@pytest.fixture
def tabbed(qtbot):
    """The run docks as the IDE places them: the plots tabbed on the right
    (Outputs in front), inputs, watch and cursors tabbed under them."""
    fake = FakeConnection()
    win = QtWidgets.QMainWindow()
    qtbot.addWidget(win)
    win.setCentralWidget(QtWidgets.QTextEdit())
    p = RunPanels(win, fake, capacity=2000)
    right = [p.dock(k) for k in ("outputs", "proc", "analog", "axes")]
    lower = [p.dock(k) for k in ("inputs", "watch", "cursors")]
    area = Qt.DockWidgetArea.RightDockWidgetArea
    win.addDockWidget(area, right[0])
    win.splitDockWidget(right[0], lower[0], Qt.Orientation.Vertical)
    for d in right[1:]:
        win.tabifyDockWidget(right[0], d)
    for d in lower[1:]:
        win.tabifyDockWidget(lower[0], d)
    win.addDockWidget(Qt.DockWidgetArea.BottomDockWidgetArea, p.dock("log"))
    right[0].raise_()
    lower[0].raise_()
    win.resize(1400, 900)
    win.show()
    qtbot.waitExposed(win)
    yield p, fake
    p.shutdown()


def test_docks_tabbed_away_neither_redraw_nor_poll(qtbot, tabbed):
    p, fake = tabbed
    # Qt calls them visible; they are out of the window
    assert p.proc.isVisible() and p.watch.isVisible()
    assert not on_screen(p.proc) and not on_screen(p.watch)
    assert on_screen(p.lanes) and on_screen(p.inputs)
    frames = [q.frames for q in p.time_panels]
    fake.sig_samples.emit([sample(t, proc=70 + (t & 1), outputs=t & 1, pwm=(t,), axes=(t,))
                           for t in range(300)])
    p.tick()
    assert [q.frames - f for q, f in zip(p.time_panels, frames)] == [0, 1, 0, 0]  # lanes only
    fake.connected = True
    fake.sig_state.emit(ControllerStatus(t_ms=300, running="M03", software=(), proc=70), 0)
    p._poll_variables()
    assert ("variables",) not in fake.calls and not p.var_timer.isActive()
    # brought to the front: they catch up, and the watch polls
    p.dock("proc").raise_()
    qtbot.waitUntil(lambda: on_screen(p.proc))
    p.tick()
    assert p.proc.frames == frames[0] + 1 and not on_screen(p.lanes)
    p.dock("watch").raise_()
    qtbot.waitUntil(lambda: ("variables",) in fake.calls)
    assert p.var_timer.isActive()


def test_a_time_only_move_leaves_the_curves_data_alone(qtbot, tabbed, monkeypatch):
    """PlotDataItem.setPos re-clips, re-downsamples and sets its curve's data
    again (a new path to build): a move must not."""
    import pyqtgraph as pg
    p, fake = tabbed
    p.timebase.set_window(1.0)
    fake.sig_samples.emit([sample(t, outputs=t & 1, pwm=(t,)) for t in range(0, 2000, 10)])
    fake.sig_samples.emit([sample(2000, outputs=1, pwm=(99,))])
    p.tick()
    curve_data = []
    orig = pg.PlotCurveItem.setData
    monkeypatch.setattr(pg.PlotCurveItem, "setData",
                        lambda self, *a, **k: (curve_data.append(self), orig(self, *a, **k)))
    lanes = p.lanes
    frames, moves = lanes.frames, lanes.moves
    fake.sig_samples.emit([sample(t, outputs=1, pwm=(99,)) for t in range(2001, 2100)])
    lanes._last_move = 0.0
    p.tick()
    assert lanes.frames == frames and lanes.moves == moves + 1
    assert curve_data == []
    item = lanes._items["outputs"]
    assert item.pos().x() == pytest.approx(lanes._drawn_offset - lanes.offset)
    assert item.viewRect().right() == pytest.approx(lanes.offset - lanes._drawn_offset, abs=1e-6)


def _idle_history(p, fake, window_s: float, end_ms: int, step_ms: int) -> None:
    """A window of window_s seconds on an idle controller (LUBE in software),
    output 0 toggling every second from 0 to end_ms (a sample every step_ms),
    drawn once."""
    p.timebase.set_window(window_s)
    p._on_state(ControllerStatus(t_ms=0, running=None, software=("LUBE",), proc=0))
    fake.sig_samples.emit([sample(t, outputs=(t // 1000) & 1, running=None)
                           for t in range(0, end_ms, step_ms)])
    p.tick()


def test_a_put_off_move_comes_back_when_due(qtbot, tabbed):
    p, fake = tabbed
    _idle_history(p, fake, 1.0, 2000, 10)
    lanes = p.lanes
    fake.sig_samples.emit([sample(2000, outputs=1, running=None)])     # only time advances
    lanes._last_move = 0.0
    p.tick()
    moves = lanes.moves
    assert moves >= 1
    # new time right after the move: the scroll rate puts it off ...
    fake.sig_samples.emit([sample(2100, outputs=1, running=None)])
    p.tick()
    assert lanes.moves == moves and lanes.move_due() is not None
    # ... the timer does not spin at the frame rate meanwhile ...
    assert p.timer.isActive() and p.timer.interval() > p.frame_ms
    # ... and the move comes without more telemetry
    qtbot.waitUntil(lambda: lanes.moves == moves + 1, timeout=2000)
    assert lanes.offset == pytest.approx(2.1)
    qtbot.waitUntil(lambda: not p.timer.isActive(), timeout=2000)


def test_time_only_telemetry_costs_one_redraw_tick_a_batch(qtbot, tabbed):
    """Issue 26.4 (measured on a real X server: a fifth of the IDE's processor
    time went to redraw ticks that did nothing): LUBE at 1x sends about ten
    batches a second that only advance time, each to cost one tick of the
    redraw timer, the move. A move leaves no follow-up frame; a batch does
    not wake the timer while a move is due anyway (but one that changes a
    value does); a move that comes a moment early is done, not put off."""
    p, fake = tabbed
    _idle_history(p, fake, 2.0, 5000, 10)
    lanes = p.lanes
    fake.sig_samples.emit([sample(5000, outputs=0, running=None)])     # only time advances
    lanes._last_move = 0.0
    p.tick()
    moves = lanes.moves
    assert moves >= 1 and not p.timer.isActive()          # no frame after the move
    # a move put off: the timer waits for it; time-only telemetry leaves it be
    fake.sig_samples.emit([sample(5050, outputs=0, running=None)])
    p.tick()
    assert lanes.move_due() is not None and p.timer.isActive()
    waiting = p.timer.interval()
    assert waiting > p.frame_ms
    fake.sig_samples.emit([sample(5060, outputs=0, running=None)])
    assert p.timer.interval() == waiting
    # a value that changed is drawn at the next frame, not at the move
    fake.sig_samples.emit([sample(5070, outputs=1, running=None)])
    assert p.timer.interval() == p.frame_ms
    p.tick()
    # a move due within a quarter of the scroll period is done at once
    fake.sig_samples.emit([sample(5200, outputs=1, running=None)])
    lanes._last_move = time.monotonic() - 0.9 / lanes.SCROLL_FPS
    moves = lanes.moves
    p.tick()
    assert lanes.moves == moves + 1 and not p.timer.isActive()


def test_less_than_a_pixel_does_not_move(qtbot, tabbed):
    p, fake = tabbed
    _idle_history(p, fake, 60.0, 61000, 100)
    lanes = p.lanes
    per_px = 60.0 / lanes.plot.getViewBox().width()
    assert per_px > 0.02
    moves = lanes.moves
    fake.sig_samples.emit([sample(61010, outputs=1, running=None)])   # 10 ms: under a pixel
    lanes._last_move = 0.0
    p.tick()
    assert lanes.moves == moves
    fake.sig_samples.emit([sample(61000 + int(per_px * 2000), outputs=1, running=None)])
    lanes._last_move = 0.0
    p.tick()
    assert lanes.moves == moves + 1


def test_the_register_browser_polls_only_while_shown(qtbot):
    from plcbuilder.ide.panels.register_browser import RegisterBrowser
    b = RegisterBrowser()
    qtbot.addWidget(b)
    b.set_connection(_workbench.FakeConnection())
    assert not b.timer.isActive()                 # hidden: no timer
    b.show()
    qtbot.waitExposed(b)
    assert b.timer.isActive()
    b.hide()
    assert not b.timer.isActive()


def test_no_timer_runs_while_the_ide_is_idle(qtbot, make_window, project):
    """The example's case: a project open, the controller connected, nothing
    running; time advances on the controller (a time-only frame a second)."""
    conn = _workbench.FakeConnection()
    w = make_window(connection=conn, start_controller=True)
    w.open_project(project)
    _workbench.settle(qtbot, w)
    qtbot.waitUntil(lambda: w.run_panels is not None, timeout=10000)
    conn.connected = True
    conn.sig_connected.emit("127.0.0.1:5700")
    for t in range(3):
        conn.sig_state.emit(ControllerStatus(t_ms=1000 * t, running=None, software=(), proc=0), 0)
        conn.sig_samples.emit([sample(1000 * t, running=None)])
        qtbot.wait(60)
    w.statusBar().clearMessage()               # a message's own timeout ends by itself
    qtbot.waitUntil(lambda: not w.run_panels.timer.isActive(), timeout=3000)
    active = [(type(t.parent()).__name__, t.interval()) for t in w.findChildren(QtCore.QTimer)
              if t.isActive()]
    assert active == []
    # an unsaved change is autosaved: its timer runs until nothing is unsaved
    ed = w.open_file(project / "hardware" / "M03.plc")
    ed.insertText(0, "// x\n")
    assert w.recovery.timer.isActive()
    assert w.recovery.autosave_now() == 1 and w.recovery.timer.isActive()
    assert w.save_editor(ed)
    w.recovery.autosave_now()
    assert not w.recovery.timer.isActive()


def test_the_time_axis_ticks_are_pyqtgraphs_at_round_absolute_times(qtbot):
    """The following time axis works its ticks out itself (pyqtgraph's way,
    without numpy: it is asked ten times a second); they are the same."""
    import random

    import pyqtgraph as pg

    from plcbuilder.ide.panels.style import TimeAxis
    ax = TimeAxis()
    rnd = random.Random(14)
    for _ in range(500):
        ax.offset = rnd.uniform(0, 5000)
        width = rnd.choice([0.01, 1, 5, 10, 60, 3600]) * rnd.uniform(0.5, 1.5)
        size = rnd.uniform(100, 2000)
        mine = ax.tickValues(-width, 0.0, size)
        ref = pg.AxisItem.tickValues(ax, ax.offset - width, ax.offset, size)
        assert [s for s, _v in mine] == pytest.approx([s for s, _v in ref])
        for (_s, a), (_t, b) in zip(mine, ref):
            assert [v + ax.offset for v in a] == pytest.approx(b, abs=1e-9)


def _grid_columns(widget, y: int) -> list[int]:
    """The x of each vertical grid line crossing row y of the widget's image."""
    from plcbuilder.ide.panels.style import plot_colours
    img = widget.grab().toImage()
    grid = QtGui.QColor(plot_colours().grid).rgb()
    xs = [x for x in range(img.width()) if img.pixel(x, y) == grid]
    return [x for i, x in enumerate(xs) if i == 0 or xs[i - 1] != x - 1]


def test_a_following_time_axis_moves_its_picture_until_a_tick_comes_or_goes(qtbot):
    """While the plots follow at 1x, the time axis was drawn again at every
    move (its tick texts: a fifth of the IDE's processor time with the plots
    shown). Its picture is moved now, and drawn again when a tick comes or
    goes, or after REDRAW_AFTER_PX; moved, it shows the grid where a picture
    drawn afresh has it."""
    from plcbuilder.ide.panels import style
    widget = style.plot_widget(style.time_axis())
    qtbot.addWidget(widget)
    widget.resize(600, 300)
    plot = widget.getPlotItem()
    style.style_plot(plot)
    ax = plot.getAxis("bottom")
    plot.setXRange(-10.0, 0.0, padding=0)
    ax.set_offset(100.5)                            # the first label well inside (30 px)
    widget.show()
    qtbot.waitExposed(widget)
    widget.grab()
    drawn = ax.redraws
    y = int(plot.vb.mapToScene(plot.vb.boundingRect().center()).y())
    px_per_s = ax.size().width() / 10.0
    step = 3.0 / px_per_s                           # three pixels a move
    spacing = ax._levels[0][0]

    def ticks(o):                                   # the first and last tick shown at o
        return math.ceil((o - 10.0) / spacing), math.floor(o / spacing)

    moved = 0
    while abs(ax.shift_px()) + 3.0 < ax.REDRAW_AFTER_PX:
        if ticks(ax.offset + step) != ticks(ax.offset):
            break                                   # a tick would come or go
        if ax._label_left is not None and ax._label_left + ax.shift_px() - 3.0 < 0:
            break                                   # the first label would be cut
        ax.set_offset(ax.offset + step)
        moved += 1
        shifted = _grid_columns(widget, y)
        assert ax.redraws == drawn, "a move of a few pixels drew the axis again"
        ax.picture = None                           # the same offset, drawn afresh
        fresh = _grid_columns(widget, y)
        assert ax.redraws == drawn + 1
        drawn = ax.redraws
        assert len(shifted) == len(fresh) and \
            all(abs(a - b) <= 1 for a, b in zip(shifted, fresh)), (shifted, fresh)
    assert moved >= 2
    # past REDRAW_AFTER_PX (or a tick coming in): drawn again
    ax.set_offset(ax.offset + 2.0)
    widget.grab()
    assert ax.redraws == drawn + 1


def test_a_moved_time_axis_never_shows_a_label_cut_at_its_left_edge(qtbot):
    """Issue 23 point 16: the first tick's label, moved left with the picture,
    was cut by the axis' edge ("66" read "6"). A move that would cut it draws
    the axis again (which leaves out a label that does not fit whole)."""
    from plcbuilder.ide.panels import style
    widget = style.plot_widget(style.time_axis())
    qtbot.addWidget(widget)
    widget.resize(600, 300)
    plot = widget.getPlotItem()
    style.style_plot(plot)
    ax = plot.getAxis("bottom")
    plot.setXRange(-10.0, 0.0, padding=0)
    ax.set_offset(100.0)
    widget.show()
    qtbot.waitExposed(widget)
    widget.grab()
    spacing = ax._levels[0][0]
    px_per_s = ax.size().width() / 10.0
    first = math.ceil(95.0 / spacing) * spacing     # a major tick, its label just inside
    half = QtGui.QFontMetricsF(ax.style["tickFont"]).horizontalAdvance(
        ax.tickStrings([first - 100.0], 1.0, spacing)[0]) / 2
    ax.set_offset(first + 10.0 - (half + 2.0) / px_per_s)
    widget.grab()
    left = ax._label_left
    assert left is not None and 0 <= left < 6, left
    drawn = ax.redraws
    ax.set_offset(ax.offset + 3.0 / px_per_s)       # three pixels on: it would be cut
    widget.grab()
    assert ax.redraws == drawn + 1
    assert ax._label_left is None or ax._label_left >= 0
