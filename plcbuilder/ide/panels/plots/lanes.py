"""The logic-analyser lanes: digital inputs and outputs over time, the
softMC virtual outputs (``VOUT n``; a PLS's output shows on its output's lane),
and the watched variables that are bits (``M80.sens``, a trigger's
``M80.var03 bit 2``), in a colour of their own above the pins."""

from __future__ import annotations

from typing import Optional

import numpy as np
from PySide6 import QtCore, QtWidgets  # before pyqtgraph (it takes the loaded binding)
import pyqtgraph as pg  # noqa: E402,I001

from plcbuilder.ide.panels import style
from plcbuilder.ide.panels.model import PINS, RunModel
from plcbuilder.ide.panels.plots import overlay
from plcbuilder.ide.panels.watched import WatchedVariables, lane_label
from plcbuilder.ide.panels.plots.timebase import (TimeBase, TimePanel, center_item, empty_text,
                                                  shift_item)

Qt = QtCore.Qt


class LanesPanel(TimePanel):
    """A logic analyser: one lane per output that has been on (and per input
    that changed, when shown), plus lanes the user pinned; named from pins.h.
    A watched variable's bit has a lane of kind ``"vars"`` keyed
    ``("vars", (name, bit))``, at the top."""

    LANE = 1.5          # lane pitch (a high level is 1)

    def __init__(self, model: RunModel, timebase: TimeBase, on_clear=None, parent=None):
        super().__init__(model, timebase, on_clear, parent)
        self.show_inputs = QtWidgets.QCheckBox("Inputs")
        self.show_inputs.setToolTip("Also show lanes for the inputs that changed")
        self.show_inputs.setChecked(True)
        self.show_inputs.toggled.connect(self._mark_dirty)
        self.toolbar.extra.addWidget(self.show_inputs)

        self.widget = style.plot_widget(style.time_axis(), menu=False)
        self.plot = self.widget.getPlotItem()
        style.style_plot(self.plot, bottom="time (s)", bottom_units=None, grid=(True, False))
        self.add_time_plot(self.plot)
        self.plot.setMouseEnabled(x=True, y=False)
        self.plot.getAxis("left").setStyle(tickLength=0)
        # no lane yet: no numbers on the lane axis ("1.0" was cut at its top)
        self.plot.getAxis("left").setTicks([[], []])
        self.widget.setContextMenuPolicy(Qt.ContextMenuPolicy.CustomContextMenu)
        self.widget.customContextMenuRequested.connect(self._context_menu)
        self.widget.setToolTip("Right-click to add or remove lanes")
        # the lane bands, the variables' and a compared trace's colour
        self.widget.theme_hooks = [lambda: self._relayout(self._lanes), self._restyle_vars,
                                   self._restyle_other]
        self._empty = empty_text(self.plot, "No output has changed yet.\n"
                                  "Right-click to add a lane.")
        self.names = {"inputs": {}, "outputs": {}, "vouts": {}}
        self.pinned: list[tuple[str, int]] = []
        self.hidden: set[tuple[str, int]] = set()
        # every lane of a kind is one curve (a path broken between lanes):
        # a curve per lane costs pyqtgraph a paint and a setData each
        self._items: dict[str, pg.PlotDataItem] = {
            kind: _merged_curve(self.plot, colour)
            for kind, colour in (("vars", style.plot_colours().variable),
                                 ("outputs", style.OUTPUT_COLOUR),
                                 ("vouts", style.OUTPUT_COLOUR),
                                 ("inputs", style.INPUT_COLOUR))}
        self._blocks: dict[str, pg.BarGraphItem] = {}     # dense runs, filled
        self._drawn: dict[str, tuple] = {}     # kind -> what its curve was made from
        self._drawn_watched = -1               # the model's watched.version drawn
        self._var_labels: list[str] = []       # the variables' lane labels drawn
        self._lanes: list[tuple[str, int]] = []
        self._lane_y: dict[tuple[str, int], float] = {}
        self._bands: Optional[pg.BarGraphItem] = None
        self.pin_count = 64
        #: (kind, pin) -> forced value: the lane's label says so
        self.forced: dict[tuple[str, int], int] = {}
        #: (menu, (kind, pin)) -> None: adds force/release items to a lane's menu
        self.force_menu = None
        #: a compared trace's path a kind (plots/overlay.py), its dense runs, its key
        self.other_items: dict[str, pg.PlotDataItem] = {}
        self._other_blocks: dict[str, pg.BarGraphItem] = {}
        self.other_key = None

        lay = QtWidgets.QVBoxLayout(self)
        lay.setContentsMargins(0, 0, 0, 0)
        lay.setSpacing(0)
        lay.addWidget(self.toolbar)
        lay.addWidget(self.widget, 1)

    # ------------------------------------------------------------------ API
    def set_pin_names(self, inputs: dict[int, str], outputs: dict[int, str]) -> None:
        self.names = {"inputs": dict(inputs), "outputs": dict(outputs),
                      "vouts": self.names.get("vouts", {})}
        self._lanes = []                 # relabel on the next draw
        self._mark_dirty()

    def lane_label(self, kind: str, pin) -> str:
        if kind == "vars":                       # pin is (name, bit)
            var, bit = pin
            o = self.comparison.model.watched if self.comparison is not None else None
            binary = self.model.watched.is_binary(var) and (o is None or o.is_binary(var))
            return lane_label(var, bit, binary)
        name = self.names[kind].get(pin)
        if kind == "vouts":                      # bit n-1 is VOUT.n
            tag, pin = "VOUT", pin + 1
        else:
            tag = "OUT" if kind == "outputs" else "IN"
        label = f"{tag} {pin}  {name}" if name else f"{tag} {pin}"
        if (kind, pin) in self.forced:
            label += f"  [forced {self.forced[(kind, pin)]}]"
        return label

    def set_forces(self, forces: list) -> None:
        """Mark the lanes of forced inputs and outputs (``[{target, value}]``)."""
        forced = {}
        for f in forces:
            kind, _, n = str(f.get("target", "")).partition(" ")
            if n.isdigit() and kind in ("in", "out"):
                forced[("inputs" if kind == "in" else "outputs", int(n))] = f.get("value")
        if forced != self.forced:
            self.forced = forced
            for key in forced:
                self.pin_lane(*key)       # a forced pin always has its lane
            self._lanes = []              # relabel on the next draw
            self._mark_dirty()

    def pin_lane(self, kind: str, pin: int) -> None:
        """Always show this pin's lane."""
        key = (kind, int(pin))
        self.hidden.discard(key)
        if key not in self.pinned:
            self.pinned.append(key)
        self._mark_dirty()

    def remove_lane(self, kind: str, pin) -> None:
        """Hide this pin's (or variable's) lane (until it is pinned again, or Reset lanes)."""
        key = (kind, pin if kind == "vars" else int(pin))
        if key in self.pinned:
            self.pinned.remove(key)
        self.hidden.add(key)
        self._mark_dirty()

    def reset_lanes(self) -> None:
        self.pinned.clear()
        self.hidden.clear()
        self._mark_dirty()

    def y_labels(self) -> list[str]:
        """The lane names, top to bottom (as last drawn)."""
        return [self.lane_label(*key) for key in self._lanes]

    def lanes(self) -> list[tuple[str, int]]:
        """The lanes shown, top to bottom."""
        m = self.model
        o = self.comparison.model if self.comparison is not None else None
        variables = m.watched.lanes()
        if o is not None:
            variables += [v for v in o.watched.lanes() if v not in variables]
        lanes = [("vars", v) for v in variables]
        outs = set(m.active_outputs) | {p for k, p in self.pinned if k == "outputs"}
        outs |= o.active_outputs if o is not None else set()
        lanes += [("outputs", p) for p in sorted(outs)]
        vouts = set(m.active_vouts) | {p for k, p in self.pinned if k == "vouts"}
        lanes += [("vouts", p) for p in sorted(vouts)]
        if self.show_inputs.isChecked():
            ins = set(m.active_inputs) | {p for k, p in self.pinned if k == "inputs"}
            ins |= o.active_inputs if o is not None else set()
            lanes += [("inputs", p) for p in sorted(ins)]
        else:
            lanes += [k for k in self.pinned if k[0] == "inputs"]
        return [k for k in lanes if k not in self.hidden]

    # ---------------------------------------------------------------- draw
    def _relayout(self, lanes: list[tuple[str, int]]) -> None:
        n = len(lanes)
        ys = np.array([(n - 1 - i) * self.LANE for i in range(n)], dtype=float)
        # one item paints every lane's band (where its 0 and 1 levels are)
        if self._bands is not None:
            self.plot.removeItem(self._bands)
            self._bands = None
        if n:
            self._bands = _Bars(
                x0=-1e9, width=2e9, y0=ys - 0.2, height=1.4, pen=pg.mkPen(None),
                brushes=[pg.mkBrush(style.plot_colours().lane_bands[i % 2]) for i in range(n)])
            self._bands.setZValue(-50)
            # (not cached in a pixmap: 2e9 s wide, they overflow its pixels)
            self.plot.addItem(self._bands, ignoreBounds=True)
        self._lane_y = {key: float(y) for key, y in zip(lanes, ys)}
        ticks = [(y + 0.5, self.lane_label(*key)) for key, y in zip(lanes, ys)]
        self.plot.getAxis("left").setTicks([ticks, []])
        top = max(n, 1) * self.LANE
        self.plot.setYRange(-0.35, top - 0.15, padding=0)
        self._lanes = lanes

    def draw(self, a: int, b: int, t0: float, t1: float) -> None:
        lanes = self.lanes()
        # a variable's label says "bit N" once it is more than 0/1
        var_labels = [self.lane_label(*k) for k in lanes if k[0] == "vars"]
        if lanes != self._lanes or var_labels != self._var_labels:
            self._var_labels = var_labels
            self._relayout(lanes)
        m = self.model
        t = m.time.view()[a:b] - self.offset
        end = self._extend if (self._extend and len(t)) else (t[-1] if len(t) else 0.0)
        px = max(16, int(self.plot.getViewBox().width()))
        per_px = max((t1 - t0) / px, 1e-12)
        left = t0 - self.offset
        self._drawn_watched = m.watched.version
        for kind, item in self._items.items():
            keys = [k for k in lanes if k[0] == kind]
            # the same samples, lanes, window and pixels as last drawn: the merged
            # curve and its blocks stand (only the paint is left)
            key = (m.epoch, m.time.total, a, b, self.offset, end, left, per_px, tuple(keys),
                   tuple(self._lane_y.get(k) for k in keys),
                   m.watched.version if kind == "vars" else None)
            if self._drawn.get(kind) == key:
                continue
            self._drawn[kind] = key
            if not keys or not (len(t) or kind == "vars"):
                item.setData([], [])
                self._set_blocks(kind, (), (), ())
                continue
            x, y, connect, blocks = self._path(m, kind, keys, a, b, t, end, t0, t1, left,
                                               per_px)
            item.setData(x, y, connect=connect)
            self._set_blocks(kind, *blocks)
        if self.comparison is not None:
            self._draw_other(lanes, t0, t1, left, per_px)
        self._empty.setVisible(not lanes)
        if not lanes:
            center_item(self._empty, self.plot)

    def _path(self, m: RunModel, kind: str, keys, a: int, b: int, t: np.ndarray, end: float,
              t0: float, t1: float, left: float, per_px: float):
        """:func:`lane_path` of the ``kind`` lanes ``keys`` of model ``m``: its
        samples [a, b) at ``t`` for the pins, its changes over [t0, t1] for the
        variables (held to ``end``, or to the model's end when not following)."""
        ys = [self._lane_y[k] for k in keys]
        if kind != "vars":
            return lane_path(m.words(kind).views()[:, a:b], [p for _, p in keys], ys, t, end,
                             left, per_px)
        if not self._extend:
            end = self.model_end(m)
        return variable_path(m.watched, [k[1] for k in keys], ys, t0, t1, self.offset, end,
                             left, per_px)

    def data_changed(self) -> bool:
        return (self.model.watched.version != self._drawn_watched
                or super().data_changed())

    def _restyle_vars(self) -> None:
        """The theme changed: the variables' lanes in its colour (items kept)."""
        colour = style.plot_colours().variable
        self._items["vars"].setPen(style.pen(colour))
        block = self._blocks.get("vars")
        if block is not None:
            block.setOpts(brush=pg.mkBrush(colour))

    # ------------------------------------------------------- a compared trace
    #: where the compared trace's levels sit in a lane (its 0 and 1 a little
    #: inside the first trace's, so both lines show where they agree)
    OTHER_LOW, OTHER_HIGH = 0.08, 0.92

    def comparison_changed(self) -> None:
        for kind in list(self.other_items):
            self.plot.removeItem(self.other_items.pop(kind))
        for kind in list(self._other_blocks):
            self.plot.removeItem(self._other_blocks.pop(kind))
        overlay.remove_key(self.other_key)
        self.other_key = None
        self._drawn.clear()                 # the lanes may change: draw them again
        comp = self.comparison
        if comp is None:
            return
        colour = overlay.overlay_colour()
        for kind in ("vars", "outputs", "inputs"):
            item = _merged_curve(self.plot, colour)
            item.setPen(style.dashed_pen(colour))
            item.setZValue(overlay.OVERLAY_Z)
            self.other_items[kind] = item
        self.other_key = overlay.key(self.plot, overlay.key_entries(comp, style.OUTPUT_COLOUR))

    def _restyle_other(self) -> None:
        """The theme changed: the compared trace in its colour (items kept)."""
        if self.comparison is None:
            return
        colour = overlay.overlay_colour()
        for item in self.other_items.values():
            item.setPen(style.dashed_pen(colour))
        c = pg.mkColor(colour)
        c.setAlpha(110)
        for block in self._other_blocks.values():
            block.setOpts(brush=pg.mkBrush(c))
        overlay.restyle_key(self.other_key,
                            overlay.key_entries(self.comparison, style.OUTPUT_COLOUR))

    def _draw_other(self, lanes, t0: float, t1: float, left: float, per_px: float) -> None:
        """The compared trace's path over each lane (its own samples, the same
        lanes and pixel thinning as the first trace's)."""
        o = self.comparison.model
        a, b = o.window(t0, t1)
        t = o.time.view()[a:b] - self.offset
        lo, span = self.OTHER_LOW, self.OTHER_HIGH - self.OTHER_LOW
        for kind, item in self.other_items.items():
            keys = [k for k in lanes if k[0] == kind]
            if not keys or not len(t):
                item.setData([], [])
                self._set_other_blocks(kind, ())
                continue
            x, y, connect, blocks = self._path(o, kind, keys, a, b, t, t[-1], t0, t1, left,
                                               per_px)
            level = np.mod(y, self.LANE) > 0.5            # 1 where the path is high
            item.setData(x, y - level + lo + span * level, connect=connect)
            self._set_other_blocks(kind, blocks)

    def _set_other_blocks(self, kind: str, blocks) -> None:
        item = self._other_blocks.get(kind)
        if not len(blocks) or not len(blocks[0]):
            if item is not None:
                item.hide()
            return
        x0, x1, y0 = blocks
        h = self.OTHER_HIGH - self.OTHER_LOW
        if item is None:
            c = pg.mkColor(overlay.overlay_colour())
            c.setAlpha(110)
            item = _Bars(x0=x0, x1=x1, y0=y0 + self.OTHER_LOW, height=h,
                                   pen=pg.mkPen(None), brush=pg.mkBrush(c))
            item.setZValue(4)
            self.plot.addItem(item)
            self._other_blocks[kind] = item
        else:
            item.setOpts(x0=x0, x1=x1, y0=y0 + self.OTHER_LOW, height=h)
        item.show()

    def other_data(self, kind: str = "outputs") -> tuple[np.ndarray, np.ndarray]:
        """The compared trace's path over every ``kind`` lane (as last drawn)."""
        item = self.other_items.get(kind)
        x, y = item.getOriginalDataset() if item is not None else (None, None)
        return (np.asarray(x) if x is not None else np.empty(0),
                np.asarray(y) if y is not None else np.empty(0))

    def _set_blocks(self, kind: str, x0, x1, y0) -> None:
        """Runs of pixel columns that each show both levels, filled (one item a kind)."""
        item = self._blocks.get(kind)
        if not len(x0):
            if item is not None:
                item.hide()
            return
        if item is None:
            colour = {"inputs": style.INPUT_COLOUR,
                      "vars": style.plot_colours().variable}.get(kind, style.OUTPUT_COLOUR)
            item = _Bars(x0=x0, x1=x1, y0=y0, height=1.0, pen=pg.mkPen(None),
                                   brush=pg.mkBrush(colour))
            self.plot.addItem(item)
            self._blocks[kind] = item
        else:
            item.setOpts(x0=x0, x1=x1, y0=y0, height=1.0)
        item.setPos(0, 0)
        item.show()

    def merged_data(self, kind: str = "outputs") -> tuple[np.ndarray, np.ndarray]:
        """The merged curve's points of every ``kind`` lane (as last drawn)."""
        x, y = self._items[kind].getOriginalDataset()
        return (np.asarray(x) if x is not None else np.empty(0),
                np.asarray(y) if y is not None else np.empty(0))

    def watched(self) -> list:
        return [self.model.inputs, self.model.outputs, self.model.vouts]

    def shift(self, dx: float) -> None:
        for item in (*self._items.values(), *self._blocks.values(), *self.other_items.values(),
                     *self._other_blocks.values()):
            shift_item(item, dx)

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
            if self.force_menu is not None and lane[0] != "vars":
                self.force_menu(menu, lane)
                menu.addSeparator()
            act = menu.addAction(f"Remove lane {self.lane_label(*lane)}")
            act.triggered.connect(lambda: self.remove_lane(*lane))
            menu.addSeparator()
        for kind, title in (("outputs", "Add output lane"), ("vouts", "Add virtual output lane"),
                            ("inputs", "Add input lane")):
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
        if kind == "vouts":
            n, ok = QtWidgets.QInputDialog.getInt(self, "Add virtual output lane",
                                                  "Virtual output (VOUT n):", 1, 1, 32)
            if ok:
                self.pin_lane(kind, n - 1)
            return
        what = "output" if kind == "outputs" else "input"
        pin, ok = QtWidgets.QInputDialog.getInt(self, f"Add {what} lane", f"{what.title()} pin:",
                                                0, 0, PINS - 1)
        if ok:
            self.pin_lane(kind, pin)


class _Bars(pg.BarGraphItem):
    """pyqtgraph's bars, with the bounding rectangle worked out once per data
    and view: Qt asks for it several times a paint, and pyqtgraph works it out
    in Python each time (the lane bands are painted at every move of the
    time axis)."""

    _rect = None

    def setOpts(self, **opts):
        self._rect = None
        super().setOpts(**opts)

    def viewTransformChanged(self):
        self._rect = None
        super().viewTransformChanged()

    def boundingRect(self):
        if self._rect is None:
            self._rect = super().boundingRect()
        return QtCore.QRectF(self._rect)


def _merged_curve(plot: pg.PlotItem, colour: str) -> pg.PlotDataItem:
    """A curve for many lanes: no clipping or downsampling by pyqtgraph (its
    x goes back to the left edge at every lane; :func:`lane_path` already
    keeps only the edges)."""
    item = pg.PlotDataItem(pen=style.pen(colour))
    item.setSkipFiniteCheck(True)
    plot.addItem(item)
    item.setClipToView(False)
    item.setDownsampling(auto=False)
    return item


def lane_path(words: np.ndarray, pins, ys, t: np.ndarray, end: float, left: float,
              per_px: float):
    """The points of a logic-analyser path for many lanes at once.

    ``words``: the (8, n) input or output words of the samples at times
    ``t``; ``pins`` the lanes' pins, ``ys`` their baselines. Each lane is held
    from its first sample to ``end``, with two points at every edge (the
    level before and after), so a lane costs 2 + 2 x its edges points however
    many samples it holds. Where edges are denser than a pixel column
    (``per_px`` seconds from ``left``), only the first and the last edge of
    each column are kept: the column still shows both levels; and where
    several columns in a row each hold both levels, the path keeps only the
    first and last edge of that run, which becomes a block (drawn filled).
    Returns x, y, pyqtgraph's ``connect`` array (False at the last point of a
    lane) and the blocks (x0, x1, baseline y)."""
    pins = np.asarray(pins, dtype=np.int64)
    lanes = len(pins)
    ys = np.asarray(ys, dtype=float)
    bits = ((words[pins // 32] >> (pins % 32).astype(np.uint32)[:, None]) & 1).astype(np.int8)
    li, ii = np.nonzero(bits[:, 1:] != bits[:, :-1])       # edges, lane by lane, in time
    ii = ii + 1                                              # the sample the new level starts at
    te = t[ii]
    blocks = (np.empty(0), np.empty(0), np.empty(0))
    if len(li) > 1:
        keep, blocks = _thin(li, te, left, per_px)
        blocks = (blocks[0], blocks[1], ys[blocks[2]])
        li, ii, te = li[keep], ii[keep], te[keep]
    edges = np.bincount(li, minlength=lanes)
    counts = 2 + 2 * edges
    starts = np.concatenate(([0], np.cumsum(counts)[:-1]))
    total = int(counts.sum())
    x = np.empty(total)
    y = np.empty(total)
    x[starts] = t[0]
    y[starts] = bits[:, 0]
    ends = starts + counts - 1
    x[ends] = end
    y[ends] = bits[:, -1]
    if len(li):
        first_edge = np.concatenate(([0], np.cumsum(edges)[:-1]))
        rank = np.arange(len(li)) - first_edge[li]
        pos = starts[li] + 1 + 2 * rank
        x[pos] = te
        x[pos + 1] = te
        y[pos] = bits[li, ii - 1]
        y[pos + 1] = bits[li, ii]
    y += np.repeat(ys, counts)
    connect = np.ones(total, dtype=bool)
    connect[ends] = False
    return x, y, connect, blocks


def variable_path(watched: WatchedVariables, lanes, ys, t0: float, t1: float, offset: float,
                  end: float, left: float, per_px: float):
    """:func:`lane_path` for watched variables' bits: each lane ``(name, bit)``
    from that variable's own changes over [t0, t1] (absolute seconds; x is
    relative to ``offset``), held to ``end``; the lanes' paths joined."""
    parts = []
    for (name, bit), y0 in zip(lanes, ys):
        times, values = watched.window(name, t0, t1)
        if not len(times):
            continue
        words = (values & 0xFFFFFFFF).astype(np.uint32).reshape(1, -1)
        t = times - offset
        parts.append(lane_path(words, [bit], [y0], t, max(end, float(t[-1])), left, per_px))
    if not parts:
        empty = np.empty(0)
        return empty, empty, np.empty(0, dtype=bool), (empty, empty, empty)
    x, y, connect = (np.concatenate([p[i] for p in parts]) for i in range(3))
    blocks = tuple(np.concatenate([p[3][i] for p in parts]) for i in range(3))
    return x, y, connect, blocks


def _thin(li: np.ndarray, te: np.ndarray, left: float, per_px: float):
    """Which edges (lane ``li``, time ``te``, sorted by lane then time) to
    keep, and the blocks (x0, x1, lane index) of runs of pixel columns that
    each hold two or more edges."""
    col = np.floor((te - left) / per_px).astype(np.int64)
    col -= col.min()
    key = li * (int(col.max()) + 2) + col        # + 2: a lane's columns never touch the next
    new = np.ones(len(key), dtype=bool)
    new[1:] = key[1:] != key[:-1]
    gf = np.nonzero(new)[0]                      # each column's first edge
    gl = np.append(gf[1:] - 1, len(key) - 1)     # and last
    gkey = key[gf]
    dense = (gl - gf) >= 1                       # both levels in the column
    # runs of dense columns next to each other (in one lane)
    joined = np.zeros(len(gf), dtype=bool)
    joined[1:] = dense[1:] & dense[:-1] & (gkey[1:] == gkey[:-1] + 1)
    run_start = ~joined
    run_id = np.cumsum(run_start) - 1
    run_len = np.bincount(run_id)
    in_block = run_len[run_id] >= 2
    keep = np.zeros(len(key), dtype=bool)
    alone = ~in_block
    keep[gf[alone]] = True
    keep[gl[alone]] = True
    rs = np.nonzero(run_start & in_block)[0]     # the first column of each block
    if len(rs):
        re = rs + run_len[run_id[rs]] - 1          # and its last
        first, last = gf[rs], gl[re]
        keep[first] = True
        keep[last] = True
        return keep, (te[first], te[last], li[first])
    return keep, (np.empty(0), np.empty(0), np.empty(0, dtype=np.int64))
