"""Status that tells the truth and goes away (issue 13, defect 8): the upload
message ends, a disconnect's reason is not kept after the reconnect, Build
Output and the run log start over with another project without a red error,
the tree follows the active tab, the Start dialog takes typing at once, and
Reset Layout brings a sideways-scrolled editor back to the left."""

import pytest
from PySide6.QtCore import Qt, QTimer
from PySide6.QtWidgets import QDialog

from plcbuilder.ide import dialogs
from plcbuilder.ide.link_reasons import CLOSED_BY_IDE
from plcbuilder.ide.panels.log import CATEGORY, TEXT
from plcbuilder.link.client import ControllerStatus
from tests.ide.test_docks_fit import prompts_off, runwin  # noqa: F401 - fixtures
from tests.ide.test_main_window import make_project


def test_the_upload_message_ends_and_a_disconnect_is_forgotten_on_reconnect(runwin, qtbot):  # noqa: F811
    w, conn = runwin
    conn.connected = True
    conn.sig_connected.emit("127.0.0.1:5555")
    w.statusBar().showMessage("Uploading eeprom.rom (6144 bytes)…", 5000)
    w._on_request_done("upload", {"accepted": True, "procedures": ["M03", "M05", "LOOP"]})
    assert w.statusBar().currentMessage() == "Uploaded the image to the controller: 3 procedures"
    conn.sig_state.emit(ControllerStatus(t_ms=1000, running="M03", proc=70), 0)
    conn.connected = False
    conn.sig_disconnected.emit("the controller process was killed (SIGKILL)")
    assert "SIGKILL" in w.statusBar().currentMessage()
    assert w.status.running_label.text() == "–"             # M03 is not known to run
    assert "SIGKILL" in w.status.connection_label.toolTip()
    assert "Disconnected" in w.run_panels.proc.status.plain_text()
    conn.connected = True
    conn.sig_connected.emit("127.0.0.1:5556")                 # the controller came back
    assert w.statusBar().currentMessage() == ""
    assert "SIGKILL" not in w.status.connection_label.toolTip()
    assert "Disconnected" not in w.run_panels.proc.status.plain_text()


def test_another_project_starts_build_output_over_without_a_red_error(runwin, qtbot, tmp_path):  # noqa: F811
    w, conn = runwin
    w.build_all()
    qtbot.waitUntil(lambda: "Build succeeded" in w.build_panel.plain_text(), timeout=20000)
    conn.connected = True
    conn.sig_connected.emit("127.0.0.1:5555")
    other = make_project(tmp_path / "other")
    # what ControllerConnection.shutdown says when the IDE restarts it for the project
    conn.connected = False
    conn.sig_disconnected.emit(CLOSED_BY_IDE)
    assert w.open_project(other)
    assert w.build_panel.plain_text() == "" and w.build_panel.status.text() == "No build yet"
    w.run_panels.tick()
    rows = w.run_panels.log.rows.rows()
    assert not any(r[CATEGORY] == "error" for r in rows), [r[TEXT] for r in rows]
    assert w.statusBar().currentMessage() == "" or "Controller" not in w.statusBar().currentMessage()


def test_the_tree_follows_the_active_tab(runwin, qtbot):  # noqa: F811
    w, _conn = runwin
    root = w.project.root
    w.open_file(str(root / "hardware" / "M03.plc"))
    w.open_file(str(root / "hardware" / "M05.plc"))
    assert w.tree.tree.currentItem().text(0) == "M05"
    w.tabs.setCurrentIndex(0)
    assert w.tree.tree.currentItem().text(0) == "M03"


def test_the_start_dialog_takes_typing_at_once(qtbot):
    from plcbuilder.api import Kind
    dlg = dialogs.StartDialog(None, [("M03", Kind.HARDWARE), ("M05", Kind.HARDWARE),
                                     ("M80", Kind.HARDWARE), ("M81", Kind.HARDWARE)], "M03", 0)
    qtbot.addWidget(dlg)
    got = []

    def type_and_enter():
        target = dlg.focusWidget()              # where the dialog sends typing
        got.append(target)
        if target is None:
            dlg.reject()
            return
        qtbot.keyClicks(target, "M81")
        qtbot.keyClick(target, Qt.Key.Key_Return)

    QTimer.singleShot(100, type_and_enter)
    assert dlg.exec() == QDialog.DialogCode.Accepted
    assert got[0] is dlg.list
    assert dlg.selected() == "M81"


def test_reset_layout_scrolls_the_editor_back_to_the_left(runwin, qtbot):  # noqa: F811
    w, _conn = runwin
    path = w.project.root / "hardware" / "M03.plc"
    path.write_text("main()\n{\n  a = 1;  // " + "a long comment " * 20 + "\n  exit(99);\n};\n")
    ed = w.open_file(str(path))
    right = w.run_docks["outputs"]
    w.resizeDocks([right], [w.width() - 500], Qt.Orientation.Horizontal)   # the editor squeezed
    qtbot.wait(50)
    ed.goto_line(3, 80)
    ed.scrollCaret()
    qtbot.waitUntil(lambda: ed.xOffset() > 0, timeout=3000)
    ed.goto_line(4, 3)                       # the caret back near the left edge
    w.reset_layout()
    qtbot.waitUntil(lambda: ed.xOffset() == 0, timeout=3000)


@pytest.mark.parametrize("t_ms", [5_000, 239_766_131, 604_800_000, 9_999_999_999, 86_400_000_000])
def test_the_simulated_time_is_never_clipped(runwin, qtbot, t_ms):  # noqa: F811
    """Issue 23 point 12: above 100,000 s the status bar showed "= 239766.131 s"
    (the label keeps a fixed width, which did not count its margins)."""
    from PySide6.QtWidgets import QStyle, QStyleOption
    w, _conn = runwin
    label = w.status.time_label
    w.status.show_state(ControllerStatus(t_ms=t_ms, running="M03"))
    qtbot.wait(10)
    text = label.text()
    assert text.startswith("t = ")
    room = label.contentsRect().width() - 2 * label.margin()
    assert label.fontMetrics().horizontalAdvance(text) <= room, (text, room)
    width = label.width()
    w.status.show_state(ControllerStatus(t_ms=t_ms + 1, running="M03"))
    assert label.width() == width                 # it still never lays the bar out again


def test_switching_back_to_a_project_reopens_its_editors(runwin, qtbot, tmp_path):  # noqa: F811
    """Issue 23 point 18: docs/ide.md says the open files of each project are
    remembered; switching to another project and back lost them."""
    w, _conn = runwin
    a = w.project.root
    w.open_file(a / "hardware" / "M03.plc")
    w.open_file(a / "hardware" / "M05.plc")
    w.open_file(a / "hardware" / "M03.plc")             # the current one
    b = make_project(tmp_path / "other")
    assert w.open_project(b)
    assert [p.rsplit("/", 1)[-1] for p in (ed.path for ed in w.editors())] == []
    w.open_file(b / "hardware" / "M05.plc")
    assert w.open_project(a)
    assert sorted(ed.path.rsplit("/", 1)[-1] for ed in w.editors()) == ["M03.plc", "M05.plc"]
    assert w.current_editor().path.endswith("M03.plc")
    assert w.open_project(b)
    assert [ed.path.rsplit("/", 1)[-1] for ed in w.editors()] == ["M05.plc"]
