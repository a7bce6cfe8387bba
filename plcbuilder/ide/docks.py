"""The main window's docks, one table: :data:`DOCKS`, a :class:`DockSpec` a dock.

A row says the dock's object name (saved layouts find the dock by it: never
rename one), its title, where the default layout puts it, whether it shows
there, and the function of its part that makes its panel. The window builds
every dock from the table (:func:`build`): its View menu entry, Reset Layout
(the table's layout again) and the saved layout all follow from it. Adding a
dock is one row here and a panel factory in its part's module.

Default layout. Left: the project over Call Stack, Breakpoints and Outline
(tabbed, the Outline in front); bottom: Problems, Build Output, Tests, the run log, Find in Files,
References and Registers (tabbed); right: the plots (tabbed) over Inputs,
Watch, Cursors, Forces and Disassembly (tabbed).

A panel that is not in the first frame is made when its dock first shows (or
the panel is asked for), never before the window's first paint: its module is
not even imported until then (:class:`DockTable`).
"""

from __future__ import annotations

import importlib
import time
from dataclasses import dataclass
from typing import Callable, Iterable, Optional

from PySide6.QtCore import Qt, QTimer
from PySide6.QtWidgets import QDockWidget, QWidget

LEFT, RIGHT, BOTTOM = "left", "right", "bottom"
_AREAS = {LEFT: Qt.DockWidgetArea.LeftDockWidgetArea,
          RIGHT: Qt.DockWidgetArea.RightDockWidgetArea,
          BOTTOM: Qt.DockWidgetArea.BottomDockWidgetArea}


@dataclass(frozen=True)
class DockSpec:
    """One dock of the main window."""

    key: str            #: the part's name for it ("registers": ``win.dock_table.panel(key)``)
    name: str           #: objectName: saved layouts restore by it (keep it stable)
    title: str
    area: str           #: LEFT, RIGHT or BOTTOM: where the default layout puts it
    make: str           #: "module:function": ``function(win, key) -> QWidget`` makes its panel
    place: str = ""     #: "" (added to the area), "below:NAME" (split under), "tab:NAME" (tabbed with)
    shown: bool = True  #: shown in the default layout
    front: bool = False  #: its tab is the current one of its group in the default layout
    eager: bool = False  #: its panel is in the first frame (made with the window)
    run: bool = False   #: a run dock: exists only with a controller connection
    then: str = ""      #: "module:function": ``function(win, key)`` once the panel is in its dock
    shortcut: str = ""  #: the View menu entry's shortcut
    shown_alone: bool = True  #: shown without a controller too (when ``shown``)

    @property
    def attr(self) -> str:
        """The window's attribute for the dock (``win.registers_dock``)."""
        return f"{self.key}_dock"

    def shown_with(self, run: bool) -> bool:
        """Whether the default layout shows it, with a controller (``run``) or without."""
        return self.shown and (run or self.shown_alone)


_RUN = "plcbuilder.ide.main_window:run_dock_panel"
_WB = "plcbuilder.ide.workbench:dock_panel"
_DBG = "plcbuilder.ide.debug:dock_panel"

#: Every dock of the window, in View menu order (within a tab group, the
#: default layout's tab order).
DOCKS: tuple[DockSpec, ...] = (
    DockSpec("project", "projectDock", "Project", LEFT, "plcbuilder.ide.project_tree:dock_panel",
             eager=True, shortcut="Alt+1"),
    DockSpec("callstack", "callStackDock", "Call Stack", LEFT, _DBG, place="below:projectDock"),
    DockSpec("breakpoints", "breakpointsDock", "Breakpoints", LEFT, _DBG,
             place="tab:callStackDock"),
    DockSpec("outline", "outlineDock", "Outline", LEFT, _WB, place="tab:callStackDock",
             eager=True, front=True, shortcut="Alt+7"),
    DockSpec("problems", "problemsDock", "Problems", BOTTOM, "plcbuilder.ide.problems:dock_panel",
             eager=True, front=True, shortcut="Alt+6"),
    DockSpec("build", "buildDock", "Build Output", BOTTOM, "plcbuilder.ide.build_panel:dock_panel",
             place="tab:problemsDock"),
    DockSpec("tests", "testsDock", "Tests", BOTTOM, "plcbuilder.ide.main_window:tests_dock_panel",
             place="tab:problemsDock", then="plcbuilder.ide.main_window:tests_dock_wire"),
    DockSpec("log", "runLogDock", "Run log", BOTTOM, _RUN, place="tab:problemsDock", run=True),
    DockSpec("find", "findInFilesDock", "Find in Files", BOTTOM, _WB, place="tab:problemsDock",
             shown=False),
    DockSpec("references", "referencesDock", "References", BOTTOM, _WB, place="tab:problemsDock",
             shown=False),
    DockSpec("registers", "registersDock", "Registers", BOTTOM, _WB, place="tab:problemsDock",
             shown=False),
    DockSpec("outputs", "runOutputsDock", "Outputs", RIGHT, _RUN, run=True, front=True),
    DockSpec("proc", "runProcDock", "Proc / messages", RIGHT, _RUN, place="tab:runOutputsDock",
             run=True),
    DockSpec("analog", "runAnalogDock", "PWM / DAC / ADC", RIGHT, _RUN, place="tab:runOutputsDock",
             run=True),
    DockSpec("axes", "runAxesDock", "Axes", RIGHT, _RUN, place="tab:runOutputsDock", run=True),
    DockSpec("inputs", "runInputsDock", "Inputs", RIGHT, _RUN, place="below:runOutputsDock",
             run=True, front=True),
    DockSpec("watch", "runWatchDock", "Watch", RIGHT, _RUN, place="tab:runInputsDock", run=True),
    DockSpec("cursors", "runCursorsDock", "Cursors", RIGHT, _RUN, place="tab:runInputsDock",
             run=True),
    # nothing can be forced without a controller: then the editor gets the room
    # (View › Forces still shows it)
    DockSpec("forces", "forcesDock", "Forces", RIGHT, _DBG, place="tab:runInputsDock",
             shown_alone=False),
    DockSpec("disasm", "disasmDock", "Disassembly", RIGHT, _WB, place="tab:runInputsDock",
             shown=False, then="plcbuilder.ide.workbench:dock_panel_made"),
)

#: How long the docks shown before the first paint may take to get their
#: panels in one turn of the event loop (after the paint): the panels of a turn
#: lay out and paint together, once, and the window answers between turns.
TURN_MS = 25

#: The run docks (key, title, objectName), as the run panels know them.
RUN_DOCKS = tuple((s.key, s.title, s.name) for s in DOCKS if s.run)


def _resolve(path: str) -> Callable:
    module, _, name = path.partition(":")
    return getattr(importlib.import_module(module), name)


class DockTable:
    """The window's docks, built from :data:`DOCKS` (those it has: no run
    docks without a controller). A dock's panel is made by its row's
    ``make`` the first time the dock shows or :meth:`panel` asks for it, and
    put in the dock; until the window's first paint (:meth:`release`) a dock
    that shows waits for it."""

    def __init__(self, win, specs: Iterable[DockSpec]):
        self.win = win
        self.specs: dict[str, DockSpec] = {s.key: s for s in specs}
        self.docks: dict[str, QDockWidget] = {}
        self.made: dict[str, QWidget] = {}
        self.held = True                     # until the first paint
        self.run = False                     # the run docks are there
        self._due: list[str] = []            # docks shown while held

    def dock(self, key: str) -> QDockWidget:
        return self.docks[key]

    def by_name(self, name: str) -> Optional[QDockWidget]:
        """The dock of an object name (None: the window has none)."""
        return next((self.docks[s.key] for s in self.specs.values()
                     if s.name == name and s.key in self.docks), None)

    def panel(self, key: str) -> QWidget:
        """The dock's panel, made now if it was not."""
        panel = self.made.get(key)
        if panel is None:
            spec = self.specs[key]
            panel = _resolve(spec.make)(self.win, key)
            self.made[key] = panel
            dock = self.docks[key]
            if dock.widget() is not panel:
                dock.setWidget(panel)
            if spec.then:
                _resolve(spec.then)(self.win, key)
            self.adopt()
            guard = getattr(self.win, "wheel_guard", None)
            if guard is not None:            # (a dock shown before its panel was made)
                guard.guard(dock)
        return panel

    def adopt(self) -> None:
        """Panels a part put in their docks itself (the run panels fill all
        theirs at once) count as made."""
        for key, dock in self.docks.items():
            if key not in self.made and dock.widget() is not None:
                self.made[key] = dock.widget()

    def view(self, keys: Iterable[str]) -> "PanelsView":
        return PanelsView(self, tuple(keys))

    def release(self, then: Optional[Callable[[], None]] = None) -> None:
        """The window painted: the docks that showed meanwhile get their panel,
        as many a turn of the event loop as fit in :data:`TURN_MS` (the
        window answers between turns; each turn's panels paint together);
        ``then`` on the turn after the last (the panels redraw first)."""
        if not self.held:
            if then is not None:
                then()
            return
        self.held = False
        due, self._due = self._due, []
        self._make_due(due, then)

    def _make_due(self, due: list, then) -> None:
        if getattr(self.win, "_closing", False):
            return
        began, made = time.perf_counter(), False
        while due:
            if made and time.perf_counter() - began > TURN_MS / 1000:
                QTimer.singleShot(0, lambda: self._make_due(due, then))
                return
            key = due.pop(0)
            if key not in self.made and on_screen(self.docks[key]):
                self.panel(key)
                made = True
        if then is not None:
            if made:
                QTimer.singleShot(0, then)   # (after their paint)
            else:
                then()

    def _shown(self, key: str) -> None:
        if key in self.made:
            return
        if self.held and not getattr(self.win, "_painted", True):
            if key not in self._due:
                self._due.append(key)
        else:
            self.panel(key)


class PanelsView:
    """A part's docks of the table: ``get(key)`` their panel (made if need
    be), ``made`` those made so far."""

    def __init__(self, table: DockTable, keys: tuple):
        self.table, self.keys = table, keys

    def get(self, key: str) -> QWidget:
        return self.table.panel(key)

    @property
    def made(self) -> dict:
        return {k: v for k, v in self.table.made.items() if k in self.keys}


def build(win, *, run: bool) -> DockTable:
    """Make the window's docks from :data:`DOCKS` (the run docks only when
    ``run``: a controller connection), each as ``win.<key>_dock``; the panels
    of the first frame now, the others when their dock first shows. Places
    them as the default layout says and fills the View menu."""
    table = DockTable(win, (s for s in DOCKS if run or not s.run))
    for spec in table.specs.values():
        dock = QDockWidget(spec.title, win)
        dock.setObjectName(spec.name)
        dock.setFeatures(QDockWidget.DockWidgetFeature.DockWidgetClosable |
                         QDockWidget.DockWidgetFeature.DockWidgetMovable |
                         QDockWidget.DockWidgetFeature.DockWidgetFloatable)
        dock.setAllowedAreas(Qt.DockWidgetArea.AllDockWidgetAreas)
        table.docks[spec.key] = dock
        setattr(win, spec.attr, dock)
        if spec.eager:
            table.panel(spec.key)
        else:
            dock.visibilityChanged.connect(lambda on, k=spec.key: on and table._shown(k))
    win.dock_table = table
    table.run = run
    place(win, table)
    return table


def place(win, table: DockTable, specs: Optional[Iterable[DockSpec]] = None) -> None:
    """The default layout of the table's docks (``specs``: of these only): each
    added to its area, split under or tabbed with the dock its row names (added
    to its area when the window has no such dock); those not shown hidden; the
    front tabs raised."""
    placing = list(table.specs.values() if specs is None else specs)
    # the splits first: Qt tabs a dock split from one already in a tab group
    # into that group instead
    for spec in sorted(placing, key=lambda s: s.place.startswith("tab:")):
        _put(win, table, spec)
    for spec in placing:
        if not spec.shown_with(table.run):
            table.docks[spec.key].hide()
    for spec in placing:
        if spec.front:
            table.docks[spec.key].raise_()
    if specs is not None:
        return
    win.right_docks = [table.docks[s.key] for s in table.specs.values()
                       if s.front and s.area == RIGHT]
    # sizes until the window shows (default_dock_sizes then): the tree is
    # filled before, and keeps the scroll position it gets at this size
    default_dock_sizes(win)


def whole_tab_titles(bar) -> None:
    """A tab bar of docks tabbed together says each dock's whole title where
    they fit (Qt elided them: "Ou…", "Disasse…", issue 23.15), and shortens them
    evenly where they do not (scrolled, the tab before the current one was cut
    at the bar's edge): tab_titles.fit_titles."""
    from plcbuilder.ide.tab_titles import fit_titles
    fit_titles(bar)


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


def _put(win, table: DockTable, spec: DockSpec) -> None:
    """Dock ``spec``'s dock at its default place (see :func:`place`)."""
    dock = table.docks[spec.key]
    how, _, other_name = spec.place.partition(":")
    other = table.by_name(other_name) if other_name else None
    win.addDockWidget(_AREAS[spec.area], dock)
    if other is not None and how == "below":
        win.splitDockWidget(other, dock, Qt.Orientation.Vertical)
    elif other is not None:
        win.tabifyDockWidget(other, dock)


def names(win) -> list[str]:
    """The object names of the window's docks (saved with its layout)."""
    return [d.objectName() for d in win.dock_table.docks.values()]


def restore_layout(win) -> None:
    """The layout the window was last closed with. Docks that layout did not
    have (the run docks of a window that had no controller) go to their
    default places: left where Qt's restore puts them, each stood alone in
    its area, and the window grew taller than the screen to hold them."""
    geom, state = win.settings.window_state()
    if geom is not None:
        win.restoreGeometry(geom)
        fit_on_screen(win)
    win.layout_restored = state is not None and win.restoreState(state)
    if win.layout_restored:
        had = _state_docks(win, state)
        table = win.dock_table
        if not table.run and any(s.run and s.name in had for s in DOCKS):
            # saved with a controller, opened without: a dock shown by default
            # only with one (the Forces: nothing can be forced) is hidden, as
            # a new window without one has it
            for spec in table.specs.values():
                if spec.shown_with(True) and not spec.shown_with(False):
                    table.docks[spec.key].hide()
        new = [s for s in table.specs.values() if s.name not in had]
        if new:
            place(win, table, new)
            # a dock whose default place is beside one of those (the Forces,
            # tabbed with the Inputs) joins it; one shown by default only with
            # a controller (the Forces again) was hidden for want of one: shown
            added = {s.name for s in new}
            for spec in table.specs.values():
                if spec not in new and spec.place.partition(":")[2] in added:
                    _put(win, table, spec)
                    if table.run and spec.shown_with(True) and not spec.shown_with(False):
                        table.docks[spec.key].show()
            for spec in new:
                if spec.front:
                    table.docks[spec.key].raise_()


def _state_docks(win, state) -> set:
    """The docks a saved layout has, by name: as saved with it, or for a
    layout saved without the list (before it was kept), the names of the
    table found in it (Qt keeps each dock's name in the state, as UTF-16)."""
    had = win.settings.window_docks()
    if had is not None:
        return had
    data = bytes(state)
    return {s.name for s in win.dock_table.specs.values()
            if s.name.encode("utf-16-be") in data}


def fit_layout(win) -> bool:
    """A restored layout whose docks, now that their panels are in them, need
    more room than the screen has (a layout saved grown, before the rule of
    :func:`restore_layout`): the default layout instead, the window fitted on
    its screen. Returns whether it did so."""
    screen = win.screen()
    if screen is None or not win.layout_restored:
        return False
    room, least = screen.availableGeometry(), win.minimumSizeHint()
    if least.width() <= room.width() and least.height() <= room.height():
        return False
    reset_layout(win)
    win.layout_restored = False
    return True


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
    # the tree keeps most of the left, over the tab group of the Outline
    h = max(win.height() - 260, 400)
    win.resizeDocks([win.project_dock, win.callstack_dock], [int(h * 0.6), int(h * 0.4)],
                    Qt.Orientation.Vertical)


def fit_on_screen(win) -> None:
    """A window larger than its screen's free area (a layout that grew it, a
    smaller screen than last time) made as large as that area at most, and
    moved onto it."""
    screen = win.screen()
    if screen is None or win.isMaximized() or win.isFullScreen():
        return
    room = screen.availableGeometry()
    frame = win.frameGeometry()
    # (the window's frame: what the window manager adds around it)
    extra_w, extra_h = frame.width() - win.width(), frame.height() - win.height()
    w = min(win.width(), room.width() - extra_w)
    h = min(win.height(), room.height() - extra_h)
    if (w, h) != (win.width(), win.height()):
        win.resize(w, h)
        frame = win.frameGeometry()
    x = min(max(frame.x(), room.x()), room.right() + 1 - frame.width())
    y = min(max(frame.y(), room.y()), room.bottom() + 1 - frame.height())
    if (x, y) != (frame.x(), frame.y()):
        win.move(max(x, room.x()), max(y, room.y()))


def reset_layout(win) -> None:
    """View › Reset Layout: the table's default layout (places, which docks
    show, the front tabs) and its sizes, in a window that fits its screen."""
    win.restoreState(win.default_state)
    fit_on_screen(win)
    apply = getattr(win, "tab_bars_apply", None)
    if apply is not None:
        QTimer.singleShot(0, apply)
    table = win.dock_table
    for spec in table.specs.values():
        dock = table.docks[spec.key]
        if dock.isFloating():
            dock.setFloating(False)
        want = spec.shown_with(table.run)
        if want == dock.isHidden():
            dock.setVisible(want)
    for spec in table.specs.values():
        if spec.front:
            table.docks[spec.key].raise_()
    default_dock_sizes(win)
    # the panels' splitters (the Watch dock's sections) as they first came
    settings = getattr(win, "settings", None)
    if settings is not None and hasattr(settings, "forget_splitter_sizes"):
        settings.forget_splitter_sizes()
    from plcbuilder.ide.panels.watch import SplitterSizes
    for kept in win.findChildren(SplitterSizes):
        kept.reset()
    QTimer.singleShot(0, lambda: scroll_editors_home(win))


def view_actions(win) -> list:
    """The View menu's entries for the docks, in the table's order: each
    dock's own show/hide action, with its row's shortcut; None between the
    areas (a separator)."""
    out: list = []
    table = win.dock_table
    area = None
    for spec in table.specs.values():
        if area is not None and spec.area != area:
            out.append(None)
        area = spec.area
        act = table.docks[spec.key].toggleViewAction()
        if spec.shortcut:
            act.setShortcut(spec.shortcut)
        out.append(act)
    return out


def scroll_editors_home(win) -> None:
    """Editors scrolled sideways while they were narrow start at the left
    again, the caret kept in view."""
    for ed in win.editors():
        if ed.xOffset():
            ed.setXOffset(0)
            ed.scrollCaret()
