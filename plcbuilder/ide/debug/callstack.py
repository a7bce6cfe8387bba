"""The Call Stack panel: while halted, every running procedure with its calls,
innermost first; clicking a frame goes to its line.

The halted state gives, per procedure, the line it is at and its ``stack``
(the calls that lead there). :func:`frames_of` turns one procedure's entry
into frames, innermost first, whichever order the stack came in.
"""

from __future__ import annotations

from pathlib import Path
from typing import Optional

from PySide6.QtCore import QEvent, Qt, Signal
from PySide6.QtGui import QBrush, QColor, QFont, QPalette
from PySide6.QtWidgets import QLabel, QTreeWidget, QTreeWidgetItem, QVBoxLayout, QWidget

from plcbuilder.ide.icons import icon

ROLE_FRAME = Qt.ItemDataRole.UserRole + 1
ROLE_TEXTS = Qt.ItemDataRole.UserRole + 2
#: the innermost frame's colour: {dark theme: (halted here, waiting at a loop's end)}
_FRAME_COLOURS = {False: ("#8a6d00", "#1f5fa8"), True: ("#e3c04f", "#86b8f0")}
REASONS = {"breakpoint": "halted at a breakpoint", "step": "halted after a step",
           "pause": "paused", "fault": "halted at a fault"}


def frames_of(proc: dict) -> list[dict]:
    """One halted procedure's frames, innermost first: ``{procedure, file,
    line, index}`` (index 0: where it is now)."""
    here = {"procedure": proc.get("name"), "file": proc.get("file"), "line": proc.get("line")}
    stack = [dict(f) for f in proc.get("stack") or () if isinstance(f, dict)]
    if stack:
        first, last = stack[0], stack[-1]
        same = lambda f: f.get("line") == here["line"] and f.get("file") == here["file"]  # noqa: E731
        if same(last) and not same(first):
            stack.reverse()                  # outermost first: make it innermost first
        if not same(stack[0]):
            stack.insert(0, here)
    else:
        stack = [here]
    for i, f in enumerate(stack):
        f["index"] = i
        f.setdefault("procedure", here["procedure"])
    return stack


def current_procedure(state: dict) -> Optional[dict]:
    """The running procedure a halted state is about: the one that halted,
    while it runs; once it ended while the controller stayed halted (Stop
    pressed: it ended and ``M02`` or ``OFF`` waits at its first line), the
    hardware procedure running, else the first running; None: none runs."""
    procs = [p for p in state.get("procedures") or () if isinstance(p, dict)]
    halting = state.get("procedure")
    return next((p for p in procs if p.get("name") == halting), None) or \
        next((p for p in procs if p.get("kind") == "hardware"), None) or \
        (procs[0] if procs else None)


def halting_ended(state: dict) -> bool:
    """The procedure that halted has ended since (the controller is still halted)."""
    halting = state.get("procedure")
    return bool(halting) and all(p.get("name") != halting for p in state.get("procedures") or ()
                                 if isinstance(p, dict))


def _where(proc: dict) -> str:
    if proc.get("file") and proc.get("line"):
        return f" at {Path(str(proc['file'])).name}:{proc['line']}"
    return ""


def halted_text(state: dict) -> str:
    """One line about why and where the controller halted (and, when the
    procedure that halted ended since, that it did and what waits now)."""
    t = int(state.get("t_ms") or 0)
    if halting_ended(state):
        now = current_procedure(state)
        text = f"Halted, t = {t} ms: {state['procedure']} ended"
        if now is not None:
            text += f"; {now.get('name')} waits{_where(now)}"
        return text + " (Continue runs on)"
    reason = REASONS.get(state.get("reason"), f"halted ({state.get('reason')})")
    where = ""
    if state.get("procedure"):
        where = f" in {state['procedure']}"
        if state.get("file") and state.get("line"):
            where += f" at {Path(str(state['file'])).name}:{state['line']}"
    text = f"{reason.capitalize()}{where}, t = {t} ms"
    fault = state.get("fault")
    if isinstance(fault, dict) and fault.get("text"):
        text += f": {fault['text']}"
    return text


class CallStackPanel(QWidget):
    """The procedures of a halted controller and their frames."""

    sig_frame_selected = Signal(str, int, str, int)
    """A frame was picked: procedure, frame index (0: innermost), file, line."""

    def __init__(self, parent: Optional[QWidget] = None):
        super().__init__(parent)
        self.header = QLabel("Not halted.")
        self.header.setWordWrap(True)
        self.header.setStyleSheet("padding: 3px 6px;")
        self.tree = QTreeWidget(self)
        self.tree.setObjectName("callStack")
        self.tree.setColumnCount(1)
        self.tree.setHeaderHidden(True)         # one column: a narrow dock shows it all
        self.tree.setUniformRowHeights(True)
        self.tree.itemClicked.connect(self._clicked)
        self.tree.itemActivated.connect(self._clicked)
        lay = QVBoxLayout(self)
        lay.setContentsMargins(0, 0, 0, 0)
        lay.setSpacing(0)
        lay.addWidget(self.header)
        lay.addWidget(self.tree, 1)
        self.state: Optional[dict] = None
        self._innermost: list[tuple[QTreeWidgetItem, bool]] = []

    # ------------------------------------------------------------------ API
    def show_state(self, state: Optional[dict]) -> None:
        """The halted state (None: running; the panel empties)."""
        self.state = state
        self.tree.clear()
        self._innermost: list[tuple[QTreeWidgetItem, bool]] = []   # (item, waiting)
        if state is None:
            self.header.setText("Running — the call stack shows while the controller is halted.")
            return
        self.header.setText(halted_text(state))
        bold = QFont()
        bold.setBold(True)
        halting = state.get("procedure")
        current = (current_procedure(state) or {}).get("name")
        for proc in state.get("procedures") or ():
            name = str(proc.get("name"))
            top = QTreeWidgetItem(self.tree)
            waiting = bool(proc.get("at_loop_end"))
            state = "waiting at its loop's end" if waiting else (
                "halted here" if name == halting else "at its line")
            top.setText(0, f"{name} — {state}")
            top.setToolTip(0, f"{name} ({proc.get('kind', '')}): {state}"
                           + (" (for the next tick)" if waiting else ""))
            top.setIcon(0, icon("file-plc-sw" if proc.get("kind") == "software" else "file-plc"))
            if name == current:
                top.setFont(0, bold)
            for f in frames_of(proc):
                item = QTreeWidgetItem(top)
                callee = f.get("procedure") or name
                where = f"{Path(str(f.get('file') or '?')).name}:{f.get('line')}"
                call = f"{callee}()" if f["index"] else f"{callee}()  ◀"
                item.setText(0, f"{call}   {where}")
                item.setData(0, ROLE_TEXTS, (call, where))
                item.setData(0, ROLE_FRAME, (name, f["index"], str(f.get("file") or ""),
                                             int(f.get("line") or 0)))
                if f["index"] == 0:
                    self._innermost.append((item, waiting))
            top.setExpanded(True)
        self._colour_frames()
        first = self.tree.topLevelItem(0)
        if first is not None and first.childCount():
            for i in range(self.tree.topLevelItemCount()):
                it = self.tree.topLevelItem(i)
                if it.font(0).bold() and it.childCount():
                    first = it
                    break
            self.tree.setCurrentItem(first.child(0))

    def frame_items(self) -> list[QTreeWidgetItem]:
        out = []
        for i in range(self.tree.topLevelItemCount()):
            top = self.tree.topLevelItem(i)
            out.extend(top.child(j) for j in range(top.childCount()))
        return out

    def frame_texts(self) -> list[tuple[str, str]]:
        """(call, where) of each frame shown: ``("find_home_z()  ◀", "M80.plc:31")``."""
        return [tuple(it.data(0, ROLE_TEXTS)) for it in self.frame_items()]

    # -------------------------------------------------------------- private
    def changeEvent(self, event) -> None:  # noqa: N802 - Qt's name
        """A new theme: the frames' colours again."""
        super().changeEvent(event)
        if event.type() in (QEvent.Type.PaletteChange, QEvent.Type.ApplicationPaletteChange) \
                and self.state is not None:
            self._colour_frames()

    def _colour_frames(self) -> None:
        """Each procedure's innermost frame in the theme's colour for halted
        here or waiting at its loop's end."""
        colours = _FRAME_COLOURS[self._dark()]
        for item, waiting in self._innermost:
            item.setForeground(0, QBrush(QColor(colours[waiting])))

    def _dark(self) -> bool:
        """The tree's palette is a dark one (the dark theme)."""
        return self.palette().color(QPalette.ColorRole.Base).lightness() < 128

    def _clicked(self, item: QTreeWidgetItem, _column: int = 0) -> None:
        data = item.data(0, ROLE_FRAME)
        if data is None and item.childCount():
            data = item.child(0).data(0, ROLE_FRAME)
        if data is not None:
            self.sig_frame_selected.emit(*data)
