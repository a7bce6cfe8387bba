"""The IDE side of the debugger (SPEC §6), one job a file:

* :mod:`.breakpoints` — the project's breakpoints, kept across sessions;
* :mod:`.markers` — breakpoint markers, the halted lines and inline values in an editor;
* :mod:`.inline` — which variables a line uses, inline and hover value texts;
* :mod:`.session` — :class:`DebugSession`: breakpoints to the controller, the
  halted state shown everywhere, the debug verbs, write/force/release;
* :mod:`.breakpoints_panel`, :mod:`.callstack`, :mod:`.forces_panel` — the docks;
* :mod:`.breakpoint_dialog` — condition, hit count and log message;
* :mod:`.actions` — the Debug menu, toolbar and keys.
"""

from __future__ import annotations

from PySide6.QtCore import Qt

from plcbuilder.ide.debug.session import DOCKS, DebugSession

__all__ = ["DebugSession", "build_docks"]


def build_docks(win) -> None:
    """Call Stack and Breakpoints (left, tabbed under the project) and Forces
    (right, beside the inputs and watch once the run docks are placed)."""
    from plcbuilder.ide.docks import LazyPanels, make_dock
    dbg = win.debug
    left = Qt.DockWidgetArea.LeftDockWidgetArea
    # empty: each gets its panel when it first shows (or the session uses it)
    win.callstack_dock = make_dock(win, "Call Stack", "callStackDock", None, left)
    win.splitDockWidget(win.project_dock, win.callstack_dock, Qt.Orientation.Vertical)
    win.breakpoints_dock = make_dock(win, "Breakpoints", "breakpointsDock", None, left)
    win.tabifyDockWidget(win.callstack_dock, win.breakpoints_dock)
    win.forces_dock = make_dock(win, "Forces", "forcesDock", None,
                                Qt.DockWidgetArea.RightDockWidgetArea)
    win.callstack_dock.raise_()
    dbg.panels = LazyPanels({key: getattr(win, name) for key, name in DOCKS.items()},
                            dbg.make_panel)
