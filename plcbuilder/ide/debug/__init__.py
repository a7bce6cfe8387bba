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

from plcbuilder.ide.debug.session import DOCKS, DebugSession

__all__ = ["DOCKS", "DebugSession", "dock_panel"]


def dock_panel(win, key: str):
    """The panel of a debug dock (Call Stack, Breakpoints, Forces: docks.DOCKS),
    made when it first shows or the session uses it."""
    return win.debug.make_panel(key)
