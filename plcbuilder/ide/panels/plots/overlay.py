"""A second trace drawn over the first (File › Compare with Trace…).

:class:`Comparison` holds the other trace as a :class:`RunModel` of its own,
the same arrays the panels draw the first one from, with its name and what
the comparison found. A time panel given one (``set_comparison``)
draws it over its own curves, dashed: the lanes in the theme's overlay colour
inside each lane's band (a little inside the first trace's levels, so both
show where they agree), each analog channel in its own colour, proc in the
overlay colour. :func:`key` puts a small legend above a plot saying which
line is which trace.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Optional

from PySide6 import QtGui  # before pyqtgraph (it takes the loaded binding)
import pyqtgraph as pg  # noqa: E402,I001

from plcbuilder.ide.panels import style
from plcbuilder.ide.panels.model import RunModel
from plcbuilder.ide.panels.steps import StepSamples
from plcbuilder.trace.samples import to_samples, trigger_bits, variables_of


@dataclass
class Comparison:
    """The other trace of a comparison, as the panels draw it."""
    model: RunModel
    name: str                    # the other trace (its file's name)
    base: str                    # the trace on show that it is compared with
    where: str                   # what the comparison found: "first difference at
                                 # 1.010 s", "no difference" or "no tick in common"


def step_samples(trace) -> list:
    """A trace's samples as the plots draw them: each change, and the value held
    on the tick before it (a curve steps, it does not ramp from one change to
    the next), up to the trace's last tick."""
    return StepSamples().feed(to_samples(trace), trace.t_end + 1)


def comparison_of(trace, name: str, base: str, where: str) -> Comparison:
    samples = step_samples(trace)
    model = RunModel(max(16, len(samples) + 16))
    model.add_samples(samples)
    model.set_watched(variables_of(trace), trigger_bits(trace))
    return Comparison(model, name, base, where)


#: the compared trace's lines above the first trace's
OVERLAY_Z = 5


def dashed_curve(plot: pg.PlotItem, colour: str, width: float = 1.6, **kw) -> pg.PlotDataItem:
    """A curve of the compared trace: dashed, over the first trace's (kw: new_curve's)."""
    item = style.new_curve(plot, colour, **kw)
    item.setPen(style.dashed_pen(colour, width))
    item.setZValue(OVERLAY_Z)
    return item


def overlay_colour() -> str:
    """The colour of the compared trace's lanes and proc, in the theme."""
    return style.plot_colours().overlay


def key(plot: pg.PlotItem, entries: list[tuple[QtGui.QPen, str]]) -> pg.LegendItem:
    """A legend above the plot's view, right-aligned in its title row: each
    pen's line and its text, side by side when they fit (over the view's top
    right corner it covered the top lanes, OUT 0 and OUT 4 in the example)."""
    c = style.plot_colours()
    lg = style.TitleLegend(plot, labelTextColor=c.text, labelTextSize="8pt",
                           colCount=len(entries), frame=False)
    lg.setZValue(40)
    for pen, text in entries:
        lg.addItem(pg.PlotDataItem(pen=pen), text)
    return lg


def restyle_key(lg: Optional[pg.LegendItem], entries: list[tuple[QtGui.QPen, str]]) -> None:
    """New pens for a key's rows (the theme changed); nothing is made or removed
    (this runs inside the scene's palette change)."""
    if lg is None:
        return
    for (sample, _label), (pen, _text) in zip(lg.items, entries):
        sample.item.setPen(pen)
        sample.update()


def remove_key(lg: Optional[pg.LegendItem]) -> None:
    """Take a key off its plot (the scene unparents it)."""
    if isinstance(lg, style.TitleLegend):
        lg.detach()
    elif lg is not None:
        scene = lg.scene()
        if scene is not None:
            scene.removeItem(lg)


def key_entries(comp: Comparison, first: str) -> list[tuple[QtGui.QPen, str]]:
    """The two rows of a key: the first trace solid in ``first``, the other dashed."""
    return [(style.pen(first, 1.6), comp.base), (style.dashed_pen(overlay_colour()), comp.name)]
