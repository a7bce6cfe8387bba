"""The Debug menu, the debug toolbar and their keys (as VS Code users know them).

    F5          Start… / Continue (while halted)     F9          Toggle Breakpoint
    F6          Pause                                Ctrl+Shift+F9  Remove All Breakpoints
    F10         Step Over                            F7          Step 1 ms (one tick)
    F11         Step Into                            Ctrl+F10    Run to Cursor
    Shift+F11   Step Out                             Shift+F5    Stop (as before)
    Shift+F10   Step Back (a statement)              Shift+F7    Step Back 1 ms
    Ctrl+Shift+F10  Run Back (to the previous breakpoint hit)

F5 keeps its old meaning (Start…) until the controller halts; then it continues.
"""

from __future__ import annotations

from PySide6.QtCore import QSize, Qt
from PySide6.QtWidgets import QToolBar

from plcbuilder.ide.actions import Act, add_action


def build_debug_actions(win, actions: dict) -> None:
    """Add the debugger's actions to the window's (``win.action(Act.STEP_OVER)``)."""
    dbg = win.debug

    def A(*args, **kw):
        return add_action(win, actions, *args, **kw)

    A(Act.PAUSE, "&Pause", dbg.pause, "F6", "pause",
      "Halt the controller at the end of this tick")
    A(Act.STEP_OVER, "Step &Over", lambda: dbg.step("over"), "F10", "debug-step-over",
      "Run the next statement of the halted procedure (a call runs whole)")
    A(Act.STEP_INTO, "Step &Into", lambda: dbg.step("into"), "F11", "debug-step-into",
      "Run the next statement, entering a called procedure")
    A(Act.STEP_OUT, "Step O&ut", lambda: dbg.step("out"), "Shift+F11", "debug-step-out",
      "Run until the called procedure returns to its caller")
    A(Act.STEP_TICK, "Step 1 &ms", lambda: dbg.step("tick"), "F7", "debug-step-tick",
      "Run exactly one 1 ms tick of the whole controller, then halt")
    A(Act.RUN_TO_CURSOR, "&Run to Cursor", dbg.run_to, "Ctrl+F10", "debug-run-to",
      "Run until a procedure reaches the caret's line")
    A(Act.STEP_BACK, "Step &Back", lambda: dbg.step_back("statement"), "Shift+F10",
      "debug-step-back", "Go back one statement of the halted procedure (the session runs "
      "again from its recording)")
    A(Act.STEP_BACK_TICK, "Step Back 1 m&s", lambda: dbg.step_back("tick"), "Shift+F7",
      "debug-step-back-tick", "Go back one 1 ms tick of the whole controller")
    A(Act.RUN_BACK, "Run Bac&k", dbg.run_back, "Ctrl+Shift+F10", "debug-run-back",
      "Go back to the previous breakpoint hit")
    A(Act.TOGGLE_BREAKPOINT, "Toggle &Breakpoint", dbg.toggle_breakpoint, "F9",
      "debug-breakpoint", "Add or remove a breakpoint on the caret's line")
    A(Act.REMOVE_ALL_BREAKPOINTS, "Remove &All Breakpoints", dbg.store.clear, "Ctrl+Shift+F9",
      None, "Remove every breakpoint of the project")
    A(Act.TOGGLE_ALL_BREAKPOINTS, "&Enable or Disable All Breakpoints",
      lambda: dbg.breakpoints_panel.toggle_all(), None, None,
      "Disable every breakpoint (or enable them all again)")
    A(Act.RELEASE_ALL, "Release All &Forces", lambda: dbg.release_all(
        dbg.forces_panel.release_mode()), None, "debug-force",
      "Release everything forced (inputs, outputs, ADC, variables...)")


def build_debug_menu(win, before) -> None:
    """The Debug menu, before ``before`` (the Help menu's action)."""
    m = win.menuBar().addMenu("&Debug")
    win.menuBar().insertMenu(before, m)
    for name in (Act.START, Act.PAUSE, Act.STOP, None, Act.STEP_OVER, Act.STEP_INTO,
                 Act.STEP_OUT, Act.STEP_TICK, Act.RUN_TO_CURSOR, None, Act.STEP_BACK,
                 Act.STEP_BACK_TICK, Act.RUN_BACK, None, Act.TOGGLE_BREAKPOINT,
                 Act.TOGGLE_ALL_BREAKPOINTS, Act.REMOVE_ALL_BREAKPOINTS, None, Act.RELEASE_ALL):
        m.addAction(win.action(name)) if name else m.addSeparator()
    win.debug_menu = m


def build_debug_toolbar(win) -> QToolBar:
    tb = QToolBar("Debug Toolbar", win)
    tb.setObjectName("debugToolbar")
    tb.setIconSize(QSize(20, 20))
    tb.setToolButtonStyle(Qt.ToolButtonStyle.ToolButtonIconOnly)
    for name in (Act.PAUSE, Act.STEP_OVER, Act.STEP_INTO, Act.STEP_OUT, Act.STEP_TICK,
                 Act.RUN_TO_CURSOR, Act.STEP_BACK, Act.STEP_BACK_TICK, Act.RUN_BACK, None,
                 Act.TOGGLE_BREAKPOINT):
        tb.addAction(win.action(name)) if name else tb.addSeparator()
    win.addToolBar(Qt.ToolBarArea.TopToolBarArea, tb)
    win.debug_toolbar = tb
    return tb


def update_debug_actions(win) -> None:
    """Enable the debug actions for the state: connected, halted, an editor."""
    dbg = getattr(win, "debug", None)
    if dbg is None:
        return
    connected = dbg.connected() and win.project is not None
    halted = connected and dbg.is_halted()
    steppable = halted and dbg.step_procedure() is not None
    ed = win.current_editor()
    win.action(Act.PAUSE).setEnabled(connected and not halted)
    for name in (Act.STEP_OVER, Act.STEP_INTO, Act.STEP_OUT):
        win.action(name).setEnabled(steppable)
    win.action(Act.STEP_TICK).setEnabled(halted)
    win.action(Act.STEP_BACK).setEnabled(halted and bool((dbg.halted or {}).get("procedure")))
    win.action(Act.STEP_BACK_TICK).setEnabled(halted)
    win.action(Act.RUN_BACK).setEnabled(halted)
    win.action(Act.RUN_TO_CURSOR).setEnabled(connected and dbg.breakable(ed))
    win.action(Act.TOGGLE_BREAKPOINT).setEnabled(dbg.breakable(ed))
    win.action(Act.RELEASE_ALL).setEnabled(connected and bool(dbg.forces))
    start = win.action(Act.START)
    if halted:
        start.setText("&Continue")
        start.setIcon(_icon("debug-continue"))
        start.setStatusTip("Continue running (F5)")
        start.setToolTip("Continue running the halted controller (F5)")
        start.setEnabled(True)
    else:
        start.setText("&Start…")
        start.setIcon(_icon("start"))
        start.setStatusTip("Start a procedure on the controller (by name or M-code, with eparam)")
        start.setToolTip("Start a procedure on the controller (by name or M-code, with "
                         "eparam) (F5)")


def _icon(name: str):
    from plcbuilder.ide.icons import icon
    return icon(name)
