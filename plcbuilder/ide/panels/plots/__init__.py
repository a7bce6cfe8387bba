"""The live plots: proc and messages, logic-analyser lanes, PWM/DAC/ADC, axes.

Every plot reads views of the :class:`~plcbuilder.ide.panels.model.RunModel`
ring buffers when :meth:`TimePanel.refresh` is called by the panels' single
redraw timer, and only when a value it shows changed or the user moved the
view; when only time advanced, the drawn curves move instead. The slice handed
to pyqtgraph is already cut to the visible time window, and each curve
peak-downsamples it to the pixels it has; the lanes are one curve per kind
that keeps only the edges.
"""

from plcbuilder.ide.panels.plots.axes import AxesPanel
from plcbuilder.ide.panels.plots.curves import AnalogPanel
from plcbuilder.ide.panels.plots.lanes import LanesPanel
from plcbuilder.ide.panels.plots.proc import ProcPanel
from plcbuilder.ide.panels.plots.timebase import TimeBase, TimePanel, TimeToolbar

__all__ = ["TimeBase", "TimeToolbar", "TimePanel", "ProcPanel", "LanesPanel", "AnalogPanel",
           "AxesPanel"]
