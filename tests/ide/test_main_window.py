"""The main window driven like a user would: open a project, type, see the
problems, build, save, react to the disk, recover from a crash, and the run
side through the connection interface (a fake connection, no process)."""

import os
from pathlib import Path

import pytest
from PySide6.QtCore import Qt
from PySide6.QtWidgets import QDialog, QMessageBox

from plcbuilder.ide import dialogs
from plcbuilder.ide.editor import IND_ERROR, IND_WARNING, MK_ERROR
from plcbuilder.ide.main_window import Act, MainWindow
from plcbuilder.ide.settings import Preferences, Settings
from plcbuilder.link.client import ControllerStatus

from tests.ide import _workbench
from tests.ide._workbench import RecordingConnection, settle, windows

SB = QMessageBox.StandardButton

M03 = """// M03: spindle on
#include pins.h

main()
{
  speed = eparam;
  pwm01 = speed;
  portset(OUTPUT_SPINDLE);
  exit(99);
};
"""
M05 = """// M05: spindle off
#include mine.h

main()
{
  portclear(MY_PIN);
  exit(99);
};
"""
LOOP = """// LOOP: a software loop
main()
{
  do {
    timer = timer + 1;
  } while (1);
};
"""
MINE = "// mine.h: my pins\n#define MY_PIN 3\n"


def make_project(root: Path) -> Path:
    (root / "hardware").mkdir(parents=True)
    (root / "software").mkdir()
    (root / "include").mkdir()
    (root / "hardware" / "M03.plc").write_text(M03)
    (root / "hardware" / "M05.plc").write_text(M05)
    (root / "software" / "LOOP.plc").write_text(LOOP)
    (root / "include" / "mine.h").write_text(MINE)
    return root


prompts, settings = _workbench.prompts, _workbench.settings


@pytest.fixture
def project(tmp_path):
    return make_project(tmp_path / "proj")


@pytest.fixture
def make_window(qtbot, settings, prompts):
    with windows(qtbot, settings, (1200, 800)) as make:
        yield make


@pytest.fixture
def win(make_window):
    return make_window()


# ------------------------------------------------------------------ project
def test_open_project_fills_tree_and_lints(win, project, qtbot):
    assert win.open_project(project)
    settle(qtbot, win)
    texts = {it.text(0) for it in win.tree._all_items()}
    assert {"Hardware PLC", "Software PLC", "Headers", "M03", "M05", "LOOP", "mine.h"} <= texts
    assert "pins.h (built-in)" in texts
    assert win.store.counts() == (0, 0)
    assert win.problems.counts() == (0, 0)
    assert "proj" in win.windowTitle()
    assert str(project.resolve()) in win.settings.recent_projects()
    # the description column shows the first comment
    assert win.tree.find_item("M03").data(0, Qt.ItemDataRole.UserRole + 3) == "spindle on"


def test_open_bad_project_says_why(win, tmp_path, prompts):
    f = tmp_path / "file.txt"
    f.write_text("x")
    assert not win.open_project(f)
    assert prompts.calls[-1][0] == "critical" and "Cannot open" in prompts.calls[-1][2]


def test_type_an_error_see_squiggle_and_problem_then_fix(win, project, qtbot):
    win.open_project(project)
    ed = win.open_file(project / "hardware" / "M03.plc")
    settle(qtbot, win)
    assert ed.indicator_ranges(IND_ERROR) == []
    line = 7                                              # "  pwm01 = speed;"
    start = ed.position_of(line, 11)
    ed.setSel(start, start + len("speed"))
    ed.replaceSel("")                                     # "  pwm01 = ;"
    qtbot.waitUntil(lambda: ed.indicator_ranges(IND_ERROR) != [], timeout=5000)
    (s, e), = ed.indicator_ranges(IND_ERROR)
    assert ed.line_col_of(s) == (7, 11) and e == s + 1    # the ';'
    assert ed.diagnostic_lines() == {7: MK_ERROR}
    items = win.problems.problem_items()
    assert len(items) == 1 and "expected an expression" in items[0].text(0)
    assert items[0].text(2) == "Ln 7, Col 11"
    assert win.problems.counts() == (1, 0)
    assert "-/512 bytes" in win.size_text()
    assert win.tabs.tabText(win.tabs.currentIndex()).endswith("●")
    # fix it
    ed.insertText(s, "speed")
    qtbot.waitUntil(lambda: ed.indicator_ranges(IND_ERROR) == [], timeout=5000)
    assert win.problems.problem_items() == []
    assert ed.diagnostic_lines() == {}
    qtbot.waitUntil(lambda: "-/" not in win.size_text(), timeout=5000)
    assert win.size_text().startswith("M03: ") and win.size_text().endswith("/512 bytes")


def test_non_ascii_line_squiggle_is_at_the_right_bytes(win, project, qtbot):
    win.open_project(project)
    ed = win.open_file(project / "hardware" / "M03.plc")
    ed.set_text("// é€𝄞 ünïcödé\nmain() { é = 1; exit(99); }\n", keep_undo=True)
    qtbot.waitUntil(lambda: ed.indicator_ranges(IND_ERROR) != [], timeout=5000)
    d = [d for d in win.store.for_file(ed.path) if d.is_error][0]
    (s, e), = ed.indicator_ranges(IND_ERROR)
    assert s == ed.position_of(d.span.line, d.span.col)
    assert ed.byte_range_text(s, e) == "é"


def test_warnings_show_as_warning_squiggles(win, project, qtbot):
    win.open_project(project)
    ed = win.open_file(project / "hardware" / "M03.plc")
    ed.insertText(ed.position_of(6, 1), "  unused = 5;\n")
    qtbot.waitUntil(lambda: ed.indicator_ranges(IND_WARNING) != [], timeout=5000)
    assert win.problems.counts()[1] >= 1
    assert "warning" in win.status.problems_button.text()


def test_problem_in_a_header_opens_the_header(win, project, qtbot):
    (project / "include" / "mine.h").write_text("#define MY_PIN 3\nbad() { x = ; }\n")
    win.open_project(project)
    settle(qtbot, win)
    items = win.problems.problem_items()
    header_items = [it for it in items if it.parent().text(0) == "include/mine.h"]
    assert header_items, [it.parent().text(0) for it in items]
    win.problems.activate_item(header_items[0])
    ed = win.current_editor()
    assert ed.path.endswith("mine.h")
    assert ed.cursor_line_col()[0] == 2
    qtbot.waitUntil(lambda: ed.indicator_ranges(IND_ERROR) != [], timeout=5000)
    # fixing the header and saving re-checks the procedures that include it
    ed.set_text("#define MY_PIN 3\n", keep_undo=True)
    assert win.save_editor(ed)
    qtbot.waitUntil(lambda: win.store.counts() == (0, 0), timeout=5000)
    assert ed.indicator_ranges(IND_ERROR) == []


def test_builtin_header_opens_read_only(win, project):
    win.open_project(project)
    ed = win.open_file("<builtin>/pins.h", 10)
    assert ed.readOnly() and ed.builtin
    assert "INPUT_HOME_X" in ed.text()
    assert not win.action(Act.SAVE).isEnabled()


# -------------------------------------------------------------------- build
def test_build_all_writes_the_image(win, project, qtbot):
    win.open_project(project)
    with qtbot.waitSignal(win.sig_build_finished, timeout=20000) as blocker:
        win.action(Act.BUILD_ALL).trigger()
    result = blocker.args[0]
    assert result.ok
    assert (project / "build" / "eeprom.rom").is_file()
    text = win.build_panel.plain_text()
    assert "M03" in text and "Build succeeded" in text and "eeprom.rom" in text
    assert "/512 bytes" in text
    assert win.action(Act.BUILD_ALL).isEnabled()


def test_build_all_saves_first_and_reports_errors(win, project, qtbot):
    win.open_project(project)
    ed = win.open_file(project / "hardware" / "M05.plc")
    ed.insertText(ed.position_of(6, 1), "  x = ;\n")
    with qtbot.waitSignal(win.sig_build_finished, timeout=20000) as blocker:
        win.build_all()
    result = blocker.args[0]
    assert not result.ok
    assert "x = ;" in (project / "hardware" / "M05.plc").read_text()     # saved first
    assert not win.is_modified(ed)
    text = win.build_panel.plain_text()
    assert "Build failed" in text and "hardware/M05.plc:6:" in text
    # double-clicking the diagnostic line opens the file there
    doc = win.build_panel.text.document()
    block = next(i for i in range(doc.blockCount())
                 if doc.findBlockByNumber(i).text().startswith("hardware/M05.plc:6:"))
    win.tabs.setCurrentIndex(0)
    assert win.build_panel.activate_line(block)
    assert win.current_editor().cursor_line_col()[0] == 6
    assert win.problems.counts()[0] == 1


# ---------------------------------------------------------- saving/prompts
def test_unsaved_changes_prompt_on_close(win, project, prompts, qtbot):
    win.open_project(project)
    ed = win.open_file(project / "hardware" / "M03.plc")
    ed.insertText(0, "// changed\n")
    prompts.answers = [SB.Cancel]
    assert not win.close_editor(ed)
    assert prompts.calls[-1][0] == "warning" and "unsaved changes" in prompts.calls[-1][2]
    assert win.editor_for(ed.path) is ed
    prompts.answers = [SB.Save]
    assert win.close_editor(ed)
    assert (project / "hardware" / "M03.plc").read_text().startswith("// changed\n")
    ed = win.open_file(project / "hardware" / "M03.plc")
    ed.insertText(0, "// again\n")
    prompts.answers = [SB.Discard]
    assert win.close_editor(ed)
    assert not (project / "hardware" / "M03.plc").read_text().startswith("// again")


def test_unsaved_changes_prompt_on_quit_and_open_project(win, project, prompts, tmp_path):
    win.open_project(project)
    ed = win.open_file(project / "hardware" / "M03.plc")
    ed.insertText(0, "// x\n")
    prompts.answers = [SB.Cancel]
    assert not win.close()
    assert win.isVisible()
    prompts.answers = [SB.Cancel]
    other = make_project(tmp_path / "other")
    assert not win.open_project(other)
    assert win.project.root == project.resolve()
    prompts.answers = [SB.Discard]
    assert win.open_project(other)


def test_save_keeps_line_ends_and_is_atomic(win, project):
    p = project / "hardware" / "M03.plc"
    p.write_bytes(M03.replace("\n", "\r\n").encode())
    win.open_project(project)
    ed = win.open_file(p)
    assert "\r" not in ed.text()
    ed.insertText(0, "// é\n")
    assert win.save_editor(ed)
    data = p.read_bytes()
    assert data.startswith("// é\r\n".encode()) and b"\r\n" in data and b"\n\n" not in data
    assert not [f for f in p.parent.iterdir() if f.name.endswith(".tmp")]


def test_file_changed_on_disk(win, project, prompts, qtbot):
    win.open_project(project)
    p = project / "hardware" / "M03.plc"
    ed = win.open_file(p)
    # not edited: reloaded without asking (preference), our own saves ignored
    p.write_text("// new\n" + M03)
    qtbot.waitUntil(lambda: ed.text().startswith("// new"), timeout=5000)
    assert not [c for c in prompts.calls if c[1] == "File Changed on Disk"]
    ed.insertText(0, "// mine\n")
    assert win.save_editor(ed)
    qtbot.wait(300)
    assert not [c for c in prompts.calls if c[1] == "File Changed on Disk"]
    # edited: asked; No keeps the editor's text
    ed.insertText(0, "// edit\n")
    prompts.answers = [SB.No]
    p.write_text("// theirs\n")
    qtbot.waitUntil(lambda: "File Changed on Disk" in prompts.titles(), timeout=5000)
    assert ed.text().startswith("// edit")
    assert win.is_modified(ed)
    # and Yes reloads
    prompts.answers = [SB.Yes]
    p.write_text("// theirs again\n")
    qtbot.waitUntil(lambda: ed.text() == "// theirs again\n", timeout=5000)
    assert not win.is_modified(ed)


def test_file_changed_on_disk_always_asks_when_preferred(win, project, prompts, qtbot):
    win.apply_preferences(Preferences(reload_unmodified=False))
    win.open_project(project)
    p = project / "hardware" / "M05.plc"
    ed = win.open_file(p)
    prompts.answers = [SB.Yes]
    os.replace(_write(project / "tmpfile", "// replaced atomically\n"), p)
    qtbot.waitUntil(lambda: ed.text() == "// replaced atomically\n", timeout=5000)
    assert "File Changed on Disk" in prompts.titles()
    # the watch survives the atomic replace
    prompts.answers = [SB.Yes]
    p.write_text("// and again\n")
    qtbot.waitUntil(lambda: ed.text() == "// and again\n", timeout=5000)


def test_file_deleted_on_disk(win, project, prompts, qtbot):
    win.open_project(project)
    p = project / "hardware" / "M05.plc"
    ed = win.open_file(p)
    prompts.answers = [SB.Yes]
    p.unlink()
    qtbot.waitUntil(lambda: "File Deleted" in prompts.titles(), timeout=5000)
    assert win.is_modified(ed)
    assert win.save_editor(ed) and p.exists()


def _write(path: Path, text: str) -> Path:
    path.write_text(text)
    return path


# ------------------------------------------------------------------ recovery
def test_recovery_after_a_crash(qtbot, settings, project, prompts, make_window):
    w1 = make_window()
    w1.open_project(project)
    ed = w1.open_file(project / "hardware" / "M03.plc")
    ed.insertText(0, "// unsaved work é\n")
    assert w1.recovery.autosave_now() == 1
    folder = settings.recovery_dir()
    assert (folder / "index.json").is_file()
    # the crash: no closeEvent, the process "dies" (another pid left the copy)
    import json
    index = json.loads((folder / "index.json").read_text())
    for v in index.values():
        v["pid"] = 999999999
    (folder / "index.json").write_text(json.dumps(index))
    w1.shutdown()
    w1._closing = True
    w1.hide()
    w1.recovery._written.clear()
    for e in w1.editors():
        e.setSavePoint()          # so that the teardown does not prompt
    # next start: offered, restored
    w2 = make_window()
    prompts.answers = [SB.Yes]
    w2.open_project(project)
    assert "Recover Unsaved Changes" in prompts.titles()
    ed2 = w2.editor_for(project / "hardware" / "M03.plc")
    assert ed2 is not None and ed2.text().startswith("// unsaved work é\n")
    assert w2.is_modified(ed2)
    assert not (project / "hardware" / "M03.plc").read_text().startswith("// unsaved")
    # restored copies are not offered twice
    w2.recovery.discard(ed2.path)
    assert w2.recovery.pending(project) == []


def test_recovery_declined_discards_the_copy(qtbot, settings, project, prompts, make_window):
    w = make_window()
    w.open_project(project)
    ed = w.open_file(project / "hardware" / "M05.plc")
    ed.insertText(0, "// x\n")
    w.recovery.autosave_now()
    import json
    folder = settings.recovery_dir()
    index = json.loads((folder / "index.json").read_text())
    for v in index.values():
        v["pid"] = 999999999
    (folder / "index.json").write_text(json.dumps(index))
    w.recovery._written.clear()
    prompts.answers = [SB.No]
    assert w.offer_recovery() == 0
    assert w.recovery.pending(project) == []


def test_clean_exit_leaves_no_recovery(settings, project, prompts, make_window):
    w = make_window()
    w.open_project(project)
    ed = w.open_file(project / "hardware" / "M05.plc")
    ed.insertText(0, "// x\n")
    w.recovery.autosave_now()
    prompts.answers = [SB.Discard]
    w.close()
    assert w.recovery.pending() == []


# ------------------------------------------------------------------ settings
def test_layout_recent_session_and_preferences_are_remembered(settings, project, prompts,
                                                              make_window, qtbot):
    w1 = make_window()
    w1.open_project(project)
    w1.open_file(project / "hardware" / "M05.plc")
    w1.open_file(project / "software" / "LOOP.plc")
    w1.apply_preferences(Preferences(font_size=15, tab_width=2))
    w1.problems_dock.hide()
    w1.close()
    w2 = make_window(settings=Settings(settings.path))
    assert w2.prefs.font_size == 15 and w2.prefs.tab_width == 2
    assert w2.problems_dock.isHidden()
    assert str(project.resolve()) in [a.text() for a in w2.recent_menu.actions()]
    w2.open_project(project)
    # (before the window's first paint only the current editor is made, then the others)
    qtbot.waitUntil(lambda: len(w2.editors()) == 2)
    assert [Path(e.path).name for e in w2.editors()] == ["M05.plc", "LOOP.plc"]
    assert Path(w2.current_editor().path).name == "LOOP.plc"
    assert w2.current_editor().tabWidth() == 2
    w2.action(Act.RESET_LAYOUT).trigger()
    assert not w2.problems_dock.isHidden()


def test_recent_projects_menu_opens_and_clears(win, project, tmp_path):
    other = make_project(tmp_path / "other")
    win.open_project(project)
    win.open_project(other)
    acts = [a for a in win.recent_menu.actions() if a.text() == str(project.resolve())]
    acts[0].trigger()
    assert win.project.root == project.resolve()
    assert win.welcome_recent.count() == 2
    clear = [a for a in win.recent_menu.actions() if a.text() == "Clear List"][0]
    clear.trigger()
    assert win.settings.recent_projects() == []


def test_open_example_project(win, prompts, monkeypatch, tmp_path):
    prompts.answers = [SB.Yes]
    assert win.open_example_project()
    assert win.project is not None
    assert win.project.root.parent == win.settings.example_dir().resolve()
    assert {"M03", "OFF"} <= {p.name for p in win.project.procedures()}
    assert win.current_editor() is not None
    # No: pick a folder
    from PySide6.QtWidgets import QFileDialog
    monkeypatch.setattr(QFileDialog, "getExistingDirectory", lambda *a, **k: str(tmp_path / "picked"))
    prompts.answers = [SB.No]
    assert win.open_example_project()
    assert win.project.root == (tmp_path / "picked" / "plc-example").resolve()
    prompts.answers = [SB.Cancel]
    assert not win.open_example_project()


def test_open_project_dialog(win, project, monkeypatch):
    from PySide6.QtWidgets import QFileDialog
    monkeypatch.setattr(QFileDialog, "getExistingDirectory", lambda *a, **k: str(project))
    win.action(Act.OPEN_PROJECT).trigger()
    assert win.project.root == project.resolve()
    monkeypatch.setattr(QFileDialog, "getExistingDirectory", lambda *a, **k: "")
    assert not win.open_project_dialog()


def test_close_project_shows_the_welcome_page(win, project):
    win.open_project(project)
    win.open_file(project / "hardware" / "M03.plc")
    assert win.stack.currentWidget() is win.tabs
    assert win.close_project()
    assert win.project is None and win.editors() == []
    assert win.stack.currentWidget() is win.welcome


# --------------------------------------------------------------- run side
@pytest.fixture
def runwin(make_window, project):
    conn = RecordingConnection()
    w = make_window(connection=conn, start_controller=True)
    w.open_project(project)
    return w, conn


def test_the_run_side_calls_the_connection(runwin, qtbot, monkeypatch, project):
    w, conn = runwin
    qtbot.waitUntil(lambda: bool(conn.calls))          # after the window's first paint
    assert conn.calls[0][0] == "start_embedded"
    args = conn.calls[0][1]
    assert "--limits" in args
    # start picker: by name with eparam
    def fake_exec(dlg):
        dlg.list.setCurrentRow([n for n, _ in dlg.procedures].index("M03"))
        dlg.eparam_spin.setValue(1234)
        dlg.accept()
        return QDialog.DialogCode.Accepted
    monkeypatch.setattr(dialogs.StartDialog, "exec", fake_exec)
    w.action(Act.START).trigger()
    assert ("start", "M03", 1234) in conn.calls
    # by M-code number
    def by_mcode(dlg):
        dlg.mcode_spin.setValue(5)
        assert dlg.by_mcode.isChecked() and dlg.selected() == "M05"
        dlg.accept()
        return QDialog.DialogCode.Accepted
    monkeypatch.setattr(dialogs.StartDialog, "exec", by_mcode)
    w.start_procedure()
    assert conn.calls[-1] == ("start", "M05", 1234)
    w.action(Act.STOP).trigger()
    assert conn.calls[-1] == ("stop",)
    w.run_actions.speed_combo.setCurrentIndex(w.run_actions.speed_combo.findData("max"))
    assert conn.calls[-1] == ("set_speed", "max")
    w.run_actions.speed_actions["pause"].trigger()
    assert conn.calls[-1] == ("set_speed", "pause")
    assert w.run_actions.speed_combo.currentData() == "pause"
    w.action(Act.RESET_CONTROLLER).trigger()
    assert conn.calls[-1] == ("reset",)


def test_upload_builds_first(runwin, qtbot, project):
    w, conn = runwin
    with qtbot.waitSignal(w.sig_build_finished, timeout=20000):
        w.action(Act.UPLOAD).trigger()
    qtbot.waitUntil(lambda: any(c[0] == "upload" for c in conn.calls), timeout=5000)
    data = [c for c in conn.calls if c[0] == "upload"][0][1]
    assert data == (project / "build" / "eeprom.rom").read_bytes()


def test_a_build_alone_does_not_upload(runwin, qtbot, project):
    from plcbuilder.ide.run_actions import Step
    w, conn = runwin
    with qtbot.waitSignal(w.sig_build_finished, timeout=20000):
        assert w.build_all()
        assert w.run_actions.step is Step.BUILD
    assert w.run_actions.step is Step.IDLE
    assert not any(c[0] == "upload" for c in conn.calls)
    from dataclasses import replace
    w.apply_preferences(replace(w.prefs, build_before_upload=True))
    with qtbot.waitSignal(w.sig_build_finished, timeout=20000):
        assert w.upload()
        assert w.run_actions.step is Step.BUILD_THEN_UPLOAD
    assert w.run_actions.step is Step.IDLE
    qtbot.waitUntil(lambda: any(c[0] == "upload" for c in conn.calls), timeout=5000)


def test_state_goes_to_the_status_bar(runwin, project):
    w, conn = runwin
    conn.connected = True
    conn.sig_connected.emit("127.0.0.1:5555")
    assert w.status.connection_label.text() == "● embedded controller"
    assert "127.0.0.1:5555" in w.status.connection_label.toolTip()
    conn.sig_state.emit(ControllerStatus(t_ms=12345, running="M03", proc=70,
                                         proc_name="plc_proc_spindle"), 0)
    assert w.status.time_label.text() == "t = 12.345 s"
    assert w.status.running_label.text() == "▶ M03"
    assert w.status.proc_label.text() == "proc 70 plc_proc_spindle"
    conn.sig_state.emit(ControllerStatus(t_ms=20000, running=None, proc=33), 0)
    assert w.status.running_label.text() == "idle"
    assert w.status.proc_label.text() == "proc 33 plc_proc_probing"       # named by abi.proc_name
    conn.sig_disconnected.emit("gone")
    assert "disconnected" in w.status.connection_label.text()


def test_a_long_status_message_is_elided_whole_in_its_tooltip(runwin, qtbot):
    """'The controller had no image: loaded the p' was cut off mid-word under the
    labels; a message that does not fit ends in '…' and the tooltip has it whole."""
    w, conn = runwin
    w.resize(1200, 800)
    conn.connected = True
    conn.sig_connected.emit("127.0.0.1:5555")
    qtbot.wait(50)
    sb = w.status
    text = ("The controller had no image: loaded the project's build/eeprom.rom — it is older "
            "than the sources: Build All (Ctrl+B) to update it")
    sb.showMessage(text, 10000)
    shown = sb.shown_message()
    assert shown != text and shown.endswith("…") and text.startswith(shown[:-1])
    assert sb.currentMessage() == text
    assert sb.fontMetrics().horizontalAdvance(shown) <= sb.problems_button.geometry().left()
    assert sb.toolTip() == text
    sb.showMessage("Saved", 3000)                       # fits: as it is, no tooltip
    assert sb.shown_message() == sb.currentMessage() == "Saved" and sb.toolTip() == ""
    sb.clearMessage()
    assert sb.toolTip() == "" and sb.currentMessage() == ""


def test_a_status_message_shown_before_the_layout_is_fitted_when_it_comes(qtbot):
    """A message shown while the window was still being laid out (Build All's
    at start) stayed cut off mid-word: it is fitted again when the bar gets its
    width, and again when it narrows, keeping its time."""
    from PySide6.QtWidgets import QMainWindow

    from plcbuilder.ide.status_bar import StatusBar
    win = QMainWindow()
    qtbot.addWidget(win)
    sb = StatusBar()
    win.setStatusBar(sb)
    text = "Build succeeded: up to date: /tmp/smoke/p_mycnc/build/eeprom.rom (6144 bytes) " * 2
    sb.showMessage(text, 60000)                     # not shown yet: no room known
    assert sb.shown_message() == text
    win.resize(1200, 400)
    win.show()
    qtbot.waitExposed(win)
    qtbot.waitUntil(lambda: sb.shown_message().endswith("…"))
    wide = sb.shown_message()
    assert sb.currentMessage() == text and sb.toolTip() == text and sb._expire.isActive()
    win.resize(1050, 400)                           # (the labels take some 900 px)
    qtbot.waitUntil(lambda: sb.shown_message() != wide)
    assert sb.shown_message().endswith("…") and len(sb.shown_message()) < len(wide)
    assert sb.fontMetrics().horizontalAdvance(sb.shown_message()) <= \
        sb.problems_button.geometry().left()


def test_the_embedded_controller_keeps_its_port_in_the_tooltip(qtbot):
    from plcbuilder.ide.status_bar import StatusBar
    sb = StatusBar()
    qtbot.addWidget(sb)
    sb.show_connected("127.0.0.1:41543", embedded=True)
    assert sb.connection_label.text() == "● embedded controller"
    assert "127.0.0.1:41543" in sb.connection_label.toolTip()
    sb.show_connected("10.0.0.5:4267", embedded=False)
    assert sb.connection_label.text() == "● controller 10.0.0.5:4267"


def test_the_status_colours_come_through_the_palette_and_go_back_to_the_theme(qtbot):
    """Green while a procedure runs, amber near the size limit, red and heavier
    over it, the theme's own colour otherwise; given by the palette and font,
    never a style sheet (a sheet re-polishes the label each time, and one set
    at start-up made the first paint wait for the style-sheet parser)."""
    from PySide6.QtGui import QPalette
    from plcbuilder.ide.looks import is_bold, text_colour
    from plcbuilder.ide.status_bar import StatusBar
    sb = StatusBar()
    qtbot.addWidget(sb)
    theme = sb.size_label.palette().color(QPalette.ColorRole.WindowText).name()

    def look(lab):
        return (text_colour(lab), lab.palette().color(QPalette.ColorRole.WindowText).name(),
                is_bold(lab), lab.styleSheet())

    sb.show_state(ControllerStatus(t_ms=5, running="M03", proc=70))
    assert look(sb.running_label) == ("#1a7f37", "#1a7f37", True, "")
    sb.show_state(ControllerStatus(t_ms=9, running=None, proc=33))
    assert look(sb.running_label) == (None, theme, False, "")
    sb.show_size("hardware/M03.plc", 1100, 1000)
    assert look(sb.size_label) == ("#d1242f", "#d1242f", True, "")
    sb.show_size("hardware/M03.plc", 950, 1000)
    assert look(sb.size_label) == ("#9a6700", "#9a6700", False, "")
    sb.show_size("hardware/M03.plc", None, 1000)
    assert look(sb.size_label)[0] == "#9a6700"
    sb.show_size("hardware/M03.plc", 100, 1000)
    assert look(sb.size_label) == (None, theme, False, "")
    sb.show_connected("127.0.0.1:1", embedded=True)
    assert text_colour(sb.connection_label) == "#1a7f37"
    sb.show_disconnected("gone")
    assert text_colour(sb.connection_label) == "#6e7781"


def test_without_a_controller_the_forces_dock_stays_out_of_the_way(win, project, qtbot):
    """Nothing can be forced without a controller: the Forces dock does not
    take a column beside the editor (View › Forces still shows it)."""
    win.open_project(project)
    qtbot.waitUntil(lambda: win._painted)
    assert win.connection is None and not win.forces_dock.isVisible()
    assert win.debug.panels.made == {}
    win.forces_dock.toggleViewAction().trigger()
    assert win.forces_dock.isVisible() and "forces" in win.debug.panels.made


def test_run_panels_are_docked_when_part_b_is_there(runwin, qtbot):
    w, conn = runwin
    pytest.importorskip("plcbuilder.ide.panels")
    qtbot.waitUntil(lambda: w.run_panels is not None, timeout=10000)
    names = {d.objectName() for d in w.run_panels.docks()}
    assert names and all(w.dockWidgetArea(d) != Qt.DockWidgetArea.NoDockWidgetArea
                         for d in w.run_panels.docks())
    view = {a.text() for a in w.view_menu.actions()}
    assert {"Project", "Build Output"} <= view and len(view) > 5


def test_no_connection_disables_the_run_actions(win, project):
    win.open_project(project)
    for name in (Act.UPLOAD, Act.START, Act.STOP):
        assert not win.action(name).isEnabled()
    assert not win.start_procedure("M03")


def test_tree_start_uses_last_eparam(runwin):
    w, conn = runwin
    w.run_actions.last_eparam = 7
    w.tree.sig_start_procedure.emit("M05")
    assert conn.calls[-1] == ("start", "M05", 7)


# ------------------------------------------------------------- keys & help
def test_keyboard_shortcuts_from_the_editor(win, project, qtbot, monkeypatch):
    win.activateWindow()
    win.open_project(project)
    ed = win.open_file(project / "hardware" / "M03.plc")
    ed.take_focus()
    ed.gotoPos(ed.position_of(9, 3))
    qtbot.keyClick(ed, Qt.Key.Key_Slash, Qt.KeyboardModifier.ControlModifier)
    assert ed.line_text(8) == "  // exit(99);"
    qtbot.keyClick(ed, Qt.Key.Key_S, Qt.KeyboardModifier.ControlModifier)
    assert "// exit(99);" in (project / "hardware" / "M03.plc").read_text()
    from plcbuilder.ide import dialogs
    asked = []
    monkeypatch.setattr(dialogs.GoToLineDialog, "exec", lambda d: asked.append(d) or 0)
    qtbot.keyClick(ed, Qt.Key.Key_G, Qt.KeyboardModifier.ControlModifier)
    assert asked
    with qtbot.waitSignal(win.sig_build_finished, timeout=20000):
        qtbot.keyClick(ed, Qt.Key.Key_B, Qt.KeyboardModifier.ControlModifier)
    qtbot.keyClick(ed, Qt.Key.Key_F, Qt.KeyboardModifier.ControlModifier)
    assert win.find_bar.isVisible()


def test_hover_and_completion_in_the_window(win, project, qtbot):
    win.open_project(project)
    ed = win.open_file(project / "hardware" / "M05.plc")
    ed.insertText(ed.position_of(6, 1), "  code = gvarget(6060);\n")
    settle(qtbot, win)
    t = ed.hover_text_at(ed.position_of(6, 20))
    assert "GVAR_CURRENT_MOTION_CODE" in t and "0x4d" in t
    t = ed.hover_text_at(ed.position_of(7, 14))            # MY_PIN
    assert "#define MY_PIN 3" in t and "mine.h:2" in t
    assert "variable of this file" in ed.hover_text_at(ed.position_of(6, 4))
    names = {n for n, _k in win.lint.complete(ed, "")}
    assert {"MY_PIN", "code", "OUTPUT_SPINDLE", "gvarget", "eparam"} <= names
    from plcbuilder.ide import highlighter as hl
    ed.highlighter.style_to(ed.length())
    assert ed.styleAt(ed.position_of(7, 14)) == hl.S_DEFINE


def test_saving_the_settings_file_applies_it(win, project, qtbot):
    win.open_project(project)
    ed = win.open_file(project / "plcbuilder.toml") if (project / "plcbuilder.toml").exists() \
        else None
    if ed is None:
        (project / "plcbuilder.toml").write_text('name = "mine"\n')
        ed = win.open_file(project / "plcbuilder.toml")
    ed.set_text('name = "renamed"\n[limits]\nhw_proc = 8\n', keep_undo=True)
    assert win.save_editor(ed)
    assert win.project.name == "renamed" and win.project.limits.hw_proc == 8
    settle(qtbot, win)
    assert any(d.code == "size-limit" for d in win.store.all())       # M03 is over 8 bytes
    ed.set_text('name = "renamed"\n[limits]\nhw_proc = "big"\n', keep_undo=True)
    assert win.save_editor(ed)
    assert win.project.limits.hw_proc == 8                           # kept
    (d,) = [d for d in win.store.all() if d.code == "settings"]
    assert d.span.line == 3 and "hw_proc" in d.message
    assert ed.diagnostic_lines() == {3: MK_ERROR}


def test_tab_menu_drop_and_status(win, project, qtbot):
    win.open_project(project)
    a = win.open_file(project / "hardware" / "M03.plc")
    b = win.open_file(project / "hardware" / "M05.plc")
    c = win.open_file(project / "software" / "LOOP.plc")
    assert win.status.eol_label.text() == "UTF-8  LF"
    menu = win.tab_menu(win.tabs.indexOf(b))
    acts = {x.objectName(): x for x in menu.actions()}
    acts["copy_path"].trigger()
    from PySide6.QtWidgets import QApplication
    assert QApplication.clipboard().text() == b.path
    acts["reveal"].trigger()
    assert win.tree.tree.currentItem().text(0) == "M05"
    acts["others"].trigger()
    assert win.editors() == [b]
    win.tab_menu(0).actions()[0].trigger()
    assert win.editors() == []
    win.open_paths([str(project / "include" / "mine.h")])
    assert win.current_editor().path.endswith("mine.h")
    other = make_project(project.parent / "dropped")
    win.open_paths([str(other)])
    assert win.project.root == other.resolve()
    del a, c


def test_run_panels_come_after_the_first_paint_and_work(make_window, project, qtbot, settings):
    from plcbuilder.controller import events as ev
    conn = RecordingConnection()
    w = MainWindow(settings, connection=conn, start_controller=True, debounce_ms=20)
    qtbot.addWidget(w)
    try:
        # before the window shows: empty docks in their places, no pyqtgraph panels
        assert w.run_panels is None
        names = {d.objectName() for d in w.run_docks.values()}
        assert {"runOutputsDock", "runProcDock", "runLogDock"} <= names
        assert all(w.dockWidgetArea(d) != Qt.DockWidgetArea.NoDockWidgetArea
                   for d in w.run_docks.values())
        assert all(d.widget() is None for d in w.run_docks.values())
        view = {a.text() for a in w.view_menu.actions()}
        assert {"Outputs", "Run log"} <= view
        w.open_project(project)
        settle(qtbot, w)                       # the lint passes pin names before the panels
        w.resize(1200, 800)
        w.show()
        qtbot.waitUntil(lambda: w.run_panels is not None, timeout=10000)
        assert w._painted
        p = w.run_panels
        assert [p.dock(k) for k, *_ in p.DOCKS] == [w.run_docks[k] for k, *_ in p.DOCKS]
        assert w.run_docks["outputs"].widget() is p.lanes
        assert "OUTPUT_SPINDLE" in p.lanes.names["outputs"].values()   # the project's pins.h
        # the connection reaches the panels
        conn.sig_samples.emit([ev.Sample(t_ms=t, running="M03", proc=70, message=0,
                                         inputs=(0,) * 8, outputs=(1,) + (0,) * 7,
                                         pwm=(0,) * 8, dac=(0,) * 8, adc=(0,) * 8,
                                         axes=(0,) * 9, velocities=(0,) * 9)
                               for t in range(50)])
        assert len(p.model) == 50
        w.run_docks["outputs"].show()
        w.run_docks["outputs"].raise_()
        qtbot.waitUntil(lambda: p.lanes.lanes() == [("outputs", 0)] and p.lanes.frames > 0,
                        timeout=5000)
        assert w.ensure_run_panels() is p          # made once
    finally:
        w.shutdown()


def test_no_menu_lists_an_action_twice(qtbot, make_window):
    """Issue 23 point 13: the Run menu listed "Build, Upload and Start" twice
    (one action made by the window, another by the workbench)."""
    w = make_window(connection=RecordingConnection(), start_controller=True)

    def walk(menu, where):
        texts = [a.text().replace("&", "") for a in menu.actions()
                 if not a.isSeparator() and a.text()]
        dup = {t for t in texts if texts.count(t) > 1}
        assert not dup, f"{where} lists {sorted(dup)} twice"
        for a in menu.actions():
            if a.menu() is not None:
                walk(a.menu(), f"{where} › {a.text().replace('&', '')}")
    for top in w.menuBar().actions():
        walk(top.menu(), top.text().replace("&", ""))
    tb = [a.text() for a in w.toolbar.actions() if a.text()]
    assert len(tb) == len(set(tb)), tb
    act = w.action(Act.BUILD_UPLOAD_START)
    assert act.shortcut().toString() == "Ctrl+R"
    run = next(a.menu() for a in w.menuBar().actions() if a.text().replace("&", "") == "Run")
    assert act in run.actions()
