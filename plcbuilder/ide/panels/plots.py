"""The live plots: proc and messages, logic-analyser lanes, PWM/DAC/ADC, axes.

Every plot reads views of the :class:`~plcbuilder.ide.panels.model.RunModel`
ring buffers when :meth:`TimePanel.refresh` is called by the panels' single
redraw timer, and only when the model changed or the user moved the view. The
slice handed to pyqtgraph is already cut to the visible time window, and each
curve peak-downsamples it to the pixels it has.
"""

from __future__ import annotations

import bisect
from typing import Callable, Optional

import numpy as np
from PySide6 import QtCore, QtGui, QtWidgets  # before pyqtgraph (it takes the loaded binding)
import pyqtgraph as pg  # noqa: E402,I001

from plcbuilder.api import abi
from plcbuilder.ide.panels import style
from plcbuilder.ide.panels.model import ANALOG_NAMES, AXES, PINS, RunModel
from plcbuilder.ide.panels.tables import RowsModel

Qt = QtCore.Qt
Signal = QtCore.Signal

__all__ = ["TimeBase", "TimeToolbar", "TimePanel", "ProcPanel", "LanesPanel", "AnalogPanel",
           "AxesPanel"]


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
        lay = QtWidgets.QHBoxLayout(self)
        lay.setContentsMargins(4, 2, 4, 2)
        lay.setSpacing(4)
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
        self.extra = QtWidgets.QHBoxLayout()
        self.extra.setSpacing(4)
        lay.addLayout(self.extra)
        lay.addStretch(1)
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
        if cur is not None and cur[0] <= lo and hi <= cur[1] and \
                (hi - lo) >= 0.5 * (cur[1] - cur[0]) / (1 + 2 * self.pad):
            return
        pad = (hi - lo) * self.pad
        self.range = (lo - pad, hi + pad)
        self.plot.setYRange(*self.range, padding=0)

    def reset(self) -> None:
        self.range = None


class TimePanel(QtWidgets.QWidget):
    """A panel of plots over time, redrawn by :meth:`refresh` from the model.

    The plots' x coordinate is time relative to ``offset`` (the right edge
    while following), so that following moves the data, not the view; the
    :class:`~plcbuilder.ide.panels.style.TimeAxis` labels absolute time.
    """

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
        self.frames = 0
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
        ax = plot.getAxis("bottom")
        if isinstance(ax, style.TimeAxis):
            self._time_axes.append(ax)

    def _user_moved(self, mask) -> None:
        if mask is None or (isinstance(mask, (list, tuple)) and mask and mask[0]):
            self._xrange = None
            self.timebase.set_follow(False)

    def _mark_dirty(self, *args) -> None:
        if not self._setting_range:
            self._view_dirty = True

    def visible_span(self) -> tuple[float, float]:
        """The absolute time range [t0, t1] (seconds) the plots show."""
        if self.timebase.follow or not self._time_plots:
            return self.timebase.span(self.model)
        (r0, r1), _ = self._time_plots[0].getViewBox().viewRange()
        return r0 + self.offset, r1 + self.offset

    def x(self, a: int, b: int) -> np.ndarray:
        """Sample times [a, b) in the plots' x coordinate."""
        return self.model.time.view()[a:b] - self.offset

    def refresh(self, force: bool = False) -> bool:
        """Redraw from the model if anything changed; returns whether it drew."""
        if not force and self.model.version == self._drawn_version and not self._view_dirty:
            return False
        if self.model.epoch != self._epoch:
            self._epoch = self.model.epoch
            self.model_cleared()
        t0, t1 = self.visible_span()
        if self.timebase.follow and self._time_plots:
            self.offset = t1
            rng = (t0 - t1, 0.0)
            if rng != self._xrange:
                self._setting_range = True
                try:
                    self._time_plots[0].setXRange(*rng, padding=0)
                finally:
                    self._setting_range = False
                self._xrange = rng
        for ax in self._time_axes:
            ax.set_offset(self.offset)
        a, b = self.model.window(t0, t1)
        self.draw(a, b, t0, t1)
        self._drawn_version = self.model.version
        self._view_dirty = False
        self.frames += 1
        return True

    def draw(self, a: int, b: int, t0: float, t1: float) -> None:  # pragma: no cover
        raise NotImplementedError

    def flush(self) -> None:
        """Move queued table rows into their views (called by the redraw timer)."""

    def model_cleared(self) -> None:
        """The model forgot its samples (cleared, or the controller started over)."""

    def set_pin_names(self, inputs: dict[int, str], outputs: dict[int, str]) -> None:
        pass


def _empty_text(plot: pg.PlotItem, text: str) -> pg.TextItem:
    item = pg.TextItem(text, color="#8a8a8a", anchor=(0.5, 0.5))
    item.setZValue(-5)
    plot.addItem(item, ignoreBounds=True)
    return item


def _center(item: pg.TextItem, plot: pg.PlotItem) -> None:
    (x0, x1), (y0, y1) = plot.getViewBox().viewRange()
    item.setPos((x0 + x1) / 2, (y0 + y1) / 2)


# ======================================================================= proc
class ProcPanel(TimePanel):
    """``proc`` as a step plot with its states named on the y axis, message
    markers with their names, and a decoded message log."""

    MAX_LABELS = 16

    def __init__(self, model: RunModel, timebase: TimeBase, on_clear=None, parent=None):
        super().__init__(model, timebase, on_clear, parent)
        self.status = QtWidgets.QLabel("No controller")
        self.status.setTextInteractionFlags(Qt.TextInteractionFlag.TextSelectableByMouse)
        self.toolbar.extra.addSpacing(12)
        self.toolbar.extra.addWidget(self.status)

        self.widget = style.plot_widget(style.time_axis())
        self.plot = self.widget.getPlotItem()
        style.style_plot(self.plot, left="proc state", bottom="time (s)", bottom_units=None)
        self.add_time_plot(self.plot)
        self.plot.setMouseEnabled(x=True, y=False)
        self.curve = style.new_curve(self.plot, style.PROC_COLOUR, "proc", width=2.0,
                                     stepMode="right")   # proc holds its value
        self.markers = pg.ScatterPlotItem(symbol="t", size=10, pen=pg.mkPen("#ffffff", width=1),
                                          brush=pg.mkBrush(style.MESSAGE_COLOUR))
        self.markers.setZValue(10)
        self.plot.addItem(self.markers)
        self._labels: list[pg.TextItem] = []
        font = QtGui.QFont()
        font.setPointSizeF(8)
        for _ in range(self.MAX_LABELS):
            t = pg.TextItem("", color=style.MESSAGE_COLOUR, anchor=(0.5, 1.05),
                            fill=pg.mkBrush(255, 255, 255, 200))
            t.setFont(font)
            t.setZValue(11)
            t.hide()
            self.plot.addItem(t, ignoreBounds=True)
            self._labels.append(t)
        self._ticks: tuple = ()
        self._tick_labels: list[tuple[int, str]] = []
        self._empty = _empty_text(self.plot, "No samples yet: start a procedure")

        self.messages = RowsModel(["Time (s)", "From", "Message", "Code", "command",
                                   "parameter", "Meaning"], limit=5000,
                                  colour=lambda r: style.FAULT_COLOUR if r[3] < 0 else None,
                                  align_right=(0, 3, 4, 5))
        self.table = QtWidgets.QTableView()
        self.table.setModel(self.messages)
        _setup_log_view(self.table)
        self.table.setToolTip("Messages the procedures sent (the message variable), by name, "
                              "with command (var00) and parameter (var01) at the time")
        for col, width in enumerate((70, 90, 250, 55, 75, 75)):
            self.table.setColumnWidth(col, width)

        split = QtWidgets.QSplitter(Qt.Orientation.Vertical)
        split.addWidget(self.widget)
        split.addWidget(self.table)
        split.setStretchFactor(0, 3)
        split.setStretchFactor(1, 1)
        split.setSizes([300, 130])
        lay = QtWidgets.QVBoxLayout(self)
        lay.setContentsMargins(0, 0, 0, 0)
        lay.setSpacing(0)
        lay.addWidget(self.toolbar)
        lay.addWidget(split, 1)

    def add_messages(self, rows) -> None:
        for m in rows:
            self.messages.queue((f"{m.t_ms / 1000:.3f}", m.source, m.label, m.code, m.command,
                                 m.parameter, m.meaning))

    def flush(self) -> None:
        if self.messages.flush():
            self.table.scrollToBottom()

    def model_cleared(self) -> None:
        self.messages.clear()

    def set_status(self, text: str) -> None:
        self.status.setText(text)

    def y_labels(self) -> list[str]:
        """The state names on the y axis, lowest value first."""
        return [label for _, label in self._tick_labels]

    def _update_ticks(self) -> None:
        values = tuple(sorted(self.model.proc_values))
        if values == self._ticks:
            return
        self._ticks = values
        labels = []
        for v in values:
            name = abi.proc_name(v)
            labels.append((v, f"{name} ({v})" if name else str(v)))
        self._tick_labels = labels
        self.plot.getAxis("left").setTicks([labels, []])
        lo, hi = min(values), max(values)
        pad = max(1.0, (hi - lo) * 0.12)
        # room above the highest state for two rows of message names
        self.plot.setYRange(lo - pad * 0.4, hi + pad * 2.6, padding=0)

    def draw(self, a: int, b: int, t0: float, t1: float) -> None:
        m = self.model
        self._update_ticks()
        t = self.x(a, b)
        proc = m.scalars.view(0)[a:b]
        self.curve.setData(t, proc)
        self._empty.setVisible(len(m) == 0)
        if len(m) == 0:
            _center(self._empty, self.plot)
        # messages in view: a marker each, names for the newest that fit
        i0 = bisect.bisect_left(m.message_times, t0)
        i1 = bisect.bisect_right(m.message_times, t1)
        rows = m.messages[i0:i1] if len(t) else []
        if rows:
            mt = np.fromiter((r.t_ms * 1e-3 for r in rows), dtype=float, count=len(rows)) \
                - self.offset
            idx = np.clip(np.searchsorted(t, mt, side="right") - 1, 0, len(t) - 1)
            my = proc[idx]
            self.markers.setData(mt, my)
        else:
            mt = my = ()
            self.markers.setData([], [])
        vb = self.plot.getViewBox()
        width_px = max(1.0, vb.width())
        height_px = max(1.0, vb.height())
        px_per_s = width_px / max(t1 - t0, 1e-9)
        (_, _), (y_lo, y_hi) = vb.viewRange()
        px_per_y = height_px / max(y_hi - y_lo, 1e-9)
        left_edge = t0 - self.offset
        line_h = 16.0
        placed_rects: list[tuple[float, float, float, float]] = []
        placed = 0
        for k in range(len(rows) - 1, -1, -1):      # newest first
            if placed >= self.MAX_LABELS:
                break
            text = rows[k].short
            w = 7 * len(text) + 12
            x = (mt[k] - left_edge) * px_per_s      # pixels from the left edge
            y = (y_hi - my[k]) * px_per_y           # pixels from the top
            # centred on the marker, unless that would cut it at an edge
            ax = 0.0 if x < w / 2 else (1.0 if width_px - x < w / 2 else 0.5)
            x0, x1 = x - ax * w, x + (1 - ax) * w
            for row in (0, 1):
                anchor_y = 1.7 + 1.05 * row
                y1 = y - (anchor_y - 1.0) * line_h
                y0 = y1 - line_h
                if y0 < 0:
                    continue
                if all(x1 <= a or x0 >= b or y1 <= c or y0 >= d
                       for a, b, c, d in placed_rects):
                    break
            else:
                continue
            placed_rects.append((x0, x1, y0, y1))
            lab = self._labels[placed]
            if lab.toPlainText() != text:
                lab.setText(text)
            lab.setAnchor((ax, anchor_y))
            lab.setPos(mt[k], my[k])
            lab.show()
            placed += 1
        for lab in self._labels[placed:]:
            lab.hide()


def _setup_log_view(view: QtWidgets.QTableView) -> None:
    view.setAlternatingRowColors(True)
    view.setSelectionBehavior(QtWidgets.QAbstractItemView.SelectionBehavior.SelectRows)
    view.setEditTriggers(QtWidgets.QAbstractItemView.EditTrigger.NoEditTriggers)
    view.verticalHeader().setVisible(False)
    view.verticalHeader().setDefaultSectionSize(20)
    view.horizontalHeader().setStretchLastSection(True)
    view.horizontalHeader().setHighlightSections(False)
    view.setWordWrap(False)


# ====================================================================== lanes
class LanesPanel(TimePanel):
    """A logic analyser: one lane per output that has been on (and per input
    that changed, when shown), plus lanes the user pinned; named from pins.h."""

    LANE = 1.5          # lane pitch (a high level is 1)

    def __init__(self, model: RunModel, timebase: TimeBase, on_clear=None, parent=None):
        super().__init__(model, timebase, on_clear, parent)
        self.show_inputs = QtWidgets.QCheckBox("Inputs")
        self.show_inputs.setToolTip("Also show lanes for the inputs that changed")
        self.show_inputs.setChecked(True)
        self.show_inputs.toggled.connect(self._mark_dirty)
        self.toolbar.extra.addWidget(self.show_inputs)

        self.widget = style.plot_widget(style.time_axis())
        self.plot = self.widget.getPlotItem()
        style.style_plot(self.plot, bottom="time (s)", bottom_units=None, grid=(True, False))
        self.add_time_plot(self.plot)
        self.plot.setMouseEnabled(x=True, y=False)
        self.plot.getAxis("left").setStyle(tickLength=0)
        self.widget.setContextMenuPolicy(Qt.ContextMenuPolicy.CustomContextMenu)
        self.widget.customContextMenuRequested.connect(self._context_menu)
        self.widget.setToolTip("Right-click to add or remove lanes")
        self._empty = _empty_text(self.plot, "No output has changed yet.\n"
                                  "Right-click to add a lane.")
        self.names = {"inputs": {}, "outputs": {}}
        self.pinned: list[tuple[str, int]] = []
        self.hidden: set[tuple[str, int]] = set()
        self._items: dict[tuple[str, int], pg.PlotDataItem] = {}
        self._lanes: list[tuple[str, int]] = []
        self._bands: list[pg.LinearRegionItem] = []
        self.pin_count = 64

        lay = QtWidgets.QVBoxLayout(self)
        lay.setContentsMargins(0, 0, 0, 0)
        lay.setSpacing(0)
        lay.addWidget(self.toolbar)
        lay.addWidget(self.widget, 1)

    # ------------------------------------------------------------------ API
    def set_pin_names(self, inputs: dict[int, str], outputs: dict[int, str]) -> None:
        self.names = {"inputs": dict(inputs), "outputs": dict(outputs)}
        self._lanes = []                 # relabel on the next draw
        self._view_dirty = True

    def lane_label(self, kind: str, pin: int) -> str:
        name = self.names[kind].get(pin)
        tag = "OUT" if kind == "outputs" else "IN"
        return f"{tag} {pin}  {name}" if name else f"{tag} {pin}"

    def pin_lane(self, kind: str, pin: int) -> None:
        """Always show this pin's lane."""
        key = (kind, int(pin))
        self.hidden.discard(key)
        if key not in self.pinned:
            self.pinned.append(key)
        self._view_dirty = True

    def remove_lane(self, kind: str, pin: int) -> None:
        """Hide this pin's lane (until it is pinned again)."""
        key = (kind, int(pin))
        if key in self.pinned:
            self.pinned.remove(key)
        self.hidden.add(key)
        self._view_dirty = True

    def reset_lanes(self) -> None:
        self.pinned.clear()
        self.hidden.clear()
        self._view_dirty = True

    def y_labels(self) -> list[str]:
        """The lane names, top to bottom (as last drawn)."""
        return [self.lane_label(*key) for key in self._lanes]

    def lanes(self) -> list[tuple[str, int]]:
        """The lanes shown, top to bottom."""
        m = self.model
        outs = set(m.active_outputs) | {p for k, p in self.pinned if k == "outputs"}
        lanes = [("outputs", p) for p in sorted(outs)]
        if self.show_inputs.isChecked():
            ins = set(m.active_inputs) | {p for k, p in self.pinned if k == "inputs"}
            lanes += [("inputs", p) for p in sorted(ins)]
        else:
            lanes += [k for k in self.pinned if k[0] == "inputs"]
        return [k for k in lanes if k not in self.hidden]

    # ---------------------------------------------------------------- draw
    def _relayout(self, lanes: list[tuple[str, int]]) -> None:
        for key in list(self._items):
            if key not in lanes:
                self.plot.removeItem(self._items.pop(key))
        for band in self._bands:
            self.plot.removeItem(band)
        self._bands = []
        n = len(lanes)
        ticks = []
        for i, key in enumerate(lanes):
            y = (n - 1 - i) * self.LANE
            # a static band behind every lane: where its 0 and 1 levels are
            band = pg.LinearRegionItem((y - 0.2, y + 1.2), orientation="horizontal",
                                       movable=False, brush=pg.mkBrush(style.LANE_BANDS[i % 2]),
                                       pen=pg.mkPen(None))
            band.setZValue(-50)
            for line in band.lines:
                line.setPen(pg.mkPen(None))
                line.setHoverPen(pg.mkPen(None))
            self.plot.addItem(band, ignoreBounds=True)
            self._bands.append(band)
            item = self._items.get(key)
            if item is None:
                c = style.OUTPUT_COLOUR if key[0] == "outputs" else style.INPUT_COLOUR
                item = style.new_curve(self.plot, c, stepMode="right")   # sample and hold
                self._items[key] = item
            item.setPos(0, y)
            ticks.append((y + 0.5, self.lane_label(*key)))
        self.plot.getAxis("left").setTicks([ticks, []])
        top = max(n, 1) * self.LANE
        self.plot.setYRange(-0.35, top - 0.15, padding=0)
        self._lanes = lanes

    def draw(self, a: int, b: int, t0: float, t1: float) -> None:
        lanes = self.lanes()
        if lanes != self._lanes:
            self._relayout(lanes)
        m = self.model
        t = self.x(a, b)
        for key, item in self._items.items():
            item.setData(t, m.bit_series(key[0], key[1], a, b))
        self._empty.setVisible(not lanes)
        if not lanes:
            _center(self._empty, self.plot)

    # --------------------------------------------------------- context menu
    def _lane_at(self, pos: QtCore.QPoint) -> Optional[tuple[str, int]]:
        scene = self.widget.mapToScene(pos)
        vb = self.plot.getViewBox()
        if not vb.sceneBoundingRect().contains(scene) and \
                not self.plot.getAxis("left").sceneBoundingRect().contains(scene):
            return None
        y = vb.mapSceneToView(scene).y()
        n = len(self._lanes)
        i = n - 1 - int(np.floor((y + 0.25) / self.LANE))
        return self._lanes[i] if 0 <= i < n else None

    def build_menu(self, lane: Optional[tuple[str, int]] = None) -> QtWidgets.QMenu:
        menu = QtWidgets.QMenu(self)
        if lane is not None:
            act = menu.addAction(f"Remove lane {self.lane_label(*lane)}")
            act.triggered.connect(lambda: self.remove_lane(*lane))
            menu.addSeparator()
        for kind, title in (("outputs", "Add output lane"), ("inputs", "Add input lane")):
            sub = menu.addMenu(title)
            shown = set(self._lanes)
            named = sorted(self.names[kind].items())
            for pin, name in named:
                act = sub.addAction(f"{pin}  {name}")
                act.setEnabled((kind, pin) not in shown)
                act.triggered.connect(lambda _=False, k=kind, p=pin: self.pin_lane(k, p))
            if named:
                sub.addSeparator()
            act = sub.addAction("Other pin…")
            act.triggered.connect(lambda _=False, k=kind: self._ask_pin(k))
        menu.addSeparator()
        act = menu.addAction("Reset lanes")
        act.setToolTip("Show the pins that changed, nothing pinned or removed")
        act.triggered.connect(self.reset_lanes)
        return menu

    def _context_menu(self, pos: QtCore.QPoint) -> None:
        menu = self.build_menu(self._lane_at(pos))
        menu.exec(self.widget.mapToGlobal(pos))

    def _ask_pin(self, kind: str) -> None:
        what = "output" if kind == "outputs" else "input"
        pin, ok = QtWidgets.QInputDialog.getInt(self, f"Add {what} lane", f"{what.title()} pin:",
                                                0, 0, PINS - 1)
        if ok:
            self.pin_lane(kind, pin)


# ===================================================================== analog
class AnalogPanel(TimePanel):
    """PWM and DAC outputs, and the ADC inputs, over time: every channel that
    has been non-zero gets a curve."""

    def __init__(self, model: RunModel, timebase: TimeBase, on_clear=None, parent=None):
        super().__init__(model, timebase, on_clear, parent)
        self.widget = style.layout_widget()
        self.out_plot = self.widget.addPlot(row=0, col=0, axisItems=style.time_axis())
        style.style_plot(self.out_plot, title="PWM and DAC outputs", left="value",
                         bottom=None, bottom_units=None)
        self.in_plot = self.widget.addPlot(row=1, col=0, axisItems=style.time_axis())
        style.style_plot(self.in_plot, title="ADC inputs", left="counts", bottom="time (s)",
                         bottom_units=None)
        for p in (self.out_plot, self.in_plot):
            self.add_time_plot(p)
            p.setMouseEnabled(x=True, y=False)
            p.getAxis("left").setWidth(56)
        self._fit = (YFit(self.out_plot), YFit(self.in_plot))
        self.widget.ci.layout.setRowStretchFactor(0, 3)
        self.widget.ci.layout.setRowStretchFactor(1, 2)
        self.out_legend = style.legend(self.out_plot, columns=2)
        self.in_legend = style.legend(self.in_plot, columns=2)
        self._curves: dict[int, pg.PlotDataItem] = {}
        self._empty_out = _empty_text(self.out_plot, "No PWM or DAC output yet")
        self._empty_in = _empty_text(self.in_plot, "All ADC channels read 0")
        lay = QtWidgets.QVBoxLayout(self)
        lay.setContentsMargins(0, 0, 0, 0)
        lay.setSpacing(0)
        lay.addWidget(self.toolbar)
        lay.addWidget(self.widget, 1)

    def channels(self) -> list[int]:
        return self.model.active_analog()

    def draw(self, a: int, b: int, t0: float, t1: float) -> None:
        m = self.model
        for col in self.channels():
            if col not in self._curves:
                plot = self.in_plot if col >= 16 else self.out_plot
                label = ANALOG_NAMES[col]
                if col < 4:
                    label += f" (pwm0{col + 1})"
                elif 8 <= col < 10:
                    label += f" (dac0{col - 7})"
                elif 16 <= col < 18:
                    label += f" (adc0{col - 15})"
                # PWM and DAC: 16 distinct colours; ADC (its own plot) starts over
                c = style.colour(col if col < 16 else col - 16)
                self._curves[col] = style.new_curve(plot, c, label)
        t = self.x(a, b)
        outs, ins = [], []
        for col, item in self._curves.items():
            y = m.analog.view(col)[a:b]
            item.setData(t, y)
            (ins if col >= 16 else outs).append(y)
        self._fit[0].fit(outs)
        self._fit[1].fit(ins)
        has_out = any(c < 16 for c in self._curves)
        has_in = any(c >= 16 for c in self._curves)
        self._empty_out.setVisible(not has_out)
        self._empty_in.setVisible(not has_in)
        if not has_out:
            _center(self._empty_out, self.out_plot)
        if not has_in:
            _center(self._empty_in, self.in_plot)

    def model_cleared(self) -> None:
        for col, item in self._curves.items():
            plot = self.in_plot if col >= 16 else self.out_plot
            plot.removeItem(item)
        self._curves.clear()
        for f in self._fit:
            f.reset()


# ======================================================================= axes
class AxesPanel(TimePanel):
    """Machine positions and velocities over time, and the XY path."""

    PATH_POINTS = 6000

    def __init__(self, model: RunModel, timebase: TimeBase, on_clear=None, parent=None):
        super().__init__(model, timebase, on_clear, parent)
        self.widget = style.layout_widget()
        self.pos_plot = self.widget.addPlot(row=0, col=0, axisItems=style.time_axis())
        style.style_plot(self.pos_plot, title="Machine position", left="position (mm)",
                         left_units=None, bottom=None, bottom_units=None)
        self.vel_plot = self.widget.addPlot(row=1, col=0, axisItems=style.time_axis())
        style.style_plot(self.vel_plot, title="Velocity", left="velocity (mm/s)",
                         bottom="time (s)", bottom_units=None)
        for p in (self.pos_plot, self.vel_plot):
            self.add_time_plot(p)
            p.setMouseEnabled(x=True, y=False)
            p.getAxis("left").setWidth(56)
        self._fit = (YFit(self.pos_plot, minimum=10.0), YFit(self.vel_plot, minimum=10.0))
        self.pos_legend = style.legend(self.pos_plot, columns=3)
        self.vel_legend = style.legend(self.vel_plot, columns=3)

        self.xy_widget = style.plot_widget()
        self.xy = self.xy_widget.getPlotItem()
        style.style_plot(self.xy, title="Path (XY, machine)", left="Y (mm)", bottom="X (mm)",
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

        split = QtWidgets.QSplitter(Qt.Orientation.Horizontal)
        split.addWidget(self.widget)
        split.addWidget(self.xy_widget)
        split.setStretchFactor(0, 3)
        split.setStretchFactor(1, 2)
        lay = QtWidgets.QVBoxLayout(self)
        lay.setContentsMargins(0, 0, 0, 0)
        lay.setSpacing(0)
        lay.addWidget(self.toolbar)
        lay.addWidget(split, 1)

    def draw(self, a: int, b: int, t0: float, t1: float) -> None:
        m = self.model
        na = len(AXES)
        for ax in m.active_axes():
            if ax not in self._pos:
                self._pos[ax] = style.new_curve(self.pos_plot, style.colour(ax), AXES[ax])
                self._vel[ax] = style.new_curve(self.vel_plot, style.colour(ax), AXES[ax])
        t = self.x(a, b)
        pos, vel = [], []
        for ax, item in self._pos.items():
            pos.append(m.axes.view(ax)[a:b])
            vel.append(m.axes.view(na + ax)[a:b])
            item.setData(t, pos[-1])
            self._vel[ax].setData(t, vel[-1])
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

    def model_cleared(self) -> None:
        self._path_version = -1
        for f in self._fit:
            f.reset()
        for d, plot in ((self._pos, self.pos_plot), (self._vel, self.vel_plot)):
            for item in d.values():
                plot.removeItem(item)
            d.clear()
