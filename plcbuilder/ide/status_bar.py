"""The window's status bar: problems · connection · sim time · running · proc ·
size · Ln/Col · encoding."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Optional

from PySide6.QtCore import QEvent, Qt, QTimer, Signal
from PySide6.QtWidgets import QLabel, QStatusBar, QToolButton

from plcbuilder import api
from plcbuilder.ide.icons import icon
from plcbuilder.ide.looks import set_text_colour

if TYPE_CHECKING:
    from plcbuilder.link.client import ControllerStatus


#: the widest time the status bar shows (its label is this wide)
WIDEST_TIME = "t = 0000000.000 s"


def time_text(t_ms: int, exact: bool = True) -> str:
    """The simulated time as the status bar shows it: seconds (to the ms while
    something runs) up to 115 days of it, then days; never wider than
    :data:`WIDEST_TIME`."""
    if t_ms >= 10_000_000_000:
        return f"t = {t_ms / 86_400_000:.1f} d"
    return f"t = {t_ms / 1000:.3f} s" if exact else f"t = {t_ms // 1000} s"


#: what moves the edge of the room a message has
_ROOM_EVENTS = (QEvent.Type.Move, QEvent.Type.Resize, QEvent.Type.Show, QEvent.Type.Hide)


class StatusBar(QStatusBar):
    """Messages on the left, the permanent labels on the right."""

    sig_show_problems = Signal()
    """The problem counts were clicked (show the Problems panel)."""

    def __init__(self, parent=None):
        super().__init__(parent)
        sb = self
        sb.setSizeGripEnabled(True)

        def lab(name, tip, min_width=0):
            w = QLabel(self)
            w.setObjectName(name)
            w.setToolTip(tip)
            # room either side (margins, not a style sheet: one makes the bar
            # and every label in it draw through the style-sheet style)
            w.setContentsMargins(10, 0, 10, 0)
            if min_width:
                w.setMinimumWidth(min_width)
            sb.addPermanentWidget(w)
            return w

        self.problems_button = QToolButton(self)
        self.problems_button.setAutoRaise(True)
        self.problems_button.setToolTip("Errors and warnings (show the Problems panel)")
        self.problems_button.clicked.connect(self.sig_show_problems)
        sb.addPermanentWidget(self.problems_button)
        self.connection_label = lab("connectionLabel", "The controller the IDE talks to")
        self.time_label = lab("timeLabel", "Simulated time on the controller", 90)
        self.running_label = lab("runningLabel", "The hardware procedure running", 80)
        self.proc_label = lab("procLabel", "proc: the running procedure's state code", 100)
        self.size_label = lab("sizeLabel", "Code size of this procedure against its limit "
                                           "(from the last compile)", 120)
        self.cursor_label = lab("cursorLabel", "Line and column of the caret", 110)
        self.eol_label = lab("eolLabel", "Encoding and line ends of the file (kept on save)")
        # the time changes five times a second: a label that keeps its width the status bar (and the window) out again each time
        # does not lay the status bar (and the window) out again each time; room
        # for the widest it shows (time_text), the label's margins counted
        m = self.time_label.contentsMargins()
        self.time_label.setFixedWidth(self.time_label.fontMetrics().horizontalAdvance(
            WIDEST_TIME) + m.left() + m.right() + 4)
        # (a fixed height too: Qt lays the parent out again unless both are fixed)
        self.time_label.setFixedHeight(self.time_label.sizeHint().height())
        self.time_label.setAlignment(Qt.AlignmentFlag.AlignRight | Qt.AlignmentFlag.AlignVCenter)
        self.show_problem_counts(0, 0)
        self.set_connection_text("no controller", False)
        self._message = ""                  # the message, whole
        self._shown = ""                    # ... as it shows (elided to the room there is)
        # the message's time: kept here, so that fitting it again to a new width
        # (showMessage again) does not start its time over
        self._expire = QTimer(self)
        self._expire.setSingleShot(True)
        self._expire.timeout.connect(self.clearMessage)
        # a message's tooltip goes when the message does
        self.messageChanged.connect(lambda text: text or self.setToolTip(""))
        for w in (self.problems_button, self.connection_label):     # its room's edge
            w.installEventFilter(self)

    def show_problem_counts(self, e: int, w: int) -> None:
        self.problems_button.setIcon(icon("error" if e else "warning" if w else "ok"))
        self.problems_button.setText(f" {e} error{'s' * (e != 1)}, {w} warning{'s' * (w != 1)}")
        self.problems_button.setToolButtonStyle(Qt.ToolButtonStyle.ToolButtonTextBesideIcon)

    def set_connection_text(self, text: str, connected: bool) -> None:
        self.connection_label.setText(("● " if connected else "○ ") + text)
        set_text_colour(self.connection_label, "#1a7f37" if connected else "#6e7781")

    def show_connected(self, address: str, embedded: bool) -> None:
        # the embedded controller's loopback port means nothing to a user: it is
        # in the tooltip, and the room goes to the messages
        self.set_connection_text("embedded controller" if embedded else f"controller {address}",
                                 True)
        self.connection_label.setToolTip(f"The controller the IDE talks to: {address}"
                                         + (" (the IDE's own, a child process)" if embedded
                                            else ""))

    # ------------------------------------------------------------- messages
    def showMessage(self, text: str, timeout: int = 0) -> None:  # noqa: N802 - Qt's name
        """A message left of the labels: elided with "…" where it does not fit
        (Qt cut it off mid-word), whole in the tooltip; fitted again when the
        room changes (the window is laid out, resized, a label grows)."""
        self._message = text
        self._fit()
        if timeout > 0:
            self._expire.start(timeout)
        else:
            self._expire.stop()

    def _fit(self) -> None:
        text = self._message
        room = self._message_room()
        shown = self.fontMetrics().elidedText(text, Qt.TextElideMode.ElideRight, room) \
            if room > 0 else text
        self.setToolTip(text if shown != text else "")
        self._shown = shown
        if shown != super().currentMessage():
            super().showMessage(shown)

    def eventFilter(self, obj, e) -> bool:  # noqa: N802 - Qt's name
        """The first labels moved (the bar was laid out, resized, a label grew):
        the message on show is fitted to its new room."""
        if e.type() in _ROOM_EVENTS and self._message \
                and super().currentMessage() == self._shown:
            self._fit()
        return False

    def currentMessage(self) -> str:  # noqa: N802 - Qt's name
        """The message on show, whole (even where it shows elided)."""
        return self._message if super().currentMessage() else ""

    def shown_message(self) -> str:
        """The message as the bar shows it (elided where it does not fit)."""
        return super().currentMessage()

    def clearMessage(self) -> None:  # noqa: N802 - Qt's name
        self._message = self._shown = ""
        self._expire.stop()
        self.setToolTip("")
        super().clearMessage()

    def _message_room(self) -> int:
        """The width left of the first shown label, or 0 before the bar is laid out."""
        lefts = [w.geometry().left() for w in (self.problems_button, self.connection_label)
                 if w.isVisible() and w.geometry().width() > 0]
        return (min(lefts) - 16) if lefts and self.isVisible() else 0

    def show_disconnected(self, reason: str) -> None:
        self.set_connection_text("disconnected", False)
        self.connection_label.setToolTip(f"Disconnected: {reason}")
        self.running_label.setText("–")         # nothing is known to run any more
        set_text_colour(self.running_label, None)
        self.proc_label.setText("")

    def show_state(self, st: ControllerStatus) -> None:
        # while nothing runs, whole seconds: the label repaints once a second, not five times
        busy = bool(st.running or st.software)
        self.time_label.setText(time_text(st.t_ms, busy))
        running = st.running
        self.running_label.setText(f"▶ {running}" if running else "idle")
        set_text_colour(self.running_label, "#1a7f37" if running else None, bold=bool(running))
        name = st.proc_name or api.proc_name(st.proc)
        self.proc_label.setText(f"proc {st.proc}" + (f" {name}" if name else ""))

    def show_editor(self, ed) -> None:
        """The caret and the line ends of the current editor (or None)."""
        if ed is not None:
            line, col = ed.cursor_line_col()
            self.show_cursor(line, col)
            self.eol_label.setText("UTF-8  " + ("CRLF" if ed.eol == "\r\n" else "LF") +
                                   ("  read-only" if ed.readOnly() else ""))
        else:
            self.cursor_label.setText("")
            self.eol_label.setText("")

    def show_cursor(self, line: int, col: int) -> None:
        self.cursor_label.setText(f"Ln {line}, Col {col}")

    def show_size(self, path: Optional[str], size: Optional[int] = None,
                  limit: Optional[int] = None) -> None:
        """A procedure's code size against its limit (no path: nothing)."""
        if path is None:
            self.size_label.setText("")
            set_text_colour(self.size_label, None)
            return
        used = "-" if size is None else str(size)
        self.size_label.setText(f"{Path(path).stem}: {used}/{limit} bytes")
        if size is not None and limit is not None and size > limit:
            set_text_colour(self.size_label, "#d1242f", bold=True)         # over the limit
        elif size is None or (limit is not None and size > 0.9 * limit):
            set_text_colour(self.size_label, "#9a6700")                    # unknown, or near it
        else:
            set_text_colour(self.size_label, None)
