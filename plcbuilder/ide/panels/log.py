"""The run log: prints, messages by name, procedure starts and exit codes by
name, faults and controller notes. A click on a fault opens its source line."""

from __future__ import annotations

from pathlib import Path
from typing import Iterable, Optional

from PySide6 import QtCore, QtWidgets

from plcbuilder.api import abi
from plcbuilder.api import events as ev
from plcbuilder.ide.panels import style
from plcbuilder.ide.panels.model import decode_message
from plcbuilder.ide.panels.tables import RowsModel
from plcbuilder.ide.typing_pause import TypingPause

Qt = QtCore.Qt
Signal = QtCore.Signal

#: Row layout: the 4 shown columns, then the filter category, the colour key,
#: and the source location (file, line) of a fault.
T, SRC, KIND_LABEL, TEXT, CATEGORY, COLOUR, FILE, LINE = range(8)

KINDS = (("print", "Prints"), ("message", "Messages"), ("procedure", "Procedures"),
         ("job", "Job"), ("fault", "Faults"), ("log", "Logpoints"), ("note", "Notes"))
#: a search of a log longer than this runs once typing pauses (each keystroke
#: filtered every row: 60-120 ms a key at 20,000; see ide/typing_pause.py)
SEARCH_AT_ONCE_ROWS = 2000
_COLOURS = {"fault": style.FAULT_COLOUR, "error": style.FAULT_COLOUR, "warning": "#b35c00",
            "print": "#2f6db5", "link": "#808080", "message": "#8a52b8",
            "log": "#2e8b7a", "job": "#1f6f8b"}


def _fmt_t(t_ms: Optional[int]) -> str:
    return "" if t_ms is None else f"{t_ms / 1000:.3f}"


def event_row(e) -> Optional[tuple]:
    """The log row of an event, or None for events the log does not show."""
    if isinstance(e, ev.Print):
        return (_fmt_t(e.t_ms), e.source, "print", f"register {e.register} = {e.value}",
                "print", "print", None, None)
    if isinstance(e, ev.Message):
        name = e.name or abi.message_name(e.message)
        label = f"{name} ({e.message})" if name else f"message {e.message}"
        meaning = decode_message(e.message, e.command, e.parameter)
        text = f"{label}  " + (meaning or f"command={e.command} parameter={e.parameter}")
        return (_fmt_t(e.t_ms), e.source, "message", text, "message",
                "error" if e.message < 0 else "message", None, None)
    if isinstance(e, ev.Started):
        return (_fmt_t(e.t_ms), e.name, "start", f"{e.name} started ({e.kind}, eparam={e.eparam})",
                "procedure", "procedure", None, None)
    if isinstance(e, ev.Ended):
        name = e.exit_name or abi.exit_name(e.exit_code)
        desc = abi.EXIT_DESCRIPTIONS.get(e.exit_code)
        code = f"{name} ({e.exit_code})" if name else str(e.exit_code)
        text = f"{e.name} ended: exit {code}" + (f" — {desc}" if desc else "") + \
            f", vexit={e.vexit}"
        colour = "procedure" if e.exit_code in (0, abi.EXIT_NORMAL) else "warning"
        return (_fmt_t(e.t_ms), e.name, "exit", text, "procedure", colour, None, None)
    if isinstance(e, ev.Fault):
        where = f"  ({e.file or e.source}:{e.line})" if e.line is not None else ""
        return (_fmt_t(e.t_ms), e.source, "fault", f"{e.text}{where}", "fault", "fault",
                e.file or f"{e.source}.plc", e.line)
    if isinstance(e, ev.Note):
        colour = e.level if e.level in ("warning", "error") else "note"
        return (_fmt_t(e.t_ms), "controller", e.level, e.text, "note", colour, None, None)
    if isinstance(e, ev.JobEvent):          # the G-code job: a line read, a procedure started
        if e.procedure and getattr(e, "exit_code", None) is not None:
            text = f"line {e.line}: {e.text}"           # "line 3: M03 exit 99 plc_exit_normal"
        elif e.procedure:
            text = f"line {e.line}: starts {e.procedure}"
        elif e.state == "running":
            text = f"line {e.line}: {e.text}"
        else:
            text = f"{e.state} at line {e.line}: {e.text}"
        colour = "error" if e.state == "error" else "job"
        return (_fmt_t(e.t_ms), Path(e.file).name, "job", text, "job", colour, None, None)
    if getattr(e, "type", None) == "log":   # a logpoint's message (the debugger)
        return (_fmt_t(e.t_ms), e.source, "log", e.text, "log", "log", None, None)
    if isinstance(e, dict):                 # an event kind this IDE does not know
        return (_fmt_t(e.get("t_ms")), str(e.get("source", "")), str(e.get("type", "?")),
                str(e), "note", "note", None, None)
    return None


class _Filter(QtCore.QSortFilterProxyModel):
    def __init__(self, parent=None):
        super().__init__(parent)
        self.kinds = {k for k, _ in KINDS}
        self.text = ""

    def filterAcceptsRow(self, row, parent) -> bool:  # noqa: N802
        r = self.sourceModel().row(row)
        if r[CATEGORY] not in self.kinds:
            return False
        if self.text:
            return self.text in f"{r[0]} {r[1]} {r[2]} {r[3]}".lower()
        return True


class LogPanel(QtWidgets.QWidget):
    """The run log. Rows are queued as events arrive and inserted by :meth:`flush`."""

    sig_open_location = Signal(str, int)
    """A fault row was clicked: its source file and line."""

    def __init__(self, limit: int = 20000, parent=None):
        super().__init__(parent)
        self.rows = RowsModel(["Time (s)", "From", "Kind", "Text"], limit=limit,
                              colour=lambda r: _COLOURS.get(r[COLOUR]),
                              tooltip=self._tooltip, align_right=(0,))
        self.proxy = _Filter(self)
        self.proxy.setSourceModel(self.rows)
        self.view = QtWidgets.QTableView()
        self.view.setModel(self.proxy)
        self.view.setAlternatingRowColors(True)
        self.view.setSelectionBehavior(QtWidgets.QAbstractItemView.SelectionBehavior.SelectRows)
        self.view.setEditTriggers(QtWidgets.QAbstractItemView.EditTrigger.NoEditTriggers)
        self.view.verticalHeader().setVisible(False)
        self.view.verticalHeader().setDefaultSectionSize(20)
        self.view.setWordWrap(False)
        hh = self.view.horizontalHeader()
        hh.setStretchLastSection(True)
        hh.setHighlightSections(False)
        self.view.setColumnWidth(0, 80)
        self.view.setColumnWidth(1, 110)
        self.view.setColumnWidth(2, 64)
        self.view.clicked.connect(self._clicked)
        self.view.activated.connect(self._clicked)

        bar = QtWidgets.QHBoxLayout()
        bar.setContentsMargins(4, 2, 4, 2)
        bar.setSpacing(4)
        self.kind_buttons: dict[str, QtWidgets.QToolButton] = {}
        for kind, text in KINDS:
            b = style.small_button(text, f"Show {text.lower()}", checkable=True)
            b.setChecked(True)
            b.toggled.connect(lambda on, k=kind: self._toggle_kind(k, on))
            self.kind_buttons[kind] = b
            bar.addWidget(b)
        self.search = QtWidgets.QLineEdit()
        self.search.setPlaceholderText("Search the log…")
        self.search.setClearButtonEnabled(True)
        self.typing = TypingPause(self.search, self._apply_search,
                                  lambda: self.rows.rowCount() > SEARCH_AT_ONCE_ROWS)
        bar.addWidget(self.search, 1)
        self.autoscroll = style.small_button("Scroll", "Keep the newest row in view", True)
        self.autoscroll.setChecked(True)
        bar.addWidget(self.autoscroll)
        clear = style.small_button("Clear", "Clear the log")
        clear.clicked.connect(self.clear)
        bar.addWidget(clear)

        lay = QtWidgets.QVBoxLayout(self)
        lay.setContentsMargins(0, 0, 0, 0)
        lay.setSpacing(0)
        lay.addLayout(bar)
        lay.addWidget(self.view, 1)

        #: the live rows while a recorded run or a trace is shown (None: live)
        self.live: Optional[list[tuple]] = None

    # ------------------------------------------------------------------ API
    def add_events(self, events: Iterable) -> None:
        """Live events (kept aside while a recorded run or trace is shown)."""
        for e in events:
            row = event_row(e)
            if row is not None:
                self._live_row(row)

    def add_note(self, text: str, kind: str = "link", t_ms: Optional[int] = None, *,
                 shown: bool = False) -> None:
        """A line from the IDE itself (connection state, a refused request);
        ``shown``: about the recorded run or trace on show (with its rows)."""
        row = (_fmt_t(t_ms), "IDE", kind, text, "note", kind, None, None)
        self.rows.queue(row) if shown else self._live_row(row)

    def show_recorded(self, text: str, events: Iterable) -> None:
        """Show the rows of a recorded run or a trace (``text`` says which, on
        the first row) instead of the live ones, which are kept, and those that
        come meanwhile, until :meth:`back_to_live` (issue 23.10: they were added
        below the live rows, the live session's own a second time)."""
        rows = [("", "IDE", "link", text, "note", "link", None, None)]
        rows += [r for r in map(event_row, events) if r is not None]
        old = self.rows.replace(rows)
        if self.live is None:
            self.live = old
        self._scroll()

    def back_to_live(self, note: Optional[str] = None) -> None:
        """The live rows again (with those that came while a run was shown)."""
        if self.live is None:
            return
        live, self.live = self.live, None
        self.rows.replace(live)
        if note:
            self.add_note(note, "link")
        self._scroll()

    def _live_row(self, row: tuple) -> None:
        if self.live is None:
            self.rows.queue(row)
        else:
            self.live.append(row)
            if len(self.live) > 2 * self.rows.limit:
                del self.live[:len(self.live) - self.rows.limit]

    def _scroll(self) -> None:
        if self.autoscroll.isChecked():
            self.view.scrollToBottom()

    def flush(self) -> None:
        if self.rows.flush() and self.autoscroll.isChecked():
            self.view.scrollToBottom()

    def clear(self) -> None:
        self.rows.clear()
        if self.live is not None:
            self.live = []

    def fault_rows(self) -> list[int]:
        """Rows (of the view) that hold faults."""
        out = []
        for r in range(self.proxy.rowCount()):
            src = self.proxy.mapToSource(self.proxy.index(r, 0))
            if self.rows.row(src.row())[CATEGORY] == "fault":
                out.append(r)
        return out

    # -------------------------------------------------------------- private
    def _refilter(self, change) -> None:
        p = self.proxy
        if hasattr(p, "beginFilterChange"):          # Qt >= 6.9
            p.beginFilterChange()
            change()
            p.endFilterChange(QtCore.QSortFilterProxyModel.Direction.Rows)
        else:
            change()
            p.invalidateFilter()

    def _toggle_kind(self, kind: str, on: bool) -> None:
        kinds = self.proxy.kinds
        self._refilter(lambda: kinds.add(kind) if on else kinds.discard(kind))

    def _apply_search(self) -> None:
        text = self.search.text().strip().lower()
        if text != self.proxy.text:
            self._refilter(lambda: setattr(self.proxy, "text", text))

    def _clicked(self, index: QtCore.QModelIndex) -> None:
        if not index.isValid():
            return
        row = self.rows.row(self.proxy.mapToSource(index).row())
        if row[CATEGORY] == "fault" and row[LINE] is not None:
            self.sig_open_location.emit(str(row[FILE]), int(row[LINE]))

    @staticmethod
    def _tooltip(row: tuple) -> Optional[str]:
        if row[CATEGORY] == "fault":
            if row[LINE] is not None:
                return f"Click to open {row[FILE]} at line {row[LINE]}"
            return "Runtime fault"
        return row[TEXT] if len(row[TEXT]) > 80 else None
