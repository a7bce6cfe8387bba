"""Two time cursors on the run plots, and the table of every signal's value at each.

:class:`Cursors` puts two draggable vertical lines, A and B, on every time
plot of the run panels (they move together on all of them) and keeps their
absolute times; :class:`CursorTable` lists Δt and, for every signal the panels
show (proc, message, the watched variables, the outputs and inputs that
change, the PWM/DAC/ADC channels in use, the axes that move), its value at A,
at B, and B − A.
"""

from __future__ import annotations

from typing import Optional

from PySide6 import QtCore, QtWidgets
import pyqtgraph as pg  # noqa: I001 - after PySide6 (it takes the loaded binding)

from plcbuilder.api import abi
from plcbuilder.ide.panels.model import ANALOG_NAMES, AXES

Qt = QtCore.Qt
Signal = QtCore.Signal

COLOURS = {"A": "#e65100", "B": "#6a1b9a"}


class Cursors(QtCore.QObject):
    """Cursor A and B over every time panel (see the module docstring)."""

    sig_moved = Signal()
    """A cursor moved, or the cursors were shown or hidden."""

    def __init__(self, panels, parent=None):
        super().__init__(parent)
        self.panels = panels
        self.enabled = False
        self.a: Optional[float] = None      # absolute times, seconds
        self.b: Optional[float] = None
        self._lines: list = []             # (panel, plot, which, InfiniteLine)
        self._placing = False

    def set_enabled(self, on: bool) -> None:
        """Show the cursors (first at a third and two thirds of the view) or hide them."""
        on = bool(on)
        if on == self.enabled:
            return
        self.enabled = on
        if on:
            made = self.panels.time_panels
            panel = made[0] if made else self.panels.lanes
            t0, t1 = panel.visible_span()
            if self.a is None or not (t0 <= self.a <= t1):
                self.a = t0 + (t1 - t0) / 3
            if self.b is None or not (t0 <= self.b <= t1):
                self.b = t0 + 2 * (t1 - t0) / 3
            self.panels.timebase.set_follow(False)
            for p in self.panels.time_panels:
                self.add_panel(p)
            self.place()
        else:
            for _p, plot, _w, line in self._lines:
                plot.removeItem(line)
            self._lines = []
        self.sig_moved.emit()

    def add_panel(self, p) -> None:
        """Lines A and B in each plot of time panel ``p`` (one made while the
        cursors show gets them too)."""
        for plot in p._time_plots:
            for which in ("A", "B"):
                line = pg.InfiniteLine(
                    angle=90, movable=True,
                    pen=pg.mkPen(COLOURS[which], width=1.5),
                    hoverPen=pg.mkPen(COLOURS[which], width=3),
                    label=which, labelOpts={"position": 0.96, "color": COLOURS[which],
                                            "fill": "#ffffffc0"})
                line.setZValue(30)
                line.sigPositionChanged.connect(
                    lambda ln, p=p, w=which: self._dragged(p, w, ln))
                plot.addItem(line, ignoreBounds=True)
                self._lines.append((p, plot, which, line))
        self.place()

    def set_times(self, a: float, b: float) -> None:
        """Put A and B at these absolute times (seconds)."""
        self.a, self.b = float(a), float(b)
        self.place()
        self.sig_moved.emit()

    @property
    def delta(self) -> Optional[float]:
        return None if self.a is None or self.b is None else self.b - self.a

    def place(self) -> None:
        """Move the lines to the cursors' times (the panels' x is relative to their offset)."""
        self._placing = True
        try:
            for p, _plot, which, line in self._lines:
                t = self.a if which == "A" else self.b
                if t is not None:
                    line.setValue(t - p.offset)
        finally:
            self._placing = False

    def _dragged(self, panel, which: str, line) -> None:
        if self._placing:
            return
        t = float(line.value()) + panel.offset
        if which == "A":
            self.a = t
        else:
            self.b = t
        self.place()
        self.sig_moved.emit()


def _fmt_time(t: Optional[float]) -> str:
    return "" if t is None else f"{t:.3f} s"


class CursorTable(QtWidgets.QWidget):
    """Δt and every shown signal's value at cursor A and B."""

    def __init__(self, panels, cursors: Cursors, parent=None):
        super().__init__(parent)
        self.panels, self.cursors = panels, cursors
        lay = QtWidgets.QVBoxLayout(self)
        lay.setContentsMargins(2, 2, 2, 2)
        self.toggle = QtWidgets.QCheckBox("Show cursors A and B on the plots")
        self.toggle.toggled.connect(cursors.set_enabled)
        lay.addWidget(self.toggle)
        self.table = QtWidgets.QTableWidget(0, 4)
        self.table.setHorizontalHeaderLabels(["Signal", "A", "B", "B − A"])
        self.table.verticalHeader().hide()
        self.table.setEditTriggers(QtWidgets.QAbstractItemView.EditTrigger.NoEditTriggers)
        self.table.setSelectionBehavior(QtWidgets.QAbstractItemView.SelectionBehavior.SelectRows)
        head = self.table.horizontalHeader()
        head.setSectionResizeMode(0, QtWidgets.QHeaderView.ResizeMode.Stretch)
        for c in (1, 2, 3):
            head.setSectionResizeMode(c, QtWidgets.QHeaderView.ResizeMode.ResizeToContents)
        lay.addWidget(self.table)
        cursors.sig_moved.connect(self.refresh)
        self.refresh()

    def rows(self) -> list[tuple[str, ...]]:
        """(signal, value at A, value at B, difference) for every row shown;
        while a second trace is compared (drawn dashed), two more: its values
        at A and at B."""
        c = self.cursors
        if not c.enabled or c.a is None or c.b is None:
            return []
        m = self.panels.model
        comp = getattr(self.panels, "comparison", None)
        o = comp.model if comp is not None else None
        sa, sb = m.sample_at(c.a), m.sample_at(c.b)
        oa, ob = (o.sample_at(c.a), o.sample_at(c.b)) if o is not None else (None, None)
        t = ("t", _fmt_time(c.a), _fmt_time(c.b), f"{c.delta * 1000:.0f} ms")
        out = [t + ((_fmt_time(c.a), _fmt_time(c.b)) if o is not None else ())]

        def row(name, get, numeric=True, show=_text):
            va, vb = get(sa), get(sb)
            diff = ""
            if va is not None and vb is not None and va != vb:
                diff = f"{vb - va:+g}" if numeric else "changed"
            cells = (name, "" if va is None else show(va), "" if vb is None else show(vb), diff)
            if o is not None:
                wa, wb = get(oa), get(ob)
                cells += ("" if wa is None else show(wa), "" if wb is None else show(wb))
            out.append(cells)

        def field(key, i=None):
            def get(s):
                if s is None:
                    return None
                return s[key] if i is None else s[key][i]
            return get

        row("proc", field("proc"), numeric=False, show=_proc)
        row("message", field("message"), numeric=False)
        lanes = self.panels.lanes
        # the watched variables: each one's value, and a trigger's bit of it
        names = m.watched.names()
        if o is not None:
            names += [n for n in o.watched.names() if n not in names]
        bits = {**(o.watched.bits if o is not None else {}), **m.watched.bits}
        for name in names:
            def var(s, name=name):
                return None if s is None else s["watched"].get(name)
            row(name, var)
            label = lanes.lane_label("vars", (name, bits.get(name, 0)))
            if name in bits and label != name:
                def var_bit(s, name=name, b=bits[name]):
                    v = var(s, name)
                    return None if v is None else (v >> b) & 1
                row(label, var_bit)
        for kind, key in (("outputs", "outputs"), ("inputs", "inputs")):
            pins = set(m.active_outputs if kind == "outputs" else m.active_inputs)
            if o is not None:
                pins |= o.active_outputs if kind == "outputs" else o.active_inputs
            for pin in sorted(pins):
                def bit(s, pin=pin, key=key):
                    return None if s is None else (s[key][pin // 32] >> (pin % 32)) & 1
                row(lanes.lane_label(kind, pin), bit)
        channels = set(m.active_analog()) | (set(o.active_analog()) if o is not None else set())
        for ch in sorted(channels):
            row(ANALOG_NAMES[ch], field("analog", ch))
        for i in m.active_axes():
            row(f"{AXES[i]} (mm)", field("positions", i))
        return out

    def set_compared(self, name) -> None:
        """Two more columns while a trace ``name`` is compared (None: not)."""
        heads = ["Signal", "A", "B", "B − A"]
        if name:
            heads += [f"A ({name})", f"B ({name})"]
        self.table.setColumnCount(len(heads))
        self.table.setHorizontalHeaderLabels(heads)
        head = self.table.horizontalHeader()
        for c in range(1, len(heads)):
            head.setSectionResizeMode(c, QtWidgets.QHeaderView.ResizeMode.ResizeToContents)
        self.refresh()

    def refresh(self) -> None:
        rows = self.rows()
        self.table.setRowCount(len(rows))
        for r, values in enumerate(rows):
            for col, text in enumerate(values):
                item = self.table.item(r, col)
                if item is None:
                    item = QtWidgets.QTableWidgetItem()
                    if col:
                        item.setTextAlignment(Qt.AlignmentFlag.AlignRight
                                              | Qt.AlignmentFlag.AlignVCenter)
                    self.table.setItem(r, col, item)
                item.setText(text)
        if not rows:
            self.table.setRowCount(0)


def _text(v) -> str:
    if isinstance(v, float):
        return f"{v:g}"
    return str(v)


def _proc(v: Optional[int]) -> str:
    if v is None:
        return ""
    name = abi.proc_name(v)
    return f"{name} ({v})" if name else str(v)
