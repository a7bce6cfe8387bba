"""The proc plot: the running procedure's state code over time, with its messages."""

from __future__ import annotations

import bisect
import re

import numpy as np
from PySide6 import QtCore, QtGui, QtWidgets  # before pyqtgraph (it takes the loaded binding)
import pyqtgraph as pg  # noqa: E402,I001

from plcbuilder.api import abi
from plcbuilder.ide.elided_label import ShownText, _plain_of
from plcbuilder.ide.panels import style
from plcbuilder.ide.panels.model import RunModel
from plcbuilder.ide.panels.tables import RowsModel
from plcbuilder.ide.panels.plots import overlay
from plcbuilder.ide.panels.plots.timebase import (TimeBase, TimePanel, center_item, empty_text,
                                                  shift_item)

Qt = QtCore.Qt


#: what the status's facts are joined with (a line may break there, not inside one)
SEPARATOR = "  ·  "
_TAG_OR_SPACE = re.compile(r"(<[^>]*>)| ")


def _unbroken(fact: str) -> str:
    """A fact of the status whose words stay on one line (its spaces made
    non-breaking; the markup's own spaces kept)."""
    return _TAG_OR_SPACE.sub(lambda m: m.group(1) or "\u00a0", fact)


class StatusLine(ShownText, QtWidgets.QLabel):
    """The proc panel's status: every fact shows, wrapped onto as many lines
    as the dock's width needs (a fact is never broken, nor elided), and it
    never widens the dock."""

    def __init__(self, text: str = "", parent=None):
        super().__init__(parent)
        self._full = self._plain = ""
        self._pending: str | None = None
        self.setWordWrap(True)
        self.setTextFormat(Qt.TextFormat.AutoText)
        self.setContentsMargins(6, 1, 6, 2)
        # the dock decides the width; the height follows it
        self.setSizePolicy(QtWidgets.QSizePolicy.Policy.Ignored,
                           QtWidgets.QSizePolicy.Policy.Minimum)
        self.setMinimumWidth(1)
        self.setText(text)

    def setText(self, text: str) -> None:  # noqa: N802 - Qt override
        self._pending = None
        self._full = text or ""
        self._plain = _plain_of(self._full)
        super().setText(SEPARATOR.join(_unbroken(f) for f in self._full.split(SEPARATOR)))

    def text(self) -> str:
        """The text as set (the label draws it with its facts kept whole)."""
        return self._full

    def is_elided(self) -> bool:
        """True when some of the text is cut off (never, once laid out)."""
        rect = self.contentsRect()
        return rect.width() > 0 and self.heightForWidth(self.width()) > self.height()


class ProcPanel(TimePanel):
    """``proc`` as a step plot with its states named on the y axis, message
    markers with their names, and a decoded message log."""

    MAX_LABELS = 16

    def __init__(self, model: RunModel, timebase: TimeBase, on_clear=None, parent=None):
        super().__init__(model, timebase, on_clear, parent)
        # the status (running, the job, software, proc, speed, a disconnect
        # reason): beside the tools where it fits on their row, else on a row
        # of its own under them, wrapped; every fact shows, and it never
        # widens the dock (nor takes a row from the plot when it need not)
        self.status = StatusLine("No controller")
        self.status.setObjectName("procStatus")
        self.status_beside: bool | None = None

        self.widget = style.plot_widget(style.time_axis(), menu=False)
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
        self._drawn_messages = -1                   # the model's message_version drawn
        self._label_pos: list[tuple[float, float, float]] = []   # where the shown labels are
        self._tick_labels: list[tuple[int, str]] = []
        self._shown_ticks: list[tuple[int, str]] | None = None
        self._empty = empty_text(self.plot, "No samples yet: start a procedure")
        #: a compared trace's proc (dashed) and the key saying which is which
        self.other_curve = None
        self.other_key = None
        self.widget.theme_hooks = [self._restyle_other]

        # what a message means comes right after its name: at the end of the
        # row it was beyond the dock's edge
        self.messages = RowsModel(["Time (s)", "From", "Message", "Meaning", "Code", "command",
                                   "parameter"], limit=5000,
                                  colour=lambda r: style.FAULT_COLOUR if r[4] < 0 else None,
                                  align_right=(0, 4, 5, 6),
                                  tooltip=lambda r: f"{r[2]} ({r[4]}): {r[3]}" if r[3] else None)
        self.table = QtWidgets.QTableView()
        self.table.setModel(self.messages)
        _setup_log_view(self.table)
        self.table.setToolTip("Messages the procedures sent (the message variable), by name, "
                              "with command (var00) and parameter (var01) at the time")
        for col, width in enumerate((60, 60, 230, 260, 55, 70)):
            self.table.setColumnWidth(col, width)
        self.table.setWordWrap(False)
        self.table.setTextElideMode(Qt.TextElideMode.ElideRight)

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
        self._place_status()

    def watched(self) -> list:
        return [self.model.scalars]

    def data_changed(self) -> bool:
        return (self.model.message_version != self._drawn_messages
                or super().data_changed())

    def comparison_changed(self) -> None:
        if self.other_curve is not None:
            self.plot.removeItem(self.other_curve)
            self.other_curve = None
        overlay.remove_key(self.other_key)
        self.other_key = None
        self._ticks = ()                     # the states of both traces on the axis
        comp = self.comparison
        if comp is None:
            return
        colour = overlay.overlay_colour()
        self.other_curve = overlay.dashed_curve(self.plot, colour, 2.0, stepMode="right")
        self.other_key = overlay.key(self.plot, overlay.key_entries(comp, style.PROC_COLOUR))

    def _restyle_other(self) -> None:
        """The theme changed: the compared trace in its colour (items kept)."""
        if self.other_curve is None or self.comparison is None:
            return
        self.other_curve.setPen(style.dashed_pen(overlay.overlay_colour(), 2.0))
        overlay.restyle_key(self.other_key,
                            overlay.key_entries(self.comparison, style.PROC_COLOUR))

    def _draw_other(self, t0: float, t1: float) -> None:
        o = self.comparison.model
        a, b = o.window(t0, t1)
        self.other_curve.setData(o.time.view()[a:b] - self.offset, o.scalars.view(0)[a:b])

    def shift(self, dx: float) -> None:
        shift_item(self.curve, dx)
        if self.other_curve is not None:
            shift_item(self.other_curve, dx)
        shift_item(self.markers, dx)
        left = self.plot.getViewBox().viewRange()[0][0]
        for lab, (x, y, edge) in zip(self._labels, self._label_pos):
            lab.setPos(x + dx, y)
            if edge + dx < left:          # moved out at the left edge: not cut in half
                lab.hide()

    def add_messages(self, rows) -> None:
        for m in rows:
            self.messages.queue((f"{m.t_ms / 1000:.3f}", m.source, m.label, m.meaning, m.code,
                                 m.command, m.parameter))

    def flush(self) -> None:
        if self.messages.flush():
            self.table.scrollToBottom()

    def model_cleared(self) -> None:
        self.messages.clear()

    def set_status(self, text: str) -> None:
        self.status.set_text_when_shown(text)     # with the time: only what can be seen
        self._place_status()

    def resizeEvent(self, event) -> None:  # noqa: N802 - Qt override
        super().resizeEvent(event)
        if event.size().width() != event.oldSize().width():
            self._place_status()

    def _tools_width(self) -> int:
        """The width the toolbar's own buttons and boxes take on their row."""
        row = self.toolbar.layout().itemAt(0).layout()
        out, n = 0, 0
        for i in range(row.count()):
            w = row.itemAt(i).widget()
            if w is not None and not w.isHidden():
                out, n = out + w.sizeHint().width(), n + 1
        m = self.toolbar.layout().contentsMargins()
        return out + row.spacing() * (n + 1) + m.left() + m.right()

    def _place_status(self) -> None:
        """The status beside the tools when its text fits there on one line,
        else on its own row under them (where it wraps)."""
        st = self.status
        need = st.fontMetrics().horizontalAdvance(st.plain_text()) + 12 + 14 + \
            st.contentsMargins().left() + st.contentsMargins().right()
        beside = self.width() > 0 and self._tools_width() + need <= self.width()
        if beside == self.status_beside:
            return
        self.status_beside = beside
        lay = self.layout()
        if beside:
            lay.removeWidget(st)
            self.toolbar.extra.addWidget(st, 1)
        else:
            self.toolbar.extra.removeWidget(st)
            lay.insertWidget(1, st)
        st.show()

    def y_labels(self) -> list[str]:
        """The state names on the y axis, lowest value first."""
        return [label for _, label in self._tick_labels]

    def shown_y_labels(self) -> list[str]:
        """The state names the axis draws: those that do not overlap."""
        return [label for _, label in (self._shown_ticks or ())]

    def _thin_ticks(self, px_per_y: float) -> None:
        """Name the states on the axis whose labels do not overlap (with
        plc_proc_probing (33) and proc_zeroing (32) a few pixels apart, the
        newest state's name wins, then the others from the top)."""
        labels = self._tick_labels
        gap = QtGui.QFontMetrics(self.plot.getAxis("left").style.get("tickFont")
                                 or QtGui.QFont()).height() + 1
        current = int(self.model.scalars.view(0)[-1]) if len(self.model) else None
        order = sorted(labels, key=lambda vl: (vl[0] != current, -vl[0]))
        kept: list[tuple[int, str]] = []
        for v, text in order:
            if all(abs(v - k) * px_per_y >= gap for k, _ in kept):
                kept.append((v, text))
        kept.sort()
        if kept != self._shown_ticks:
            self._shown_ticks = kept
            self.plot.getAxis("left").setTicks([kept, []])

    def _update_ticks(self) -> None:
        values = set(self.model.proc_values)
        if self.comparison is not None:
            values |= self.comparison.model.proc_values
        values = tuple(sorted(values))
        if values == self._ticks:
            return
        self._ticks = values
        labels = []
        for v in values:
            name = abi.proc_name(v)
            labels.append((v, f"{name} ({v})" if name else str(v)))
        self._tick_labels = labels
        self._shown_ticks = None                     # thinned for the height at the next draw
        lo, hi = min(values), max(values)
        pad = max(1.0, (hi - lo) * 0.12)
        # room above the highest state for two rows of message names
        self.plot.setYRange(lo - pad * 0.4, hi + pad * 2.6, padding=0)

    def draw(self, a: int, b: int, t0: float, t1: float) -> None:
        m = self.model
        self._update_ticks()
        t = self.x(a, b)
        proc = m.scalars.view(0)[a:b]
        self.curve.setData(t, self.hold(proc))
        if self.other_curve is not None:
            self._draw_other(t0, t1)
        self._drawn_messages = m.message_version
        self._empty.setVisible(len(m) == 0)
        if len(m) == 0:
            center_item(self._empty, self.plot)
        # messages in view: a marker each, names for the newest that fit
        i0 = bisect.bisect_left(m.message_times, t0)
        i1 = bisect.bisect_right(m.message_times, t1)
        rows = m.messages[i0:i1] if len(t) else []
        if rows:
            mt = np.fromiter((r.t_ms * 1e-3 for r in rows), dtype=float, count=len(rows)) \
                - self.offset
            idx = np.clip(np.searchsorted(t, mt, side="right") - 1, 0, len(proc) - 1)
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
        self._thin_ticks(px_per_y)
        left_edge = t0 - self.offset
        line_h = 16.0
        placed_rects: list[tuple[float, float, float, float]] = []
        placed = 0
        self._label_pos = []
        for k in range(len(rows) - 1, -1, -1):      # newest first
            if placed >= self.MAX_LABELS:
                break
            text = rows[k].short
            lab = self._labels[placed]
            if lab.toPlainText() != text:
                lab.setText(text)
            w = lab.textItem.boundingRect().width() + 4     # as drawn (a guess cut some)
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
            lab.setAnchor((ax, anchor_y))
            lab.setPos(mt[k], my[k])
            # (x, y, where its left edge is, in the plot's x)
            self._label_pos.append((mt[k], my[k], mt[k] - ax * w / px_per_s))
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
