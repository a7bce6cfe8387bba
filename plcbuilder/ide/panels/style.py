"""Look of the run panels: dark-on-light plots, one palette, small helpers.

Styling is applied per widget (never through pyqtgraph's global options), so
nothing else in the IDE changes look because the panels were imported.
"""

from __future__ import annotations

import PySide6  # noqa: F401  (pyqtgraph picks the binding imported first)
import pyqtgraph as pg
from PySide6 import QtCore, QtGui, QtWidgets

BACKGROUND = "#ffffff"
AXIS = "#5a5a5a"
TEXT = "#202020"
GRID = "#e3e3e3"
#: Line colours that read well on white (a colour-blind-friendly ordering).
PALETTE = ("#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#17becf",
           "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22", "#393b79", "#637939",
           "#8c6d31", "#843c39", "#7b4173", "#3182bd")
OUTPUT_COLOUR = "#1f77b4"
INPUT_COLOUR = "#2ca02c"
PROC_COLOUR = "#393b79"
MESSAGE_COLOUR = "#d62728"
FAULT_COLOUR = "#c62828"
LANE_BANDS = ("#f3f6fa", "#fafbfc")   # alternating logic-analyser lane backgrounds
LINE_WIDTH = 1.0          # wider lines leave Qt's fast path: 5-10x slower to draw
DOWNSAMPLE_FACTOR = 1.0   # samples per pixel column after peak downsampling


def colour(i: int) -> str:
    return PALETTE[i % len(PALETTE)]


def pen(c: str, width: float = LINE_WIDTH) -> QtGui.QPen:
    p = pg.mkPen(c, width=width)
    p.setCosmetic(True)
    return p


class TimeAxis(pg.AxisItem):
    """A time axis whose view coordinate 0 is the absolute time ``offset``.

    The live plots draw ``t - offset`` and keep their view range still while
    following, moving ``offset`` instead: a view range that changes every frame
    makes pyqtgraph paint twice per frame. The ticks and labels are placed at
    round absolute times, so the axis still reads in controller time.
    """

    def __init__(self, orientation: str = "bottom", **kw):
        super().__init__(orientation, **kw)
        self.offset = 0.0

    def set_offset(self, offset: float) -> None:
        if offset != self.offset:
            self.offset = float(offset)
            self.picture = None
            self.update()

    def tickValues(self, minVal, maxVal, size):  # noqa: N802
        o = self.offset
        levels = super().tickValues(minVal + o, maxVal + o, size)
        return [(spacing, [v - o for v in values]) for spacing, values in levels]

    def tickStrings(self, values, scale, spacing):  # noqa: N802
        o = self.offset
        return super().tickStrings([v + o for v in values], scale, spacing)


def time_axis() -> dict:
    """``axisItems`` for a plot with a live time axis at the bottom."""
    return {"bottom": TimeAxis("bottom")}


def style_plot(plot: pg.PlotItem, title: str | None = None, left: str | None = None,
               bottom: str | None = "time", left_units: str | None = None,
               bottom_units: str | None = "s", grid: tuple[bool, bool] = (True, True)
               ) -> pg.PlotItem:
    """Dark axes and labels, a light grid, a title."""
    for name in ("left", "bottom", "right", "top"):
        ax = plot.getAxis(name)
        ax.setPen(pg.mkPen(AXIS))
        ax.setTextPen(pg.mkPen(TEXT))
        ax.enableAutoSIPrefix(False)
        # an opaque, light grid on the major ticks only: lines with alpha
        # make every frame several times slower to paint
        ax.setTickPen(pg.mkPen(GRID))
        ax.setStyle(tickFont=_tick_font(), maxTickLevel=0, tickAlpha=255)
        ax.setTickDensity(1.6)
        ax.setZValue(-1000)     # grid lines under the curves (the ViewBox is at -100)
    if title:
        plot.setTitle(title, color=TEXT, size="10pt", bold=True)
    if left:
        plot.setLabel("left", left, units=left_units, color=TEXT)
    if bottom:
        plot.setLabel("bottom", bottom, units=bottom_units, color=TEXT)
    plot.getAxis("bottom").setGrid(255 if grid[0] else False)
    plot.getAxis("left").setGrid(255 if grid[1] else False)
    return plot


def _tick_font() -> QtGui.QFont:
    f = QtGui.QFont()
    f.setPointSizeF(8.5)
    return f


def legend(plot: pg.PlotItem, columns: int = 1) -> pg.LegendItem:
    lg = plot.addLegend(offset=(8, 8), labelTextColor=TEXT, labelTextSize="8pt",
                        brush=pg.mkBrush(255, 255, 255, 215), pen=pg.mkPen("#c8c8c8"),
                        colCount=columns)
    return lg


def new_curve(plot: pg.PlotItem, c: str, name: str | None = None, width: float = LINE_WIDTH,
              **kw) -> pg.PlotDataItem:
    """A live curve: clip-to-view and peak downsampling, set through the setters
    (pyqtgraph 0.14 refuses them as plot() arguments)."""
    item = pg.PlotDataItem(pen=pen(c, width), name=name, **kw)
    # peak downsampling keeps min and max of each pixel column: one sample a
    # pixel loses nothing visible (pyqtgraph's default draws five)
    item.opts["autoDownsampleFactor"] = DOWNSAMPLE_FACTOR
    item.setSkipFiniteCheck(True)
    plot.addItem(item)
    # after addItem, which applies the plot's own (context menu) modes to the item
    item.setClipToView(True)
    item.setDownsampling(auto=True, method="peak")
    return item


def plot_widget(axisItems: dict | None = None) -> pg.PlotWidget:  # noqa: N803
    w = pg.PlotWidget(background=BACKGROUND, axisItems=axisItems)
    w.setMinimumSize(160, 120)
    return w


def layout_widget() -> pg.GraphicsLayoutWidget:
    w = pg.GraphicsLayoutWidget()
    w.setBackground(BACKGROUND)
    w.setMinimumSize(160, 120)
    return w


def small_button(text: str, tip: str = "", checkable: bool = False) -> QtWidgets.QToolButton:
    b = QtWidgets.QToolButton()
    b.setText(text)
    b.setToolTip(tip)
    b.setCheckable(checkable)
    b.setAutoRaise(True)
    b.setToolButtonStyle(QtCore.Qt.ToolButtonStyle.ToolButtonTextOnly)
    return b
