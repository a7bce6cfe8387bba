"""The axes: machine positions and velocities over time, and the XY path."""

from __future__ import annotations

import math

import numpy as np
from PySide6 import QtCore, QtWidgets  # before pyqtgraph (it takes the loaded binding)
import pyqtgraph as pg  # noqa: E402,I001

from plcbuilder.ide.panels import style
from plcbuilder.ide.panels.model import AXES, RunModel
from plcbuilder.ide.panels.plots.timebase import TimeBase, TimePanel, YFit, shift_item

Qt = QtCore.Qt


class AxesPanel(TimePanel):
    """Machine positions and velocities over time, and the XY path."""

    PATH_POINTS = 6000

    def __init__(self, model: RunModel, timebase: TimeBase, on_clear=None, parent=None):
        super().__init__(model, timebase, on_clear, parent)
        self.widget = style.layout_widget()
        self.pos_plot = self.widget.addPlot(row=0, col=0, axisItems=style.time_axis(),
                                            enableMenu=False)
        # (the titles say what: the axis labels only the unit, which fits the
        # height of a short plot; "position (mm)" ran into "velocity (mm/s)")
        style.style_plot(self.pos_plot, title="Machine position", left="mm",
                         left_units=None, bottom=None, bottom_units=None)
        self.vel_plot = self.widget.addPlot(row=1, col=0, axisItems=style.time_axis(),
                                            enableMenu=False)
        style.style_plot(self.vel_plot, title="Velocity", left="mm/s",
                         bottom="time (s)", bottom_units=None)
        for p in (self.pos_plot, self.vel_plot):
            self.add_time_plot(p)
            p.setMouseEnabled(x=True, y=False)
            p.getAxis("left").setWidth(56)
        self._fit = (YFit(self.pos_plot, minimum=10.0), YFit(self.vel_plot, minimum=10.0))
        # one legend names the axes' colours for both plots (the same in each)
        self.pos_legend = style.legend(self.pos_plot, columns=3)

        self.xy_widget = style.plot_widget({"bottom": style.SpacedAxis("bottom")})
        self.xy = self.xy_widget.getPlotItem()
        style.style_plot(self.xy, title="XY path", left="Y (mm)", bottom="X (mm)",
                         bottom_units=None)
        for name in ("left", "bottom"):
            self.xy.getAxis(name).enableAutoSIPrefix(False)
        self.xy.setAspectLocked(True)
        self.xy.hideButtons()
        self.xy_path = pg.PlotDataItem(pen=style.pen(style.colour(0), 1.8))
        self.xy_path.setSkipFiniteCheck(True)
        self.xy.addItem(self.xy_path)
        self.xy_here = pg.ScatterPlotItem(size=11, symbol="o", pen=pg.mkPen("#ffffff", width=1.5),
                                          brush=pg.mkBrush(style.MESSAGE_COLOUR))
        self.xy.addItem(self.xy_here)
        self._pos: dict[int, pg.PlotDataItem] = {}
        self._vel: dict[int, pg.PlotDataItem] = {}
        self._path_version = -1

        # side by side where the dock is wide enough for both plots, else the
        # XY path folded away at the right (its handle stays, to drag it out):
        # the panel asks no more width than the other run panels, so making it
        # never widens the dock it joins (the plots' minimums summed to 324 px
        # and widened a narrower dock), and the time plots are never cut
        self.widget.setMinimumWidth(120)
        self.xy_widget.setMinimumWidth(90)
        self._narrow = False
        self.split = split = QtWidgets.QSplitter(Qt.Orientation.Horizontal)
        split.addWidget(self.widget)
        split.addWidget(self.xy_widget)
        split.setStretchFactor(0, 3)
        split.setStretchFactor(1, 2)
        lay = QtWidgets.QVBoxLayout(self)
        lay.setContentsMargins(0, 0, 0, 0)
        lay.setSpacing(0)
        lay.addWidget(self.toolbar)
        lay.addWidget(split, 1)

    def side_by_side_width(self) -> int:
        """The least width that shows both plots whole side by side."""
        # (the plots' scenes know it; their views' own hints are a few pixels)
        frames = sum(2 * w.frameWidth() for w in (self.widget, self.xy_widget))
        return (math.ceil(self.widget.ci.minimumWidth()) + math.ceil(self.xy.minimumWidth())
                + frames + self.split.handleWidth())

    def resizeEvent(self, event) -> None:  # noqa: N802 - Qt override
        narrow = event.size().width() < self.side_by_side_width()
        if narrow != self._narrow:
            self._narrow = narrow
            self.split.setSizes([1, 0] if narrow else [3, 2])
            self.split.handle(1).setToolTip("Drag to show the XY path" if narrow else "")
        super().resizeEvent(event)

    def xy_folded(self) -> bool:
        """True while the XY path is folded away (a narrow dock)."""
        return self.split.sizes()[1] == 0

    def draw(self, a: int, b: int, t0: float, t1: float) -> None:
        m = self.model
        na = len(AXES)
        for ax in m.active_axes():
            if ax not in self._pos:
                self._pos[ax] = style.new_curve(self.pos_plot, style.colour(ax), AXES[ax])
                self._vel[ax] = style.new_curve(self.vel_plot, style.colour(ax))
        t = self.x(a, b)
        pos, vel = [], []
        for ax, item in self._pos.items():
            pos.append(m.axes.view(ax)[a:b])
            vel.append(m.axes.view(na + ax)[a:b])
            item.setData(t, self.hold(pos[-1]))
            self._vel[ax].setData(t, self.hold(vel[-1]))
        self._fit[0].fit(pos)
        self._fit[1].fit(vel)
        if m.version != self._path_version:
            self._path_version = m.version
            x = m.axes.view(0)
            y = m.axes.view(1)
            step = max(1, len(x) // self.PATH_POINTS)
            if len(x):
                xs, ys = x[::step], y[::step]
                if step > 1:            # always end at the newest point
                    xs, ys = np.append(xs, x[-1]), np.append(ys, y[-1])
                self.xy_path.setData(xs, ys)
                self.xy_here.setData([x[-1]], [y[-1]])
            else:
                self.xy_path.setData([], [])
                self.xy_here.setData([], [])

    def watched(self) -> list:
        return [self.model.axes]

    def shift(self, dx: float) -> None:
        for d in (self._pos, self._vel):
            for item in d.values():
                shift_item(item, dx)

    def model_cleared(self) -> None:
        self._path_version = -1
        for f in self._fit:
            f.reset()
        for d, plot in ((self._pos, self.pos_plot), (self._vel, self.vel_plot)):
            for item in d.values():
                plot.removeItem(item)
            d.clear()
