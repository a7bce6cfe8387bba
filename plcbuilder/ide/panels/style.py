"""Look of the run panels: dark-on-light plots, one palette, small helpers.

Styling is applied per widget (never through pyqtgraph's global options), so
nothing else in the IDE changes look because the panels were imported.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import PySide6  # noqa: F401  (pyqtgraph picks the binding imported first)
import pyqtgraph as pg
from PySide6 import QtCore, QtGui, QtWidgets

Qt = QtCore.Qt

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
PROC_COLOUR = "#5a5fc8"     # reads on the light and the dark plot background
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

    #: a picture moved this far (pixels) is drawn again: a label that came
    #: fully into the axis on the right shows by then
    REDRAW_AFTER_PX = 16.0

    def __init__(self, orientation: str = "bottom", **kw):
        super().__init__(orientation, **kw)
        self.offset = 0.0
        self.drawn_offset: float | None = None   # the offset the picture was drawn at
        # per tick level when last worked out: (spacing, where its ticks start,
        # the first tick's number, how many), see _ticks_between
        self._levels: list[tuple[float, float, int, int]] = []
        self.redraws = 0
        #: the left edge (pixels) of the leftmost label drawn whole, when drawn
        self._label_left: float | None = None

    def set_offset(self, offset: float) -> None:
        """Follow: the axis now starts at absolute time ``offset``. While its
        ticks stay the same ones and the picture has moved less than
        ``REDRAW_AFTER_PX``, the picture drawn before is painted moved, not
        drawn again (the tick texts took a fifth of the IDE's processor time
        while a procedure ran at 1x with the plots shown)."""
        if offset == self.offset:
            return
        self.offset = float(offset)
        if self.picture is not None and not self._may_move():
            self.picture = None
        self.update()

    def shift_px(self) -> float:
        """How far the picture drawn at ``drawn_offset`` has to move now (pixels)."""
        if self.drawn_offset is None or self.orientation not in ("bottom", "top"):
            return 0.0
        span = self.range[1] - self.range[0]
        if not span:
            return 0.0
        return -(self.offset - self.drawn_offset) * self.size().width() / span

    def _may_move(self) -> bool:
        """Whether the picture drawn before still shows the axis, moved: the
        same ticks (and so the same texts), a move of a few pixels."""
        if self.drawn_offset is None or not self._levels or self._tickLevels is not None \
                or self.logMode or self.scale != 1.0 or self.orientation not in ("bottom", "top") \
                or abs(self.shift_px()) >= self.REDRAW_AFTER_PX:
            return False
        if self._label_left is not None and self._label_left + self.shift_px() < 0:
            return False        # the first label would be cut at the left ("66" read "6")
        lo, hi = sorted((self.range[0] + self.offset, self.range[1] + self.offset))
        return all(_ticks_between(lo, hi, spacing, first) == (k0, n)
                   for spacing, first, k0, n in self._levels)

    def paint(self, p, opt, widget):
        if self.picture is None:
            self.drawn_offset = self.offset
            self.redraws += 1
            super().paint(p, opt, widget)
            self._label_left = self._leftmost_label()
            return
        dx = self.shift_px()
        if not dx:
            self.picture.play(p)
            return
        p.save()
        p.setClipRect(self.boundingRect())
        p.translate(dx, 0)
        self.picture.play(p)
        p.restore()

    def _leftmost_label(self) -> float | None:
        """The left edge (pixels) of the leftmost tick label that is drawn
        whole (pyqtgraph leaves out one that would be cut)."""
        if self.orientation not in ("bottom", "top") or not self._levels:
            return None
        lo, hi = self.range
        span = hi - lo
        width = self.size().width()
        if not span or width <= 0:
            return None
        fm = QtGui.QFontMetricsF(self.style.get("tickFont") or QtGui.QFont())
        left = None
        texts = min(len(self._levels), 1 + int(self.style.get("maxTextLevel", 1)),
                    1 + int(self.style.get("maxTickLevel", 2)))
        for spacing, first, k0, n in self._levels[:texts]:
            if n <= 0:
                continue
            v = first + k0 * spacing - self.offset             # the level's first tick
            text = self.tickStrings([v], self.scale, spacing)[0]
            edge = (v - lo) * width / span - fm.horizontalAdvance(text) / 2
            if edge >= 0 and (left is None or edge < left):
                left = edge
        return left

    def tickValues(self, minVal, maxVal, size):  # noqa: N802
        """The ticks of each level (``tickSpacing``'s), at round absolute
        times, in view coordinates; a tick a higher level has is left out.
        (pyqtgraph's own spends most of its time in numpy on lists this short,
        and a following axis asks ten times a second.)"""
        o = self.offset
        if self.logMode or self.scale != 1.0:
            levels = super().tickValues(minVal + o, maxVal + o, size)
            return [(spacing, [v - o for v in values]) for spacing, values in levels]
        lo, hi = sorted((minVal + o, maxVal + o))
        out, seen, levels = [], [], []
        for spacing, start_at in self.tickSpacing(lo, hi, size):
            start = math.ceil((lo - start_at) / spacing) * spacing + start_at
            eps = spacing * 0.01
            values = []
            for i in range(int((hi - start) / spacing) + 1):
                v = start + i * spacing
                if not any(abs(v - u) <= eps for u in seen):
                    values.append(v)
            seen.extend(values)
            out.append((spacing, [v - o for v in values]))
            levels.append((spacing, start_at) + _ticks_between(lo, hi, spacing, start_at))
        self._levels = levels
        return out

    def tickStrings(self, values, scale, spacing):  # noqa: N802
        o = self.offset
        if self.logMode or scale != 1.0 or not spacing:
            return super().tickStrings([v + o for v in values], scale, spacing)
        return [_time_text(v + o, spacing) for v in values]

    def tickSpacing(self, minVal, maxVal, size):  # noqa: N802 - pyqtgraph's name
        """pyqtgraph's spacing, made wider (2×, 5×, 10× …) where the numbers
        would run together: late in a session a time is six digits and more
        ("2270972270972270972270 98" in a narrow dock). Called with absolute
        times (tickValues)."""
        levels = super().tickSpacing(minVal, maxVal, size)
        if not levels or self.orientation not in ("bottom", "top") or size <= 0 \
                or self.logMode or self.scale != 1.0:
            return levels
        fm = QtGui.QFontMetricsF(self.style.get("tickFont") or QtGui.QFont())
        span = abs(maxVal - minVal) or 1.0
        spacing, offset = levels[0]
        for factor in (1, 2, 5, 10, 20, 50, 100, 200, 500, 1000):
            s = spacing * factor
            widest = max(fm.horizontalAdvance(_time_text(v, s))
                         for v in (minVal, maxVal)) + 10
            if span / s * widest <= size:
                break
        return levels if factor == 1 else [(s, offset)]


def _time_text(t: float, spacing: float) -> str:
    """A tick's time with the decimals its spacing needs (pyqtgraph's own
    turns to six significant digits from 10000 on: 227097.1 s read "227097")."""
    places = max(0, math.ceil(-math.log10(spacing) - 1e-9)) if spacing < 1 else 0
    return f"{t:.{places}f}"


class SpacedAxis(pg.AxisItem):
    """A horizontal axis whose tick numbers never run together: where the
    spacing pyqtgraph picks leaves less room than the numbers need (a narrow
    plot, issue 23.16: "99.8100.0100.2"), it takes 2×, 5×, 10× … that."""

    def tickSpacing(self, minVal, maxVal, size):  # noqa: N802 - pyqtgraph's name
        levels = super().tickSpacing(minVal, maxVal, size)
        if not levels or self.orientation not in ("bottom", "top") or size <= 0:
            return levels
        spacing, offset = levels[0]
        fm = QtGui.QFontMetricsF(self.style.get("tickFont") or QtGui.QFont())
        widest = max(fm.horizontalAdvance(t) for t in self.tickStrings(
            [minVal, maxVal, (minVal + maxVal) / 2], self.scale, spacing)) + 10
        span = abs(maxVal - minVal) or 1.0
        for factor in (1, 2, 5, 10, 20, 50, 100):
            if span / (spacing * factor) * widest <= size:
                break
        return [(spacing * factor, offset)]


def _ticks_between(lo: float, hi: float, spacing: float, first: float) -> tuple[int, int]:
    """The ticks ``first + k * spacing`` from lo to hi: (the first k, how many)."""
    k0 = math.ceil((lo - first) / spacing)
    return k0, max(0, math.floor((hi - first) / spacing) - k0 + 1)


def time_axis() -> dict:
    """``axisItems`` for a plot with a live time axis at the bottom."""
    return {"bottom": TimeAxis("bottom")}


def style_plot(plot: pg.PlotItem, title: str | None = None, left: str | None = None,
               bottom: str | None = "time", left_units: str | None = None,
               bottom_units: str | None = "s", grid: tuple[bool, bool] = (True, True)
               ) -> pg.PlotItem:
    """Axes, labels and a grid in the theme's colours, a title."""
    c = plot_colours()
    for name in ("left", "bottom", "right", "top"):
        ax = plot.getAxis(name)
        ax.setPen(pg.mkPen(c.axis))
        ax.setTextPen(pg.mkPen(c.text))
        ax.enableAutoSIPrefix(False)
        # an opaque, light grid on the major ticks only: lines with alpha
        # make every frame several times slower to paint
        ax.setTickPen(pg.mkPen(c.grid))
        ax.setStyle(tickFont=_tick_font(), maxTickLevel=0, tickAlpha=255)
        ax.setTickDensity(1.6)
        ax.setZValue(-1000)     # grid lines under the curves (the ViewBox is at -100)
    if title:
        plot.setTitle(title, color=c.text, size="10pt", bold=True)
    if left:
        plot.setLabel("left", left, units=left_units, color=c.text)
    if bottom:
        plot.setLabel("bottom", bottom, units=bottom_units, color=c.text)
    plot.getAxis("bottom").setGrid(255 if grid[0] else False)
    plot.getAxis("left").setGrid(255 if grid[1] else False)
    return plot


def _tick_font() -> QtGui.QFont:
    f = QtGui.QFont()
    f.setPointSizeF(8.5)
    return f


class Legend(pg.LegendItem):
    """A legend that draws no frame while it has no rows (an empty one showed as a
    small stray box in the plot's corner until the first curve came)."""

    def paint(self, p, *args):
        if self.items:
            super().paint(p, *args)


def new_legend(plot: pg.PlotItem, offset: tuple[int, int], columns: int = 1) -> Legend:
    """A :class:`Legend` in the theme's look on ``plot``'s view (a positive offset
    from its top left corner, a negative one from the right)."""
    c = plot_colours()
    lg = Legend(offset=offset, labelTextColor=c.text, labelTextSize="8pt",
                brush=pg.mkBrush(*c.legend_back), pen=pg.mkPen(c.legend_border),
                colCount=columns)
    lg.setParentItem(plot.vb)
    return lg


def legend(plot: pg.PlotItem, columns: int = 1) -> pg.LegendItem:
    """The plot's legend (what ``addLegend`` makes, as a :class:`Legend`), in
    the plot's title row, right of the title: never over a curve (issue 23.16).
    It takes as many columns as fit beside the title (``columns`` at least one
    row's worth is not guaranteed); the title row grows for more rows."""
    if plot.legend is None:
        c = plot_colours()
        lg = TitleLegend(plot, labelTextColor=c.text, labelTextSize="8pt", colCount=columns,
                         frame=False)
        plot.legend = lg
    return plot.legend


#: the height of a plot's title row (pyqtgraph's own)
TITLE_ROW = 30


class TitleLegend(Legend):
    """A legend in its plot's title row, right-aligned, beside the left-aligned
    title, with as many columns as fit there; when even one column does not
    fit beside the title, it goes under the title (the title row grows)."""

    def __init__(self, plot: pg.PlotItem, **kw):
        super().__init__(offset=None, **kw)
        self.plot = plot
        self.layout.setContentsMargins(2, 0, 2, 0)
        self.layout.setVerticalSpacing(0)
        self.setParentItem(plot)
        self._fitted = None
        title = plot.titleLabel                 # at the left: the legend takes the right
        title.opts["justify"] = "left"
        title.setText(title.text)
        title.resizeEvent(None)
        self._detached = False
        plot.vb.sigResized.connect(self._on_resized)
        plot.geometryChanged.connect(self._on_resized)

    def _on_resized(self, *_a) -> None:
        if not self._detached:
            self.fit()

    def detach(self) -> None:
        """Take the legend off its plot: its rows go, the title row gets its
        own height back and a resize no longer places it."""
        self.clear()
        self._detached = True
        for sig in (self.plot.vb.sigResized, self.plot.geometryChanged):
            try:
                sig.disconnect(self._on_resized)
            except (RuntimeError, TypeError):
                pass
        scene = self.scene()
        if scene is not None:
            scene.removeItem(self)

    def addItem(self, item, name):  # noqa: N802 - pyqtgraph's name
        super().addItem(item, name)
        self.fit(force=True)
        # (a new label knows its width once laid out: fitted again then)
        QtCore.QTimer.singleShot(0, self, self._fit_again)

    def _fit_again(self) -> None:
        if self._detached:
            return
        try:
            self.fit(force=True)
        except RuntimeError:          # the plot went with its window meanwhile
            pass

    def removeItem(self, item):  # noqa: N802 - pyqtgraph's name
        super().removeItem(item)
        self.fit(force=True)

    def clear(self):
        super().clear()
        self.fit(force=True)

    def fit(self, force: bool = False) -> None:
        """Columns and place for the plot's width now."""
        plot = self.plot
        title = plot.titleLabel
        shown = title.isVisible()
        view_left = plot.vb.pos().x()
        right = plot.width() - 6
        left = view_left + (title.item.boundingRect().width() + 12 if shown else 0)
        room = max(40.0, right - left)
        widths = [s.width() + lab.width() + 6 for s, lab in self.items]
        key = (round(room), round(right), tuple(round(w) for w in widths), shown)
        if key == self._fitted and not force:
            return
        self._fitted = key
        cols = self._columns(widths, room)
        under = False
        if shown and widths:            # under the title when that takes fewer rows
            below = self._columns(widths, max(40.0, right - view_left))
            rows = -(-len(widths) // cols)
            if self._row_width(widths, cols) > room or -(-len(widths) // below) < rows:
                under, cols = True, below
        if cols != self.columnCount:
            self.setColumnCount(cols)
        self.updateSize()
        h = self.height() if self.items else 0
        y = TITLE_ROW - 6 if under else (max(0.0, (TITLE_ROW - h) / 2) if shown else 2)
        row = TITLE_ROW if shown else 0
        plot.layout.setRowFixedHeight(0, max(row, y + h + 2) if self.items else row)
        if shown:
            title.setMaximumHeight(TITLE_ROW)
        # right-aligned; a key wider than the room right of the axis goes over
        # the axis column (in the title row) rather than out of the plot
        self.setPos(max(0.0, right - self.width()), y)

    @classmethod
    def _columns(cls, widths: list, room: float) -> int:
        """The most columns whose rows fit in ``room`` (at least one)."""
        cols = max(1, len(widths))
        while cols > 1 and cls._row_width(widths, cols) > room:
            cols -= 1
        return cols

    @staticmethod
    def _row_width(widths: list, cols: int) -> float:
        if not widths:
            return 0.0
        return sum(max(widths[i::cols]) for i in range(cols))


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


def plot_widget(axisItems: dict | None = None, menu: bool = True) -> pg.PlotWidget:  # noqa: N803
    """A plot in the theme's colours; ``menu``: pyqtgraph's own right-click
    menu (a time plot has none: pyqtgraph then does not build its menus, a
    fifth of making the run panels)."""
    w = ThemedPlotWidget(background=plot_colours().background, axisItems=axisItems,
                         enableMenu=menu)
    w.setMinimumSize(160, 120)
    return w


def layout_widget() -> pg.GraphicsLayoutWidget:
    w = ThemedLayoutWidget()
    w.setBackground(plot_colours().background)
    w.setMinimumSize(160, 120)
    return w


# ------------------------------------------------------------ the theme
@dataclass(frozen=True)
class PlotColours:
    """The colours a plot takes from the window's theme."""
    background: str
    axis: str
    text: str
    grid: str
    lane_bands: tuple[str, str]
    legend_back: tuple[int, int, int, int]
    legend_border: str
    label_fill: tuple[int, int, int, int]
    #: the second trace of a comparison, drawn dashed over the first
    overlay: str = "#c2185b"
    #: watched variables (``M80.sens``): their lanes, apart from the pins'
    variable: str = "#a35200"


LIGHT_PLOTS = PlotColours(BACKGROUND, AXIS, TEXT, GRID, LANE_BANDS, (255, 255, 255, 215),
                          "#c8c8c8", (255, 255, 255, 200), "#c2185b", "#a35200")
DARK_PLOTS = PlotColours("#1e1f22", "#9da0a6", "#dfe1e5", "#34363a", ("#26292e", "#212327"),
                         (43, 45, 48, 215), "#4a4d52", (30, 31, 34, 200), "#f48fb1",
                         "#ffb74d")


def is_dark() -> bool:
    """True when the application's palette is a dark one (the dark theme)."""
    app = QtWidgets.QApplication.instance()
    if app is None:
        return False
    return QtWidgets.QApplication.palette().color(QtGui.QPalette.ColorRole.Base).lightness() < 128


def plot_colours() -> PlotColours:
    return DARK_PLOTS if is_dark() else LIGHT_PLOTS


def dashed_pen(c: str, width: float = 1.6) -> QtGui.QPen:
    """The pen of a compared trace's curves: dashed, a little wider than the first's."""
    p = pg.mkPen(c, width=width, style=Qt.PenStyle.DashLine)
    p.setCosmetic(True)
    return p


def restyle(widget) -> None:
    """Give a plot widget and its plots the current theme's colours."""
    c = plot_colours()
    widget.setBackground(c.background)
    scene = widget.scene() if hasattr(widget, "scene") else None
    if scene is None:
        return
    for item in scene.items():
        if isinstance(item, pg.PlotItem):
            _restyle_plot(item, c)
        elif isinstance(item, pg.LegendItem):
            item.setBrush(pg.mkBrush(*c.legend_back))
            item.setPen(pg.mkPen(c.legend_border))
            item.setLabelTextColor(c.text)
        elif isinstance(item, pg.TextItem) and item.fill.style() != Qt.BrushStyle.NoBrush:
            item.fill = pg.mkBrush(*c.label_fill)
            item.update()


def _restyle_plot(plot: pg.PlotItem, c: PlotColours) -> None:
    for name in ("left", "bottom", "right", "top"):
        ax = plot.getAxis(name)
        ax.setPen(pg.mkPen(c.axis))
        ax.setTextPen(pg.mkPen(c.text))
        ax.setTickPen(pg.mkPen(c.grid))
        if ax.labelText or ax.labelUnits:
            ax.setLabel(ax.labelText, ax.labelUnits, ax.labelUnitPrefix,
                        **dict(ax.labelStyle, color=c.text))
            if not ax.label.isVisible():
                ax.showLabel(False)
    title = plot.titleLabel
    if title.text:
        title.setText(title.text, **dict(title.opts, color=c.text))


class _Themed:
    """Follows the application's theme: on a palette change, restyle."""

    def changeEvent(self, event) -> None:  # noqa: N802 - Qt override
        super().changeEvent(event)
        if event.type() == QtCore.QEvent.Type.PaletteChange:
            restyle(self)
            for hook in getattr(self, "theme_hooks", ()):
                hook()


class ThemedPlotWidget(_Themed, pg.PlotWidget):
    """A PlotWidget in the window's theme."""


class ThemedLayoutWidget(_Themed, pg.GraphicsLayoutWidget):
    """A GraphicsLayoutWidget in the window's theme."""


def small_button(text: str, tip: str = "", checkable: bool = False) -> QtWidgets.QToolButton:
    b = QtWidgets.QToolButton()
    b.setText(text)
    b.setToolTip(tip)
    b.setCheckable(checkable)
    b.setAutoRaise(True)
    b.setToolButtonStyle(QtCore.Qt.ToolButtonStyle.ToolButtonTextOnly)
    return b
