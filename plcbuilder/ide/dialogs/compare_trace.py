"""File › Compare with Trace…: the trace file to compare the trace on show
with, and how to line the two up (the same times, the starts together, the
captures' triggers together), then moved by an offset in ms. Two captures of
one session (before and after a change) overlay with their triggers together."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

from PySide6.QtCore import QTimer
from PySide6.QtWidgets import (QButtonGroup, QDialog, QFileDialog, QFormLayout, QHBoxLayout,
                               QLabel, QLineEdit, QPushButton, QRadioButton, QSpinBox,
                               QVBoxLayout, QWidget)

from plcbuilder import api
from plcbuilder.ide.dialogs.common import error_label, fit_height, ok_cancel

TRACE_FILTER = "PLC Builder traces (*.plctrace);;All files (*)"
#: (the button's text, the align value, what it is for)
ALIGNMENTS = (("&Same times", "none", "compare tick for tick at the same times (a replay "
                                      "against its session)"),
              ("S&tarts together", "start", "the file's first tick under the first tick on "
                                            "show (two runs started at different moments)"),
              ("T&riggers together", "trigger", "the file's trigger under the trigger on show "
                                                "(two captures: before and after a change)"))
OFFSET_LIMIT = 2 ** 31 - 1


def describe(trace) -> str:
    """``0.110 .. 0.160 s, trigger out 3 rise at 0.120 s`` (or ``no trigger``)."""
    from plcbuilder.trace.compare import trigger_ms
    span = f"{trace.t_start / 1000:.3f} .. {trace.t_end / 1000:.3f} s"
    t = trigger_ms(trace)
    if t is None:
        return f"{span}, no trigger"
    return f"{span}, trigger {trace.meta['trigger'].get('spec', '?')} at {t / 1000:.3f} s"


class CompareDialog(QDialog):
    """The file and the alignment; :meth:`get` runs it."""

    def __init__(self, parent=None, base=None, base_name: str = "the trace on show",
                 folder: str = "", path: Optional[str] = None):
        super().__init__(parent)
        self.setWindowTitle("Compare with Trace")
        self.base = base
        self.folder = folder
        self.other = None                       # the file's trace, once it reads
        self._chosen_by_user = False            # an alignment the user picked stays
        self._auto = False
        lay = QVBoxLayout(self)
        self.on_show = QLabel(f"On show: {base_name}"
                              + (f" ({describe(base)})" if base is not None else ""), self)
        self.on_show.setWordWrap(True)
        lay.addWidget(self.on_show)
        form = QFormLayout()
        row = QHBoxLayout()
        self.path = QLineEdit(self)
        self.path.setPlaceholderText("a .plctrace file")
        self.path.editingFinished.connect(self._read)
        # typed: read the file once the typing stops
        self._typed = QTimer(self)
        self._typed.setSingleShot(True)
        self._typed.setInterval(300)
        self._typed.timeout.connect(self._read)
        self.path.textEdited.connect(lambda _t: self._typed.start())
        self.browse = QPushButton("&Browse…", self)
        self.browse.clicked.connect(self._browse)
        row.addWidget(self.path, 1)
        row.addWidget(self.browse)
        holder = QWidget(self)
        holder.setLayout(row)
        row.setContentsMargins(0, 0, 0, 0)
        form.addRow("&Trace file:", holder)
        self.info = QLabel(self)
        self.info.setWordWrap(True)
        form.addRow("", self.info)
        self.group = QButtonGroup(self)
        line_up = QVBoxLayout()
        self.buttons: dict[str, QRadioButton] = {}
        for text, value, tip in ALIGNMENTS:
            b = QRadioButton(text, self)
            b.setToolTip(tip)
            self.group.addButton(b)
            self.buttons[value] = b
            line_up.addWidget(b)
            b.toggled.connect(self._touched)
        self._choose("none")
        box = QWidget(self)
        box.setLayout(line_up)
        line_up.setContentsMargins(0, 0, 0, 0)
        form.addRow("Line up:", box)
        self.offset = QSpinBox(self)
        self.offset.setRange(-OFFSET_LIMIT, OFFSET_LIMIT)
        self.offset.setSuffix(" ms")
        self.offset.setToolTip("then move the file's trace by this much more (later: positive)")
        form.addRow("Then &move by:", self.offset)
        lay.addLayout(form)
        self.error = error_label(self)
        lay.addWidget(self.error)
        self.box = ok_cancel(self, lay)
        self.box.button(self.box.StandardButton.Ok).setText("&Compare")
        self.resize(560, self.sizeHint().height())
        if path:
            self.path.setText(str(path))
            self._read()
        self._update()
        fit_height(self)

    # ---------------------------------------------------------------- file
    def _browse(self) -> None:
        start = str(Path(self.path.text()).parent) if self.path.text() else self.folder
        path, _ = QFileDialog.getOpenFileName(self, "Compare with Trace", start, TRACE_FILTER)
        if path:
            self.path.setText(path)
            self._read()

    def _read(self) -> None:
        """Read the file named (to say what it holds and whether it has a trigger)."""
        self._typed.stop()
        text = self.path.text().strip()
        if text == getattr(self, "_read_path", None):
            return
        self._read_path = text
        self.other = None
        if not text:
            self.info.setText("")
        else:
            try:
                self.other = api.load_trace(text)
                self.info.setText(describe(self.other))
                self.info.setStyleSheet("")
            except api.TraceFileError as exc:
                self.info.setText(str(exc))
                self.info.setStyleSheet("color: #c62828;")
        both = self.other is not None and self.base is not None and \
            _has_trigger(self.other) and _has_trigger(self.base)
        if both and not self._chosen_by_user:
            self._choose("trigger")
        self._update()

    def _choose(self, value: str) -> None:
        """Select an alignment for the user (not as their choice)."""
        self._auto = True
        try:
            self.buttons[value].setChecked(True)
        finally:
            self._auto = False

    def _touched(self, on: bool) -> None:
        if on and not self._auto:
            self._chosen_by_user = True
            self._update()

    # ----------------------------------------------------------- alignment
    def align(self) -> str:
        return next(v for v, b in self.buttons.items() if b.isChecked())

    def _update(self) -> None:
        trig = self.buttons["trigger"]
        base_ok = self.base is None or _has_trigger(self.base)
        other_ok = self.other is None or _has_trigger(self.other)
        trig.setEnabled(base_ok and other_ok)
        if not trig.isEnabled():
            trig.setToolTip("needs a trigger in both traces: "
                            + ("the trace on show has none" if not base_ok else
                               "the file has none"))
            if trig.isChecked():
                self._choose("none")
        else:
            trig.setToolTip(ALIGNMENTS[2][2])
        self.error.setText("" if self.other is not None or not self.path.text().strip()
                           else "choose a trace file that can be read")
        self.box.button(self.box.StandardButton.Ok).setEnabled(self.other is not None)

    def values(self) -> tuple[str, str, int]:
        return self.path.text().strip(), self.align(), self.offset.value()

    @classmethod
    def get(cls, parent=None, base=None, base_name: str = "the trace on show",
            folder: str = "", path: Optional[str] = None) -> Optional[tuple[str, str, int]]:
        """(the file, the alignment, the offset in ms), or None when cancelled."""
        d = cls(parent, base, base_name, folder, path)
        if d.exec() != QDialog.DialogCode.Accepted:
            return None
        return d.values()


def _has_trigger(trace) -> bool:
    from plcbuilder.trace.compare import trigger_ms
    return trigger_ms(trace) is not None
