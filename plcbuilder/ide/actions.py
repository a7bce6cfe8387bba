"""The main window's actions, menus and toolbar.

Actions are named by :class:`Act` (``window.action(Act.BUILD_ALL)``); the
functions here make them for a :class:`~plcbuilder.ide.main_window.MainWindow`,
put them in the menus and the toolbar, and enable them for the window's state.
"""

from __future__ import annotations

from PySide6.QtCore import QSize, Qt
from PySide6.QtGui import QAction, QKeySequence
from PySide6.QtWidgets import QLabel, QToolBar

from plcbuilder.api import Kind
from plcbuilder.ide.icons import icon


class Act:
    """Names of the window's actions (``window.action(Act.BUILD_ALL)``)."""
    NEW_PROCEDURE = "new_procedure"
    NEW_PROJECT = "new_project"
    NEW_HEADER = "new_header"
    OPEN_PROJECT = "open_project"
    OPEN_EXAMPLE = "open_example"
    CLOSE_PROJECT = "close_project"
    SAVE = "save"
    SAVE_ALL = "save_all"
    REVERT = "revert"
    CLOSE_EDITOR = "close_editor"
    CLOSE_ALL = "close_all"
    PREFERENCES = "preferences"
    QUIT = "quit"
    UNDO = "undo"
    REDO = "redo"
    CUT = "cut"
    COPY = "copy"
    PASTE = "paste"
    SELECT_ALL = "select_all"
    TOGGLE_COMMENT = "toggle_comment"
    FIND = "find"
    REPLACE = "replace"
    FIND_NEXT = "find_next"
    FIND_PREVIOUS = "find_previous"
    GOTO_LINE = "goto_line"
    GOTO_DEFINITION = "goto_definition"
    COMPLETE = "complete"
    ZOOM_IN = "zoom_in"
    ZOOM_OUT = "zoom_out"
    ZOOM_RESET = "zoom_reset"
    NEXT_TAB = "next_tab"
    PREVIOUS_TAB = "previous_tab"
    RESET_LAYOUT = "reset_layout"
    BUILD_ALL = "build_all"
    UPLOAD = "upload"
    START = "start"
    START_CURRENT = "start_current"
    STOP = "stop"
    RUN_TESTS = "run_tests"
    RESET_CONTROLLER = "reset_controller"
    CONNECT = "connect"
    EMBEDDED = "embedded"
    ABOUT = "about"
    BUILD_UPLOAD_START = "build_upload_start"
    RUN_GCODE = "run_gcode"
    PAUSE_GCODE = "pause_gcode"
    PLAY_GCODE = "play_gcode"
    STOP_GCODE = "stop_gcode"
    ISSUE_CODE = "issue_code"
    # the debugger (plcbuilder.ide.debug.actions makes these)
    PAUSE = "pause"
    STEP_OVER = "step_over"
    STEP_INTO = "step_into"
    STEP_OUT = "step_out"
    STEP_TICK = "step_tick"
    RUN_TO_CURSOR = "run_to_cursor"
    STEP_BACK = "step_back"
    STEP_BACK_TICK = "step_back_tick"
    RUN_BACK = "run_back"
    TOGGLE_BREAKPOINT = "toggle_breakpoint"
    TOGGLE_ALL_BREAKPOINTS = "toggle_all_breakpoints"
    REMOVE_ALL_BREAKPOINTS = "remove_all_breakpoints"
    RELEASE_ALL = "release_all"
    OPEN_TRACE = "open_trace"
    SAVE_TRACE = "save_trace"
    EXPORT_TRACE = "export_trace"
    EXPORT_PLOT = "export_plot"
    COMPARE_TRACE = "compare_trace"
    CLEAR_COMPARISON = "clear_comparison"
    SAVE_RECORDING = "save_recording"
    REPLAY_SESSION = "replay_session"
    # navigation, build insight, registers and help (made by plcbuilder.ide.workbench)
    BACK = "back"
    FORWARD = "forward"
    QUICK_OPEN = "quick_open"
    FIND_IN_FILES = "find_in_files"
    FIND_REFERENCES = "find_references"
    RENAME_SYMBOL = "rename_symbol"
    SHOW_DISASSEMBLY = "show_disassembly"
    CODE_BYTES = "code_bytes"
    REGISTERS = "registers"
    MANUAL = "manual"
    SHORTCUTS = "shortcuts"
    WHAT_IS_THIS = "what_is_this"


def add_action(win, actions: dict, name, text, slot=None, shortcut=None, ic=None, tip=None,
                editor_scope=False, checkable=False) -> QAction:
    act = QAction(text, win)
    act.setObjectName(name)
    if ic:
        act.setIcon(icon(ic))
    if shortcut:
        act.setShortcuts(shortcut if isinstance(shortcut, list) else [QKeySequence(shortcut)])
    if tip:
        act.setStatusTip(tip)
        act.setToolTip(f"{tip} ({act.shortcut().toString(QKeySequence.SequenceFormat.NativeText)})"
                       if shortcut else tip)
    act.setCheckable(checkable)
    if slot is not None:
        act.triggered.connect(lambda _checked=False: slot())
    if editor_scope:
        act.setShortcutContext(Qt.ShortcutContext.WidgetWithChildrenShortcut)
        win.stack.addAction(act)
    else:
        win.addAction(act)
    actions[name] = act
    return act


def build_actions(win) -> dict[str, QAction]:
    """The window's actions, by name (:class:`Act`)."""
    actions: dict[str, QAction] = {}
    K = QKeySequence.StandardKey

    def A(*args, **kw):
        return add_action(win, actions, *args, **kw)

    def ed(fn):
        return with_editor(win, fn)

    A(Act.NEW_PROCEDURE, "&New Procedure…", lambda: win.tree.new_procedure(Kind.HARDWARE),
      "Ctrl+N", "new", "Create a procedure")
    A(Act.NEW_HEADER, "New &Header…", win.tree.new_header, None, "file-header",
      "Create a header in include/")
    A(Act.NEW_PROJECT, "New &Project…", win.new_project, "Ctrl+Shift+N", "project",
      "Create a project for myCNC, Huazhong or TG Motion from its example, and open it")
    A(Act.OPEN_PROJECT, "&Open Project…", win.open_project_dialog, "Ctrl+Shift+O", "open",
      "Open a project folder")
    A(Act.OPEN_EXAMPLE, "Open &Example Project…", win.open_example_project, None, "example",
      "Make a copy of the example project and open it")
    A(Act.CLOSE_PROJECT, "Close Project", win.close_project)
    A(Act.SAVE, "&Save", win.save_editor, "Ctrl+S", "save", "Save the file")
    A(Act.SAVE_ALL, "Save A&ll", win.save_all, "Ctrl+Shift+S", "save-all", "Save every file")
    A(Act.REVERT, "&Revert to Saved", win.revert_editor)
    A(Act.CLOSE_EDITOR, "&Close Editor", win.close_editor, "Ctrl+W")
    A(Act.CLOSE_ALL, "Close All Editors", lambda: win.editor_stack.close_all(), "Ctrl+Shift+W")
    A(Act.PREFERENCES, "&Preferences…", win.edit_preferences, "Ctrl+,")
    A(Act.QUIT, "&Quit", win.close, "Ctrl+Q")
    A(Act.UNDO, "&Undo", ed(lambda e: e.undo()), K.Undo, editor_scope=True)
    A(Act.REDO, "&Redo", ed(lambda e: e.redo()), [QKeySequence("Ctrl+Y"),
                                                 QKeySequence("Ctrl+Shift+Z")], editor_scope=True)
    A(Act.CUT, "Cu&t", ed(lambda e: e.cut()), K.Cut, editor_scope=True)
    A(Act.COPY, "&Copy", ed(lambda e: e.copy()), K.Copy, editor_scope=True)
    A(Act.PASTE, "&Paste", ed(lambda e: e.paste()), K.Paste, editor_scope=True)
    A(Act.SELECT_ALL, "Select &All", ed(lambda e: e.selectAll()), K.SelectAll,
      editor_scope=True)
    A(Act.TOGGLE_COMMENT, "Toggle &Comment", ed(lambda e: e.toggle_comment()), "Ctrl+/",
      "comment", "Comment or uncomment the selected lines", editor_scope=True)
    A(Act.FIND, "&Find…", lambda: win.show_find(False), "Ctrl+F", "find", "Find in the file")
    A(Act.REPLACE, "R&eplace…", lambda: win.show_find(True), "Ctrl+H", None,
      "Find and replace in the file")
    A(Act.FIND_NEXT, "Find &Next", lambda: win.find_bar.find_next(), "F3")
    A(Act.FIND_PREVIOUS, "Find Pre&vious", lambda: win.find_bar.find_previous(), "Shift+F3")
    A(Act.GOTO_LINE, "&Go to Line…", win.goto_line_dialog, "Ctrl+G", "goto",
      "Go to a line of the file")
    A(Act.GOTO_DEFINITION, "Go to &Definition", ed(lambda e: win.goto_definition(
        e.word_under_caret())), "F12", None, "Go to where the name under the caret is defined",
      editor_scope=True)
    A(Act.COMPLETE, "Complete", ed(lambda e: e.show_completions(explicit=True)), "Ctrl+Space",
      editor_scope=True)
    A(Act.ZOOM_IN, "Zoom &In", ed(lambda e: e.zoomIn()), [QKeySequence("Ctrl++"),
                                                       QKeySequence("Ctrl+=")])
    A(Act.ZOOM_OUT, "Zoom &Out", ed(lambda e: e.zoomOut()), "Ctrl+-")
    A(Act.ZOOM_RESET, "Reset Zoom", ed(lambda e: e.setZoom(0)), "Ctrl+0")
    A(Act.NEXT_TAB, "Next Editor", lambda: win.editor_stack.cycle_tab(1), "Ctrl+PgDown")
    A(Act.PREVIOUS_TAB, "Previous Editor", lambda: win.editor_stack.cycle_tab(-1), "Ctrl+PgUp")
    A(Act.RESET_LAYOUT, "Reset Layout", win.reset_layout)
    A(Act.BUILD_ALL, "&Build All", win.build_all, "Ctrl+B", "build",
      "Compile every procedure and write build/eeprom.rom")
    A(Act.UPLOAD, "&Upload", win.upload, "Ctrl+U", "upload",
      "Upload build/eeprom.rom to the controller")
    A(Act.START, "&Start…", win.start_or_continue, "F5", "start",
      "Start a procedure on the controller (by name or M-code, with eparam)")
    A(Act.BUILD_UPLOAD_START, "Build, Upload and Start", win.run_actions.build_upload_start,
      "Ctrl+R", "start", "Build All, upload the image and start the current editor's "
      "procedure")
    A(Act.START_CURRENT, "Start &This Procedure", win.run_actions.start_current, "Ctrl+F5", None,
      "Start the procedure of the current editor with the last eparam")
    A(Act.STOP, "S&top", win.stop, "Shift+F5", "stop",
      "Stop: the first press starts M02, the second OFF")
    A(Act.RUN_GCODE, "Run &G-code Program…", lambda: win.run_actions.run_gcode(), None, None,
      "Run a G-code program as a job: its M-codes start their procedures "
      "(docs/controller.md, G-code jobs)")
    A(Act.PAUSE_GCODE, "Pause G-code Program", lambda: win.run_actions.job("pause"), None, None,
      "Pause the G-code job (its move decelerates; Continue goes on)")
    A(Act.PLAY_GCODE, "Continue G-code Program", lambda: win.run_actions.job("play"), None, None,
      "Continue the paused G-code job, or run it again from its first line")
    A(Act.STOP_GCODE, "Stop G-code Program", lambda: win.run_actions.job("stop"), None, None,
      "Stop the G-code job (its move decelerates; __HANDLER_GCODE_STOP runs)")
    A(Act.ISSUE_CODE, "&Issue Code…", lambda: win.run_actions.issue_code(), None, None,
      "The CNC issues an M, S, B or T code (M3, S12000) to the running controller, as a "
      "G-code program or a scenario's 'code M3' does")
    A(Act.RUN_TESTS, "Run &Tests", lambda: (win.tests_dock.show(), win.tests_dock.raise_(),
                                            win.tests_panel.run_tests()), "Ctrl+T", None,
      "Build the project and run its scenario tests (tests/*.toml)")
    A(Act.RESET_CONTROLLER, "&Reset Controller", win.run_actions.reset_controller, None, "reset",
      "A fresh controller with the same image (time starts again at 0)")
    A(Act.CONNECT, "&Connect to Controller…", win.connect_dialog, None, "connect",
      "Connect to a running plcbuilder controller")
    A(Act.EMBEDDED, "Use the &Embedded Controller", win.run_actions.use_embedded, None, "controller",
      "Run the simulated controller as a child process of the IDE")
    A(Act.ABOUT, "&About PLC Builder", win.about)
    from plcbuilder.ide import trace_actions as ta
    A(Act.OPEN_TRACE, "Open &Trace…", lambda: ta.open_trace(win), None, None,
      "Open a saved trace or capture (.plctrace) in the run panels")
    A(Act.SAVE_TRACE, "Save Trace…", lambda: ta.save_trace(win), None, None,
      "Save the trace on show, or the whole session so far, as a .plctrace file")
    A(Act.EXPORT_TRACE, "Export Trace…", lambda: ta.export_trace(win), None, None,
      "Export the trace on show, or the whole session, as VCD or CSV")
    A(Act.EXPORT_PLOT, "Export Plot Image…", lambda: ta.export_plot(win), None, None,
      "Save the plots of the first visible run dock as PNG or SVG")
    A(Act.COMPARE_TRACE, "Compare with Trace…", lambda: ta.compare_trace(win), None, None,
      "Draw a trace file over the trace on show (or the session), with a line at the "
      "first tick where they differ")
    A(Act.CLEAR_COMPARISON, "Clear Comparison", lambda: ta.clear_comparison(win), None, None,
      "Stop drawing the compared trace over the one on show")
    actions[Act.CLEAR_COMPARISON].setEnabled(False)      # until a comparison is on show
    A(Act.SAVE_RECORDING, "Save Session &Recording…", lambda: ta.save_recording(win), None, None,
      "Save everything done to the controller since it started, as a scenario file that "
      "replays the session")
    A(Act.REPLAY_SESSION, "Re&play Session…", lambda: ta.replay_session(win), None, None,
      "Run a session recording on the project's image and show its trace")
    context = [actions[a] for a in (Act.TOGGLE_COMMENT, Act.GOTO_DEFINITION)] + \
        [None] + [actions[a] for a in (Act.FIND, Act.GOTO_LINE)]
    win.editor_stack.context_actions = context
    win.run_actions.sig_job_state.connect(lambda _state: update_actions(win))
    return actions


def build_menus(win) -> None:
    mb = win.menuBar()
    a = win.action
    m = mb.addMenu("&File")
    for name in (Act.NEW_PROJECT, Act.NEW_PROCEDURE, Act.NEW_HEADER, None, Act.OPEN_PROJECT,
                 Act.OPEN_EXAMPLE):
        m.addAction(a(name)) if name else m.addSeparator()
    win.recent_menu = m.addMenu("Recent &Projects")
    m.addAction(a(Act.CLOSE_PROJECT))
    m.addSeparator()
    for name in (Act.SAVE, Act.SAVE_ALL, Act.REVERT, None, Act.CLOSE_EDITOR, Act.CLOSE_ALL,
                 None, Act.OPEN_TRACE, Act.SAVE_TRACE, Act.EXPORT_TRACE, Act.EXPORT_PLOT,
                 Act.COMPARE_TRACE, Act.CLEAR_COMPARISON, None, Act.PREFERENCES, None, Act.QUIT):
        m.addAction(a(name)) if name else m.addSeparator()
    m = mb.addMenu("&Edit")
    for name in (Act.UNDO, Act.REDO, None, Act.CUT, Act.COPY, Act.PASTE, Act.SELECT_ALL, None,
                 Act.TOGGLE_COMMENT, Act.COMPLETE, None, Act.FIND, Act.REPLACE, Act.FIND_NEXT,
                 Act.FIND_PREVIOUS, None, Act.GOTO_LINE, Act.GOTO_DEFINITION):
        m.addAction(a(name)) if name else m.addSeparator()
    win.view_menu = mb.addMenu("&View")
    m = mb.addMenu("&Build")
    for name in (Act.BUILD_ALL, Act.UPLOAD):
        m.addAction(a(name))
    m = mb.addMenu("&Run")
    for name in (Act.START, Act.START_CURRENT, Act.BUILD_UPLOAD_START, Act.STOP, None,
                 Act.RUN_GCODE, Act.PAUSE_GCODE, Act.PLAY_GCODE, Act.STOP_GCODE,
                 Act.ISSUE_CODE, None,
                 Act.RUN_TESTS, None, Act.SAVE_RECORDING, Act.REPLAY_SESSION):
        m.addAction(a(name)) if name else m.addSeparator()
    m.addSeparator()
    speed = m.addMenu(icon("speed"), "Simulation &Speed")
    for act in win.run_actions.speed_actions.values():
        speed.addAction(act)
    m.addAction(a(Act.RESET_CONTROLLER))
    m.addSeparator()
    m.addAction(a(Act.CONNECT))
    m.addAction(a(Act.EMBEDDED))
    m = mb.addMenu("&Help")
    m.addAction(a(Act.ABOUT))
    fill_recent_menu(win)


def fill_view_menu(win) -> None:
    m = win.view_menu
    m.clear()
    # the window's docks, as its dock table lists them
    from plcbuilder.ide.docks import view_actions
    for act in view_actions(win):
        m.addAction(act) if act is not None else m.addSeparator()
    m.addSeparator()
    m.addAction(win.toolbar.toggleViewAction())
    if getattr(win, "debug_toolbar", None) is not None:
        m.addAction(win.debug_toolbar.toggleViewAction())
    m.addSeparator()
    for name in (Act.ZOOM_IN, Act.ZOOM_OUT, Act.ZOOM_RESET, None, Act.NEXT_TAB,
                 Act.PREVIOUS_TAB, None, Act.RESET_LAYOUT):
        m.addAction(win.action(name)) if name else m.addSeparator()


def fill_recent_menu(win) -> None:
    m = win.recent_menu
    m.clear()
    recent = win.settings.recent_projects()
    for path in recent:
        act = m.addAction(icon("project"), path)
        act.triggered.connect(lambda _c=False, p=path: win.open_project(p))
    if recent:
        m.addSeparator()
        m.addAction("Clear List", lambda: clear_recent(win))
    else:
        act = m.addAction("(none yet)")
        act.setEnabled(False)
    win.welcome.set_recent(recent)


def clear_recent(win) -> None:
    win.settings.clear_recent_projects()
    fill_recent_menu(win)


def build_toolbar(win) -> None:
    tb = QToolBar("Main Toolbar", win)
    tb.setObjectName("mainToolbar")
    tb.setIconSize(QSize(20, 20))
    tb.setMovable(False)
    tb.setToolButtonStyle(Qt.ToolButtonStyle.ToolButtonTextBesideIcon)
    for name in (Act.NEW_PROCEDURE, Act.SAVE, Act.SAVE_ALL):
        tb.addAction(win.action(name))
        tb.widgetForAction(win.action(name)).setToolButtonStyle(
            Qt.ToolButtonStyle.ToolButtonIconOnly)
    tb.addSeparator()
    tb.addAction(win.action(Act.BUILD_ALL))
    tb.addAction(win.action(Act.UPLOAD))
    tb.addSeparator()
    tb.addAction(win.action(Act.START))
    tb.addAction(win.action(Act.STOP))
    tb.addSeparator()
    lab = QLabel(" Speed ", tb)
    lab.setPixmap(icon("speed").pixmap(16, 16))
    tb.addWidget(lab)
    tb.addWidget(win.run_actions.make_speed_combo(tb))
    win.toolbar = tb
    win.addToolBar(Qt.ToolBarArea.TopToolBarArea, tb)


def with_editor(win, fn):
    def run():
        ed = win.current_editor()
        if ed is not None:
            fn(ed)
    return run


def update_actions(win) -> None:
    has_project = win.project is not None
    ed = win.current_editor()
    has_editor = ed is not None
    for name in (Act.NEW_PROCEDURE, Act.NEW_HEADER, Act.CLOSE_PROJECT, Act.RUN_TESTS):
        win.action(name).setEnabled(has_project)
    win.action(Act.BUILD_ALL).setEnabled(has_project and not win.run_actions.building())
    for name in (Act.SAVE, Act.REVERT, Act.CLOSE_EDITOR, Act.CLOSE_ALL, Act.FIND,
                 Act.REPLACE, Act.GOTO_LINE, Act.TOGGLE_COMMENT, Act.GOTO_DEFINITION):
        win.action(name).setEnabled(has_editor)
    if has_editor and ed.builtin:
        win.action(Act.SAVE).setEnabled(False)
        win.action(Act.TOGGLE_COMMENT).setEnabled(False)
    run = win.connection is not None and has_project
    for name in (Act.UPLOAD, Act.START, Act.START_CURRENT, Act.STOP, Act.RESET_CONTROLLER,
                 Act.BUILD_UPLOAD_START, Act.RUN_GCODE, Act.ISSUE_CODE):
        win.action(name).setEnabled(run)
    for name, verb in ((Act.PAUSE_GCODE, "pause"), (Act.PLAY_GCODE, "play"),
                       (Act.STOP_GCODE, "stop")):         # as the job's state allows
        win.action(name).setEnabled(run and win.run_actions.job_allows(verb))
    if Act.BUILD_UPLOAD_START in win._actions:          # the workbench's actions
        win.action(Act.BUILD_UPLOAD_START).setEnabled(run)
        for name in (Act.FIND_REFERENCES, Act.RENAME_SYMBOL, Act.WHAT_IS_THIS):
            win.action(name).setEnabled(has_editor)
        win.action(Act.RENAME_SYMBOL).setEnabled(has_editor and has_project and not ed.builtin)
        for name in (Act.QUICK_OPEN, Act.FIND_IN_FILES):
            win.action(name).setEnabled(has_project)
    for name in (Act.CONNECT, Act.EMBEDDED):
        win.action(name).setEnabled(win.connection is not None)
    win.run_actions.speed_combo.setEnabled(win.connection is not None)
    if win.connection is None:
        tip = "The run side (controller connection) is not available"
        for name in (Act.UPLOAD, Act.START, Act.STOP):
            win.action(name).setToolTip(tip)
