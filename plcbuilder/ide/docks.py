"""The main window's docks: where they go, their default sizes, the saved layout.

Left: the project; bottom: Problems, Build Output and the run log (tabbed);
right: the plots (tabbed) over inputs and watch (tabbed).
"""

from __future__ import annotations

from typing import Callable, Mapping, Optional

from PySide6.QtCore import Qt, QTimer
from PySide6.QtWidgets import QDockWidget, QWidget


class LazyPanels:
    """The panels of docks that are hidden or tabbed away at start: each is made
    by ``make(key)`` (which wires it and brings it up to date) the first time its
    dock shows or :meth:`get` asks for it, and put in its dock; ``then(key)``
    runs once it is there. Until then neither the panel nor its module is loaded
    (the window's first paint does not wait for them)."""

    def __init__(self, docks: Mapping[str, QDockWidget], make: Callable[[str], QWidget],
                 then: Optional[Callable[[str], None]] = None):
        self.docks = dict(docks)
        self._make, self._then = make, then
        self.made: dict[str, QWidget] = {}
        for key, dock in self.docks.items():
            dock.visibilityChanged.connect(lambda on, k=key: on and self.get(k))

    def get(self, key: str) -> QWidget:
        """The dock's panel, made now if it was not."""
        panel = self.made.get(key)
        if panel is None:
            panel = self.made[key] = self._make(key)
            self.docks[key].setWidget(panel)
            if self._then is not None:
                self._then(key)
        return panel


def build_docks(win) -> None:
    """The project (left), Problems, Build Output and Tests (bottom, tabbed)."""
    win.project_dock = make_dock(win, "Project", "projectDock", win.tree,
                                 Qt.DockWidgetArea.LeftDockWidgetArea)
    win.problems_dock = make_dock(win, "Problems", "problemsDock", win.problems,
                                  Qt.DockWidgetArea.BottomDockWidgetArea)
    win.build_dock = make_dock(win, "Build Output", "buildDock", None,
                               Qt.DockWidgetArea.BottomDockWidgetArea)
    win.build_dock.visibilityChanged.connect(lambda on: on and win.build_panel)
    win.tabifyDockWidget(win.problems_dock, win.build_dock)
    win.tests_dock = make_dock(win, "Tests", "testsDock", None,
                               Qt.DockWidgetArea.BottomDockWidgetArea)
    win.tabifyDockWidget(win.build_dock, win.tests_dock)
    # the panel is made (and the tests read) when their tab first shows, or
    # when they are asked for
    win.tests_dock.visibilityChanged.connect(lambda on: on and win.tests_panel.ensure_loaded())
    win.problems_dock.raise_()
    win.resizeDocks([win.project_dock], [250], Qt.Orientation.Horizontal)
    win.resizeDocks([win.problems_dock], [200], Qt.Orientation.Vertical)


def make_dock(win, title, name, widget, area) -> QDockWidget:
    """A dock of the window (``widget`` None: its panel comes later)."""
    dock = QDockWidget(title, win)
    dock.setObjectName(name)
    if widget is not None:
        dock.setWidget(widget)
    dock.setFeatures(QDockWidget.DockWidgetFeature.DockWidgetClosable |
                     QDockWidget.DockWidgetFeature.DockWidgetMovable |
                     QDockWidget.DockWidgetFeature.DockWidgetFloatable)
    win.addDockWidget(area, dock)
    return dock


#: The run docks (key, title, objectName): made empty before the window shows,
#: filled with the run panels after its first paint (pyqtgraph is not loaded
#: until then).
RUN_DOCKS = (("proc", "Proc / messages", "runProcDock"),
             ("outputs", "Outputs", "runOutputsDock"),
             ("analog", "PWM / DAC / ADC", "runAnalogDock"),
             ("axes", "Axes", "runAxesDock"),
             ("inputs", "Inputs", "runInputsDock"),
             ("watch", "Watch", "runWatchDock"),
             ("log", "Run log", "runLogDock"),
             ("cursors", "Cursors", "runCursorsDock"))


def whole_tab_titles(bar) -> None:
    """A tab bar of docks tabbed together says each dock's whole title: Qt
    elides them ("Ou…", "Disasse…", issue 23.15); it scrolls instead when the
    tabs do not all fit."""
    if bar.elideMode() != Qt.TextElideMode.ElideNone:
        bar.setElideMode(Qt.TextElideMode.ElideNone)
        bar.setUsesScrollButtons(True)


def follow_tab_bars(win) -> None:
    """Whole titles on the window's dock tab bars now, and on those Qt makes
    when docks are tabbed together later (a dock moved, the layout reset or
    restored). Done after the first paint: the window's start does not wait."""
    from PySide6.QtWidgets import QTabBar

    def apply(*_a) -> None:
        for bar in win.findChildren(QTabBar):
            if bar.parent() is win:             # the docks' bars, not a panel's own tabs
                whole_tab_titles(bar)
    apply()
    for dock in win.findChildren(QDockWidget):
        dock.dockLocationChanged.connect(lambda *_a: QTimer.singleShot(0, apply))
        dock.topLevelChanged.connect(lambda *_a: QTimer.singleShot(0, apply))
    win.tab_bars_apply = apply


def on_screen(widget) -> bool:
    """Whether ``widget`` can be seen: visible, and not in a dock whose tab is
    put aside. Qt keeps the docks of a tab group that are not current
    "visible" and moves them out of the window instead (right or bottom edge
    below 0, the rule by which QDockWidget itself says ``visibilityChanged``):
    ``isVisible()`` alone would make them redraw and poll unseen."""
    if not widget.isVisible():
        return False
    dock = dock_of(widget)
    if dock is None or dock.isFloating():
        return True
    g = dock.geometry()
    return g.right() >= 0 and g.bottom() >= 0


def dock_of(widget):
    """The dock ``widget`` is in (None: in none)."""
    w = widget
    while w is not None:
        if isinstance(w, QDockWidget):
            return w
        w = w.parentWidget()
    return None


def empty_run_docks(win) -> dict:
    """The run docks, empty, by key (the run panels fill them later)."""
    out = {}
    for key, title, name in RUN_DOCKS:
        dock = QDockWidget(title, win)
        dock.setObjectName(name)
        dock.setAllowedAreas(Qt.DockWidgetArea.AllDockWidgetAreas)
        out[key] = dock
    return out


def place_run_docks(win, docks: list) -> None:
    """Right: the plots (tabbed) over inputs and watch (tabbed); the run log
    beside Problems and Build Output at the bottom."""
    by_name = {d.objectName(): d for d in docks}
    right = [by_name[n] for n in ("runOutputsDock", "runProcDock", "runAnalogDock",
                                  "runAxesDock") if n in by_name]
    lower = [by_name[n] for n in ("runInputsDock", "runWatchDock", "runCursorsDock")
             if n in by_name]
    log = by_name.get("runLogDock")
    placed = set(right) | set(lower) | ({log} if log else set())
    area = Qt.DockWidgetArea.RightDockWidgetArea
    if right:
        win.addDockWidget(area, right[0])
    if lower:
        if right:
            win.splitDockWidget(right[0], lower[0], Qt.Orientation.Vertical)
        else:
            win.addDockWidget(area, lower[0])
    for d in right[1:]:
        win.tabifyDockWidget(right[0], d)
    for d in lower[1:]:
        win.tabifyDockWidget(lower[0], d)
    if log is not None:
        win.tabifyDockWidget(win.build_dock, log)
    for d in docks:
        if d not in placed:
            win.addDockWidget(area, d)
    for d in (right[:1] + lower[:1]):
        d.raise_()
    win.problems_dock.raise_()
    win.right_docks = right[:1] + lower[:1]


def restore_layout(win) -> None:
    geom, state = win.settings.window_state()
    if geom is not None:
        win.restoreGeometry(geom)
    win.layout_restored = state is not None and win.restoreState(state)


def default_dock_sizes(win) -> None:
    """Sizes for the default layout (they only apply once the window is shown)."""
    w = max(win.width(), 800)
    # the tree shows the procedures' descriptions beside their names: room for
    # "M09  coolant off (mist and flood)" at the default window size
    win.resizeDocks([win.project_dock], [max(230, min(360, int(w * 0.22)))],
                    Qt.Orientation.Horizontal)
    if win.right_docks:
        win.resizeDocks(win.right_docks[:1], [int(w * 0.30)], Qt.Orientation.Horizontal)
        if len(win.right_docks) > 1:
            h = max(win.height() - 200, 400)
            win.resizeDocks(win.right_docks, [int(h * 0.62), int(h * 0.38)],
                             Qt.Orientation.Vertical)
    # about ten rows of Problems, Build Output or the run log
    win.resizeDocks([win.problems_dock], [max(230, int(win.height() * 0.3))],
                     Qt.Orientation.Vertical)
    if getattr(win, "callstack_dock", None) is not None:     # the tree keeps most of the left
        h = max(win.height() - 260, 400)
        win.resizeDocks([win.project_dock, win.callstack_dock], [int(h * 0.6), int(h * 0.4)],
                         Qt.Orientation.Vertical)


def reset_layout(win) -> None:
    win.restoreState(win.default_state)
    apply = getattr(win, "tab_bars_apply", None)
    if apply is not None:
        QTimer.singleShot(0, apply)
    for dock in win.findChildren(QDockWidget):
        if dock.parent() is win:
            dock.show()
    win.problems_dock.raise_()
    default_dock_sizes(win)
    QTimer.singleShot(0, lambda: scroll_editors_home(win))


def scroll_editors_home(win) -> None:
    """Editors scrolled sideways while they were narrow start at the left
    again, the caret kept in view."""
    for ed in win.editors():
        if ed.xOffset():
            ed.setXOffset(0)
            ed.scrollCaret()
