"""Where the bytes go, in the real window: the Disassembly dock (the records
``plcbuilder disasm`` prints, with their source lines), the code bytes in the
editor margin, and Build, Upload and Start."""

from pathlib import Path

from plcbuilder import api
from plcbuilder.ide import code_bytes
from plcbuilder.ide.actions import Act
from plcbuilder.ide.editor import file_key
from plcbuilder.ide.run_actions import Step
from tests.ide import _workbench
from tests.ide._workbench import FakeConnection, caret_on, settle

# the fixtures
make_window, project, prompts, win = (_workbench.make_window, _workbench.project,
                                      _workbench.prompts, _workbench.win)


def compiled(path: Path):
    return api.compile_file(path, api.options_for(path))


def test_disassembly_lists_the_records_with_their_source_lines(win, project, qtbot):
    w = win
    path = project / "hardware" / "M03.plc"
    ed = w.open_file(path)
    settle(qtbot, w)
    w.action(Act.SHOW_DISASSEMBLY).trigger()
    view = w.workbench.disasm
    assert w.disasm_dock.isVisible()
    result = compiled(path)
    records = api.instructions(result.program)
    assert view.header.text().startswith(f"<b>M03.plc</b>: {result.size} of 512 bytes")
    top = view.tree.topLevelItem(0)
    assert top.text(0) == f"main()   {result.size} bytes"
    lines = [top.child(i) for i in range(top.childCount())]
    assert lines[0].text(0).endswith("M03.plc:7  speed = eparam;")
    shown = [(c.text(0).strip(), c.text(2), c.text(3)) for ln in lines
             for c in (ln.child(j) for j in range(ln.childCount()))]
    assert shown == [(str(d.offset), d.op.name, d.operand) for d in records]
    assert sum(view.line_bytes().values()) == result.size
    # the caret's line is selected; a double-click on a line opens it
    caret_on(ed, "portset")
    qtbot.waitUntil(lambda: view.tree.currentItem() is not None and
                    "portset(MY_PIN)" in view.tree.currentItem().text(0))
    ed.goto_line(1)
    view.tree.itemDoubleClicked.emit(lines[0], 0)
    assert ed.cursor_line_col()[0] == 7


def test_disassembly_says_why_there_is_no_code(win, project, qtbot):
    w = win
    w.action(Act.SHOW_DISASSEMBLY).trigger()
    w.open_file(project / "include" / "mine.h")
    assert "not a procedure" in w.workbench.disasm.header.text()
    ed = w.open_file(project / "hardware" / "M05.plc")
    ed.set_text(ed.text().replace("exit(99);", "exit(99"), keep_undo=True)
    qtbot.waitUntil(lambda: "error" in w.workbench.disasm.header.text(), timeout=10000)
    assert w.workbench.disasm.tree.topLevelItemCount() == 0


def test_code_bytes_in_the_margin_follow_the_compile(win, project, qtbot):
    w = win
    path = project / "hardware" / "M03.plc"
    ed = w.open_file(path)
    settle(qtbot, w)
    assert code_bytes.margin_texts(ed) == {}
    w.action(Act.CODE_BYTES).trigger()                     # View → Code Bytes in Margin
    counts = code_bytes.bytes_by_line(api.instructions(compiled(path).program), str(path))
    expected = {line: str(n) for line, n in code_bytes.lines_of_file(counts, str(path)).items()}
    assert code_bytes.margin_texts(ed) == expected
    assert sum(int(v) for v in expected.values()) == compiled(path).size
    # a longer line: its bytes grow as the check comes back
    before = int(expected[8])
    ed.goto_line(8)
    ed.lineEnd()
    ed.replaceSel(" pwm02 = speed + 1;")
    qtbot.waitUntil(lambda: int(code_bytes.margin_texts(ed).get(8, 0)) > before, timeout=10000)
    w.action(Act.CODE_BYTES).trigger()
    assert code_bytes.margin_texts(ed) == {}
    assert w.action(Act.CODE_BYTES) in w.view_menu.actions()


def test_code_bytes_in_the_margin_is_remembered(make_window, project, qtbot):
    w = make_window()
    w.action(Act.CODE_BYTES).trigger()
    w.settings.sync()
    again = make_window()
    assert again.action(Act.CODE_BYTES).isChecked()
    again.open_project(project)
    ed = again.open_file(project / "hardware" / "M05.plc")
    qtbot.waitUntil(lambda: code_bytes.margin_texts(ed) != {}, timeout=10000)


def test_build_upload_and_start_runs_the_steps_in_order(make_window, project, qtbot):
    conn = FakeConnection()
    w = make_window(connection=conn, start_controller=True)
    w.open_project(project)
    ed = w.open_file(project / "hardware" / "M05.plc")
    assert w.action(Act.BUILD_UPLOAD_START).isEnabled()
    assert w.action(Act.BUILD_UPLOAD_START) in w.toolbar.actions()
    w.run_actions.last_eparam = 7
    with qtbot.waitSignal(w.sig_build_finished, timeout=20000):
        w.action(Act.BUILD_UPLOAD_START).trigger()          # Ctrl+R
        assert w.run_actions.step is Step.BUILD_UPLOAD_START
    verbs = [c for c in conn.calls if c[0] in ("upload", "start")]
    assert [v[0] for v in verbs] == ["upload", "start"]
    assert verbs[0][1] == (project / "build" / "eeprom.rom").read_bytes()
    assert verbs[1] == ("start", "M05", 7)
    # a build that fails uploads and starts nothing
    conn.calls.clear()
    ed.set_text("main() { exit(99) }\n", keep_undo=True)
    w.save_editor(ed)
    with qtbot.waitSignal(w.sig_build_finished, timeout=20000):
        w.run_actions.build_upload_start()
    assert not [c for c in conn.calls if c[0] in ("upload", "start")]
    assert w.run_actions.pending_start is None and w.run_actions.step is Step.IDLE
    assert file_key(w.current_editor().path) == file_key(ed.path)
