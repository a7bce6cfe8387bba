"""The Watch dock on a TG Motion project: the Watch table, the registers and
the oscilloscope are sections of splitters (not three tables squeezed into one
column), so the user drags each to the room it needs; the sizes are kept in
the IDE's settings and come back in the next window."""

from __future__ import annotations

from PySide6.QtCore import QEvent, QPoint, QPointF, Qt
from PySide6.QtGui import QMouseEvent
from PySide6.QtWidgets import QApplication, QSplitter

from plcbuilder import api
from plcbuilder.ide.settings import Settings
from tests.ide._workbench import RecordingConnection, windows
from tests.ide.test_docks_fit import prompts_off  # noqa: F401 - fixture

REPORT = {"target_profile": "tgmotion",
          "registers": {"TGM_Data": {str(i): i + 1 for i in range(12)}},
          "calls": {"Program_01": 1170, "Program_02": 23381, "Program_03": 23381,
                    "Program_04": 46762, "Program_05": 233810, "Program_Ini": 2},
          "oscilloscope": {"samples": 40, "signals": ["in 9", "plc.n4"],
                           "last": [[100 * k, k, 0, k] for k in range(12)]}}


def _settle(qtbot):
    for _ in range(5):
        QApplication.processEvents()
    qtbot.wait(30)


def _drag(qtbot, splitter: QSplitter, index: int, dy: int) -> None:
    """Drag the handle above section ``index`` by ``dy`` pixels, as a user does."""
    handle = splitter.handle(index)
    centre = handle.rect().center()
    left, none = Qt.MouseButton.LeftButton, Qt.MouseButton.NoButton

    def send(kind, at, button, buttons):
        QApplication.sendEvent(handle, QMouseEvent(kind, QPointF(at), QPointF(handle.mapToGlobal(at)),
                                                   button, buttons, Qt.KeyboardModifier.NoModifier))
    send(QEvent.Type.MouseButtonPress, centre, left, left)
    for step in (dy // 2, dy):
        send(QEvent.Type.MouseMove, centre + QPoint(0, step), none, left)
    send(QEvent.Type.MouseButtonRelease, centre + QPoint(0, dy), left, none)
    qtbot.wait(10)


def _tgmotion_window(make, tmp_path, qtbot, floating=True):
    w = make(connection=RecordingConnection(), start_controller=True)
    qtbot.waitUntil(lambda: w.run_panels is not None, timeout=10000)
    root = tmp_path / "tg"
    if not root.exists():
        api.create_project(root, target="tgmotion")
    assert w.open_project(root, offer_recovery=False)
    dock = w.run_docks["watch"]
    dock.show()
    dock.raise_()
    if floating:
        dock.setFloating(True)                # a tall dock, as a user makes it
        dock.resize(500, 700)
    panels = w.run_panels
    panels.watch.set_variables({"Program_04": {f"v{i}": i for i in range(20)}}, "Program_04")
    panels._on_registers(REPORT)             # what the controller's report does
    _settle(qtbot)
    return w, panels


def test_the_watch_registers_and_oscilloscope_share_the_dock_by_splitters(
        qtbot, tmp_path, prompts_off):  # noqa: F811
    settings = Settings(str(tmp_path / "cfg" / "settings.ini"))
    with windows(qtbot, settings, (1200, 800)) as make:
        w, panels = _tgmotion_window(make, tmp_path, qtbot)
        watch, regs = panels.watch, panels.registers
        outer, inner = watch.split, regs.split
        assert isinstance(outer, QSplitter) and isinstance(inner, QSplitter)
        assert outer.indexOf(regs) == 1 and inner.indexOf(regs.scope_part) == 1
        assert regs.isVisible() and regs.scope.isVisible()
        assert outer.handle(1).isVisible() and inner.handle(1).isVisible()
        row = watch.table.verticalHeader().defaultSectionSize()
        _calls_whole(regs)
        # give the oscilloscope room: drag the handle above it up, then the
        # registers' handle down; each table shows what the user asked for
        before = inner.sizes()
        _drag(qtbot, inner, 1, -60)
        assert inner.sizes()[1] > before[1] + 30
        before = outer.sizes()
        _drag(qtbot, outer, 1, -80)
        assert outer.sizes()[1] > before[1] + 40
        assert regs.scope.viewport().height() >= 3 * row
        _calls_whole(regs)
        assert settings.splitter_sizes("watch") == outer.sizes()
        # (the registers section grew with the outer drag: its split kept its share)
        assert abs(_share(settings.splitter_sizes("registers")) - _share(inner.sizes())) < 0.03
        shares = (_share(outer.sizes()), _share(inner.sizes()))
    # the next window (same settings) gives the sections the same room
    with windows(qtbot, Settings(str(tmp_path / "cfg" / "settings.ini")), (1200, 800)) as make:
        w, panels = _tgmotion_window(make, tmp_path, qtbot)
        qtbot.waitUntil(lambda: abs(_share(panels.watch.split.sizes()) - shares[0]) < 0.03 and
                        abs(_share(panels.registers.split.sizes()) - shares[1]) < 0.03,
                        timeout=5000)


def test_reset_layout_gives_the_sections_their_first_sizes(qtbot, tmp_path, prompts_off):  # noqa: F811
    """View › Reset Layout puts the splitters back as they first came and
    forgets the sizes the user left (the next window starts from them too)."""
    settings = Settings(str(tmp_path / "cfg" / "settings.ini"))
    with windows(qtbot, settings, (1200, 800)) as make:
        w, panels = _tgmotion_window(make, tmp_path, qtbot)
        outer = panels.watch.split
        first = outer.sizes()
        _drag(qtbot, outer, 1, -80)
        assert outer.sizes() != first and settings.splitter_sizes("watch") == outer.sizes()
        w.reset_layout()
        _settle(qtbot)
        assert settings.splitter_sizes("watch") is None
        assert settings.splitter_sizes("registers") is None
        if not w.run_docks["watch"].isFloating():       # docked again: its height is the layout's
            assert abs(_share(outer.sizes()) - _share(first)) < 0.05
        w.run_docks["watch"].show()
        _settle(qtbot)
        assert abs(_share(outer.sizes()) - _share(first)) < 0.05


def _calls_whole(regs) -> None:
    """The calls line (wrapped) has the height its text needs, under the table."""
    calls = regs.calls
    assert calls.height() >= calls.heightForWidth(calls.width()) > calls.fontMetrics().height()
    assert regs.table.geometry().bottom() < calls.geometry().top()


def _share(sizes) -> float:
    """The first section's share of a splitter."""
    return sizes[0] / max(1, sum(sizes))


def test_on_mycnc_the_watch_has_the_dock_alone(qtbot, tmp_path, prompts_off):  # noqa: F811
    settings = Settings(str(tmp_path / "cfg" / "settings.ini"))
    with windows(qtbot, settings, (1200, 800)) as make:
        w = make(connection=RecordingConnection(), start_controller=True)
        qtbot.waitUntil(lambda: w.run_panels is not None, timeout=10000)
        w.run_docks["watch"].show()
        _settle(qtbot)
        watch = w.run_panels.watch
        assert not w.run_panels.registers.isVisible() and not watch.split.handle(1).isVisible()
        assert watch.table.height() > watch.height() - watch.bar.height() - 40


def test_in_a_short_docked_watch_nothing_is_drawn_over(qtbot, tmp_path, prompts_off):  # noqa: F811
    """Docked at its default height every section is at its least: the wrapped
    calls line still has its lines, under the registers' table (not under it)."""
    with windows(qtbot, Settings(str(tmp_path / "cfg" / "settings.ini")), (1200, 800)) as make:
        _w, panels = _tgmotion_window(make, tmp_path, qtbot, floating=False)
        _calls_whole(panels.registers)
