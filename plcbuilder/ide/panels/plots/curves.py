"""The analog curves: PWM and DAC outputs, ADC inputs over time, and the
watched variables that are numbers (``M80.timer``), each a step curve named in
its own plot's legend (the plot shows while there is one)."""

from __future__ import annotations

import numpy as np
from PySide6 import QtWidgets  # before pyqtgraph (it takes the loaded binding)
import pyqtgraph as pg  # noqa: E402,I001

from plcbuilder.ide.panels import style
from plcbuilder.ide.panels.model import ANALOG_NAMES, RunModel
from plcbuilder.ide.panels.plots import overlay
from plcbuilder.ide.panels.plots.timebase import (TimeBase, TimePanel, YFit, center_item,
                                                  empty_text, shift_item)

QWIDGETSIZE_MAX = 16777215       # Qt's "no maximum"



class AnalogPanel(TimePanel):
    """PWM and DAC outputs, and the ADC inputs, over time: every channel that
    has been non-zero gets a curve; under them, every watched variable that is
    a number (not only 0/1: those have a lane in the Outputs plot)."""

    def __init__(self, model: RunModel, timebase: TimeBase, on_clear=None, parent=None):
        super().__init__(model, timebase, on_clear, parent)
        self.widget = style.layout_widget()
        self.out_plot = self.widget.addPlot(row=0, col=0, axisItems=style.time_axis(),
                                            enableMenu=False)
        style.style_plot(self.out_plot, title="PWM and DAC outputs", left="value",
                         bottom=None, bottom_units=None)
        self.in_plot = self.widget.addPlot(row=1, col=0, axisItems=style.time_axis(),
                                           enableMenu=False)
        style.style_plot(self.in_plot, title="ADC inputs", left="counts", bottom="time (s)",
                         bottom_units=None)
        self.var_plot = self.widget.addPlot(row=2, col=0, axisItems=style.time_axis(),
                                            enableMenu=False)
        style.style_plot(self.var_plot, title="Watched variables", left="value",
                         bottom="time (s)", bottom_units=None)
        for p in (self.out_plot, self.in_plot, self.var_plot):
            self.add_time_plot(p)
            p.setMouseEnabled(x=True, y=False)
            p.getAxis("left").setWidth(56)
        self._fit = (YFit(self.out_plot), YFit(self.in_plot), YFit(self.var_plot))
        self.widget.ci.layout.setRowStretchFactor(0, 3)
        self.widget.ci.layout.setRowStretchFactor(1, 2)
        self.out_legend = style.legend(self.out_plot, columns=2)
        self.in_legend = style.legend(self.in_plot, columns=2)
        self.var_legend = style.legend(self.var_plot, columns=2)
        #: a watched variable's step curve, by name (and a compared trace's, dashed)
        self.var_curves: dict[str, pg.PlotDataItem] = {}
        self.other_var_curves: dict[str, pg.PlotDataItem] = {}
        self._var_colours: dict[str, str] = {}
        self._show_var_plot(False)             # until a variable is more than 0/1
        self._drawn_vars: tuple = ()           # what the variables' curves were made from
        self._drawn_watched = -1               # the model's watched.version drawn
        self._curves: dict[int, pg.PlotDataItem] = {}
        self._drawn: dict[int, tuple] = {}     # col -> what its curve's data were made from
        #: a compared trace's curve per channel (dashed), and its rows in the legends
        self.other_curves: dict[int, pg.PlotDataItem] = {}
        self._other_keys: list[tuple[pg.LegendItem, pg.PlotDataItem]] = []
        self.widget.theme_hooks = [self._restyle_other]
        self._empty_out = empty_text(self.out_plot, "No PWM or DAC output yet")
        self._empty_in = empty_text(self.in_plot, "All ADC channels read 0")
        lay = QtWidgets.QVBoxLayout(self)
        lay.setContentsMargins(0, 0, 0, 0)
        lay.setSpacing(0)
        lay.addWidget(self.toolbar)
        lay.addWidget(self.widget, 1)

    def channels(self) -> list[int]:
        return self.model.active_analog()

    def _plot_of(self, col: int) -> pg.PlotItem:
        return self.in_plot if col >= 16 else self.out_plot

    def draw(self, a: int, b: int, t0: float, t1: float) -> None:
        m = self.model
        for col in self.channels():
            if col not in self._curves:
                self._curves[col] = style.new_curve(self._plot_of(col), _colour(col),
                                                    _label(col))
        # the same samples, window and x origin as a curve was last given: its
        # data stand, and only the paint is left (setData costs a copy and a
        # downsampling pass a curve)
        key = (m.epoch, m.time.total, a, b, self.offset, self._extend)
        t = None
        outs, ins = [], []
        for col, item in self._curves.items():
            y = m.analog.view(col)[a:b]
            if self._drawn.get(col) != key:
                if t is None:
                    t = self.x(a, b)
                item.setData(t, self.hold(y))
                self._drawn[col] = key
            (ins if col >= 16 else outs).append(y)
        if self.comparison is not None:
            self._draw_other(t0, t1, outs, ins)
        self._draw_variables(t0, t1)
        self._fit[0].fit(outs)
        self._fit[1].fit(ins)
        shown = (*self._curves, *self.other_curves)
        has_out = any(c < 16 for c in shown)
        has_in = any(c >= 16 for c in shown)
        self._empty_out.setVisible(not has_out)
        self._empty_in.setVisible(not has_in)
        if not has_out:
            center_item(self._empty_out, self.out_plot)
        if not has_in:
            center_item(self._empty_in, self.in_plot)

    def watched(self) -> list:
        return [self.model.analog]

    def data_changed(self) -> bool:
        w = self.model.watched
        if w.version != self._drawn_watched and (self.var_curves or w.curves()):
            return True
        return super().data_changed()

    # ---------------------------------------------------- watched variables
    def _var_colour(self, name: str) -> str:
        c = self._var_colours.get(name)
        if c is None:
            c = self._var_colours[name] = style.colour(len(self._var_colours))
        return c

    def _var_end(self, m: RunModel) -> float:
        """Where a variable's last value is held to (x): the horizon while
        following, else the model's end."""
        return self._extend or self.model_end(m)

    def _show_var_plot(self, shown: bool) -> None:
        """Show or hide the variables' plot. Hidden, its row takes no room (a
        grid layout keeps a hidden item's minimum size), and its legend is
        hidden itself (only hidden with the plot, it was moved while the plot
        was being deleted, and asked its deleted view box where to go)."""
        plot = self.var_plot
        self.var_legend.setVisible(shown)
        plot.setVisible(shown)
        plot.setMinimumHeight(-1 if shown else 0)          # -1: its own minimum again
        plot.setMaximumHeight(QWIDGETSIZE_MAX if shown else 0)
        self.widget.ci.layout.setRowStretchFactor(2, 2 if shown else 0)
        self.in_plot.getAxis("bottom").showLabel(not shown)     # "time (s)" once, at the bottom

    def _draw_variables(self, t0: float, t1: float) -> None:
        """Each watched variable that is a number as a step curve (its own
        changes, held to the horizon), a compared trace's dashed."""
        m = self.model
        o = self.comparison.model if self.comparison is not None else None
        key = (m.epoch, m.watched.version, m.time.total, t0, t1, self.offset, self._extend,
               o is not None)
        self._drawn_watched = m.watched.version
        if key == self._drawn_vars:
            return
        self._drawn_vars = key
        arrays = []
        for model, curves, dashed in ((m, self.var_curves, False),
                                      (o, self.other_var_curves, True)):
            names = model.watched.curves() if model is not None else []
            for name in [n for n in curves if n not in names]:
                self.var_plot.removeItem(curves.pop(name))
            for name in names:
                item = curves.get(name)
                if item is None:
                    colour = self._var_colour(name)
                    item = curves[name] = (
                        overlay.dashed_curve(self.var_plot, colour, stepMode="right") if dashed
                        else style.new_curve(self.var_plot, colour, name, stepMode="right"))
                times, values = model.watched.window(name, t0, t1)
                x = times - self.offset
                end = self._var_end(model)
                if len(x) and end > x[-1]:
                    x, values = np.append(x, end), np.append(values, values[-1])
                item.setData(x, values.astype(np.float64))
                arrays.append(values)
        shown = bool(self.var_curves or self.other_var_curves)
        if shown != self.var_plot.isVisible():
            self._show_var_plot(shown)
        if shown:
            self._fit[2].fit(arrays)

    # ------------------------------------------------------- a compared trace
    def comparison_changed(self) -> None:
        for col, item in self.other_curves.items():
            self._plot_of(col).removeItem(item)
        self.other_curves.clear()
        for legend, sample in self._other_keys:
            legend.removeItem(sample)
        self._other_keys = []
        for item in self.other_var_curves.values():
            self.var_plot.removeItem(item)
        self.other_var_curves.clear()
        self._drawn_vars = ()
        comp = self.comparison
        if comp is None:
            return
        colour = style.plot_colours().text
        for legend in (self.out_legend, self.in_legend, self.var_legend):
            sample = pg.PlotDataItem(pen=style.dashed_pen(colour))
            legend.addItem(sample, f"dashed: {comp.name}")
            self._other_keys.append((legend, sample))

    def _restyle_other(self) -> None:
        """The theme changed: the legends' dashed row in the text colour (items kept)."""
        pen = style.dashed_pen(style.plot_colours().text)
        for _legend, sample in self._other_keys:
            sample.setPen(pen)

    def _draw_other(self, t0: float, t1: float, outs: list, ins: list) -> None:
        """Each channel the compared trace uses, dashed in the channel's colour."""
        o = self.comparison.model
        a, b = o.window(t0, t1)
        t = o.time.view()[a:b] - self.offset
        for col in o.active_analog():
            item = self.other_curves.get(col)
            if item is None:
                item = overlay.dashed_curve(self._plot_of(col), _colour(col))
                self.other_curves[col] = item
            y = o.analog.view(col)[a:b]
            item.setData(t, y)
            (ins if col >= 16 else outs).append(y)

    def shift(self, dx: float) -> None:
        for item in (*self._curves.values(), *self.other_curves.values(),
                     *self.var_curves.values(), *self.other_var_curves.values()):
            shift_item(item, dx)

    def model_cleared(self) -> None:
        for col, item in self._curves.items():
            plot = self.in_plot if col >= 16 else self.out_plot
            plot.removeItem(item)
        self._curves.clear()
        self._drawn.clear()
        for curves in (self.var_curves, self.other_var_curves):
            for item in curves.values():
                self.var_plot.removeItem(item)
            curves.clear()
        self._var_colours.clear()
        self._drawn_vars = ()
        for f in self._fit:
            f.reset()


def _label(col: int) -> str:
    label = ANALOG_NAMES[col]
    if col < 4:
        label += f" (pwm0{col + 1})"
    elif 8 <= col < 10:
        label += f" (dac0{col - 7})"
    elif 16 <= col < 18:
        label += f" (adc0{col - 15})"
    return label


def _colour(col: int) -> str:
    """PWM and DAC: 16 distinct colours; ADC (its own plot) starts over."""
    return style.colour(col if col < 16 else col - 16)
