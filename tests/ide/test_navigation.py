"""Navigation in the real window: Back/Forward, Quick Open, Find in Files,
Find References, Rename Symbol and the Outline, driven through the actions,
keys and widgets a user touches."""

from pathlib import Path

from PySide6.QtCore import Qt
from PySide6.QtWidgets import QDialog

from plcbuilder.ide.actions import Act
from plcbuilder.ide.dialogs.quick_open import QuickOpenDialog, fuzzy_score, rank
from plcbuilder.ide.dialogs.rename import RenameDialog
from plcbuilder.ide.editor import file_key
from plcbuilder.ide.panels.find_in_files import SearchError, search
from tests.ide import _workbench
from tests.ide._workbench import caret_on, settle

# the fixtures
make_window, project, prompts, win = (_workbench.make_window, _workbench.project,
                                      _workbench.prompts, _workbench.win)


def where(w):
    ed = w.current_editor()
    return Path(ed.path).name, ed.cursor_line_col()[0]


# ------------------------------------------------------------ back / forward
def test_back_and_forward_over_definition_jumps_and_tabs(win, project, qtbot):
    w = win
    m03 = w.open_file(project / "hardware" / "M03.plc")
    caret_on(m03, "MY_PIN")
    assert not w.action(Act.BACK).isEnabled()
    w.action(Act.GOTO_DEFINITION).trigger()                     # F12
    assert where(w) == ("mine.h", 2)
    assert w.action(Act.BACK).isEnabled()
    w.open_file(project / "hardware" / "M05.plc", 6)           # a click into another file
    assert where(w) == ("M05.plc", 6)
    w.action(Act.BACK).trigger()                                # Alt+Left
    assert where(w) == ("mine.h", 2)
    w.action(Act.BACK).trigger()
    assert where(w) == ("M03.plc", 9)
    assert not w.action(Act.BACK).isEnabled() and w.action(Act.FORWARD).isEnabled()
    w.action(Act.FORWARD).trigger()                             # Alt+Right
    assert where(w) == ("mine.h", 2)
    w.action(Act.FORWARD).trigger()
    assert where(w) == ("M05.plc", 6)
    assert not w.action(Act.FORWARD).isEnabled()
    # a new jump forgets Forward
    w.action(Act.BACK).trigger()
    w.goto_definition("MY_PIN")
    assert not w.action(Act.FORWARD).isEnabled()


def test_alt_left_is_back_in_the_editor(win, project, qtbot):
    w = win
    m03 = w.open_file(project / "hardware" / "M03.plc")
    caret_on(m03, "MY_PIN")
    w.goto_definition("MY_PIN")
    header = w.current_editor()
    header.take_focus()
    qtbot.waitUntil(header.hasFocus)
    qtbot.keyClick(header, Qt.Key.Key_Left, Qt.KeyboardModifier.AltModifier)
    assert where(w) == ("M03.plc", 9)


def test_places_of_deleted_files_are_skipped(win, project):
    w = win
    w.open_file(project / "hardware" / "M03.plc", 5)
    w.open_file(project / "hardware" / "M05.plc", 6)
    w.open_file(project / "hardware" / "LONE.plc", 2)
    w.workbench.nav.forget_file(str(project / "hardware" / "M05.plc"))
    w.action(Act.BACK).trigger()
    assert where(w) == ("M03.plc", 5)


# ------------------------------------------------------------------ quick open
def test_fuzzy_matching_ranks_names():
    assert fuzzy_score("m3", "M03.plc") is not None
    assert fuzzy_score("m3x", "M03.plc") is None
    files = [(n, f"hardware/{n}") for n in ("M30.plc", "M03.plc", "OFF.plc", "M13.plc")]
    files.append(("__HANDLER_INIT.plc", "software/__HANDLER_INIT.plc"))
    assert rank("m03", files)[0][0] == "M03.plc"
    assert [p for p, _ in rank("hinit", files)] == ["__HANDLER_INIT.plc"]
    assert [p for p, _ in rank("soft/", files)] == ["__HANDLER_INIT.plc"]   # a path query
    assert len(rank("", files)) == len(files)


def test_quick_open_opens_the_file_typed(win, project, monkeypatch, qtbot):
    seen = {}

    def run(dlg):
        qtbot.keyClicks(dlg.edit, "m5")
        seen["listed"] = [dlg.list.item(i).text() for i in range(dlg.list.count())]
        qtbot.keyClick(dlg.edit, Qt.Key.Key_Return)
        return dlg.result()
    monkeypatch.setattr(QuickOpenDialog, "exec", run)
    win.action(Act.QUICK_OPEN).trigger()                        # Ctrl+P
    assert seen["listed"][0].startswith("M05.plc")
    assert where(win)[0] == "M05.plc"


# --------------------------------------------------------------- find in files
def test_search_options():
    texts = {"a.plc": "portset(MY_PIN);\nmy_pin2 = 1; // MY_PIN\n"}
    assert [(h.line, h.col) for h in search(texts, "my_pin")[0]] == [(1, 9), (2, 1), (2, 17)]
    assert [(h.line, h.col) for h in search(texts, "MY_PIN", case=True)[0]] == [(1, 9), (2, 17)]
    assert [h.line for h in search(texts, "my_pin", whole_word=True)[0]] == [1, 2]
    assert [h.col for h in search(texts, r"port\w+", regex=True)[0]] == [1]
    hits, more = search(texts, "_", limit=2)
    assert len(hits) == 2 and more
    try:
        search(texts, "(", regex=True)
    except SearchError as exc:
        assert "regular expression" in str(exc)
    else:
        raise AssertionError("a bad pattern must be refused")


def test_find_in_files_lists_matches_of_unsaved_text_and_opens_them(win, project, qtbot):
    w = win
    m05 = w.open_file(project / "hardware" / "M05.plc")
    m05.set_text(m05.text() + "// MY_PIN once more\n", keep_undo=True)   # not saved
    w.action(Act.FIND_IN_FILES).trigger()                       # Ctrl+Shift+F
    panel = w.workbench.find_panel
    assert w.find_dock.isVisible() and panel.pattern.hasFocus()
    qtbot.keyClicks(panel.pattern, "MY_PIN")
    qtbot.keyClick(panel.pattern, Qt.Key.Key_Return)
    shown = [(Path(f).name, line) for f, line, _c in panel.tree.hits_shown()]
    assert ("M05.plc", 9) in shown and ("mine.h", 2) in shown and ("M03.plc", 9) in shown
    assert "matches in 4 files" in panel.summary.text()
    tops = [panel.tree.topLevelItem(i).text(0) for i in range(panel.tree.topLevelItemCount())]
    assert "hardware/M05.plc  (3)" in tops                   # paths in the project
    panel.whole_word.setChecked(True)
    panel.regex.setChecked(True)
    panel.pattern.setText("MY_P[")
    assert panel.run_search() == 0 and "regular expression" in panel.summary.text()
    panel.pattern.setText(r"MY_\w+")
    assert panel.run_search() == len(shown)
    # a click on a match opens its line
    top = panel.tree.topLevelItem(0)
    target = top.child(0)
    rect = panel.tree.visualItemRect(target)
    qtbot.mouseClick(panel.tree.viewport(), Qt.MouseButton.LeftButton, pos=rect.center())
    f, line, _col = target.data(0, Qt.ItemDataRole.UserRole + 1)
    assert file_key(w.current_editor().path) == file_key(f)
    assert w.current_editor().cursor_line_col()[0] == line


# ------------------------------------------------------------ find references
def test_find_references_of_a_header_define(win, project, qtbot):
    w = win
    m05 = w.open_file(project / "hardware" / "M05.plc")
    caret_on(m05, "MY_PIN", 1)                  # the code, not the comment
    w.action(Act.FIND_REFERENCES).trigger()     # Shift+F12
    panel = w.workbench.references
    assert w.references_dock.isVisible()
    places = [(Path(f).name, line) for f, line, _c in panel.tree.hits_shown()]
    assert sorted(places) == [("M03.plc", 9), ("M05.plc", 6), ("mine.h", 2)]   # not LONE.plc
    assert "3 references in 3 files" in panel.summary.text()
    assert "(definition)" in panel.tree.findItems("mine.h", Qt.MatchFlag.MatchContains)[0] \
        .child(0).text(1)
    panel.tree.sig_open_location.emit(str(project / "hardware" / "M03.plc"), 9, 11)
    assert where(w) == ("M03.plc", 9)
    w.action(Act.BACK).trigger()
    assert where(w) == ("M05.plc", 6)


# -------------------------------------------------------------------- rename
def test_rename_previews_then_changes_every_file_and_is_undoable(win, project, qtbot,
                                                                 monkeypatch):
    w = win
    m03 = w.open_file(project / "hardware" / "M03.plc")
    caret_on(m03, "MY_PIN")
    seen = {}

    def run(dlg):
        dlg.edit.setText("portset")                 # a built-in name: refused
        dlg.update_preview()
        seen["refused"] = (dlg.error.text(), dlg.ok_button().isEnabled())
        dlg.edit.setText("SPINDLE_PIN")
        dlg.update_preview()
        seen["files"] = [dlg.preview.topLevelItem(i).text(0)
                         for i in range(dlg.preview.topLevelItemCount())]
        seen["m05"] = [(dlg.preview.topLevelItem(i).child(0).text(1),
                        dlg.preview.topLevelItem(i).child(0).text(2))
                       for i in range(dlg.preview.topLevelItemCount())
                       if dlg.preview.topLevelItem(i).text(0).startswith("hardware/M05")]
        seen["summary"] = dlg.summary.text()
        dlg.accept()
        return QDialog.DialogCode.Accepted
    monkeypatch.setattr(RenameDialog, "exec", run)
    w.action(Act.RENAME_SYMBOL).trigger()           # F2
    assert "built-in" in seen["refused"][0] and not seen["refused"][1]
    assert sorted(seen["files"]) == ["hardware/M03.plc  (1)", "hardware/M05.plc  (1)",
                                     "include/mine.h  (1)"]
    assert seen["m05"] == [("portclear(MY_PIN);", "portclear(SPINDLE_PIN);")]
    assert seen["summary"] == "3 changes in 3 files"
    # written: the open editor (saved, it had no other change) and the closed files
    assert "portset(SPINDLE_PIN);" in (project / "hardware" / "M03.plc").read_text()
    assert "portclear(SPINDLE_PIN);" in (project / "hardware" / "M05.plc").read_text()
    assert "MY_PIN in a comment" in (project / "hardware" / "M05.plc").read_text()
    assert (project / "include" / "mine.h").read_text() == \
        "// mine.h: my pins\n#define SPINDLE_PIN 3\n"
    assert "portset(MY_PIN);" in (project / "hardware" / "LONE.plc").read_text()  # its own
    assert not list(project.rglob("*.tmp*"))
    settle(qtbot, w)
    assert w.store.counts() == (0, 0)
    # one undo in the editor takes it back
    assert not w.is_modified(m03)
    m03.undo()
    assert "portset(MY_PIN);" in m03.text() and "SPINDLE_PIN" not in m03.text()


def test_rename_keeps_unsaved_editors_unsaved(win, project, monkeypatch):
    w = win
    m05 = w.open_file(project / "hardware" / "M05.plc")
    m05.set_text(m05.text().replace("exit(99);", "exit(99); // later"), keep_undo=True)
    m03 = w.open_file(project / "hardware" / "M03.plc")
    caret_on(m03, "MY_PIN")

    def run(dlg):
        dlg.edit.setText("PIN3")
        dlg.update_preview()
        dlg.accept()
        return QDialog.DialogCode.Accepted
    monkeypatch.setattr(RenameDialog, "exec", run)
    assert w.workbench.rename_symbol()
    assert "portclear(PIN3);" in m05.text() and w.is_modified(m05)
    assert "portclear(MY_PIN);" in (project / "hardware" / "M05.plc").read_text()


def test_rename_of_a_builtin_name_says_why_not(win, project, prompts):
    m03 = win.open_file(project / "hardware" / "M03.plc")
    caret_on(m03, "pwm01")
    assert not win.workbench.rename_symbol()
    assert prompts.calls and "built-in" in prompts.calls[-1][2]


# -------------------------------------------------------------------- outline
def test_outline_lists_goes_and_follows(win, project, qtbot):
    w = win
    ed = w.open_file(project / "hardware" / "LONE.plc")
    outline = w.workbench.outline
    groups = [outline.tree.topLevelItem(i).text(0) for i in range(outline.tree.topLevelItemCount())]
    assert groups == ["Procedures (1)", "Defines (1)"]
    item = outline.item_named("MY_PIN")
    assert item.text(1) == "4"
    ed.goto_line(5)
    outline.tree.itemClicked.emit(item, 0)
    assert ed.cursor_line_col()[0] == 1
    ed.goto_line(4, 3)
    qtbot.waitUntil(lambda: outline.selected().name == "main")     # the caret's procedure
    ed.goto_line(1, 3)
    qtbot.waitUntil(lambda: outline.selected().name == "MY_PIN")
    # it follows the text after a pause in typing
    ed.goto_line(4, 3)
    ed.replaceSel("count = 1; ")
    qtbot.waitUntil(lambda: outline.item_named("count") is not None, timeout=3000)
    w.open_file(project / "include" / "mine.h")
    assert outline.item_named("MY_PIN").text(1) == "3"


def test_a_very_large_file_is_not_outlined(win, project, qtbot):
    from plcbuilder.ide.panels.outline import MAX_OUTLINE_CHARS
    ed = win.open_file(project / "hardware" / "LONE.plc")
    outline = win.workbench.outline
    ed.set_text("main()\n{\n" + "  a = 1;\n" * (MAX_OUTLINE_CHARS // 9 + 1) + "};\n",
                keep_undo=True)
    outline.refresh()
    assert "too large to outline" in outline.note.text() and not outline.items


def test_matches_on_one_line_share_a_row(qtbot):
    from plcbuilder.ide.panels.results import Hit, ResultsTree
    tree = ResultsTree()
    qtbot.addWidget(tree)
    line = "timer=2;do{timer--;}while(timer>0);"
    hits = [Hit("/p/M03.plc", 20, c, c + 5, line) for c in (1, 12, 27)] + \
        [Hit("/p/M03.plc", 21, 1, 6, "timer=0;")]
    assert tree.set_hits(hits) == 4
    top = tree.topLevelItem(0)
    assert top.text(0) == "/p/M03.plc  (4)"
    assert [top.child(i).text(0) for i in range(top.childCount())] == ["20  ×3", "21"]
    assert tree.hits_shown() == [("/p/M03.plc", 20, 1), ("/p/M03.plc", 21, 1)]
