"""The watch panel: the variables of the running (or last run) procedure.

Values come from the controller's ``variables`` verb, which the panels poll a
few times a second while something runs (see :class:`RunPanels`), or from the
halted state while the controller is halted. A value that changed since the
previous poll is shown highlighted.

Values are editable (SPEC §6): typing a value and Enter writes it once; the
Force column's checkbox (or the context menu) holds it; a forced value is shown
bold in orange with the force icon.
"""

from __future__ import annotations

import time
from typing import Optional

from PySide6 import QtCore, QtGui, QtWidgets

from plcbuilder.api import abi
from plcbuilder.ide.panels.flowbar import FlowBar

Qt = QtCore.Qt

HIGHLIGHT_S = 1.0
_PREDEFINED = ("eparam", "proc", "timer", "vexit", "message", "Param")
_CHANGED = QtGui.QColor("#fff2b3")
FORCED_COLOUR = QtGui.QColor("#c75a00")
COL_NAME, COL_VALUE, COL_HEX, COL_FORCE = range(4)


def parse_value(text: str) -> Optional[int]:
    """A value typed into the watch: decimal, 0x hex, 0b binary; None if not a number."""
    try:
        v = int(text.strip().replace("_", ""), 0)
    except ValueError:
        return None
    return v if -(1 << 31) <= v < (1 << 32) else None


def _order(names: list[str]) -> list[str]:
    """The program's own variables first (in slot order), then the predefined
    ones, then var00..var15."""
    own = [n for n in names if n not in abi.SLOT_NAMES and n not in _PREDEFINED]
    pre = [n for n in _PREDEFINED if n in names]
    regs = [n for n in names if n.startswith("var") and n in abi.SLOT_NAMES]
    rest = [n for n in names if n not in own and n not in pre and n not in regs]
    return own + pre + rest + regs


def small_minimum(table: QtWidgets.QTableWidget, rows: int = 1) -> None:
    """A table in a splitter section may be dragged down to its header and
    ``rows`` rows (a table's own minimum is about four rows: three such
    sections filled a short dock at their minimums, and no handle moved)."""
    header = table.horizontalHeader().sizeHint().height()
    row = table.verticalHeader().defaultSectionSize()
    bar = table.horizontalScrollBar().sizeHint().height()     # (it may show: a row's room)
    table.setMinimumHeight(header + rows * row + bar + 2 * table.frameWidth() + 2)


class _GripHandle(QtWidgets.QSplitterHandle):
    """A splitter handle that shows it is one: a short grip across its middle."""

    def paintEvent(self, event) -> None:  # noqa: N802 - Qt's name
        p = QtGui.QPainter(self)
        colour = self.palette().color(QtGui.QPalette.ColorRole.Mid)
        p.setPen(QtGui.QPen(colour, 1))
        r = self.rect()
        cx, cy = r.center().x(), r.center().y()
        if self.orientation() == Qt.Orientation.Vertical:
            for dy in (-1, 1):
                p.drawLine(cx - 14, cy + dy, cx + 14, cy + dy)
        else:
            for dx in (-1, 1):
                p.drawLine(cx + dx, cy - 14, cx + dx, cy + 14)
        p.end()


class GripSplitter(QtWidgets.QSplitter):
    """A QSplitter whose handles show a grip (a plain one is an invisible
    strip: nobody knew the sections could be resized)."""

    def __init__(self, orientation, parent=None):
        super().__init__(orientation, parent)
        self.setHandleWidth(7)
        self.setChildrenCollapsible(False)

    def createHandle(self) -> QtWidgets.QSplitterHandle:  # noqa: N802 - Qt's name
        return _GripHandle(self.orientation(), self)


class SplitterSizes(QtCore.QObject):
    """Keeps a panel's splitter sizes in the window's settings (``name``): saved
    as the user moves a handle while every section shows, and given back when
    they all show again (the registers and oscilloscope appear with a target
    project). The window is the first ancestor with ``settings``."""

    def __init__(self, splitter: QtWidgets.QSplitter, name: str):
        super().__init__(splitter)
        self.splitter, self.name = splitter, name
        self._applied = False
        self._default: Optional[list[int]] = None   # Qt's own sizes, before any saved ones
        splitter.splitterMoved.connect(self._moved)
        splitter.installEventFilter(self)

    def watch(self, widget: QtWidgets.QWidget) -> None:
        """A section whose showing may make every section show."""
        widget.installEventFilter(self)

    def _settings(self):
        w = self.splitter.parentWidget()
        while w is not None:
            s = getattr(w, "settings", None)
            if s is not None and hasattr(s, "splitter_sizes"):
                return s
            w = w.parentWidget()
        return None

    def _all_shown(self) -> bool:
        sp = self.splitter
        return sp.count() > 1 and all(not sp.widget(i).isHidden() for i in range(sp.count()))

    def eventFilter(self, obj, event) -> bool:  # noqa: N802 - Qt's name
        kind = event.type()
        if kind == QtCore.QEvent.Type.Show:
            QtCore.QTimer.singleShot(0, self.restore)
        elif kind == QtCore.QEvent.Type.Hide and obj is not self.splitter:
            self._applied = False
        return False

    def restore(self) -> None:
        """The sizes saved, once every section shows (and the splitter does)."""
        if self._applied or not self._all_shown() or not self.splitter.isVisible():
            return
        self._applied = True
        if self._default is None:
            self._default = self.splitter.sizes()
        s = self._settings()
        sizes = s.splitter_sizes(self.name) if s is not None else None
        if sizes and len(sizes) == self.splitter.count():
            self.splitter.setSizes(sizes)

    def reset(self) -> None:
        """View › Reset Layout: the sizes the splitter had before any the user
        left (the saved ones are forgotten by the settings)."""
        if self._default is not None and len(self._default) == self.splitter.count():
            self.splitter.setSizes(self._default)

    def _moved(self, *_args) -> None:
        if not self._all_shown():
            return
        s = self._settings()
        if s is not None:
            s.save_splitter_sizes(self.name, self.splitter.sizes())


class WatchPanel(QtWidgets.QWidget):
    """A table of one procedure's variables, refreshed from polls."""

    sig_write = QtCore.Signal(str, int)
    """Write a variable once: the target (``PROC.var``) and the value."""

    sig_force = QtCore.Signal(str, int)
    """Force a variable: the target and the value it is held at."""

    sig_release = QtCore.Signal(str, str)
    """Release a forced variable: the target and ``keep`` or ``restore``."""

    def __init__(self, parent=None):
        super().__init__(parent)
        self.procedure = QtWidgets.QComboBox()
        self.procedure.setToolTip("Whose variables to show (follows the running procedure)")
        self.procedure.setMinimumContentsLength(12)
        self.procedure.activated.connect(self._picked)
        self.follow = QtWidgets.QCheckBox("Follow running")
        self.follow.setChecked(True)
        self.follow.setToolTip("Show the procedure that is running")
        self.show_regs = QtWidgets.QCheckBox("var00–var15")
        self.show_regs.setToolTip("Also show var00..var15 (initialised from plc-variables.xml)")
        self.show_regs.toggled.connect(lambda _: self._fill())
        self.hex = QtWidgets.QCheckBox("Hex")
        self.hex.setChecked(True)
        self.hex.toggled.connect(lambda _: self._fill())
        # one row where the dock is wide enough, else the boxes under the combo
        self.bar = FlowBar(((QtWidgets.QLabel("Procedure"), 0), (self.procedure, 1)),
                           ((self.follow, 0), (self.show_regs, 0), (self.hex, 0)))

        self.table = QtWidgets.QTableWidget(0, 4)
        self.table.setHorizontalHeaderLabels(["Variable", "Value", "Hex", "Force"])
        self.table.horizontalHeaderItem(COL_FORCE).setToolTip(
            "Checked: the value is forced (held whatever the program writes)")
        self.table.horizontalHeaderItem(COL_VALUE).setToolTip(
            "Double-click (or type) a value and press Enter to write it")
        self.table.verticalHeader().setVisible(False)
        self.table.verticalHeader().setDefaultSectionSize(20)
        Trig = QtWidgets.QAbstractItemView.EditTrigger
        self.table.setEditTriggers(Trig.DoubleClicked | Trig.EditKeyPressed | Trig.AnyKeyPressed)
        self.table.itemChanged.connect(self._item_changed)
        self.table.setContextMenuPolicy(Qt.ContextMenuPolicy.CustomContextMenu)
        self.table.customContextMenuRequested.connect(self._menu)
        self.table.setSelectionBehavior(QtWidgets.QAbstractItemView.SelectionBehavior.SelectRows)
        self.table.setAlternatingRowColors(True)
        hh = self.table.horizontalHeader()
        hh.setSectionResizeMode(0, QtWidgets.QHeaderView.ResizeMode.Stretch)
        hh.setSectionResizeMode(1, QtWidgets.QHeaderView.ResizeMode.ResizeToContents)
        hh.setSectionResizeMode(2, QtWidgets.QHeaderView.ResizeMode.ResizeToContents)
        hh.setSectionResizeMode(3, QtWidgets.QHeaderView.ResizeMode.ResizeToContents)
        self.hint = QtWidgets.QLabel("Variables appear while a procedure runs.")
        self.hint.setStyleSheet("color: #6a6a6a; padding: 2px 6px;")

        # the watch, and under it (a target project) the registers and the
        # oscilloscope: sections of a splitter, each as tall as the user drags it
        part = QtWidgets.QWidget()
        plain = QtWidgets.QVBoxLayout(part)
        plain.setContentsMargins(0, 0, 0, 0)
        plain.setSpacing(2)
        plain.addWidget(self.table, 1)
        plain.addWidget(self.hint)
        small_minimum(self.table)
        self.split = GripSplitter(Qt.Orientation.Vertical)
        self.split.setObjectName("watchSplitter")
        self.split.addWidget(part)
        self.sizes = SplitterSizes(self.split, "watch")
        lay = QtWidgets.QVBoxLayout(self)
        lay.setContentsMargins(0, 0, 0, 0)
        lay.setSpacing(2)
        lay.addWidget(self.bar)
        lay.addWidget(self.split, 1)

        self.variables: dict[str, dict[str, int]] = {}
        self._changed: dict[tuple[str, str], float] = {}
        self.current: Optional[str] = None
        self.forced: dict[str, int] = {}        # target (PROC.var) -> forced value
        self.editable = False                   # a controller that writes and forces
        self._filling = False
        self._rows: list[str] = []              # the variable of each row

    # ------------------------------------------------------------------ API
    def add_section(self, widget: QtWidgets.QWidget) -> None:
        """Another section under the watch (the target's registers), with a
        splitter handle above it; hidden, it takes no room."""
        self.split.addWidget(widget)
        self.split.setStretchFactor(0, 2)
        self.split.setStretchFactor(self.split.count() - 1, 1)
        self.sizes.watch(widget)

    def set_variables(self, variables: dict, running: Optional[str] = None) -> None:
        """A poll's answer: ``{procedure: {variable: value}}``."""
        now = time.monotonic()
        for proc, vals in variables.items():
            old = self.variables.get(proc, {})
            for name, v in vals.items():
                if name in old and old[name] != v:
                    self._changed[(proc, name)] = now + HIGHLIGHT_S
        self.variables = {p: dict(v) for p, v in variables.items()}
        names = sorted(self.variables)
        if [self.procedure.itemText(i) for i in range(self.procedure.count())] != names:
            self.procedure.blockSignals(True)
            self.procedure.clear()
            self.procedure.addItems(names)
            self.procedure.blockSignals(False)
        if self.follow.isChecked() and running and running in self.variables:
            self.current = running
        elif self.current not in self.variables:
            self.current = running if running in self.variables else (names[0] if names else None)
        if self.current is not None:
            self.procedure.setCurrentText(self.current)
        self._fill()

    def clear(self) -> None:
        self.variables = {}
        self._changed.clear()
        self.procedure.clear()
        self.current = None
        self._fill()

    def value(self, name: str, procedure: Optional[str] = None) -> Optional[int]:
        return self.variables.get(procedure or self.current or "", {}).get(name)

    def set_forces(self, forces: list) -> None:
        """What the controller has forced (``[{target, value}]``): the rows of
        forced variables are marked."""
        self.forced = {str(f.get("target")): f.get("value") for f in forces
                       if "." in str(f.get("target", ""))}
        self._fill()

    def row_of(self, name: str) -> int:
        return self._rows.index(name) if name in self._rows else -1

    def target(self, name: str) -> str:
        return f"{self.current}.{name}"

    def write_value(self, name: str, value: int) -> None:
        """Write (or, when forced, force) a variable of the shown procedure."""
        t = self.target(name)
        (self.sig_force if t in self.forced else self.sig_write).emit(t, int(value))

    def menu_for(self, name: str) -> QtWidgets.QMenu:
        """The context menu of a variable's row (built, not shown: tests use it)."""
        menu = QtWidgets.QMenu(self)
        t = self.target(name)
        v = self.value(name) or 0

        def add(text, obj, slot, enabled=True):
            act = menu.addAction(text, slot)
            act.setObjectName(obj)
            act.setEnabled(enabled and self.editable)
        add(f"Write {name}…", "write", lambda: self._ask(name, force=False))
        add(f"Force {name} at {v}", "force", lambda: self.sig_force.emit(t, int(v)),
            t not in self.forced)
        add(f"Force {name} at…", "force_at", lambda: self._ask(name, force=True))
        add("Release (keep the value)", "release_keep",
            lambda: self.sig_release.emit(t, "keep"), t in self.forced)
        add("Release (restore the program's value)", "release_restore",
            lambda: self.sig_release.emit(t, "restore"), t in self.forced)
        return menu

    # -------------------------------------------------------------- private
    def _picked(self, index: int) -> None:
        self.current = self.procedure.itemText(index)
        self.follow.setChecked(False)
        self._fill()

    def _ask(self, name: str, force: bool) -> None:
        v, ok = QtWidgets.QInputDialog.getInt(
            self, "Force" if force else "Write", f"{'Force' if force else 'Write'} "
            f"{self.target(name)} =", int(self.value(name) or 0), -(1 << 31), (1 << 31) - 1)
        if ok:
            (self.sig_force if force else self.sig_write).emit(self.target(name), v)

    def _menu(self, pos) -> None:
        item = self.table.itemAt(pos)
        if item is not None and 0 <= item.row() < len(self._rows):
            self.menu_for(self._rows[item.row()]).exec(self.table.viewport().mapToGlobal(pos))

    def _item_changed(self, item: QtWidgets.QTableWidgetItem) -> None:
        if self._filling or not 0 <= item.row() < len(self._rows):
            return
        name = self._rows[item.row()]
        t = self.target(name)
        if item.column() == COL_VALUE:
            v = parse_value(item.text())
            if v is None or not self.editable:
                self._fill(force=True)           # not a number: show the value again
                return
            self.write_value(name, v)
        elif item.column() == COL_FORCE and self.editable:
            on = item.checkState() == Qt.CheckState.Checked
            if on and t not in self.forced:
                self.sig_force.emit(t, int(self.value(name) or 0))
            elif not on and t in self.forced:
                self.sig_release.emit(t, "keep")

    def _fill(self, force: bool = False) -> None:
        if not force and self.table.state() == \
                QtWidgets.QAbstractItemView.State.EditingState:
            return                               # the user is typing a value
        self._filling = True
        try:
            self._fill_rows()
        finally:
            self._filling = False

    def _fill_rows(self) -> None:
        vals = self.variables.get(self.current or "", {})
        names = _order(list(vals))
        if not self.show_regs.isChecked():
            names = [n for n in names if not (n.startswith("var") and n in abi.SLOT_NAMES)]
        now = time.monotonic()
        self.table.setColumnHidden(2, not self.hex.isChecked())
        if self.table.rowCount() != len(names):
            self.table.setRowCount(len(names))
        bold = QtGui.QFont()
        bold.setBold(True)
        self._rows = list(names)
        self.table.setColumnHidden(COL_FORCE, not self.editable)
        from plcbuilder.ide.icons import icon
        for r, name in enumerate(names):
            v = int(vals[name])
            forced = self.target(name) in self.forced
            cells = (name, str(v), f"0x{v & 0xFFFFFFFF:08x}", "")
            hot = self._changed.get((self.current, name), 0) > now
            for c, text in enumerate(cells):
                item = self.table.item(r, c)
                if item is None:
                    item = QtWidgets.QTableWidgetItem()
                    if c:
                        item.setTextAlignment(Qt.AlignmentFlag.AlignRight
                                              | Qt.AlignmentFlag.AlignVCenter)
                    flags = Qt.ItemFlag.ItemIsEnabled | Qt.ItemFlag.ItemIsSelectable
                    if c == COL_VALUE:
                        flags |= Qt.ItemFlag.ItemIsEditable
                    elif c == COL_FORCE:
                        flags |= Qt.ItemFlag.ItemIsUserCheckable
                        item.setCheckState(Qt.CheckState.Unchecked)   # (draws the box)
                    item.setFlags(flags)
                    self.table.setItem(r, c, item)
                if item.text() != text:
                    item.setText(text)
                item.setBackground(_CHANGED if hot else QtGui.QBrush())
                if c == COL_NAME:
                    item.setFont(bold if name not in abi.SLOT_NAMES and name not in _PREDEFINED
                                 else QtGui.QFont())
                    item.setIcon(icon("debug-force") if forced else QtGui.QIcon())
                    item.setToolTip(f"{self.target(name)} is forced" if forced else "")
                elif c == COL_VALUE:
                    item.setFont(bold if forced else QtGui.QFont())
                    item.setForeground(FORCED_COLOUR if forced else QtGui.QBrush())
                elif c == COL_FORCE:
                    state = Qt.CheckState.Checked if forced else Qt.CheckState.Unchecked
                    if item.checkState() != state:
                        item.setCheckState(state)
        self.hint.setVisible(not names)
