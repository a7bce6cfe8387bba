"""The debugger's IDE side driven like a user would, against a connection that
records what the window asks and plays the controller's answers (the halted
state, the forces) as the debug contract names them. The same flows against
the real embedded controller are in test_debug_live.py."""

from __future__ import annotations

import zlib

import pytest
import shiboken6
from PySide6.QtCore import Qt, QTimer, Signal
from PySide6.QtGui import QKeySequence
from PySide6.QtWidgets import QDialog, QMessageBox

from plcbuilder.ide.actions import Act
from plcbuilder.ide.debug.breakpoint_dialog import BreakpointDialog
from plcbuilder.ide.debug.callstack import frames_of
from plcbuilder.ide.debug.inline import inline_values, names_on_lines
from plcbuilder.ide.editor import (MK_BREAKPOINT, MK_BREAKPOINT_CONDITIONAL,
                                   MK_BREAKPOINT_DISABLED, MK_BREAKPOINT_UNVERIFIED,
                                   MK_LOGPOINT, MK_WAIT)
from plcbuilder.ide.settings import Settings
from plcbuilder.link.client import ControllerStatus
from plcbuilder.project.new import create_project

from tests.ide import _workbench
from tests.ide._debug import HOME_LINE, click_margin
from tests.ide._workbench import RecordingConnection, windows


class DebugConnection(RecordingConnection):
    """The ControllerConnection interface with the debugger's requests."""
    sig_result = Signal(str, dict)
    sig_variables = Signal(object)
    sig_note = Signal(str)
    sig_halted = Signal(object)
    sig_resumed = Signal(int)
    sig_breakpoints = Signal(str, list)
    sig_breakpoints_refused = Signal(str, str)
    sig_forces_changed = Signal(list)
    sig_log = Signal(object)
    VERBS = RecordingConnection.VERBS + (
        "request_variables", "set_breakpoints", "debug_continue", "debug_pause", "debug_step",
        "debug_run_to", "request_debug_state", "write", "force", "release", "release_all",
        "request_forces", "send_event")

    def __init__(self):
        super().__init__()
        self.debugger = True
        self.last_state = ControllerStatus()

    def named(self, name):
        return [c for c in self.calls if c[0] == name]

    def connect_now(self):
        self.connected = True
        self.sig_connected.emit("127.0.0.1:5999")


settings = _workbench.settings


@pytest.fixture
def example(tmp_path):
    return create_project(tmp_path / "example", name="example").root


@pytest.fixture
def no_prompts(monkeypatch):
    calls = []
    for name in ("warning", "question", "critical", "information"):
        monkeypatch.setattr(QMessageBox, name, lambda *a, _n=name, **k: (
            calls.append((_n,) + a[1:3]), QMessageBox.StandardButton.No)[1])
    return calls


@pytest.fixture
def make_window(qtbot, settings, no_prompts):
    with windows(qtbot, settings, (1300, 850)) as make_main:
        def make(conn=None, **kw):
            conn = conn or DebugConnection()
            return make_main(connection=conn, start_controller=True, **kw), conn
        yield make


def open_m80(w, example):
    assert w.open_project(example)
    return w.open_file(example / "hardware" / "M80.plc")


def halted_state(t_ms=1234, line=HOME_LINE, statez=0, sens=0):
    return {
        "reason": "breakpoint", "t_ms": t_ms, "procedure": "M80", "file": "M80.plc",
        "line": line, "fault": None, "breakpoint": {"id": 1, "file": "M80.plc", "line": line},
        "procedures": [
            {"name": "M80", "kind": "hardware", "file": "M80.plc", "line": line,
             "at_loop_end": False,
             "stack": [{"procedure": "main", "file": "M80.plc", "line": 75},
                       {"procedure": "find_home_z", "file": "M80.plc", "line": line}],
             "vars": {"code": 0, "statez": statez, "speed": 500, "speed_slow": 100,
                      "direction": 1024, "changed": 0, "sens": sens, "ready": 0}},
            {"name": "LUBE", "kind": "software", "file": "LUBE.plc", "line": 14,
             "at_loop_end": True, "stack": [], "vars": {"timer": 12}},
        ],
        "machine": {"inputs": [0] * 8, "outputs": [0] * 8, "adc": [0] * 8, "pwm": [0] * 8,
                    "dac": [0] * 8, "axes": {"Z": -1200}},
    }


# ------------------------------------------------------------------ pure parts
def test_inline_values_name_the_variables_each_line_uses():
    text = "a = b + 1; // c is not used\n/* d */ x = y;\n#define Q 1\nif (a) { a = 2; }\n"
    assert names_on_lines(text) == {1: ["a", "b"], 2: ["x", "y"], 4: ["a"]}
    shown = inline_values(text, {"a": 3, "b": -1, "y": 7}, forced=frozenset({"y"}))
    assert shown == {1: "a = 3 · b = -1", 2: "y = 7 (forced)", 4: "a = 3"}


def test_frames_come_innermost_first_whatever_the_stack_order():
    proc = {"name": "M80", "file": "M80.plc", "line": 31,
            "stack": [{"procedure": "main", "file": "M80.plc", "line": 75},
                      {"procedure": "find_home_z", "file": "M80.plc", "line": 31}]}
    frames = frames_of(proc)
    assert [(f["procedure"], f["line"], f["index"]) for f in frames] == \
        [("find_home_z", 31, 0), ("main", 75, 1)]
    proc["stack"].reverse()
    assert [f["line"] for f in frames_of(proc)] == [31, 75]


# ------------------------------------------------------------------ breakpoints
def test_clicking_the_margin_toggles_a_breakpoint_that_follows_edits(make_window, example,
                                                                      qtbot):
    w, _conn = make_window()
    ed = open_m80(w, example)
    click_margin(qtbot, ed, HOME_LINE)
    bp = w.debug.store.at(ed.path, HOME_LINE)
    assert bp is not None and bp.enabled
    assert ed.debug_marks.breakpoint_lines() == {HOME_LINE: MK_BREAKPOINT}
    items = w.debug.breakpoints_panel.breakpoint_items()
    assert [(i.text(0), i.text(1)) for i in items] == [("M80.plc", str(HOME_LINE))]
    # two lines typed above it: the marker and the breakpoint move with the text
    ed.insertText(ed.position_of(6, 1), "// one\n// two\n")
    assert ed.debug_marks.breakpoint_lines() == {HOME_LINE + 2: MK_BREAKPOINT}
    assert bp.line == HOME_LINE + 2
    assert w.debug.breakpoints_panel.breakpoint_items()[0].text(1) == str(HOME_LINE + 2)
    click_margin(qtbot, ed, HOME_LINE + 2)
    assert len(w.debug.store) == 0 and ed.debug_marks.breakpoint_lines() == {}


def test_margin_menu_adds_a_logpoint_and_edits_a_condition(make_window, example, qtbot,
                                                           monkeypatch):
    w, _conn = make_window()
    ed = open_m80(w, example)
    answers = []

    def fake_exec(dlg):
        field, text = answers.pop(0)
        getattr(dlg, field).setText(text)
        dlg.accept()
        return QDialog.DialogCode.Accepted
    monkeypatch.setattr(BreakpointDialog, "exec", fake_exec)
    menu = ed.margin_menu_provider(ed, 41)
    names = [a.objectName() for a in menu.actions() if a.objectName()]
    assert names == ["add", "add_condition", "add_hit", "add_log", "run_to"]
    answers.append(("log", "statez={statez} sens={sens}"))
    next(a for a in menu.actions() if a.objectName() == "add_log").trigger()
    bp = w.debug.store.at(ed.path, 41)
    assert bp.log == "statez={statez} sens={sens}" and bp.kind == "logpoint"
    assert ed.debug_marks.breakpoint_lines() == {41: MK_LOGPOINT}
    menu = ed.margin_menu_provider(ed, 41)
    assert [a.objectName() for a in menu.actions() if a.objectName()][:5] == \
        ["remove", "enable", "edit_condition", "edit_hit", "edit_log"]
    answers.append(("condition", "statez == 1"))
    answers.append(("log", ""))
    next(a for a in menu.actions() if a.objectName() == "edit_condition").trigger()
    next(a for a in ed.margin_menu_provider(ed, 41).actions()
         if a.objectName() == "edit_log").trigger()
    assert (bp.condition, bp.log) == ("statez == 1", None)
    assert ed.debug_marks.breakpoint_lines() == {41: MK_BREAKPOINT_CONDITIONAL}
    assert "when statez == 1" in w.debug.breakpoints_panel.breakpoint_items()[0].text(2)
    next(a for a in ed.margin_menu_provider(ed, 41).actions()
         if a.objectName() == "enable").trigger()
    assert not bp.enabled and ed.debug_marks.breakpoint_lines() == {41: MK_BREAKPOINT_DISABLED}


def test_breakpoints_are_kept_per_project_across_sessions(make_window, example, qtbot,
                                                          settings):
    w, _conn = make_window()
    ed = open_m80(w, example)
    click_margin(qtbot, ed, HOME_LINE)
    w.debug.toggle_breakpoint(ed, 62)
    w.debug.store.update(w.debug.store.at(ed.path, 62), enabled=False, condition="timer > 3",
                         hit={"mode": "ge", "n": 2})
    w.close()
    assert settings.breakpoints(example)[0]["path"] == "hardware/M80.plc"
    w2, _c2 = make_window(settings=Settings(settings.path))
    ed2 = open_m80(w2, example)
    bps = [(b.line, b.enabled, b.condition, b.hit) for b in w2.debug.store.all()]
    assert bps == [(HOME_LINE, True, None, None), (62, False, "timer > 3", {"mode": "ge", "n": 2})]
    assert ed2.debug_marks.breakpoint_lines() == {HOME_LINE: MK_BREAKPOINT,
                                                  62: MK_BREAKPOINT_DISABLED}


def test_breakpoints_panel_enables_goes_to_the_line_and_removes(make_window, example, qtbot):
    w, _conn = make_window()
    ed = open_m80(w, example)
    for line in (HOME_LINE, 41, 62):
        w.debug.toggle_breakpoint(ed, line)
    panel = w.debug.breakpoints_panel
    items = panel.breakpoint_items()
    assert [i.text(1) for i in items] == ["31", "41", "62"]
    items[1].setCheckState(0, Qt.CheckState.Unchecked)
    # the row clicked outlives its own change (the list is rebuilt after it:
    # rebuilt inside it, the row was deleted under Qt's feet and the IDE crashed)
    assert shiboken6.isValid(items[1])
    assert not w.debug.store.at(ed.path, 41).enabled
    assert ed.debug_marks.breakpoint_lines()[41] == MK_BREAKPOINT_DISABLED
    qtbot.waitUntil(lambda: not shiboken6.isValid(items[1]))          # then rebuilt
    assert panel.breakpoint_items()[1].checkState(0) == Qt.CheckState.Unchecked
    ed.goto_line(1)
    panel.tree.itemDoubleClicked.emit(panel.breakpoint_items()[2], 0)
    assert w.current_editor() is ed and ed.cursor_line_col()[0] == 62
    panel.tree.setCurrentItem(panel.breakpoint_items()[0])
    qtbot.keyClick(panel.tree, Qt.Key.Key_Delete)
    assert [b.line for b in w.debug.store.all()] == [41, 62]
    panel.remove_all_button.click()
    assert len(w.debug.store) == 0 and panel.breakpoint_items() == []


def test_breakpoints_go_to_the_controller_and_show_its_answer(make_window, example, qtbot):
    w, conn = make_window()
    ed = open_m80(w, example)
    w.debug.toggle_breakpoint(ed, HOME_LINE)
    w.debug.toggle_breakpoint(ed, 6)
    assert conn.named("set_breakpoints") == []          # not connected yet
    conn.connect_now()
    (_, file, specs), = conn.named("set_breakpoints")
    assert file == "M80.plc"
    assert [(s["line"], s["enabled"], s["condition"]) for s in specs] == \
        [(6, True, None), (HOME_LINE, True, None)]
    conn.sig_breakpoints.emit("M80.plc", [
        {"id": 1, "file": "M80.plc", "line": 7, "verified": True, "reason": None},
        {"id": 2, "file": "M80.plc", "line": HOME_LINE, "verified": True, "reason": None}])
    assert [i.text(1) for i in w.debug.breakpoints_panel.breakpoint_items()] == \
        ["6 → 7", str(HOME_LINE)]
    w.debug.toggle_breakpoint(ed, 200 if ed.lineCount() >= 200 else ed.lineCount())
    qtbot.waitUntil(lambda: len(conn.named("set_breakpoints")) == 2)
    conn.sig_breakpoints.emit("M80.plc", [
        {"id": 1, "file": "M80.plc", "line": 7, "verified": True, "reason": None},
        {"id": 2, "file": "M80.plc", "line": HOME_LINE, "verified": True, "reason": None},
        {"id": 3, "file": "M80.plc", "line": 79, "verified": False,
         "reason": "no code at or after this line"}])
    last = w.debug.breakpoints_panel.breakpoint_items()[-1]
    assert "not set: no code at or after this line" in last.text(2)
    assert ed.debug_marks.breakpoint_lines()[ed.lineCount()] == MK_BREAKPOINT_UNVERIFIED


# ------------------------------------------------------------------ halted
def test_a_halt_shows_lines_call_stack_inline_values_and_hover(make_window, example, qtbot):
    w, conn = make_window()
    ed = open_m80(w, example)
    lube = w.open_file(example / "software" / "LUBE.plc")
    conn.connect_now()
    w.ensure_run_panels()
    caret_line = ed.caretLineBack()
    assert not w.action(Act.STEP_OVER).isEnabled()
    conn.sig_halted.emit(halted_state())
    # the halting procedure's editor is current, at its line, marked
    assert w.current_editor() is ed and ed.cursor_line_col()[0] == HOME_LINE
    assert ed.debug_marks.exec_lines() == [HOME_LINE] and not ed.caretLineVisible()
    assert lube.debug_marks.exec_lines(MK_WAIT) == [14]          # waiting at its loop's end
    # call stack: M80's frames innermost first, LUBE waiting
    texts = w.debug.call_stack.frame_texts()
    assert texts[:2] == [("find_home_z()  ◀", f"M80.plc:{HOME_LINE}"), ("main()", "M80.plc:75")]
    assert "Halted at a breakpoint in M80 at M80.plc:31" in w.debug.call_stack.header.text()
    # inline values on the lines that use the variables
    assert ed.debug_marks.inline_text(HOME_LINE) == "sens = 0"
    assert ed.debug_marks.inline_text(29) == "statez = 0"
    assert bytes(ed.eOLAnnotationText(HOME_LINE - 1)).decode() == "sens = 0"
    # the watch shows the halted values, hover shows the live value
    assert w.run_panels.watch.value("statez", "M80") == 0
    pos = ed.position_of(HOME_LINE, 8)
    assert ed.hover_text_at(pos).startswith("M80.sens = 0 (0x0) — halted")
    # the actions follow: F5 continues, steps step M80
    assert w.action(Act.START).text() == "&Continue"
    assert w.action(Act.STEP_OVER).isEnabled() and not w.action(Act.PAUSE).isEnabled()
    w.action(Act.STEP_OVER).trigger()
    assert conn.calls[-1] == ("debug_step", "over", "M80")
    w.action(Act.STEP_TICK).trigger()
    assert conn.calls[-1] == ("debug_step", "tick", None)
    # a caller's frame clicked: its line is marked, F10 still steps M80
    item = w.debug.call_stack.frame_items()[1]
    w.debug.call_stack.tree.itemClicked.emit(item, 0)
    assert ed.cursor_line_col()[0] == 75
    # after the step the new halt moves the marks
    conn.sig_halted.emit(halted_state(t_ms=1234, line=32, sens=1))
    assert ed.debug_marks.exec_lines() == [32]
    assert ed.debug_marks.inline_text(HOME_LINE) == "sens = 1"
    w.action(Act.START).trigger()
    assert conn.calls[-1] == ("debug_continue",)
    conn.sig_resumed.emit(1300)
    assert ed.debug_marks.exec_lines() == [] and ed.debug_marks.inline == {}
    assert bytes(ed.eOLAnnotationText(HOME_LINE - 1)) == b""
    # the caret line, hidden while halted (it would cover the halted line), is back
    assert ed.caretLineVisible() and ed.caretLineBack() == caret_line
    assert w.action(Act.START).text() == "&Start…" and w.action(Act.PAUSE).isEnabled()


def test_debug_keys_do_not_clash(make_window, example):
    w, _conn = make_window()
    open_m80(w, example)
    keys = {}
    for act in w.findChildren(type(w.action(Act.START))):
        for seq in act.shortcuts():
            text = seq.toString()
            if text:
                assert text not in keys, f"{text}: {keys.get(text)} and {act.objectName()}"
                keys[text] = act.objectName()
    expected = {"F5": Act.START, "F6": Act.PAUSE, "F10": Act.STEP_OVER, "F11": Act.STEP_INTO,
                "Shift+F11": Act.STEP_OUT, "Ctrl+F10": Act.RUN_TO_CURSOR, "F7": Act.STEP_TICK,
                "F9": Act.TOGGLE_BREAKPOINT, "Shift+F5": Act.STOP, "Shift+F10": Act.STEP_BACK,
                "Shift+F7": Act.STEP_BACK_TICK, "Ctrl+Shift+F10": Act.RUN_BACK}
    for key, name in expected.items():
        assert keys[QKeySequence(key).toString()] == name


def test_f9_and_run_to_cursor_from_the_editor(make_window, example, qtbot):
    w, conn = make_window()
    w.activateWindow()
    ed = open_m80(w, example)
    qtbot.waitUntil(w.isActiveWindow)
    ed.take_focus()
    ed.goto_line(62)
    qtbot.keyClick(ed, Qt.Key.Key_F9)
    assert [b.line for b in w.debug.store.all()] == [62]
    conn.connect_now()
    ed.goto_line(41)
    qtbot.keyClick(ed, Qt.Key.Key_F10, Qt.KeyboardModifier.ControlModifier)
    assert conn.calls[-1] == ("debug_run_to", "M80.plc", 41)


# ------------------------------------------------------------------ forces
def test_forces_are_listed_marked_and_released(make_window, example, qtbot):
    w, conn = make_window()
    open_m80(w, example)
    conn.connect_now()
    panels = w.ensure_run_panels()
    conn.sig_connected.emit("127.0.0.1:5999")        # the panels learn it can force
    forces = [{"target": "in 12", "value": 1, "since_ms": 40},
              {"target": "M80.statez", "value": 1, "since_ms": 41},
              {"target": "out 3", "value": 0, "since_ms": 42}]
    conn.sig_forces_changed.emit(forces)
    fp = w.debug.forces_panel
    assert fp.targets() == ["in 12", "M80.statez", "out 3"]
    # marked wherever shown: the input toggle, the output lane, the watch row
    assert panels.inputs.button(12).property("forced") == "true"
    assert panels.lanes.lane_label("outputs", 3).endswith("[forced 0]")
    conn.sig_halted.emit(halted_state(statez=1))
    watch = panels.watch
    assert watch.current == "M80"
    row = watch.row_of("statez")
    assert watch.table.item(row, 3).checkState() == Qt.CheckState.Checked
    # the inline value says so too
    ed = w.current_editor()
    assert ed.debug_marks.inline_text(29) == "statez = 1 (forced)"
    # release one from the panel (restore), then all (keep)
    fp.mode.setCurrentIndex(fp.mode.findData("restore"))
    fp.tree.setCurrentItem(fp.tree.topLevelItem(0))
    fp.release_button.click()
    assert conn.calls[-1] == ("release", "in 12", "restore")
    fp.mode.setCurrentIndex(fp.mode.findData("keep"))
    fp.release_all_button.click()
    assert conn.calls[-1] == ("release_all", "keep")
    # the watch writes on Enter and forces with its checkbox
    watch.table.item(watch.row_of("speed"), 1).setText("250")
    assert conn.calls[-1] == ("write", "M80.speed", 250)
    watch.table.item(watch.row_of("sens"), 3).setCheckState(Qt.CheckState.Checked)
    assert conn.calls[-1] == ("force", "M80.sens", 0)
    watch.table.item(row, 3).setCheckState(Qt.CheckState.Unchecked)
    assert conn.calls[-1] == ("release", "M80.statez", "keep")
    # an input: the right-click menu forces and releases; a click forces
    menu = panels.inputs.pin_menu(9)
    next(a for a in menu.actions() if a.objectName() == "force_on").trigger()
    assert conn.calls[-1] == ("force", "in 9", 1)
    assert not next(a for a in menu.actions() if a.objectName() == "release_keep").isEnabled()
    panels.inputs.button(4).click()
    assert conn.calls[-1] == ("force", "in 4", 1)
    menu = panels.inputs.pin_menu(12)
    next(a for a in menu.actions() if a.objectName() == "release_restore").trigger()
    assert conn.calls[-1] == ("release", "in 12", "restore")
    conn.sig_forces_changed.emit([])
    assert fp.targets() == [] and panels.inputs.button(12).property("forced") == "false"


# ------------------------------------------------------------------ start and image
def _build(w, qtbot, example):
    assert w.open_project(example)
    with qtbot.waitSignal(w.sig_build_finished, timeout=30000):
        assert w.build_all()


def test_start_with_unsaved_changes_offers_build_upload_and_start(make_window, example, qtbot):
    w, conn = make_window()
    _build(w, qtbot, example)
    image = (example / "build" / "eeprom.rom").read_bytes()
    conn.last_state = ControllerStatus(image_crc32=f"{zlib.crc32(image):08x}")
    conn.connect_now()
    ed = w.open_file(example / "hardware" / "M03.plc")
    # nothing changed: Start starts at once
    assert w.start_procedure("M03", 0)
    assert conn.calls[-1] == ("start", "M03", 0)
    ed.insertText(ed.position_of(5, 1), "// changed\n")
    seen = []

    def answer(button_text):
        box = w.run_actions.stale_box
        seen.append(box.text())
        next(b for b in box.buttons() if b.text() == button_text).click()
    QTimer.singleShot(50, lambda: answer("Cancel"))
    assert not w.start_procedure("M03", 0)
    assert "unsaved changes in M03.plc" in seen[-1]
    assert conn.calls[-1] == ("start", "M03", 0) and len(conn.named("start")) == 1
    QTimer.singleShot(50, lambda: answer("Build, Upload and Start"))
    with qtbot.waitSignal(w.sig_build_finished, timeout=30000):
        assert w.start_procedure("M03", 0)
    assert [c[0] for c in conn.calls[-2:]] == ["upload", "start"]
    assert conn.calls[-1] == ("start", "M03", 0)
    assert conn.calls[-2][1] == (example / "build" / "eeprom.rom").read_bytes() != image
    assert not w.is_modified(ed)
    # the controller still reports the old image: Start Anyway starts it
    QTimer.singleShot(50, lambda: answer("Start Anyway"))
    assert w.start_procedure("M03", 5)
    assert "not uploaded" in seen[-1]
    assert conn.calls[-1] == ("start", "M03", 5)


def test_saved_back_to_what_was_built_is_not_changed_since_the_build(make_window, example,
                                                                     qtbot):
    """Save, undo, save again: the file's bytes are the ones Build All read,
    only its time is newer. Start starts at once (staleness compares content);
    a real change saved is still named."""
    w, conn = make_window()
    _build(w, qtbot, example)
    image = (example / "build" / "eeprom.rom").read_bytes()
    conn.last_state = ControllerStatus(image_crc32=f"{zlib.crc32(image):08x}")
    conn.connect_now()
    path = example / "hardware" / "M03.plc"
    built = path.read_bytes()
    ed = w.open_file(path)
    ed.goto_line(5)
    seen = []

    def answer():
        box = w.run_actions.stale_box
        if box is not None:
            seen.append(box.text())
            box.reject()

    qtbot.keyClicks(ed, "x")
    qtbot.keyClick(ed, Qt.Key.Key_S, Qt.KeyboardModifier.ControlModifier)
    qtbot.waitUntil(lambda: not w.is_modified(ed) and path.read_bytes() != built, timeout=5000)
    qtbot.keyClick(ed, Qt.Key.Key_Z, Qt.KeyboardModifier.ControlModifier)
    assert w.is_modified(ed)
    qtbot.keyClick(ed, Qt.Key.Key_S, Qt.KeyboardModifier.ControlModifier)
    qtbot.waitUntil(lambda: not w.is_modified(ed), timeout=5000)
    assert path.read_bytes() == built
    assert path.stat().st_mtime_ns > (example / "build" / "eeprom.rom").stat().st_mtime_ns
    QTimer.singleShot(50, answer)
    assert w.start_procedure("M03", 0)
    assert seen == [] and conn.calls[-1] == ("start", "M03", 0)
    assert w.run_actions.stale_reasons() == []

    qtbot.keyClicks(ed, "y")                       # a real change, saved
    qtbot.keyClick(ed, Qt.Key.Key_S, Qt.KeyboardModifier.ControlModifier)
    qtbot.waitUntil(lambda: not w.is_modified(ed), timeout=5000)
    QTimer.singleShot(50, answer)
    assert not w.start_procedure("M03", 0)
    assert "M03.plc changed since the last Build All" in seen[-1]


def test_an_empty_controller_gets_the_projects_image(make_window, example, qtbot):
    w, conn = make_window()
    _build(w, qtbot, example)
    image = (example / "build" / "eeprom.rom").read_bytes()
    conn.connect_now()
    conn.sig_state.emit(ControllerStatus(image_crc32=None), 0)
    assert [c[:2] for c in conn.named("upload")] == [("upload", image)]
    assert "The controller had no image: loaded" in w.statusBar().currentMessage()
    # a controller running another image is told about, not overwritten
    conn.connect_now()
    conn.sig_state.emit(ControllerStatus(image_crc32="12345678"), 0)
    assert len(conn.named("upload")) == 1
    assert "runs another image" in w.statusBar().currentMessage()
    # a later state does not upload again
    conn.sig_state.emit(ControllerStatus(image_crc32=None), 0)
    assert len(conn.named("upload")) == 1


@pytest.mark.parametrize("theme", ["light", "dark"])
def test_the_halted_line_and_the_stack_follow_the_theme(make_window, example, qtbot, theme):
    """Issue 13 defect 4 (every widget follows the theme), for the debugger's
    marks: the halted line's background is light in the light theme and dark
    in the dark one (a light yellow band under light text was unreadable), and
    the call stack's innermost frame keeps a readable colour."""
    import dataclasses

    from PySide6.QtWidgets import QApplication

    from plcbuilder.ide.app import apply_theme
    w, conn = make_window()
    ed = open_m80(w, example)
    conn.connect_now()
    w.ensure_run_panels()
    try:
        other = "light" if theme == "dark" else "dark"
        w.apply_preferences(dataclasses.replace(w.prefs, theme=other))
        conn.sig_halted.emit(halted_state())
        qtbot.wait(20)
        # the theme changes while halted: the marks and the stack follow at once
        w.apply_preferences(dataclasses.replace(w.prefs, theme=theme))
        qtbot.wait(20)
        assert ed.debug_marks.exec_lines() == [HOME_LINE] and not ed.caretLineVisible()
        img = ed.viewport().grab().toImage()
        pos = ed.position_of(HOME_LINE, 1)
        y = ed.pointYFromPosition(pos) + ed.textHeight(HOME_LINE - 1) // 2
        band = img.pixelColor(img.width() - 8, y).lightness()
        text = ed.viewport().palette()
        frame = w.debug.call_stack.frame_items()[0].foreground(0).color().lightness()
        paper = w.debug.call_stack.tree.palette().color(text.ColorRole.Base).lightness()
        if theme == "dark":
            assert band < 100 and frame > 150, (band, frame)
        else:
            assert band > 180 and frame < 110, (band, frame)
        assert abs(frame - paper) > 80
    finally:
        apply_theme(QApplication.instance(), "light")
