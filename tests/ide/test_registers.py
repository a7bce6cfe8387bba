"""The Registers dock: every ABI name with its number, searchable, inserted
into the editor on Enter/double-click, live values for the rows on screen
through the connection, and What Is This? (Shift+F1) on a name."""

from PySide6.QtCore import Qt

from plcbuilder.api import abi
from plcbuilder.ide.actions import Act
from plcbuilder.ide.panels.register_browser import (COL_KIND, COL_NAME, COL_NUMBER, COL_VALUE,
                                             MAX_LIVE_ROWS, RegisterBrowser, rows)
from tests.ide import _workbench
from tests.ide._workbench import FakeConnection, caret_on, settle

# the fixtures
make_window, project, prompts, win = (_workbench.make_window, _workbench.project,
                                      _workbench.prompts, _workbench.win)


def listed(b: RegisterBrowser, col=COL_NAME):
    return [b.proxy.index(r, col).data() for r in range(b.proxy.rowCount())]


def test_every_abi_name_is_listed_with_its_number():
    table = {name: (value, kind) for name, value, kind, _m in rows()}
    for name, value in abi.BUILTIN_NAMES.items():
        assert table[name] == (value, abi.BUILTIN_KIND[name])
    assert table["GVAR_CURRENT_MOTION_CODE"] == (6060, "register")
    assert table["plc_exit_normal"] == (99, "exit code")
    assert table["plc_proc_spindle"] == (70, "proc state")
    assert table["PLC_MESSAGE_PLASMA_OK"] == (101, "message")
    assert table["pwm01"] == (7278, "predefined variable")


def test_search_and_kind_filter(qtbot):
    b = RegisterBrowser()
    qtbot.addWidget(b)
    total = b.proxy.rowCount()
    qtbot.keyClicks(b.search, "6060")
    assert listed(b) == ["GVAR_CURRENT_MOTION_CODE"]
    assert b.status.text() == f"1 of {total} names"
    b.search.setText("jog")                        # by meaning too
    assert "GVAR_PLC_JOG" in listed(b)
    b.search.clear()
    b.kind.setCurrentIndex(b.kind.findData("exit code"))
    assert set(listed(b, COL_KIND)) == {"exit code"}
    assert "plc_exit_normal" in listed(b)
    b.kind.setCurrentIndex(0)
    b.table.sortByColumn(COL_NUMBER, Qt.SortOrder.DescendingOrder)
    numbers = [int(n) for n in listed(b, COL_NUMBER)]
    assert numbers == sorted(numbers, reverse=True)


def test_enter_inserts_the_name_at_the_caret(win, project, qtbot):
    w = win
    ed = w.open_file(project / "hardware" / "M05.plc")
    ed.goto_line(6, 3)
    w.action(Act.REGISTERS).trigger()
    b = w.workbench.registers
    assert w.registers_dock.isVisible()
    b.search.setText("plc_exit_normal")
    b.table.setCurrentIndex(b.proxy.index(0, 0))
    b.table.setFocus()
    qtbot.keyClick(b.table, Qt.Key.Key_Return)
    assert ed.line_text(5).startswith("  plc_exit_normalportclear(")


def test_live_values_of_the_rows_on_screen(win, qtbot):
    conn = FakeConnection()
    b = win.workbench.registers
    b.set_connection(conn)
    win.registers_dock.setFloating(True)                    # room for the eight PWM rows
    win.registers_dock.resize(700, 900)
    win.registers_dock.show()
    win.registers_dock.raise_()
    qtbot.waitUntil(b.isVisible)
    assert not b.poll()                                     # not connected: nothing asked
    conn.connected = True
    b.search.setText("GVAR_HW_PWM")
    assert b.poll()
    (verb, addrs), = [c for c in conn.calls if c[0] == "request_registers"]
    assert addrs == [abi.GVAR_HW_PWM0 + i for i in range(8)]
    conn.sig_registers.emit({abi.GVAR_HW_PWM0: 1234, abi.GVAR_HW_PWM0 + 1: -5})
    assert b.value_of("GVAR_HW_PWM0") == "1234" and b.value_of("GVAR_HW_PWM1") == "-5"
    assert b.value_of("pwm01") == "1234"                    # the same register
    # only rows on screen, and never more than the limit
    b.search.clear()
    assert len(b.visible_addresses()) <= MAX_LIVE_ROWS
    shown_last = b.table.rowAt(b.table.viewport().height() - 1)
    assert shown_last < b.proxy.rowCount() - 1
    assert set(b.visible_addresses()) <= {b.proxy.index(r, COL_NAME).data(Qt.ItemDataRole.UserRole + 1)
                                          for r in range(shown_last + 1)}
    win.registers_dock.hide()
    conn.calls.clear()
    assert not b.poll() and not conn.calls
    conn.sig_disconnected.emit("gone")
    assert b.value_of("GVAR_HW_PWM0") == ""
    assert b.model.item(0, COL_VALUE) is not None


def test_what_is_this_explains_the_name_at_the_caret(win, project, qtbot):
    w = win
    ed = w.open_file(project / "hardware" / "M03.plc")
    ed.set_text(ed.text().replace("exit(99);", "message = PLCCMD_REPLY_TO_MYCNC; exit(99);"),
                keep_undo=True)
    settle(qtbot, w)
    caret_on(ed, "PLCCMD_REPLY_TO_MYCNC")
    w.action(Act.WHAT_IS_THIS).trigger()                    # Shift+F1
    assert ed.callTipActive()
    assert w.workbench.what_is_this().startswith("PLCCMD_REPLY_TO_MYCNC = 1100")
    assert w.registers_dock.isVisible()
    assert w.workbench.registers.current_name() == "PLCCMD_REPLY_TO_MYCNC"
    caret_on(ed, "MY_PIN")
    assert "#define MY_PIN 3" in w.workbench.what_is_this()


def test_what_is_this_on_a_number_selects_what_it_means(win, project, qtbot):
    w = win
    ed = w.open_file(project / "hardware" / "M03.plc")
    ed.set_text(ed.text().replace("exit(99);", "code = gvarget(6060); exit(99);"),
                keep_undo=True)
    caret_on(ed, "6060")
    assert "GVAR_CURRENT_MOTION_CODE" in w.workbench.what_is_this()
    assert w.workbench.registers.current_name() == "GVAR_CURRENT_MOTION_CODE"
    caret_on(ed, "99")
    assert w.workbench.what_is_this().startswith("exit code 99")
    assert w.workbench.registers.current_name() == "plc_exit_normal"


def test_a_target_project_lists_its_headers_names(win, project, qtbot, tmp_path):
    """View › Registers on a TG Motion project lists tgmotion.h's TGM_… names
    (and on a Huazhong one plc.h's), found by the search like the ABI's; back
    on a myCNC project they are gone."""
    from plcbuilder import api
    w = win
    w.action(Act.REGISTERS).trigger()
    b = w.workbench.registers
    qtbot.waitUntil(b.isVisible)
    b.search.setText("TGM_DATA")
    assert listed(b) == []
    tg = api.create_project(tmp_path / "tg", target="tgmotion")
    assert w.open_project(tg.root, offer_recovery=False)
    names = listed(b)                             # the search kept, the rows followed
    row = names.index("TGM_DATA")                 # (then the names whose comment names it)
    assert (listed(b, COL_NUMBER)[row], listed(b, COL_KIND)[row]) == \
        (2000000, "tgmotion.h name")
    b.search.setText("DIO_")
    assert listed(b) == ["DIO_DI", "DIO_DO", "DIO_AI", "DIO_AO"]
    assert "ADC channel" in b.proxy.index(2, 4).data()
    assert b.kind.findData("tgmotion.h name") > 0
    b.search.setText("TGM_")
    assert {"TGM_DATA", "TGM_SERVO", "TGM_DIO", "TGM_OSC"} <= set(listed(b))

    hz = api.create_project(tmp_path / "hz", target="huazhong")
    assert w.open_project(hz.root, offer_recovery=False)
    assert listed(b) == []                        # TG Motion's are gone
    b.search.setText("M_CODE")
    assert listed(b) == ["M_CODE"] and listed(b, COL_KIND) == ["plc.h name"]
    assert b.kind.findData("tgmotion.h name") < 0 and b.kind.findData("plc.h name") > 0
    b.table.setCurrentIndex(b.proxy.index(0, 0))   # Enter inserts it, as an ABI name
    ed = w.open_file(hz.root / "hardware" / "plc.plc")
    ed.goto_line(1, 1)
    b.table.setFocus()
    qtbot.keyClick(b.table, Qt.Key.Key_Return)
    assert ed.line_text(0).startswith("M_CODE")

    assert w.open_project(project, offer_recovery=False)
    assert listed(b) == [] and b.kind.findData("plc.h name") < 0
