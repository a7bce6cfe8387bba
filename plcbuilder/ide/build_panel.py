"""Build All's output panel.

:class:`BuildPanel` shows the output the way a compiler prints it — one line
per procedure with its size against its limit, every diagnostic with its
source line and caret, the hardware total, the image — and double-clicking a
diagnostic opens its file at its line. The build itself runs in
:class:`~plcbuilder.ide.build_runner.BuildRunner` (given here too).
"""

from __future__ import annotations

import re
import time
from pathlib import Path

from PySide6.QtCore import Qt, Signal
from PySide6.QtGui import QColor, QFont, QFontDatabase, QTextCharFormat, QTextCursor
from PySide6.QtWidgets import (QHBoxLayout, QLabel, QPlainTextEdit, QProgressBar, QToolButton,
                               QVBoxLayout, QWidget)

from plcbuilder.api import render_text
from plcbuilder.ide.build_runner import BuildRunner  # noqa: F401 - given here too
from plcbuilder.ide.icons import icon

_LOCATION_RE = re.compile(r"^(?P<file>.+?):(?P<line>\d+):(?P<col>\d+): (error|warning|note)")

COLOURS = {"error": "#d1242f", "warning": "#9a6700", "ok": "#1a7f37", "dim": "#6e7781",
           "head": "#3a74c9", "text": None, "note": "#6e7781"}


class BuildPanel(QWidget):
    """The Build Output dock's widget."""

    sig_open_location = Signal(str, int, int)
    """Open a file at (line, column): a diagnostic line was double-clicked."""

    def __init__(self, parent=None):
        super().__init__(parent)
        self._locations: dict[int, tuple[str, int, int]] = {}
        lay = QVBoxLayout(self)
        lay.setContentsMargins(0, 0, 0, 0)
        lay.setSpacing(0)
        bar = QWidget(self)
        bl = QHBoxLayout(bar)
        bl.setContentsMargins(6, 2, 6, 2)
        self.status = QLabel("No build yet", bar)
        self.progress = QProgressBar(bar)
        self.progress.setMaximumWidth(160)
        self.progress.setMaximumHeight(14)
        self.progress.setTextVisible(False)
        self.progress.hide()
        self.clear_button = QToolButton(bar)
        self.clear_button.setIcon(icon("clear"))
        self.clear_button.setToolTip("Clear the output")
        self.clear_button.setAutoRaise(True)
        bl.addWidget(self.status, 1)
        bl.addWidget(self.progress)
        bl.addWidget(self.clear_button)
        lay.addWidget(bar)
        self.text = QPlainTextEdit(self)
        self.text.setReadOnly(True)
        self.text.setFrameShape(QPlainTextEdit.Shape.NoFrame)
        self.text.setLineWrapMode(QPlainTextEdit.LineWrapMode.NoWrap)
        self.text.setMaximumBlockCount(20000)
        font = QFontDatabase.systemFont(QFontDatabase.SystemFont.FixedFont)
        self.text.setFont(font)
        self.text.viewport().setCursor(Qt.CursorShape.IBeamCursor)
        self.text.mouseDoubleClickEvent = self._double_click
        lay.addWidget(self.text, 1)
        self.clear_button.clicked.connect(self.clear)

    # ---------------------------------------------------------------- public
    def clear(self) -> None:
        self.text.clear()
        self._locations.clear()

    def forget(self) -> None:
        """Another project (or none): its build is not this one's."""
        self.clear()
        self.status.setText("No build yet")

    def plain_text(self) -> str:
        return self.text.toPlainText()

    def append(self, line: str, kind: str = "text", location=None, bold=False) -> None:
        cursor = self.text.textCursor()
        cursor.movePosition(QTextCursor.MoveOperation.End)
        fmt = QTextCharFormat()
        colour = COLOURS.get(kind)
        if colour:
            fmt.setForeground(QColor(colour))
        if bold:
            fmt.setFontWeight(QFont.Weight.Bold)
        if self.text.document().isEmpty():
            cursor.insertText(line, fmt)
        else:
            cursor.insertBlock()
            cursor.insertText(line, fmt)
        if location is not None:
            self._locations[cursor.blockNumber()] = location
        self.text.setTextCursor(cursor)
        self.text.ensureCursorVisible()

    def begin(self, project) -> None:
        """A build of project starts."""
        self.clear()
        stamp = time.strftime("%H:%M:%S")
        self.append(f"Build All: {project.name}  ({project.root})    {stamp}", "head", bold=True)
        self.status.setText("Building…")
        self.progress.setRange(0, 0)
        self.progress.show()

    def on_progress(self, done: int, total: int, name: str) -> None:
        self.progress.setRange(0, max(total, 1))
        self.progress.setValue(done)
        if name:
            self.status.setText(f"Building… {done}/{total} {name}")

    def show_result(self, result, elapsed: float = 0.0) -> None:
        """The result of a build (a BuildResult or the exception it raised)."""
        self.progress.hide()
        if isinstance(result, BaseException):
            self.append(f"Build failed: {type(result).__name__}: {result}", "error", bold=True)
            self.status.setText("Build failed")
            return
        root = result.project.root
        width = max([len(p.name) for p in result.procedures] + [8])
        for pb in result.procedures:
            errors, warns = pb.errors, pb.warnings
            size = f"{pb.size}/{pb.limit} bytes" if pb.size is not None else f"-/{pb.limit} bytes"
            if errors:
                state, kind = f"{errors} error{'s' * (errors != 1)}", "error"
            elif warns:
                state, kind = f"ok, {warns} warning{'s' * (warns != 1)}", "warning"
            else:
                state, kind = "ok", "ok"
            cached = "  (unchanged)" if pb.cached else ""
            self.append(f"  {pb.name:<{width}}  {pb.kind.label:<8}  {size:>17}  {state}{cached}",
                        kind, (str(pb.path), 1, 1))
        diags = [(d, pb.source_line) for pb in result.procedures if pb.errors or pb.warnings
                 for d in pb.diagnostics] + [(d, result.source_line) for d in result.diagnostics]
        if diags:
            self.append("")
        for d, source_line in diags:
            kind = "error" if d.is_error else "warning"
            text = render_text(d, source_line)
            for i, line in enumerate(text.split("\n")):
                loc = (d.span.file, d.span.line, d.span.col) if d.span is not None else None
                shown = _relative(line, root) if i == 0 else line
                self.append(shown, kind if i == 0 else ("dim" if line.startswith("    ") else "note"),
                            loc)
        self.append("")
        self.append(f"Hardware procedures: {result.hw_total}/{result.limits.hw_total} bytes", "dim")
        self.append(result.image_message, "ok" if result.image_written else "warning")
        e, w = result.error_count, result.warning_count
        verdict = "Build succeeded" if result.ok else "Build failed"
        extra = f"{elapsed:.2f} s; {result.compiled} compiled, {result.reused} unchanged"
        self.append(f"{verdict}: {e} error{'s' * (e != 1)}, {w} warning{'s' * (w != 1)} ({extra})",
                    "ok" if result.ok else "error", bold=True)
        self.status.setText(f"{verdict} — {e} error{'s' * (e != 1)}, {w} warning{'s' * (w != 1)}")

    def location_at_line(self, block: int):
        return self._locations.get(block)

    def activate_line(self, block: int) -> bool:
        loc = self._locations.get(block)
        if loc is None:
            line = self.text.document().findBlockByNumber(block).text()
            m = _LOCATION_RE.match(line)
            if not m:
                return False
            loc = (m.group("file"), int(m.group("line")), int(m.group("col")))
        self.sig_open_location.emit(str(loc[0]), int(loc[1]), int(loc[2]))
        return True

    # --------------------------------------------------------------- private
    def _double_click(self, event) -> None:
        cursor = self.text.cursorForPosition(event.position().toPoint())
        self.activate_line(cursor.blockNumber())


def _relative(line: str, root: Path) -> str:
    prefix = str(root).rstrip("/\\") + "/"
    return line[len(prefix):] if line.startswith(prefix) else line


def dock_panel(win, key: str) -> "BuildPanel":
    """The Build Output dock's panel (docks.DOCKS), made when it first shows
    or a build needs it."""
    panel = BuildPanel(win)
    panel.sig_open_location.connect(win.open_location)
    return panel
