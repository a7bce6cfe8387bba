"""The IDE on a target project (docs/targets.md): the project tree shows the
target's procedures with when they run; the run panels show its registers
(X/Y bits as named lanes, the non-zero G/F/… words in a table under the watch)."""

from __future__ import annotations

import pytest

pytest.importorskip("PySide6")

from PySide6 import QtCore  # noqa: E402

from plcbuilder import api  # noqa: E402
from plcbuilder.ide.project_tree import ROLE_DESCRIPTION  # noqa: E402
from plcbuilder.ide.settings import Settings  # noqa: E402
from tests.controller._targets import compiled, tgm  # noqa: E402
from tests.ide._workbench import windows  # noqa: E402
from tests.link.linkkit import image_of  # noqa: E402

Qt = QtCore.Qt
WAIT = 15_000


@pytest.fixture
def window(qtbot, tmp_path):
    with windows(qtbot, Settings(str(tmp_path / "cfg" / "s.ini")), None) as make:
        yield make()


def _children(item) -> list[tuple[str, str]]:
    return [(item.child(i).text(0), item.child(i).data(0, ROLE_DESCRIPTION))
            for i in range(item.childCount())]


def test_tree_shows_huazhong_structure(window, tmp_path):
    project = api.create_project(tmp_path / "mill", target="huazhong")
    assert window.open_project(project.root, offer_recovery=False)
    tree = window.tree
    program = tree.find_item("plc")
    assert program.parent().text(0) == "Huazhong PLC"
    assert _children(program) == [("init()", "once, at the start"),
                                  ("plc1()", "every plc1_time ms (16 until set)"),
                                  ("plc2()", "every plc2_time ms (32 until set)")]
    sw = next(tree.tree.topLevelItem(0).child(i) for i in range(tree.tree.topLevelItem(0).childCount())
              if tree.tree.topLevelItem(0).child(i).text(0) == "Software PLC")
    assert sw.isHidden()
    assert tree.find_item(str(project.root / "parameters.toml")) is not None
    tree._activated(program.child(1))
    assert window.current_editor().path.endswith("plc.plc")


@pytest.mark.parametrize("target, says", [
    ("huazhong", "Huazhong PLC: init(), plc1(), plc2()."),
    ("tgmotion", "TG Motion PLC: Program_Ini(), Program_01(), Program_02(), Program_03(), "
                 "Program_04(), Program_05()."),
    ("mycnc", "11 hardware and 2 software procedures.")])
def test_the_welcome_page_names_the_targets_procedures(window, tmp_path, target, says):
    """It said '1 hardware and 0 software procedures' for a TG Motion project."""
    project = api.create_project(tmp_path / target, target=target)
    assert window.open_project(project.root, offer_recovery=False)
    assert says in window.welcome.welcome_text.text()


def test_tree_shows_tgmotion_periods(window, tmp_path):
    project = api.create_project(tmp_path / "tg", target="tgmotion")
    text = project.settings_path.read_text().replace("cycle_time_program_02_us = 1000",
                                                     "cycle_time_program_02_us = 2500")
    project.settings_path.write_text(text)
    src = project.root / "hardware" / "Program.plc"
    src.write_text(src.read_text().replace("Program_03()", "Program_3()"))
    assert window.open_project(project.root, offer_recovery=False)
    program = window.tree.find_item("Program")
    kids = dict(_children(program))
    assert kids["Program_02()"] == "every 2500 µs"
    assert kids["Program_04()"] == "every cycle (500 µs), in the fourth slot"
    assert kids["Program_05()"] == "every slot (100 µs)"
    missing = next(program.child(i) for i in range(program.childCount())
                   if program.child(i).text(0) == "Program_03()")
    assert "not in the program yet" in missing.toolTip(0)


def test_run_panels_show_huazhong_registers(qtbot, live_run_panels):
    win, conn, panels = live_run_panels
    panels.set_target("huazhong")
    panels.set_pin_names({0: "INPUT_HOME_X"}, {7: "OUTPUT_ALARM_LAMP"})
    assert panels.lanes.names["outputs"][7] == "Y0.7 OUTPUT_ALARM_LAMP"
    assert panels.lanes.names["inputs"][9] == "X1.1"
    src = """
        init() { G[2] = 0x1234; }
        plc1() { if (X[1] & 2) Y[0] |= 0x80; else Y[0] &= ~0x80; }
        plc2() { }"""
    conn.upload(image_of([compiled(src, "huazhong")]), {"name": "huazhong"})
    panels.dock("watch").show()
    panels.dock("watch").raise_()
    conn.set_input(9, 1)
    qtbot.waitUntil(lambda: panels.registers.isVisible() and panels.registers.report.get(
        "registers", {}).get("Y") == {"0": 128}, timeout=WAIT)
    table = panels.registers.table
    rows = {table.item(r, 0).text(): table.item(r, 2).text() for r in range(table.rowCount())}
    assert rows["G[2]"] == "0x1234" and rows["Y[0]"] == "0x80"
    assert "plc1" in panels.registers.calls.text()
    panels.set_target("mycnc")
    assert not panels.registers.isVisible()


def test_run_panels_show_the_tgmotion_oscilloscope(qtbot, live_run_panels):
    """Issue 27.9 in the IDE: the signals the project picks for TG Motion's
    oscilloscope and their newest samples are shown under the registers."""
    _win, conn, panels = live_run_panels
    panels.set_target("tgmotion")
    src = tgm(p04="n4++;")
    conn.upload(image_of([compiled(src, "tgmotion")]),
                {"name": "tgmotion", "scope": ["in 9", "plc.n4"]})
    panels.dock("watch").show()
    panels.dock("watch").raise_()
    reg = panels.registers
    qtbot.waitUntil(lambda: reg.report.get("oscilloscope", {}).get("samples", 0) > 2,
                    timeout=WAIT)
    assert reg.scope.isVisible() and "samples of in 9, plc.n4" in reg.scope_title.text()
    headers = [reg.scope.horizontalHeaderItem(c).text() for c in range(reg.scope.columnCount())]
    assert headers == ["t (µs)", "cycle", "in 9", "plc.n4"]
    newest = [float(reg.scope.item(0, c).text()) for c in range(4)]
    older = [float(reg.scope.item(1, c).text()) for c in range(4)]
    assert newest[0] > older[0] and newest[3] == older[3] + 1     # n4 counts the samples
    panels.set_target("huazhong")
    reg.set_report({"target_profile": "huazhong", "registers": {}})
    assert not reg.scope.isVisible()


def test_the_embedded_controller_keeps_huazhong_b_across_ide_restarts(window, tmp_path):
    """SPEC §9: 'B[n] (100 16-bit words kept across controller restarts)': the IDE
    starts its controller with a state file in the project's build/ (a myCNC
    project has no such state)."""
    from plcbuilder.ide.run_actions import STATE_FILE
    mill = api.create_project(tmp_path / "mill", target="huazhong")
    assert window.open_project(mill.root, offer_recovery=False)
    args = window.run_actions.controller_args()
    assert args[args.index("--state") + 1] == str(mill.root / "build" / STATE_FILE)
    plain = api.create_project(tmp_path / "plain")
    assert window.open_project(plain.root, offer_recovery=False)
    assert "--state" not in window.run_actions.controller_args()
