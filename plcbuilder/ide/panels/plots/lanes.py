"""The logic-analyser lanes: digital inputs and outputs over time."""

from __future__ import annotations

from typing import Optional

import numpy as np
from PySide6 import QtCore, QtWidgets  # before pyqtgraph (it takes the loaded binding)
import pyqtgraph as pg  # noqa: E402,I001

from plcbuilder.ide.panels import style
from plcbuilder.ide.panels.model import PINS, RunModel
from plcbuilder.ide.panels.plots.timebase import TimeBase, TimePanel, center_item, empty_text

Qt = QtCore.Qt


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
        self._empty = empty_text(self.plot, "No output has changed yet.\n"
                                  "Right-click to add a lane.")
        self.names = {"inputs": {}, "outputs": {}}
        self.pinned: list[tuple[str, int]] = []
        self.hidden: set[tuple[str, int]] = set()
        self._items: dict[tuple[str, int], pg.PlotDataItem] = {}
        self._lanes: list[tuple[str, int]] = []
        self._lane_y: dict[tuple[str, int], float] = {}
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
        self._mark_dirty()

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
        self._mark_dirty()

    def remove_lane(self, kind: str, pin: int) -> None:
        """Hide this pin's lane (until it is pinned again)."""
        key = (kind, int(pin))
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
            self._lane_y[key] = y
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
            item.setData(t, self.hold(m.bit_series(key[0], key[1], a, b)))
        self._empty.setVisible(not lanes)
        if not lanes:
            center_item(self._empty, self.plot)

    def watched(self) -> list:
        return [self.model.inputs, self.model.outputs]

    def shift(self, dx: float) -> None:
        for key, item in self._items.items():
            item.setPos(dx, self._lane_y.get(key, 0.0))

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
