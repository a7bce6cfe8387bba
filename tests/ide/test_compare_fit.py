"""The trace comparison view keeps everything readable (issue 23, the walk's
leftovers): the key saying which line is which trace never covers a lane, the
bar above the plots says what is compared without being cut (or, where the
dock is too narrow, elides it with the whole text in its tooltip), and the
first tab of the plots' dock shows its whole label, at the window's default
size and in a narrow dock. Driven through the real menu action and widgets."""

from __future__ import annotations

import pytest
from PySide6.QtCore import QRectF, Qt
from PySide6.QtWidgets import QApplication, QTabBar

from plcbuilder.ide import trace_actions
from plcbuilder.ide.settings import Settings
from tests.ide._workbench import RecordingConnection, windows
from tests.ide.test_docks_fit import prompts_off  # noqa: F401 - fixture
from tests.ide.test_main_window import make_project
from tests.ide.test_trace_compare import _drawn, files  # noqa: F401 - fixture


def _settle(qtbot, ms: int = 60):
    for _ in range(5):
        QApplication.processEvents()
    qtbot.wait(ms)


@pytest.fixture(params=["default", "narrow"])
def compared(request, qtbot, tmp_path, prompts_off, files):  # noqa: F811
    """A window at its default size with the plots' dock at its default width,
    or made as narrow as it goes; the before trace shown, the after trace compared."""
    conn = RecordingConnection()
    with windows(qtbot, Settings(str(tmp_path / "cfg" / "s.ini")), None) as make:
        w = make(connection=conn, start_controller=True)
        qtbot.waitUntil(lambda: w.run_panels is not None, timeout=10000)
        w.open_project(make_project(tmp_path / "proj"))
        outputs = w.run_docks["outputs"]
        if request.param == "narrow":
            w.resizeDocks([outputs], [200], Qt.Orientation.Horizontal)
        _settle(qtbot)
        a, b = files
        assert trace_actions.open_trace(w, str(a))
        trace_actions.compare_trace(w, str(b))
        panels = _drawn(qtbot, w)
        outputs.show()
        outputs.raise_()
        _settle(qtbot, 200)
        yield w, panels


def _scene_rect(item) -> QRectF:
    return item.mapRectToScene(item.boundingRect())


def test_the_key_covers_no_lane(compared, qtbot):
    w, panels = compared
    for panel in (panels.lanes, panels.proc):
        if panel is panels.proc:
            w.run_docks["proc"].show()
            w.run_docks["proc"].raise_()
            _settle(qtbot, 200)
        key = panel.other_key
        assert key is not None and key.isVisible() and key.items
        qtbot.waitUntil(lambda: key.width() > 20, timeout=3000)
        view = _scene_rect(panel.plot.vb)                 # where the lanes (the curves) are
        rect = _scene_rect(key)
        assert not rect.intersects(view), (panel, rect, view)
        # and the key is inside the plot, not cut at its edge
        plot = _scene_rect(panel.plot)
        assert plot.contains(rect), (rect, plot)
    # each lane's band in particular
    lanes = panels.lanes
    vb = lanes.plot.vb
    key = _scene_rect(lanes.other_key)
    for lane, y in lanes._lane_y.items():
        band = vb.mapRectToScene(QRectF(vb.viewRange()[0][0], y - 0.2,
                                        vb.viewRange()[0][1] - vb.viewRange()[0][0], 1.4))
        assert not key.intersects(band), lane


def test_the_banner_says_what_is_compared_without_cutting_it(compared, qtbot):
    w, panels = compared
    label = panels.banners[0]
    assert label.isVisible()
    text = label.plain_text()
    assert "after.plctrace" in text and "first difference at 0.140 s" in text
    fits = label.fontMetrics().horizontalAdvance(text) <= label.contentsRect().width()
    if w.run_docks["outputs"].width() >= 340:          # the default width: the whole text
        assert fits, (text, label.contentsRect().width())
    else:                                              # narrow: elided, the whole in the tip
        tip = label.toolTip()
        assert fits or (label.is_elided() and "after.plctrace (dashed)" in tip
                        and "first difference at 0.140 s" in tip)
    # the links keep their room beside or under it
    for link in (panels.banner_links[0], panels.compare_links[0]):
        assert link.isVisible() and link.width() >= link.sizeHint().width()
        assert not link.geometry().intersects(label.geometry())
    # the whole sentence (which trace is solid) is in the tooltip
    assert "trace before.plctrace (solid)" in label.toolTip()


def test_the_first_tab_of_the_plots_dock_shows_its_whole_label(compared, qtbot):
    w, _panels = compared
    bars = [b for b in w.findChildren(QTabBar) if b.isVisible()
            and "Outputs" in [b.tabText(i) for i in range(b.count())]]
    assert bars
    for bar in bars:
        i = [bar.tabText(k) for k in range(bar.count())].index("Outputs")
        rect = bar.tabRect(i)
        need = bar.fontMetrics().horizontalAdvance(bar.tabText(i))
        assert rect.width() >= need
        assert bar.rect().contains(rect), (rect, bar.rect())
        # and no scroll button lies over it
        from PySide6.QtWidgets import QToolButton
        for button in bar.findChildren(QToolButton):
            if button.isVisible():
                assert not button.geometry().intersects(rect), (button.geometry(), rect)


def _tab_bars(w):
    return [b for b in w.findChildren(QTabBar) if b.parent() is w and b.isVisible()
            and b.count() > 1]


def test_no_dock_tab_is_cut_in_a_narrow_dock(qtbot, tmp_path, prompts_off):
    """The screenshot's narrow left dock read "kpoints | Outline": its tab bar
    scrolled to the current tab and cut the one before it. A tab bar whose
    whole titles do not fit shortens them ("Call St…") with the whole title in
    the tab's tooltip; no tab lies partly outside the bar or under its buttons;
    where they fit (the default width) the titles are whole."""
    from PySide6.QtWidgets import QToolButton
    conn = RecordingConnection()
    with windows(qtbot, Settings(str(tmp_path / "cfg" / "s.ini")), None) as make:
        w = make(connection=conn, start_controller=True)
        qtbot.waitUntil(lambda: w.run_panels is not None, timeout=10000)
        w.open_project(make_project(tmp_path / "proj"))
        w.outline_dock.show()
        w.outline_dock.raise_()
        _settle(qtbot, 100)
        bar = next(b for b in _tab_bars(w) if "Outline" in
                   [b.tabText(i) for i in range(b.count())])
        for i in range(bar.count()):                    # the default width: whole titles
            need = bar.fontMetrics().horizontalAdvance(bar.tabText(i))
            assert bar.tabRect(i).width() >= need
            assert bar.rect().contains(bar.tabRect(i))
        w.resizeDocks([w.project_dock], [160], Qt.Orientation.Horizontal)
        _settle(qtbot, 100)
        assert bar.width() < sum(bar.tabSizeHint(i).width() for i in range(bar.count()))
        buttons = [b.geometry() for b in bar.findChildren(QToolButton) if b.isVisible()]
        for i in range(bar.count()):
            rect, title = bar.tabRect(i), bar.tabText(i)
            assert bar.rect().contains(rect), (title, rect, bar.rect())
            assert not any(b.intersects(rect) for b in buttons), (title, rect, buttons)
            if rect.width() < bar.fontMetrics().horizontalAdvance(title):
                assert bar.elideMode() == Qt.TextElideMode.ElideRight
                assert bar.tabToolTip(i) == title
        # wide again: whole titles again
        w.resizeDocks([w.project_dock], [400], Qt.Orientation.Horizontal)
        _settle(qtbot, 100)
        for i in range(bar.count()):
            need = bar.fontMetrics().horizontalAdvance(bar.tabText(i))
            assert bar.tabRect(i).width() >= need and bar.rect().contains(bar.tabRect(i))


def test_the_disassembly_column_titles_are_whole(qtbot):
    """The walk's Disassembly read "Instructio": its columns were sized for the
    code's monospace text, not for their titles."""
    from plcbuilder import api
    from plcbuilder.ide.panels.disasm_view import DisasmView
    view = DisasmView()
    qtbot.addWidget(view)
    view.resize(400, 300)
    view.show()
    result = api.compile_source("main() { gvarset(7000, 1); exit(99); };\n", "/x/M01.plc",
                                api.CompileOptions(kind=api.kind_of("M01.plc")))
    assert view.show_result("/x/M01.plc", result) > 0
    header = view.tree.header()
    fm = header.fontMetrics()
    for col in range(view.tree.columnCount() - 1):          # the last one stretches
        title = view.tree.headerItem().text(col)
        assert header.sectionSize(col) >= fm.horizontalAdvance(title) + 12, title
