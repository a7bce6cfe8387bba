"""What every time plot shares: the time window (:class:`TimeBase`), its toolbar,
the y-range fit and :class:`TimePanel`, the base of the plots."""

from __future__ import annotations

import time
from typing import Callable, Optional

import numpy as np
from PySide6 import QtCore, QtWidgets  # before pyqtgraph (it takes the loaded binding)
import pyqtgraph as pg  # noqa: E402,I001

from plcbuilder.ide.panels import style
from plcbuilder.ide.panels.model import RunModel

Signal = QtCore.Signal


class TimeBase(QtCore.QObject):
    """The shared time window of every time plot: follow the newest sample
    over ``window`` seconds (0 = all that is kept), or stay where the user
    panned to."""

    sig_changed = Signal()
    """Follow or the window length changed."""

    WINDOWS = (("1 s", 1.0), ("2 s", 2.0), ("5 s", 5.0), ("10 s", 10.0), ("30 s", 30.0),
               ("60 s", 60.0), ("All", 0.0))

    def __init__(self, window: float = 10.0, parent=None):
        super().__init__(parent)
        self.follow = True
        self.window = float(window)

    def set_follow(self, on: bool) -> None:
        if bool(on) != self.follow:
            self.follow = bool(on)
            self.sig_changed.emit()

    def set_window(self, seconds: float) -> None:
        self.window = float(seconds)
        self.follow = True
        self.sig_changed.emit()

    def span(self, model: RunModel) -> tuple[float, float]:
        """The followed time range [t0, t1] in seconds."""
        t = model.time.view()
        first = float(t[0]) if len(t) else 0.0
        t1 = model.t_end
        if self.window > 0:
            # fill the window from the left, then scroll
            t0 = max(t1 - self.window, first)
            t1 = max(t1, t0 + self.window)
        else:
            t0 = first
        if t1 - t0 < 1e-3:
            t1 = t0 + 1.0
        return t0, t1


class TimeToolbar(QtWidgets.QWidget):
    """Follow, window length and clear, shared by every time plot."""

    def __init__(self, timebase: TimeBase, on_clear: Optional[Callable[[], None]] = None,
                 parent=None):
        super().__init__(parent)
        self.timebase = timebase
        outer = QtWidgets.QVBoxLayout(self)
        outer.setContentsMargins(4, 2, 4, 2)
        outer.setSpacing(2)
        lay = QtWidgets.QHBoxLayout()
        lay.setSpacing(4)
        outer.addLayout(lay)
        self.follow = style.small_button("Follow", "Scroll with the newest sample "
                                         "(panning or zooming a plot stops following)", True)
        self.follow.toggled.connect(timebase.set_follow)
        lay.addWidget(self.follow)
        self.window = QtWidgets.QComboBox()
        self.window.setToolTip("How much time the plots show while following")
        for text, secs in TimeBase.WINDOWS:
            self.window.addItem(text, secs)
        self.window.activated.connect(lambda i: timebase.set_window(self.window.itemData(i)))
        lay.addWidget(QtWidgets.QLabel("Window"))
        lay.addWidget(self.window)
        #: the plot's own controls, beside the buttons
        self.extra = QtWidgets.QHBoxLayout()
        self.extra.setSpacing(4)
        lay.addLayout(self.extra)
        lay.addStretch(1)
        #: rows under the buttons for what is shown only at times: beside them,
        #: it widened the dock. What is on show has a row of its own (beside
        #: the links, a comparison's text was cut at the default width) ...
        self.banner_row = QtWidgets.QHBoxLayout()
        outer.addLayout(self.banner_row)
        #: ... and Back to Live, Clear Comparison the row under it
        self.shown_row = QtWidgets.QHBoxLayout()
        self.shown_row.setSpacing(8)
        outer.addLayout(self.shown_row)
        if on_clear is not None:
            clear = style.small_button("Clear", "Forget the recorded samples and messages")
            clear.clicked.connect(on_clear)
            lay.addWidget(clear)
        timebase.sig_changed.connect(self._sync)
        self._sync()

    def _sync(self) -> None:
        self.follow.blockSignals(True)
        self.follow.setChecked(self.timebase.follow)
        self.follow.blockSignals(False)
        for i in range(self.window.count()):
            if self.window.itemData(i) == self.timebase.window:
                self.window.setCurrentIndex(i)


def _time_axis(plot: pg.PlotItem) -> None:
    plot.hideButtons()
    plot.setMenuEnabled(False)


class YFit:
    """Keeps a plot's y range around its data, with hysteresis: the range
    changes only when data leaves it or fills less than half of it (a range
    change costs a second paint)."""

    def __init__(self, plot: pg.PlotItem, pad: float = 0.08, minimum: float = 1.0):
        self.plot = plot
        self.pad = pad
        self.minimum = minimum
        self.range: Optional[tuple[float, float]] = None
        #: a legend in the plot's top corner: the range leaves room above the
        #: data for it, so it never covers a curve
        self.legend: Optional[pg.LegendItem] = None
        self._share = 0.0

    def legend_share(self) -> float:
        """The part of the plot's height the legend takes (0 without one)."""
        lg = self.legend
        if lg is None or not lg.isVisible() or not lg.items:
            return 0.0
        h = self.plot.getViewBox().height()
        if h <= 1:
            return 0.0
        return min(0.6, (lg.boundingRect().height() + 10) / h)

    def fit(self, arrays) -> None:
        lo, hi = np.inf, -np.inf
        for a in arrays:
            if len(a):
                lo = min(lo, float(a.min()))
                hi = max(hi, float(a.max()))
        if not np.isfinite(lo):
            return
        if hi - lo < self.minimum:
            mid = (hi + lo) / 2
            lo, hi = mid - self.minimum / 2, mid + self.minimum / 2
        cur = self.range
        share = self.legend_share()
        if cur is not None and abs(share - self._share) < 0.02 and cur[0] <= lo and \
                hi <= cur[1] - (cur[1] - cur[0]) * self._share and \
                (hi - lo) >= 0.5 * (cur[1] - cur[0]) * (1 - self._share) / (1 + 2 * self.pad):
            return
        pad = (hi - lo) * self.pad
        lo, hi = lo - pad, hi + pad
        hi += (hi - lo) * share / (1 - share)          # the legend's room above the data
        self._share = share
        self.range = (lo, hi)
        self.plot.setYRange(*self.range, padding=0)

    def reset(self) -> None:
        self.range = None
        self._share = 0.0


class TimePanel(QtWidgets.QWidget):
    """A panel of plots over time, redrawn by :meth:`refresh` from the model.

    The plots' x coordinate is time relative to ``offset`` (the right edge
    while following), so that following moves the data, not the view; the
    :class:`~plcbuilder.ide.panels.style.TimeAxis` labels absolute time.

    Redraws cost only what changed: a panel redraws its curves (``setData``)
    when the values it shows changed, its view changed or the model started
    over. When only time advanced (every new sample equals the last one
    drawn), the curves are not touched: they were drawn holding their last
    value up to a horizon ahead of the newest sample, and following just
    moves them left (``setPos``) and the time axis with them, at most
    ``SCROLL_FPS`` times a second, and only while something runs.
    """

    sig_dirty = Signal()
    """The view changed (window, follow, lanes, pins): a redraw is due."""

    SCROLL_FPS = 10         # time-only moves a second (at most, give or take SCROLL_SLACK)
    SCROLL_SLACK = 0.25     # a move this part of its period early is done at once
    HORIZON = 0.25          # curves hold their last value this part of the window ahead

    def __init__(self, model: RunModel, timebase: TimeBase,
                 on_clear: Optional[Callable[[], None]] = None, parent=None):
        super().__init__(parent)
        self.model = model
        self.timebase = timebase
        self.toolbar = TimeToolbar(timebase, on_clear)
        self._time_plots: list[pg.PlotItem] = []
        self._time_axes: list[style.TimeAxis] = []
        self._drawn_version = -1
        self._epoch = model.epoch
        self._view_dirty = True
        self._setting_range = False
        self._xrange: Optional[tuple[float, float]] = None
        self.offset = 0.0
        self.frames = 0             # full redraws
        self.moves = 0              # time-only moves
        self._drawn_offset = 0.0    # the offset the curves' data were drawn at
        self._horizon = 0.0         # absolute time the drawn curves hold up to
        self._extend = 0.0          # x (relative) the next draw holds curves up to (0: none)
        self._base: list = []       # the newest row of each watched buffer at the last draw
        self._checked = 0           # model rows compared with _base so far
        self._last_move = 0.0
        self._move_due: Optional[float] = None   # a time-only move put off: due in (s)
        #: a second trace drawn over this one (plots/overlay.py), or None
        self.comparison = None
        timebase.sig_changed.connect(self._mark_dirty)

    # ------------------------------------------------------------- plumbing
    def add_time_plot(self, plot: pg.PlotItem) -> None:
        """Make ``plot`` (created with ``style.time_axis()``) follow the time base."""
        _time_axis(plot)
        vb = plot.getViewBox()
        vb.disableAutoRange(axis=pg.ViewBox.XAxis)
        vb.sigRangeChangedManually.connect(self._user_moved)
        vb.sigXRangeChanged.connect(self._mark_dirty)
        if self._time_plots:
            plot.setXLink(self._time_plots[0])
        self._time_plots.append(plot)
        # the value axis stays while time moves: drawn into a pixmap once (again
        # when its ticks change), not by its Python paint at every move
        plot.getAxis("left").setCacheMode(_CACHED)
        ax = plot.getAxis("bottom")
        if isinstance(ax, style.TimeAxis):
            self._time_axes.append(ax)

    def show_span(self, t0: float, t1: float) -> None:
        """Stop following and show the absolute time range [t0, t1] (seconds)."""
        self.timebase.set_follow(False)
        if self._time_plots:
            self.offset, self._xrange = 0.0, None
            self._time_plots[0].setXRange(t0, t1, padding=0)
        self._mark_dirty()

    def _user_moved(self, mask) -> None:
        if mask is None or (isinstance(mask, (list, tuple)) and mask and mask[0]):
            self._xrange = None
            self.timebase.set_follow(False)

    def _mark_dirty(self, *args) -> None:
        if not self._setting_range:
            self._view_dirty = True
            self.sig_dirty.emit()

    def visible_span(self) -> tuple[float, float]:
        """The absolute time range [t0, t1] (seconds) the plots show."""
        if self.timebase.follow or not self._time_plots:
            return self.timebase.span(self.model)
        (r0, r1), _ = self._time_plots[0].getViewBox().viewRange()
        return r0 + self.offset, r1 + self.offset

    def x(self, a: int, b: int) -> np.ndarray:
        """Sample times [a, b) in the plots' x coordinate; while following, one
        more point at the horizon (see :meth:`hold`)."""
        t = self.model.time.view()[a:b] - self.offset
        if self._extend and len(t):
            t = np.append(t, self._extend)
        return t

    def hold(self, y: np.ndarray) -> np.ndarray:
        """``y`` with its last value held to the horizon (pairs with :meth:`x`)."""
        if self._extend and len(y):
            return np.append(y, y[-1])
        return y

    def model_end(self, m) -> float:
        """The x of model ``m``'s newest sample or watched variable's change (where
        a watched variable's last value is held to when not following)."""
        return max(m.t_end, m.watched.t_end()) - self.offset

    def watched(self) -> list:
        """The model's ring buffers this panel shows (a change in them redraws)."""
        return []

    def data_changed(self) -> bool:
        """Whether a value this panel shows changed since it last drew (not
        only time: new samples equal to the last one drawn change nothing)."""
        m = self.model
        total = m.time.total
        n = total - self._checked
        if n <= 0:
            return False
        if not self._base or n >= len(m):
            return True
        for rb, base in zip(self.watched(), self._base):
            new = rb.views(last=n)
            if new.shape[1] and bool((new != base[:, None]).any()):
                return True
        self._checked = total
        return False

    def refresh(self, force: bool = False, moving: bool = True) -> bool:
        """Redraw from the model what changed; returns whether it drew or moved.
        ``moving``: time may scroll (something runs); when False, samples
        that only advance time leave the plots still."""
        m = self.model
        if m.epoch != self._epoch:
            self._epoch = m.epoch
            self.model_cleared()
            force = True
        if not force and not self._view_dirty:
            if m.version == self._drawn_version:
                # nothing new; a move put off earlier may be due now
                return self._move(moving) if self._move_due is not None else False
            if self.data_changed():
                force = True
            else:
                self._drawn_version = m.version
                return self._move(moving)
        return self._redraw()

    def _move(self, moving: bool) -> bool:
        """Only time advanced: move the curves, not their data; at most
        ``SCROLL_FPS`` times a second, and only by a pixel or more (a window
        of a minute moves less than a pixel in a tenth of a second)."""
        if not self.timebase.follow or not moving or not self._time_plots:
            self._move_due = None
            return False
        now = time.monotonic()
        wait = self._last_move + 1.0 / self.SCROLL_FPS - now
        # a move due a moment from now is done now: new samples arrive about
        # as often as moves may be done, and a timer for the little left was a
        # second redraw tick for each move
        if wait > self.SCROLL_SLACK / self.SCROLL_FPS:
            self._move_due = wait
            return False
        t0, t1 = self.visible_span()
        if t1 > self._horizon:
            return self._redraw()
        if t1 == self.offset:
            self._move_due = None
            return False
        px = self.pixels_per_second(t1 - t0)
        if px > 0 and (t1 - self.offset) * px < 1.0:
            # less than a pixel: nothing to see yet (due when it makes one, at 1x)
            self._move_due = max(1.0 / self.SCROLL_FPS, (1.0 - (t1 - self.offset) * px) / px)
            return False
        self._last_move = now
        self._move_due = None
        self.offset = t1
        self.shift(self._drawn_offset - t1)
        for ax in self._time_axes:
            ax.set_offset(t1)
        self.moves += 1
        return True

    def pixels_per_second(self, span: float) -> float:
        """The plots' width in pixels over ``span`` seconds (0: not laid out)."""
        if span <= 0 or not self._time_plots:
            return 0.0
        return self._time_plots[0].getViewBox().width() / span

    def move_due(self) -> Optional[float]:
        """Seconds until a time-only move that was put off is due (None: none
        is): the redraw timer comes back then, not at every frame."""
        return self._move_due

    def _redraw(self) -> bool:
        m = self.model
        t0, t1 = self.visible_span()
        follow = self.timebase.follow and bool(self._time_plots)
        if follow:
            self.offset = t1
            rng = (t0 - t1, 0.0)
            if rng != self._xrange:
                self._setting_range = True
                try:
                    self._time_plots[0].setXRange(*rng, padding=0)
                finally:
                    self._setting_range = False
                self._xrange = rng
            ahead = max(0.05, (t1 - t0) * self.HORIZON)
            self._extend = ahead
            self._horizon = t1 + ahead
        else:
            self._extend = 0.0
            self._horizon = m.t_end
        for ax in self._time_axes:
            ax.set_offset(self.offset)
        a, b = m.window(t0, t1)
        self._drawn_offset = self.offset
        self.shift(0.0)
        self.draw(a, b, t0, t1)
        self._drawn_version = m.version
        self._base = [rb.latest() for rb in self.watched()] if len(m) else []
        self._checked = m.time.total
        self._view_dirty = False
        self._move_due = None
        self._last_move = time.monotonic()
        self.frames += 1
        return True

    def set_comparison(self, comparison) -> None:
        """Draw ``comparison`` (plots/overlay.py) over this panel's own curves
        from the next redraw on; None removes it."""
        self.comparison = comparison
        self.comparison_changed()
        self._mark_dirty()

    def comparison_changed(self) -> None:
        """Make or remove the items that draw ``self.comparison``."""

    def shift(self, dx: float) -> None:
        """Move the drawn curves ``dx`` along x (time-only moves)."""

    def draw(self, a: int, b: int, t0: float, t1: float) -> None:  # pragma: no cover
        raise NotImplementedError

    def flush(self) -> None:
        """Move queued table rows into their views (called by the redraw timer)."""

    def model_cleared(self) -> None:
        """The model forgot its samples (cleared, or the controller started over)."""

    def set_pin_names(self, inputs: dict[int, str], outputs: dict[int, str]) -> None:
        pass


def shift_item(item: pg.GraphicsObject, dx: float, y: float = 0.0) -> None:
    """Move a drawn item to (dx, y) and nothing else. ``PlotDataItem.setPos``
    also re-clips, re-downsamples and re-sets its curve's data (a new path to
    build and paint) for every move; the data drawn up to the horizon
    already cover the view until the next redraw, so a time-only move keeps
    them and only forgets the item's cached view rectangle (a redraw, or a
    view change, clips to the view as it is then)."""
    if item.cacheMode() != _CACHED:
        # painted once into a pixmap of the view; a move blits it (and paints
        # only what comes into view) instead of calling the item's Python paint
        item.setCacheMode(_CACHED)
        # and moved without geometry change notices: Qt called the item's
        # Python itemChange twice a move, which told the view its bounds
        # changed (they do not: the x range is the time window's; a new
        # curve's data tells it anyway)
        item.setFlag(_GEOMETRY_CHANGES, False)
    pg.GraphicsObject.setPos(item, dx, y)
    item.viewTransformChanged()


_CACHED = QtWidgets.QGraphicsItem.CacheMode.DeviceCoordinateCache
_GEOMETRY_CHANGES = QtWidgets.QGraphicsItem.GraphicsItemFlag.ItemSendsGeometryChanges


def empty_text(plot: pg.PlotItem, text: str) -> pg.TextItem:
    item = pg.TextItem(text, color="#8a8a8a", anchor=(0.5, 0.5))
    item.setZValue(-5)
    plot.addItem(item, ignoreBounds=True)
    return item


def center_item(item: pg.TextItem, plot: pg.PlotItem) -> None:
    (x0, x1), (y0, y1) = plot.getViewBox().viewRange()
    item.setPos((x0 + x1) / 2, (y0 + y1) / 2)
