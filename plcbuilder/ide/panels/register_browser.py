"""The Registers dock: every name of the controller's ABI
(:mod:`plcbuilder.bytecode.abi`, through the facade) with its number — the
registers, the predefined variables that live in registers, messages and
commands, proc states and exit codes — searchable by name, number or meaning.
Double-click or Enter inserts the name at the editor's caret. On a target
project (TG Motion, Huazhong: docs/targets.md) the names its built-in header
defines (``tgmotion.h``'s ``TGM_…``, Huazhong's ``plc.h``) are listed too, of
the kind ``tgmotion.h name`` / ``plc.h name``, with the header's comment.

When a controller is connected, the Value column shows the live value of the
registers among the rows on screen: the browser asks for those (and no
others) about once a second, and only while it is visible.
"""

from __future__ import annotations

import re
from typing import Optional

from PySide6.QtCore import QSortFilterProxyModel, Qt, QTimer, Signal
from PySide6.QtGui import QStandardItem, QStandardItemModel
from PySide6.QtWidgets import (QAbstractItemView, QComboBox, QHBoxLayout, QHeaderView, QLabel,
                               QLineEdit, QTableView, QVBoxLayout, QWidget)

from plcbuilder.api import abi
from plcbuilder.ide.docks import on_screen

COL_NAME, COL_NUMBER, COL_VALUE, COL_KIND, COL_MEANING = range(5)
HEADERS = ("Name", "Number", "Value", "Kind", "Meaning")
ROLE_ADDRESS = Qt.ItemDataRole.UserRole + 1     # on the Name item of a register row
KIND_VARIABLE = "predefined variable"
#: The kinds a register value can be read for.
LIVE_KINDS = ("register", KIND_VARIABLE)
POLL_MS = 1000
#: Rows asked for at most in one request.
MAX_LIVE_ROWS = 200


def rows() -> list[tuple[str, int, str, str]]:
    """(name, number, kind, meaning) of every ABI name, in table order, then
    the predefined variables that are registers."""
    out = []
    for name, value in abi.BUILTIN_NAMES.items():
        kind = abi.BUILTIN_KIND.get(name, "built-in name")
        meaning = ""
        if kind == "register":
            desc = abi.describe_register(value)
            meaning = desc if desc and desc != name else ""
            if meaning.startswith(name + ":"):
                meaning = meaning[len(name) + 1:].strip()
            m = re.fullmatch(r"GVAR_HW_(ADC|DAC|PWM)(\d)", name)
            if m and not meaning:
                meaning = f"{m.group(1)} channel {m.group(2)}"
        elif kind == "exit code":
            meaning = abi.EXIT_DESCRIPTIONS.get(value, "")
        out.append((name, value, kind, meaning))
    for name, reg in abi.MAPPED_VARIABLES.items():
        desc = abi.describe_register(reg) or ""
        ro = " (read-only)" if name in abi.READ_ONLY_VARIABLES else ""
        out.append((name, reg, KIND_VARIABLE, f"register {reg}, {desc}{ro}"))
    return out


#: the built-in header (lang/builtin_headers.py) whose names each target lists too
TARGET_HEADERS = {"tgmotion": "tgmotion.h", "huazhong": "plc.h"}

_DEFINE = re.compile(r"^\s*#\s*define\s+([A-Za-z_]\w*)\s+(0[xX][0-9A-Fa-f]+|-?\d+)\b"
                     r"\s*(?://\s*(.*))?$")


def header_rows(target: str) -> list[tuple[str, int, str, str]]:
    """(name, number, kind, meaning) of each number the target's built-in
    header #defines (none for myCNC): the meaning is the define's comment,
    else the first line of the comment above its group."""
    header = TARGET_HEADERS.get(target or "")
    if header is None:
        return []
    from plcbuilder.lang.builtin_headers import builtin_header
    text = builtin_header(header) or ""
    out, section, comment_block = [], "", False
    for line in text.splitlines():
        stripped = line.strip()
        if stripped.startswith("//"):
            if not comment_block:               # a group's comment: its first line
                section = stripped[2:].strip()
            comment_block = True
            continue
        comment_block = False
        if not stripped:
            section = ""
            continue
        m = _DEFINE.match(line)
        if m:
            name, value, own = m.group(1), int(m.group(2), 0), (m.group(3) or "").strip()
            out.append((name, value, f"{header} name", own or section))
    return out


class _Filter(QSortFilterProxyModel):
    """Rows whose name, number or meaning hold the search text, of one kind."""

    def __init__(self, parent=None):
        super().__init__(parent)
        self.text = ""
        self.kind = ""

    def set(self, text: str, kind: str) -> None:
        if hasattr(self, "beginFilterChange"):          # Qt 6.9 and later
            self.beginFilterChange()
            self.text, self.kind = text.strip().lower(), kind
            self.endFilterChange(QSortFilterProxyModel.Direction.Rows)
        else:
            self.text, self.kind = text.strip().lower(), kind
            self.invalidateFilter()

    def filterAcceptsRow(self, row: int, parent) -> bool:  # noqa: N802 - Qt override
        m = self.sourceModel()
        if self.kind and m.item(row, COL_KIND).text() != self.kind:
            return False
        if not self.text:
            return True
        hay = " ".join(m.item(row, c).text() for c in (COL_NAME, COL_NUMBER, COL_MEANING))
        addr = m.item(row, COL_NAME).data(ROLE_ADDRESS)
        if addr is not None and self.text.startswith("0x"):
            hay += f" 0x{addr:x}"
        return self.text in hay.lower()


class RegisterBrowser(QWidget):
    """The searchable table of ABI names; see the module docstring."""

    sig_insert = Signal(str)
    """Insert this name at the editor's caret."""

    def __init__(self, parent=None, poll_ms: int = POLL_MS):
        super().__init__(parent)
        self.connection = None
        self.model = QStandardItemModel(0, len(HEADERS), self)
        self.model.setHorizontalHeaderLabels(list(HEADERS))
        self._rows_of: dict[int, list[int]] = {}      # register -> model rows
        for name, value, kind, meaning in rows():
            items = [QStandardItem(name), QStandardItem(str(value)), QStandardItem(""),
                     QStandardItem(kind), QStandardItem(meaning)]
            for it in items:
                it.setEditable(False)
            items[COL_NUMBER].setData(int(value), Qt.ItemDataRole.DisplayRole)   # sorts as a number
            items[COL_NUMBER].setTextAlignment(Qt.AlignmentFlag.AlignRight |
                                               Qt.AlignmentFlag.AlignVCenter)
            items[COL_VALUE].setTextAlignment(Qt.AlignmentFlag.AlignRight |
                                              Qt.AlignmentFlag.AlignVCenter)
            if kind in LIVE_KINDS:
                items[COL_NAME].setData(int(value), ROLE_ADDRESS)
                self._rows_of.setdefault(int(value), []).append(self.model.rowCount())
            items[COL_NAME].setToolTip(f"{name} = {value}\nDouble-click or Enter inserts it")
            self.model.appendRow(items)
        self.proxy = _Filter(self)
        self.proxy.setSourceModel(self.model)
        self.search = QLineEdit(self)
        self.search.setPlaceholderText("Search names, numbers, meanings…")
        self.search.setClearButtonEnabled(True)
        self.search.textChanged.connect(self._refilter)
        self.kind = QComboBox(self)
        self.kind.addItem("All kinds", "")
        for k in dict.fromkeys(r[2] for r in rows()):
            self.kind.addItem(k, k)
        self.kind.currentIndexChanged.connect(self._refilter)
        self.table = QTableView(self)
        self.table.setModel(self.proxy)
        self.table.setSelectionBehavior(QAbstractItemView.SelectionBehavior.SelectRows)
        self.table.setSelectionMode(QAbstractItemView.SelectionMode.SingleSelection)
        self.table.setEditTriggers(QAbstractItemView.EditTrigger.NoEditTriggers)
        self.table.verticalHeader().hide()
        self.table.verticalHeader().setDefaultSectionSize(
            self.table.fontMetrics().height() + 6)
        self.table.setSortingEnabled(True)
        self.table.sortByColumn(-1, Qt.SortOrder.AscendingOrder)
        hh = self.table.horizontalHeader()
        hh.setSectionResizeMode(QHeaderView.ResizeMode.Interactive)
        hh.setStretchLastSection(True)
        fm = self.table.fontMetrics()
        for col, sample in ((COL_NAME, "GVAR_CURRENT_MOTION_CODE__"), (COL_NUMBER, "-0000000"),
                            (COL_VALUE, "-00000000"), (COL_KIND, "predefined variable_")):
            self.table.setColumnWidth(col, fm.horizontalAdvance(sample))
        self.table.activated.connect(self._on_activated)
        self.status = QLabel("", self)
        self.status.setContentsMargins(6, 0, 6, 2)
        row = QHBoxLayout()
        row.setContentsMargins(4, 3, 4, 0)
        row.addWidget(self.search, 1)
        row.addWidget(self.kind)
        lay = QVBoxLayout(self)
        lay.setContentsMargins(0, 0, 0, 0)
        lay.setSpacing(2)
        lay.addLayout(row)
        lay.addWidget(self.table, 1)
        lay.addWidget(self.status)
        self.timer = QTimer(self)
        self.timer.setInterval(poll_ms)
        self.timer.timeout.connect(self.poll)
        self._abi_rows = self.model.rowCount()
        self.target = "mycnc"
        # the open project's target header names: now, and with each project
        self._window = parent
        opened = getattr(parent, "sig_project_opened", None)
        if opened is not None:
            opened.connect(lambda _root: self._follow_project())
        self._follow_project()
        self._show_count()

    # ------------------------------------------------------------ public
    def set_connection(self, connection) -> None:
        """Read live values through this controller connection (None: no values)."""
        self.connection = connection
        if connection is not None and hasattr(connection, "sig_registers"):
            connection.sig_registers.connect(self.on_registers)
            connection.sig_disconnected.connect(lambda _why: self.clear_values())
        self._run_timer()

    def set_target(self, target: Optional[str]) -> None:
        """List the names of ``target``'s built-in header after the ABI's (and
        no other target's); myCNC's names are the ABI's alone."""
        target = target or "mycnc"
        if target == self.target:
            return
        self.target = target
        extra = self.model.rowCount() - self._abi_rows
        if extra:
            self.model.removeRows(self._abi_rows, extra)
        for i in range(self.kind.count() - 1, 0, -1):
            if self.kind.itemData(i).endswith(".h name"):
                self.kind.removeItem(i)
        added = header_rows(target)
        for name, value, kind, meaning in added:
            items = [QStandardItem(name), QStandardItem(str(value)), QStandardItem(""),
                     QStandardItem(kind), QStandardItem(meaning)]
            for it in items:
                it.setEditable(False)
            items[COL_NUMBER].setData(int(value), Qt.ItemDataRole.DisplayRole)
            items[COL_NUMBER].setTextAlignment(Qt.AlignmentFlag.AlignRight |
                                               Qt.AlignmentFlag.AlignVCenter)
            items[COL_NAME].setToolTip(f"{name} = {value} ({TARGET_HEADERS[target]})\n"
                                       "Double-click or Enter inserts it")
            self.model.appendRow(items)
        if added:
            self.kind.addItem(added[0][2], added[0][2])
        self._refilter()

    def _follow_project(self) -> None:
        project = getattr(self._window, "project", None)
        self.set_target(getattr(project, "target", None) if project is not None else None)

    def select_name(self, name: str) -> bool:
        """Show and select the row of ``name`` (the search is cleared); False if none."""
        hits = self.model.findItems(name, Qt.MatchFlag.MatchExactly, COL_NAME)
        if not hits:
            return False
        self.kind.setCurrentIndex(0)
        self.search.clear()
        idx = self.proxy.mapFromSource(hits[0].index())
        self.table.setCurrentIndex(idx)
        self.table.scrollTo(idx, QAbstractItemView.ScrollHint.PositionAtCenter)
        return True

    def select_number(self, value: int, kind: str) -> bool:
        """Show and select the first row of this kind with this number (a
        register number under the caret: kind "register"); False if none."""
        for row in range(self.model.rowCount()):
            if self.model.item(row, COL_KIND).text() == kind and \
                    self.model.item(row, COL_NUMBER).data(Qt.ItemDataRole.DisplayRole) == value:
                return self.select_name(self.model.item(row, COL_NAME).text())
        return False

    def current_name(self) -> Optional[str]:
        idx = self.table.currentIndex()
        if not idx.isValid():
            return None
        return self.proxy.index(idx.row(), COL_NAME).data()

    def visible_addresses(self) -> list[int]:
        """The registers of the rows on screen, in order, at most MAX_LIVE_ROWS."""
        vp = self.table.viewport()
        top = self.table.rowAt(0)
        if top < 0:
            return []
        bottom = self.table.rowAt(vp.height() - 1)
        if bottom < 0:
            bottom = self.proxy.rowCount() - 1
        out: list[int] = []
        for r in range(top, bottom + 1):
            addr = self.proxy.index(r, COL_NAME).data(ROLE_ADDRESS)
            if addr is not None and addr not in out:
                out.append(int(addr))
            if len(out) >= MAX_LIVE_ROWS:
                break
        return out

    def poll(self) -> bool:
        """Ask for the values of the registers on screen (when connected and
        visible); True when a request went out."""
        c = self.connection
        if c is None or not getattr(c, "connected", False) or not on_screen(self):
            return False
        addrs = self.visible_addresses()
        if not addrs:
            return False
        c.request_registers(addrs)
        return True

    def on_registers(self, values: dict) -> None:
        """Values arrived: {register: value}."""
        for addr, value in values.items():
            for row in self._rows_of.get(int(addr), ()):
                item = self.model.item(row, COL_VALUE)
                text = str(int(value))
                if item.text() != text:
                    item.setText(text)

    def clear_values(self) -> None:
        for rows_ in self._rows_of.values():
            for row in rows_:
                self.model.item(row, COL_VALUE).setText("")

    def value_of(self, name: str) -> str:
        hits = self.model.findItems(name, Qt.MatchFlag.MatchExactly, COL_NAME)
        return self.model.item(hits[0].row(), COL_VALUE).text() if hits else ""

    def showEvent(self, event) -> None:  # noqa: N802 - Qt override
        super().showEvent(event)
        self._follow_project()          # (a project's settings may have changed its target)
        self._run_timer()

    def hideEvent(self, event) -> None:  # noqa: N802 - Qt override
        super().hideEvent(event)
        self._run_timer()

    # ------------------------------------------------------------ private
    def _run_timer(self) -> None:
        """Poll only while shown with a connection (a hidden browser asks for
        nothing, so it needs no timer waking the IDE)."""
        if self.connection is not None and self.isVisible():
            if not self.timer.isActive():
                self.timer.start()
        else:
            self.timer.stop()

    def _refilter(self, *_args) -> None:
        self.proxy.set(self.search.text(), self.kind.currentData() or "")
        self._show_count()

    def _show_count(self) -> None:
        n, total = self.proxy.rowCount(), self.model.rowCount()
        self.status.setText(f"{n} of {total} names" if n != total else f"{total} names")

    def _on_activated(self, idx) -> None:
        name = self.proxy.index(idx.row(), COL_NAME).data()
        if name:
            self.sig_insert.emit(name)
