"""Issue 28.5: the window's docks come from one table, ``docks.DOCKS``.

Every row is a dock of the window and an entry of the View menu; Reset Layout
gives the table's layout back; a saved layout comes back by the rows' object
names; and a dock is added by adding a row (its panel made when it first shows).
"""

from __future__ import annotations

import importlib

import pytest
from PySide6.QtCore import Qt
from PySide6.QtWidgets import QDockWidget, QLabel

from plcbuilder.ide import docks
from plcbuilder.ide.docks import DOCKS, DockSpec, on_screen
from plcbuilder.ide.settings import Settings
from tests.ide._workbench import FakeConnection, windows

AREA = {docks.LEFT: Qt.DockWidgetArea.LeftDockWidgetArea,
        docks.RIGHT: Qt.DockWidgetArea.RightDockWidgetArea,
        docks.BOTTOM: Qt.DockWidgetArea.BottomDockWidgetArea}


@pytest.fixture
def make(qtbot, tmp_path):
    with windows(qtbot, Settings(str(tmp_path / "cfg" / "s.ini")), (1360, 860)) as make:
        yield make


def _window_docks(w) -> list[QDockWidget]:
    return w.findChildren(QDockWidget, options=Qt.FindChildOption.FindDirectChildrenOnly)


def _groups(specs) -> dict[str, list[str]]:
    """Each tab group's rows (by the first row's name), in the table's order."""
    groups: dict[str, list[str]] = {}
    for s in specs:
        how, _, other = s.place.partition(":")
        groups.setdefault(other if how == "tab" else s.name, []).append(s.name)
    return groups


# ------------------------------------------------------------ the table itself
def test_the_table_is_consistent():
    names = [s.name for s in DOCKS]
    keys = [s.key for s in DOCKS]
    assert len(set(names)) == len(names) and len(set(keys)) == len(keys)
    assert len({s.title for s in DOCKS}) == len(DOCKS)
    for i, s in enumerate(DOCKS):
        assert s.area in AREA, s
        how, _, other = s.place.partition(":")
        assert how in ("", "below", "tab"), s
        if other:      # a dock it goes with: an earlier row of the same area
            before = {d.name: d for d in DOCKS[:i]}
            assert other in before and before[other].area == s.area, s
        for path in (s.make, s.then):
            if path:
                module, _, func = path.partition(":")
                assert callable(getattr(importlib.import_module(module), func)), path
    shortcuts = [d.shortcut for d in DOCKS if d.shortcut]
    assert len(set(shortcuts)) == len(shortcuts)
    # at most one front tab a group; a group's rows are all run docks or none
    for group in _groups(DOCKS).values():
        rows = [s for s in DOCKS if s.name in group]
        assert sum(s.front for s in rows) <= 1, group
    # the run panels fill exactly the table's run rows
    from plcbuilder.ide.panels.runpanels import RunPanels
    assert [n for _k, _t, n in RunPanels.DOCKS] == [s.name for s in DOCKS if s.run]
    # object names saved layouts restore by: unchanged from before the table
    assert set(names) == {
        "projectDock", "outlineDock", "callStackDock", "breakpointsDock", "problemsDock",
        "buildDock", "testsDock", "runLogDock", "findInFilesDock", "referencesDock",
        "registersDock", "runOutputsDock", "runProcDock", "runAnalogDock", "runAxesDock",
        "runInputsDock", "runWatchDock", "runCursorsDock", "forcesDock", "disasmDock"}


@pytest.mark.parametrize("run", [True, False])
def test_every_row_is_a_dock_of_the_window_and_in_the_view_menu(make, run):
    w = make(connection=FakeConnection(), start_controller=True) if run else make()
    rows = [s for s in DOCKS if run or not s.run]
    assert sorted(d.objectName() for d in _window_docks(w)) == sorted(s.name for s in rows)
    menu = [a for a in w.view_menu.actions() if not a.isSeparator()]
    toggles = [w.dock_table.dock(s.key).toggleViewAction() for s in rows]
    assert [a for a in menu if a in toggles] == toggles            # each, in the table's order
    for s, act in zip(rows, toggles):
        assert act.text() == s.title and getattr(w, s.attr) is w.dock_table.dock(s.key)
        assert act.shortcut().toString() == s.shortcut
        assert w.dockWidgetArea(w.dock_table.dock(s.key)) == AREA[s.area]
    # the menu's entries show and hide the docks
    find = w.dock_table.dock("find")
    assert find.isHidden()
    find.toggleViewAction().trigger()
    assert not find.isHidden()


def _assert_the_tables_layout(w, qtbot) -> None:
    table = w.dock_table
    for s in table.specs.values():
        dock = table.dock(s.key)
        want = s.shown and (table.run or s.shown_alone)
        assert dock.isHidden() != want, s.name
        assert not dock.isFloating() and w.dockWidgetArea(dock) == AREA[s.area], s.name
    for group in _groups(table.specs.values()).values():
        shown = [table.by_name(n) for n in group if not table.by_name(n).isHidden()]
        tabbed = {d.objectName() for d in w.tabifiedDockWidgets(shown[0])} if shown else set()
        assert tabbed == {d.objectName() for d in shown[1:]}, group
        fronts = [s for s in table.specs.values() if s.name in group and s.front]
        if fronts and len(shown) > 1:
            qtbot.waitUntil(lambda d=table.dock(fronts[0].key): on_screen(d))


def test_reset_layout_gives_the_tables_layout_back(make, qtbot):
    w = make(connection=FakeConnection(), start_controller=True)
    qtbot.waitUntil(lambda: w.run_panels is not None, timeout=10000)
    _assert_the_tables_layout(w, qtbot)
    t = w.dock_table
    # moved, hidden, floated, shown, raised
    w.addDockWidget(Qt.DockWidgetArea.LeftDockWidgetArea, t.dock("outputs"))
    w.addDockWidget(Qt.DockWidgetArea.RightDockWidgetArea, t.dock("problems"))
    t.dock("project").hide()
    t.dock("inputs").setFloating(True)
    t.dock("registers").show()
    t.dock("disasm").show()
    t.dock("axes").raise_()
    w.splitDockWidget(t.dock("outline"), t.dock("breakpoints"), Qt.Orientation.Horizontal)
    qtbot.wait(20)
    w.reset_layout()
    qtbot.wait(20)
    _assert_the_tables_layout(w, qtbot)
    assert w.project_dock.width() >= 230 and w.problems_dock.height() >= 200


def test_without_a_controller_reset_layout_keeps_forces_out_of_the_way(make, qtbot):
    w = make()
    w.dock_table.dock("forces").show()
    w.reset_layout()
    _assert_the_tables_layout(w, qtbot)
    assert w.forces_dock.isHidden()


def test_a_saved_layout_comes_back_by_the_rows_names(qtbot, tmp_path):
    settings = Settings(str(tmp_path / "cfg" / "s.ini"))
    with windows(qtbot, settings, (1360, 860)) as make:
        w = make(connection=FakeConnection(), start_controller=True)
        w.registers_dock.show()
        w.registers_dock.raise_()
        w.project_dock.hide()
        w.addDockWidget(Qt.DockWidgetArea.LeftDockWidgetArea, w.watch_dock)
        w.close()
    with windows(qtbot, Settings(settings.path), None) as make:
        w2 = make(connection=FakeConnection(), start_controller=True)
        assert w2.layout_restored
        assert not w2.registers_dock.isHidden() and w2.project_dock.isHidden()
        assert w2.dockWidgetArea(w2.watch_dock) == Qt.DockWidgetArea.LeftDockWidgetArea
        # shown by the restored layout: its panel comes after the first paint
        qtbot.waitUntil(lambda: "registers" in w2.dock_table.made, timeout=10000)
        assert w2.registers_dock.widget() is w2.workbench.registers


@pytest.mark.parametrize("named", [True, False])
def test_a_layout_saved_without_a_controller_gives_the_run_docks_their_places(
        qtbot, tmp_path, named):
    """A window closed without a controller (``--no-controller``) saved a
    layout with no run docks; the next window, with one, left each run dock
    where Qt's restore put it, alone in the right area, and grew the window
    far taller than its screen (1,475 px on a 1,000 px screen) to hold them.
    Those docks now go to the table's places (tabbed), the Forces with the
    Inputs and shown, as a new window has them; the rest is as saved. (Not
    ``named``: saved before the layout's docks were kept with it, found by
    their names in it.)"""
    settings = Settings(str(tmp_path / "cfg" / "s.ini"))
    with windows(qtbot, settings, (1360, 860)) as make:
        w = make()                                   # no controller: no run docks
        assert "outputs" not in w.dock_table.docks
        w.addDockWidget(Qt.DockWidgetArea.LeftDockWidgetArea, w.problems_dock)   # the user's
        w.close()
    if not named:
        settings.qs.remove("window/docks")
        settings.sync()
    with windows(qtbot, Settings(settings.path), None) as make:
        w2 = make(connection=FakeConnection(), start_controller=True)
        assert w2.layout_restored
        assert w2.dockWidgetArea(w2.problems_dock) == Qt.DockWidgetArea.LeftDockWidgetArea
        t = w2.dock_table
        for s in t.specs.values():
            if (s.run or s.key == "forces") and s.key != "log":
                assert w2.dockWidgetArea(t.dock(s.key)) == AREA[s.area], s.name
        # the run log goes with the Problems, where the user put them
        assert t.dock("log") in w2.tabifiedDockWidgets(w2.problems_dock)
        assert {d.objectName() for d in w2.tabifiedDockWidgets(t.dock("outputs"))} == \
            {"runProcDock", "runAnalogDock", "runAxesDock"}
        assert {d.objectName() for d in w2.tabifiedDockWidgets(t.dock("inputs"))} == \
            {"runWatchDock", "runCursorsDock", "forcesDock"}
        assert not w2.forces_dock.isHidden()
        # as tall as a new window's layout needs, not the sum of eight docks
        assert w2.minimumSizeHint().height() < 900, w2.minimumSizeHint()
        qtbot.waitUntil(lambda: on_screen(w2.inputs_dock) and on_screen(w2.outputs_dock))


def test_a_layout_saved_with_a_controller_opened_without_one_hides_the_forces(qtbot, tmp_path):
    """The other way round: a window without a controller (nothing can be
    forced) restoring a layout saved with one keeps the Forces dock hidden,
    as a new window without one has it, not shown and empty."""
    settings = Settings(str(tmp_path / "cfg" / "s.ini"))
    with windows(qtbot, settings, (1360, 860)) as make:
        w = make(connection=FakeConnection(), start_controller=True)
        assert not w.forces_dock.isHidden()
        w.close()
    with windows(qtbot, Settings(settings.path), None) as make:
        w2 = make()
        assert w2.layout_restored and w2.forces_dock.isHidden()


def test_a_saved_layout_that_cannot_fit_on_the_screen_gives_way_to_the_default(
        qtbot, tmp_path, monkeypatch):
    """A layout saved grown (before the rule above: the run docks each alone,
    taller together than the screen once their panels are in them; 1,391 px
    on a 1,000 px screen) gives way to the default layout once the panels are
    made, and the status bar says so: the window fits on its screen again."""
    from PySide6.QtCore import QRect
    from PySide6.QtGui import QScreen
    settings = Settings(str(tmp_path / "cfg" / "s.ini"))
    with windows(qtbot, settings, (1360, 860)) as make:
        w = make(connection=FakeConnection(), start_controller=True)
        for key in ("outputs", "proc", "analog", "axes", "inputs", "watch", "cursors"):
            w.addDockWidget(Qt.DockWidgetArea.RightDockWidgetArea, w.dock_table.dock(key))
        w.close()
    # a screen as tall as the default layout needs and less than the saved one
    room = QRect(0, 0, 1600, 800)
    monkeypatch.setattr(QScreen, "availableGeometry", lambda self: QRect(room))
    with windows(qtbot, Settings(settings.path), None) as make:
        w2 = make(connection=FakeConnection(), start_controller=True)
        assert w2.layout_restored
        qtbot.waitUntil(lambda: not w2.layout_restored, timeout=10000)
        assert "the default layout is back" in w2.statusBar().currentMessage()
        assert w2.minimumSizeHint().height() <= room.height()
        qtbot.waitUntil(lambda: room.contains(w2.frameGeometry()), timeout=3000)
        assert {d.objectName() for d in w2.tabifiedDockWidgets(w2.dock_table.dock("inputs"))} \
            == {"runWatchDock", "runCursorsDock", "forcesDock"}


def test_reset_layout_fits_a_grown_window_on_its_screen(make, qtbot):
    """A window a layout grew taller than its screen (see above) comes back on
    the screen with Reset Layout."""
    w = make(connection=FakeConnection(), start_controller=True)
    room = w.screen().availableGeometry()
    t = w.dock_table
    for key in ("proc", "analog", "axes", "watch", "cursors"):  # each alone: stacked
        w.addDockWidget(Qt.DockWidgetArea.RightDockWidgetArea, t.dock(key))
    w.resize(w.width(), room.height() + 400)
    qtbot.waitUntil(lambda: w.frameGeometry().height() > room.height())
    w.reset_layout()
    qtbot.waitUntil(lambda: room.contains(w.frameGeometry()), timeout=3000)


# ------------------------------------------------------------ adding a dock
def notes_panel(win, key):
    """A dock's panel, as a part's module gives it (the row below names it)."""
    made.append(key)
    return QLabel("notes")


made: list = []


def test_a_dock_is_added_by_one_row(make, qtbot, monkeypatch):
    row = DockSpec("notes", "notesDock", "Notes", docks.BOTTOM,
                   f"{__name__}:notes_panel", place="tab:problemsDock", shown=False)
    monkeypatch.setattr(docks, "DOCKS", DOCKS + (row,))
    made.clear()
    w = make()
    act = w.notes_dock.toggleViewAction()
    assert act in w.view_menu.actions() and w.notes_dock.isHidden()
    assert made == [] and w.notes_dock.widget() is None      # made when first shown
    qtbot.waitUntil(lambda: w._painted)
    act.trigger()
    w.notes_dock.raise_()
    qtbot.waitUntil(lambda: made == ["notes"])
    assert w.notes_dock.widget().text() == "notes"
    assert w.notes_dock in w.tabifiedDockWidgets(w.problems_dock)
    w.reset_layout()
    assert w.notes_dock.isHidden()
