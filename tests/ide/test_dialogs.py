"""Every dialog path: go to line, find/replace, start picker, names,
preferences, connect — and the project tree's new/rename/duplicate/delete."""

from pathlib import Path

import pytest
from PySide6.QtWidgets import QDialog, QDialogButtonBox, QMessageBox

from plcbuilder.bytecode.program import Kind
from plcbuilder.ide import dialogs
from plcbuilder.ide.main_window import Act, MainWindow
from plcbuilder.ide.settings import Settings

SB = QMessageBox.StandardButton
ACCEPTED = QDialog.DialogCode.Accepted
REJECTED = QDialog.DialogCode.Rejected


def make_project(root: Path) -> Path:
    for d in ("hardware", "software", "include"):
        (root / d).mkdir(parents=True)
    (root / "hardware" / "M03.plc").write_text("// M03: on\nmain() {\n  portset(1);\n  exit(99);\n};\n")
    (root / "hardware" / "M05.plc").write_text("// M05: off\nmain() {\n  portclear(1);\n  exit(99);\n};\n")
    (root / "software" / "__HANDLER_INIT.plc").write_text("main() { exit(99); };\n")
    (root / "include" / "mine.h").write_text("#define MINE 1\n")
    return root


@pytest.fixture
def prompts(monkeypatch):
    calls, answers = [], []

    def make(name, default):
        def prompt(parent, title, text, *a, **k):
            calls.append((name, title, text))
            return answers.pop(0) if answers else default
        return prompt
    for name, default in (("warning", SB.Discard), ("question", SB.No), ("critical", SB.Ok),
                          ("information", SB.Ok)):
        monkeypatch.setattr(QMessageBox, name, make(name, default))
    monkeypatch.setattr(QMessageBox, "about", lambda *a, **k: calls.append(("about",) + a[1:]))
    return calls, answers


@pytest.fixture
def win(qtbot, tmp_path, prompts):
    w = MainWindow(Settings(str(tmp_path / "cfg" / "s.ini")), start_controller=False,
                   debounce_ms=20)
    qtbot.addWidget(w)
    w.show()
    w.open_project(make_project(tmp_path / "proj"))
    yield w
    w.shutdown()


def driving(monkeypatch, cls, fill, result=ACCEPTED):
    """Make cls.exec() fill the dialog's widgets and accept (or reject) it."""
    seen = []

    def fake_exec(dlg):
        seen.append(dlg)
        fill(dlg)
        if result == ACCEPTED:
            dlg.accept()
            return ACCEPTED if dlg.result() == ACCEPTED else REJECTED
        dlg.reject()
        return REJECTED
    monkeypatch.setattr(cls, "exec", fake_exec)
    return seen


# ------------------------------------------------------------ go to line
def test_go_to_line(win, monkeypatch):
    ed = win.open_file(win.project.hardware_dir / "M03.plc")
    driving(monkeypatch, dialogs.GoToLineDialog, lambda d: d.edit.setText("3:5"))
    win.action(Act.GOTO_LINE).trigger()
    assert ed.cursor_line_col() == (3, 5)
    driving(monkeypatch, dialogs.GoToLineDialog, lambda d: d.edit.setText("4"))
    assert win.goto_line_dialog()
    assert ed.cursor_line_col() == (4, 1)
    driving(monkeypatch, dialogs.GoToLineDialog, lambda d: None, REJECTED)
    assert not win.goto_line_dialog()


def test_go_to_line_validates(qtbot):
    d = dialogs.GoToLineDialog(None, 1, 10)
    qtbot.addWidget(d)
    for text, ok in (("5", True), ("10:3", True), ("11", False), ("0", False), ("x", False),
                     ("2,4", True)):
        d.edit.setText(text)
        assert (d.value() is not None) == ok, text
        assert d.buttons.button(QDialogButtonBox.StandardButton.Ok).isEnabled() == ok


# ---------------------------------------------------------- find/replace
def test_find_replace_bar(win, qtbot):
    ed = win.open_file(win.project.hardware_dir / "M03.plc")
    ed.setSel(ed.position_of(3, 3), ed.position_of(3, 10))       # "portset"
    win.action(Act.FIND).trigger()
    bar = win.find_bar
    assert bar.isVisible() and not bar.replace_row.isVisible()
    assert bar.find_edit.text() == "portset"
    assert bar.count_label.text() == "1 match"
    bar.find_edit.setText("exit")
    assert ed.selected_text() == "exit"
    bar.find_edit.setText("nope")
    assert bar.count_label.text() == "No results"
    assert "background" in bar.find_edit.styleSheet()
    win.action(Act.REPLACE).trigger()
    assert bar.replace_row.isVisible()
    bar.find_edit.setText("1")
    bar.replace_edit.setText("2")
    assert bar.replace_all() == 1
    assert "portset(2)" in ed.text()
    bar.find_edit.setText("99")
    bar.replace_edit.setText("100")
    ed.gotoPos(0)
    bar.find_next()
    bar.replace_one()
    assert "exit(100)" in ed.text()
    win.action(Act.FIND_NEXT).trigger()
    win.action(Act.FIND_PREVIOUS).trigger()
    bar.regex_box.setChecked(True)
    bar.find_edit.setText("p[a-z]+t")
    assert bar.count_label.text() == "1 match"          # portset
    bar.word_box.setChecked(True)
    bar.find_edit.setText("p[a-z]+")
    assert bar.count_label.text() == "1 match"
    bar.regex_box.setChecked(False)
    bar.word_box.setChecked(False)
    bar.find_edit.setText("PORTSET")
    assert bar.count_label.text() == "1 match"
    bar.case_box.setChecked(True)
    assert bar.count_label.text() == "No results"
    bar.close_bar()
    assert not bar.isVisible()


# ------------------------------------------------------------ start picker
def test_start_dialog_paths(qtbot):
    procs = [("M03", Kind.HARDWARE), ("M05", Kind.HARDWARE), ("OFF", Kind.HARDWARE),
             ("__HANDLER_INIT", Kind.SOFTWARE)]
    d = dialogs.StartDialog(None, procs, "M05", 42)
    qtbot.addWidget(d)
    assert d.selected() == "M05" and d.eparam() == 42
    assert d.mcode_spin.value() == 5
    d.mcode_spin.setValue(3)
    assert d.by_mcode.isChecked() and d.selected() == "M03"
    assert d.mcode_status.text() == "→ M03.plc"
    d.mcode_spin.setValue(7)
    assert d.selected() is None and not d.start_button.isEnabled()
    assert "no procedure" in d.error.text()
    d.list.setCurrentRow(3)
    assert d.by_name.isChecked() and d.selected() == "__HANDLER_INIT"
    d.eparam_spin.setValue(-5)
    assert d.eparam() == -5


@pytest.mark.parametrize("initial", ["M80", "M02"])
def test_start_dialog_from_the_keyboard_starts_the_m_code_typed(qtbot, initial):
    """Issue 23 point 11: F5, Alt+M, Ctrl+A, type 5, Enter started the previous
    M-code (M80 again): Alt+M checked the radio button and kept the keys, so the
    digit was lost. The M-code box takes the keys, its number selected."""
    from PySide6.QtCore import Qt
    from PySide6.QtWidgets import QApplication
    procs = [(n, Kind.HARDWARE) for n in ("M02", "M03", "M05", "M80", "OFF")]
    d = dialogs.StartDialog(None, procs, initial, 0)
    qtbot.addWidget(d)
    d.show()
    qtbot.waitExposed(d)
    d.activateWindow()
    qtbot.waitUntil(lambda: QApplication.focusWidget() is not None)
    for _ in range(2):                    # also when the radio button is already checked
        qtbot.keyClick(QApplication.focusWidget(), Qt.Key.Key_M, Qt.KeyboardModifier.AltModifier)
        qtbot.waitUntil(lambda: d.by_mcode.isChecked() and QApplication.focusWidget()
                        in (d.mcode_spin, d.mcode_spin.lineEdit()), timeout=2000)
    focus = QApplication.focusWidget()
    qtbot.keyClick(focus, Qt.Key.Key_A, Qt.KeyboardModifier.ControlModifier)
    qtbot.keyClicks(focus, "5")
    assert d.selected() == "M05", d.mcode_spin.text()
    with qtbot.waitSignal(d.accepted, timeout=2000):
        qtbot.keyClick(focus, Qt.Key.Key_Return)
    assert d.selected() == "M05"


@pytest.mark.parametrize("procs, row", [([("plc", Kind.HARDWARE)], False),
                                        ([("Program", Kind.HARDWARE)], False),
                                        ([("M03", Kind.HARDWARE), ("OFF", Kind.HARDWARE)], True)])
def test_start_dialog_offers_m_codes_only_where_there_are_some(qtbot, procs, row):
    """A Huazhong ('plc') or TG Motion ('Program') project has no M-code
    procedure: the 'By M-code number' row (showing 'M0 no such procedure') is
    not offered; picking by name works as before."""
    d = dialogs.StartDialog(None, procs, procs[0][0], 0)
    qtbot.addWidget(d)
    d.show()
    qtbot.waitExposed(d)
    assert d.by_mcode.isVisible() is row and d.mcode_spin.isVisible() is row
    assert d.selected() == procs[0][0] and d.start_button.isEnabled()


def test_start_dialog_cancel(win, monkeypatch):
    driving(monkeypatch, dialogs.StartDialog, lambda d: None, REJECTED)
    assert dialogs.StartDialog.get_start(win, [("M03", Kind.HARDWARE)]) is None


# ------------------------------------------------------------- names
def test_procedure_name_dialog_validation(qtbot):
    d = dialogs.ProcedureNameDialog(None, existing={"M03"}, initial="M03", allow_kind=True)
    qtbot.addWidget(d)
    ok = d.buttons.button(QDialogButtonBox.StandardButton.Ok)
    assert not ok.isEnabled() and "already" in d.error.text()
    d.name_edit.setText("bad name!")
    assert not ok.isEnabled()
    d.name_edit.setText("M10")
    assert ok.isEnabled() and "M-code M10" in d.hint.text()
    d.kind_combo.setCurrentIndex(1)
    d.name_edit.setText("__HANDLER_EXIT")
    assert d.kind() is Kind.SOFTWARE and "system procedure" in d.hint.text()
    assert dialogs.check_procedure_name("", ()) == "Type a name."
    assert dialogs.check_procedure_name("x" * 65, ()) is not None


def test_new_rename_duplicate_delete_procedure(win, monkeypatch, prompts, qtbot):
    calls, answers = prompts
    tree = win.tree
    hw = win.project.hardware_dir
    # new
    driving(monkeypatch, dialogs.ProcedureNameDialog, lambda d: d.name_edit.setText("M10"))
    win.action(Act.NEW_PROCEDURE).trigger()
    assert (hw / "M10.plc").is_file()
    assert "exit(99)" in (hw / "M10.plc").read_text()
    assert win.current_editor().path == str(hw / "M10.plc")
    assert tree.find_item("M10") is not None
    # new software procedure
    def software(d):
        d.kind_combo.setCurrentIndex(1)
        d.name_edit.setText("POLL")
    driving(monkeypatch, dialogs.ProcedureNameDialog, software)
    tree.action_new_sw.trigger()
    assert (win.project.software_dir / "POLL.plc").is_file()
    # rename (the open editor follows)
    ed = win.editor_for(hw / "M10.plc")
    ed.insertText(0, "// unsaved\n")
    driving(monkeypatch, dialogs.ProcedureNameDialog, lambda d: d.name_edit.setText("M11"))
    menu = tree.context_menu_for(tree.find_item("M10"))
    next(a for a in menu.actions() if a.objectName() == "rename").trigger()
    assert not (hw / "M10.plc").exists() and (hw / "M11.plc").exists()
    assert ed.path == str(hw / "M11.plc") and ed.text().startswith("// unsaved")
    assert win.tabs.tabText(win.tabs.indexOf(ed)).startswith("M11.plc")
    # duplicate
    driving(monkeypatch, dialogs.ProcedureNameDialog, lambda d: None)
    new = tree.duplicate(str(hw / "M03.plc"))
    assert new == hw / "M03_copy.plc"
    assert new.read_text() == (hw / "M03.plc").read_text()
    # delete: asked, No keeps it, Yes deletes and closes its editor
    answers.append(SB.No)
    assert not tree.delete(str(new))
    assert new.exists()
    win.open_file(new)
    answers.append(SB.Yes)
    menu = tree.context_menu_for(tree.find_item("M03_copy"))
    next(a for a in menu.actions() if a.objectName() == "delete").trigger()
    assert not new.exists() and win.editor_for(new) is None
    # cancelled dialogs change nothing
    driving(monkeypatch, dialogs.ProcedureNameDialog, lambda d: None, REJECTED)
    assert tree.new_procedure() is None
    assert tree.rename(str(hw / "M03.plc")) is None


def test_new_and_rename_header(win, monkeypatch):
    driving(monkeypatch, dialogs.HeaderNameDialog, lambda d: d.name_edit.setText("io"))
    win.action(Act.NEW_HEADER).trigger()
    h = win.project.include_dir / "io.h"
    assert h.is_file() and "#ifndef IO_H" in h.read_text()
    driving(monkeypatch, dialogs.HeaderNameDialog, lambda d: d.name_edit.setText("mine.h"))
    assert win.tree.rename(str(h)) is None           # exists: the dialog refuses
    driving(monkeypatch, dialogs.HeaderNameDialog, lambda d: d.name_edit.setText("io2.h"))
    assert win.tree.rename(str(h)) == h.with_name("io2.h")


def test_tree_context_menus_and_opening(win, qtbot):
    tree = win.tree
    root_menu = tree.context_menu_for(None)
    assert {a.text() for a in root_menu.actions()} >= {"New Hardware Procedure…",
                                                       "New Software Procedure…", "New Header…"}
    item = tree.find_item("M05")
    menu = tree.context_menu_for(item)
    start = next(a for a in menu.actions() if a.objectName() == "start")
    assert start.isEnabled()
    tree._activated(item)
    assert win.current_editor().path.endswith("M05.plc")
    tree._activated(tree.find_item("<builtin>/pins.h"))
    assert win.current_editor().builtin
    # changes made outside the IDE show up
    (win.project.hardware_dir / "M42.plc").write_text("main() { exit(99); };\n")
    qtbot.waitUntil(lambda: tree.find_item("M42") is not None, timeout=5000)


# ------------------------------------------------------------- preferences
def test_preferences_dialog(win, monkeypatch):
    ed = win.open_file(win.project.hardware_dir / "M03.plc")

    def fill(d):
        d.size_spin.setValue(16)
        d.tab_spin.setValue(8)
        d.theme_combo.setCurrentIndex(1)
        d.ws_box.setChecked(True)
        d.autosave_spin.setValue(9)
        d.reload_box.setChecked(False)
        d.ac_box.setChecked(False)
        d.first_frame_box.setChecked(False)
    driving(monkeypatch, dialogs.PreferencesDialog, fill)
    win.action(Act.PREFERENCES).trigger()
    p = win.prefs
    assert (p.font_size, p.tab_width, p.theme, p.show_whitespace, p.autosave_seconds,
            p.reload_unmodified, p.autocomplete, p.first_frame) == \
        (16, 8, "dark", True, 9, False, False, False)
    assert ed.tabWidth() == 8 and ed.viewWS() == 1
    assert win.recovery.timer.interval() == 9000
    assert win.settings.preferences() == p
    driving(monkeypatch, dialogs.PreferencesDialog, lambda d: d.size_spin.setValue(6), REJECTED)
    assert not win.edit_preferences()
    assert win.prefs.font_size == 16


def test_connect_dialog(qtbot):
    d = dialogs.ConnectDialog(None, "10.0.0.2", 6000, "tok")
    qtbot.addWidget(d)
    assert d.value() == ("10.0.0.2", 6000, "tok")
    d.host_edit.setText("")
    assert d.value()[0] == "127.0.0.1"


def test_header_name_dialog(qtbot):
    d = dialogs.HeaderNameDialog(None, {"a.h"})
    qtbot.addWidget(d)
    d.name_edit.setText("a")
    assert d.problem() == "a.h exists already."
    d.name_edit.setText("../x.h")
    assert d.problem() is not None
    d.name_edit.setText("b")
    assert d.name() == "b.h" and d.problem() is None


def test_goto_definition(win, qtbot):
    (win.project.hardware_dir / "M07.plc").write_text(
        "#include mine.h\nhelp() { a = 1; }\nmain() { help(); portset(MINE); exit(99); };\n")
    ed = win.open_file(win.project.hardware_dir / "M07.plc")
    qtbot.waitUntil(lambda: not win.busy(), timeout=5000)
    assert win.goto_definition("MINE")
    assert win.current_editor().path.endswith("mine.h")
    win.tabs.setCurrentWidget(ed)
    assert win.goto_definition("help")
    assert ed.cursor_line_col()[0] == 2
    assert win.goto_definition("OUTPUT_SPINDLE")          # the built-in pins.h
    assert win.current_editor().builtin
    win.tabs.setCurrentWidget(ed)
    assert not win.goto_definition("GVAR_HW_PWM0")


def test_editor_actions_reach_the_current_editor(win, qtbot, prompts):
    ed = win.open_file(win.project.hardware_dir / "M03.plc")
    ed.gotoPos(ed.position_of(3, 1))
    win.action(Act.TOGGLE_COMMENT).trigger()
    assert ed.line_text(2).lstrip().startswith("//")
    win.action(Act.UNDO).trigger()
    assert not ed.line_text(2).lstrip().startswith("//")
    win.action(Act.REDO).trigger()
    assert ed.line_text(2).lstrip().startswith("//")
    z = ed.zoom()
    win.action(Act.ZOOM_IN).trigger()
    assert ed.zoom() == z + 1
    win.action(Act.ZOOM_RESET).trigger()
    assert ed.zoom() == 0
    win.open_file(win.project.hardware_dir / "M05.plc")
    win.action(Act.NEXT_TAB).trigger()
    assert win.current_editor() is ed
    win.action(Act.SAVE_ALL).trigger()
    assert not win.modified_editors()
    win.action(Act.CLOSE_ALL).trigger()
    assert win.editors() == []
    win.action(Act.ABOUT).trigger()
    assert prompts[0][-1][0] == "about"


# ------------------------------------------------------------ new project
@pytest.mark.parametrize("target, label, first", [("mycnc", "myCNC", "M02.plc"),
                                                  ("huazhong", "Huazhong", "plc.plc"),
                                                  ("tgmotion", "TG Motion", "Program.plc")])
def test_file_new_project_creates_a_project_of_each_target_and_opens_it(
        win, monkeypatch, tmp_path, qtbot, target, label, first):
    """Issue 23, what users expect: File › New Project… with the target, a folder
    and a name, as `plcbuilder new --target` (the IDE could only copy the myCNC
    example)."""
    from plcbuilder.project.model import Project
    act = win.action(Act.NEW_PROJECT)
    assert act.shortcut().toString() == "Ctrl+Shift+N"
    file_menu = win.menuBar().actions()[0].menu()
    assert file_menu.actions()[0] is act
    where = tmp_path / "projects"
    where.mkdir()

    def fill(d):
        assert d.name_edit.text() == "plc-project"
        assert d.buttons.button(QDialogButtonBox.StandardButton.Ok).isEnabled()
        i = d.target_combo.findText(label)
        d.target_combo.setCurrentIndex(i)
        assert label in d.what.text()
        d.folder_edit.setText(str(where))
        d.name_edit.selectAll()
        qtbot.keyClicks(d.name_edit, f"table {target}")
        assert d.where.text() == f"Creates {where / f'table {target}'}"
    driving(monkeypatch, dialogs.NewProjectDialog, fill)
    act.trigger()
    root = where / f"table {target}"
    assert win.project is not None and win.project.root == root.resolve()
    assert Project.open(root).target == target and win.project.name == f"table {target}"
    assert win.current_editor() is not None and win.current_editor().path.endswith(first)
    # the next New Project starts in the same folder, with a name not taken there
    seen = driving(monkeypatch, dialogs.NewProjectDialog, lambda d: None, REJECTED)
    act.trigger()
    assert seen[0].folder_edit.text() == str(where)
    assert seen[0].name_edit.text() == "plc-project"


def test_the_new_project_dialog_says_what_is_wrong(qtbot, tmp_path):
    (tmp_path / "used").mkdir()
    (tmp_path / "used" / "x").write_text("x")
    d = dialogs.NewProjectDialog(None, tmp_path, "used")
    qtbot.addWidget(d)
    ok = d.buttons.button(QDialogButtonBox.StandardButton.Ok)
    assert not ok.isEnabled() and "not an empty folder" in d.error.text()
    d.name_edit.setText("a/b")
    assert not ok.isEnabled() and "one folder's name" in d.error.text()
    d.name_edit.setText("fresh")
    d.folder_edit.setText(str(tmp_path / "nowhere"))
    assert not ok.isEnabled() and "no such folder" in d.error.text()
    d.folder_edit.setText(str(tmp_path))
    assert ok.isEnabled() and d.error.text() == "" and d.destination() == tmp_path / "fresh"
    d.accept()
    assert d.result() == ACCEPTED


def test_open_project_starts_where_a_project_was_last_opened(win, monkeypatch, tmp_path):
    """File dialogs remember their last folder (issue 23, what users expect)."""
    from PySide6.QtWidgets import QFileDialog
    elsewhere = tmp_path / "far" / "away"
    other = make_project(elsewhere / "other")
    asked = []
    monkeypatch.setattr(QFileDialog, "getExistingDirectory",
                        lambda _p, _t, start, *a, **k: (asked.append(start), str(other))[1])
    assert win.open_project_dialog()
    assert win.project.root == other.resolve()
    win.open_project(tmp_path / "proj")
    monkeypatch.setattr(QFileDialog, "getExistingDirectory",
                        lambda _p, _t, start, *a, **k: (asked.append(start), "")[1])
    assert not win.open_project_dialog()
    assert asked[-1] == str(elsewhere)


def test_eparam_and_speed_are_each_projects_own(qtbot, tmp_path, prompts, monkeypatch):
    """Issue 23, what users expect: the eparam typed for one project's M03 was
    offered in another project's Start dialog, and its speed carried over."""
    from tests.ide._workbench import RecordingConnection
    conn = RecordingConnection()
    conn.connected = True
    w = MainWindow(Settings(str(tmp_path / "cfg" / "s.ini")), connection=conn,
                   start_controller=True, debounce_ms=20)
    qtbot.addWidget(w)
    w.show()
    a = make_project(tmp_path / "a")
    b = make_project(tmp_path / "b")
    assert w.open_project(a)
    seen = []

    def fill(d):
        seen.append((d.eparam(), d.selected()))
        d.eparam_spin.setValue(12000)
    driving(monkeypatch, dialogs.StartDialog, fill)
    monkeypatch.setattr(w.run_actions, "stale_reasons", lambda: [])
    assert w.start_procedure()
    assert ("start", "M03", 12000) in conn.calls
    w.run_actions.speed_combo.setCurrentIndex(w.run_actions.speed_combo.findData("10"))
    assert ("set_speed", "10") in conn.calls
    assert w.open_project(b)
    assert w.run_actions.speed_combo.currentData() == "realtime"
    assert conn.calls[-1] == ("set_speed", "realtime")
    w.start_procedure()
    assert seen[-1][0] == 0                       # not a's 12000
    assert w.open_project(a)
    assert w.run_actions.speed_combo.currentData() == "10"
    assert conn.calls[-1] == ("set_speed", "10")
    w.start_procedure()
    assert seen[-1] == (12000, "M03")
    # and after the IDE starts again
    w.shutdown()
    w2 = MainWindow(Settings(str(tmp_path / "cfg" / "s.ini")), connection=RecordingConnection(),
                    start_controller=True, debounce_ms=20)
    qtbot.addWidget(w2)
    assert w2.open_project(a)
    assert w2.run_actions.last_eparam == 12000 and w2.run_actions.last_start == "M03"
    assert w2.run_actions.speed_combo.currentData() == "10"
    w2.shutdown()
