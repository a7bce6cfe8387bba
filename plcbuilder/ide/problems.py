"""The Problems panel: the errors and warnings of every open file and of the
last Build All, grouped by file; double-click (or Enter) jumps there —
into headers too.

:class:`ProblemStore` holds diagnostics by *source* (one compile of one
procedure, or the project-level checks of Build All): a newer compile of a
procedure replaces its older diagnostics wherever they point, and a
diagnostic that several procedures report (a header's) is listed once.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Iterable, Optional

from PySide6.QtCore import Qt, Signal
from PySide6.QtWidgets import (QHBoxLayout, QHeaderView, QLabel, QLineEdit, QToolButton,
                               QTreeWidget, QTreeWidgetItem, QVBoxLayout, QWidget)

from plcbuilder.api import Diagnostic, Severity
from plcbuilder.ide.editor import file_key
from plcbuilder.ide.icons import icon
from plcbuilder.ide.typing_pause import TypingPause

ROLE_LOCATION = Qt.ItemDataRole.UserRole + 1
PROJECT_GROUP = "<project>"
#: with more problems than this the filter runs once typing pauses (at 5,000,
#: each key rebuilt the list: 150-240 ms; see ide/typing_pause.py)
FILTER_AT_ONCE = 1000


class ProblemStore:
    """Diagnostics by source; see the module docstring."""

    def __init__(self):
        self._sources: dict[str, list[Diagnostic]] = {}

    def set(self, source: str, diagnostics: Iterable[Diagnostic]) -> None:
        self._sources[source] = list(diagnostics)

    def remove(self, source: str) -> None:
        self._sources.pop(source, None)

    def clear(self) -> None:
        self._sources.clear()

    def sources(self) -> list[str]:
        return list(self._sources)

    def for_source(self, source: str) -> list[Diagnostic]:
        """The diagnostics one source set (none: an empty list)."""
        return list(self._sources.get(source, ()))

    def all(self) -> list[Diagnostic]:
        """Every diagnostic once, sorted by file, line, column, severity."""
        seen = set()
        out = []
        for diags in self._sources.values():
            for d in diags:
                k = (d.severity, d.code, d.message, d.span)
                if k not in seen:
                    seen.add(k)
                    out.append(d)
        out.sort(key=lambda d: (d.span is None, d.sort_key(), d.severity))
        return out

    def for_file(self, path) -> list[Diagnostic]:
        key = file_key(path)
        return [d for d in self.all() if d.span is not None and file_key(d.span.file) == key]

    def counts(self) -> tuple[int, int]:
        diags = self.all()
        return (sum(1 for d in diags if d.severity == Severity.ERROR),
                sum(1 for d in diags if d.severity == Severity.WARNING))


class ProblemsPanel(QWidget):
    """The Problems dock's widget."""

    sig_open_location = Signal(str, int, int)
    """Open a file at (line, column): a problem was activated."""

    sig_counts_changed = Signal(int, int)
    """The number of (errors, warnings) listed changed."""

    def __init__(self, parent=None):
        super().__init__(parent)
        self.root: Optional[Path] = None
        self._diagnostics: list[Diagnostic] = []
        self._counts = (0, 0)
        lay = QVBoxLayout(self)
        lay.setContentsMargins(0, 0, 0, 0)
        lay.setSpacing(0)
        bar = QWidget(self)
        bl = QHBoxLayout(bar)
        bl.setContentsMargins(6, 3, 6, 3)
        bl.setSpacing(4)
        self.errors_button = QToolButton(bar)
        self.errors_button.setCheckable(True)
        self.errors_button.setChecked(True)
        self.errors_button.setIcon(icon("error"))
        self.errors_button.setToolButtonStyle(Qt.ToolButtonStyle.ToolButtonTextBesideIcon)
        self.errors_button.setAutoRaise(True)
        self.warnings_button = QToolButton(bar)
        self.warnings_button.setCheckable(True)
        self.warnings_button.setChecked(True)
        self.warnings_button.setIcon(icon("warning"))
        self.warnings_button.setToolButtonStyle(Qt.ToolButtonStyle.ToolButtonTextBesideIcon)
        self.warnings_button.setAutoRaise(True)
        self.filter_edit = QLineEdit(bar)
        self.filter_edit.setPlaceholderText("Filter (text or file)")
        self.filter_edit.setClearButtonEnabled(True)
        self.filter_edit.setMaximumWidth(260)
        self.summary = QLabel(bar)
        self.summary.setObjectName("problemsSummary")
        bl.addWidget(self.errors_button)
        bl.addWidget(self.warnings_button)
        bl.addSpacing(8)
        bl.addWidget(self.filter_edit)
        bl.addStretch(1)
        bl.addWidget(self.summary)
        lay.addWidget(bar)
        self.tree = QTreeWidget(self)
        self.tree.setColumnCount(3)
        self.tree.setHeaderLabels(["Problem", "Code", "Location"])
        self.tree.setRootIsDecorated(True)
        self.tree.setUniformRowHeights(True)
        self.tree.setAlternatingRowColors(False)
        self.tree.setFrameShape(QTreeWidget.Shape.NoFrame)
        header = self.tree.header()
        header.setSectionResizeMode(0, QHeaderView.ResizeMode.Stretch)
        header.setSectionResizeMode(1, QHeaderView.ResizeMode.ResizeToContents)
        header.setSectionResizeMode(2, QHeaderView.ResizeMode.ResizeToContents)
        header.setStretchLastSection(False)
        lay.addWidget(self.tree, 1)
        self.tree.itemActivated.connect(self._activate)
        self.tree.itemDoubleClicked.connect(self._activate)
        self.errors_button.toggled.connect(self._refill)
        self.warnings_button.toggled.connect(self._refill)
        self.typing = TypingPause(self.filter_edit, self._refill,
                                  lambda: len(self._diagnostics) > FILTER_AT_ONCE)
        self._update_buttons()

    # ---------------------------------------------------------------- public
    def set_root(self, root: Optional[Path]) -> None:
        self.root = Path(root) if root else None
        self._refill()

    def set_problems(self, diagnostics: list[Diagnostic]) -> None:
        """Show these diagnostics (replacing what was shown)."""
        if diagnostics == self._diagnostics:
            return
        self._diagnostics = list(diagnostics)
        self._refill()

    def diagnostics(self) -> list[Diagnostic]:
        return list(self._diagnostics)

    def counts(self) -> tuple[int, int]:
        return self._counts

    def problem_items(self) -> list[QTreeWidgetItem]:
        """The leaf items (one per problem shown), in order."""
        out = []
        for i in range(self.tree.topLevelItemCount()):
            group = self.tree.topLevelItem(i)
            for j in range(group.childCount()):
                out.append(group.child(j))
        return out

    def activate_item(self, item: QTreeWidgetItem) -> None:
        self._activate(item, 0)

    # --------------------------------------------------------------- private
    def display_name(self, file: str) -> str:
        if file == PROJECT_GROUP:
            return "Project"
        if file.startswith("<"):
            return file
        if self.root is not None:
            try:
                return os.path.relpath(file, self.root).replace(os.sep, "/")
            except ValueError:
                pass
        return file

    def _update_buttons(self) -> None:
        e, w = self._counts
        self.errors_button.setText(f"{e} error{'s' * (e != 1)}")
        self.warnings_button.setText(f"{w} warning{'s' * (w != 1)}")

    def _refill(self, *_args) -> None:
        self.typing.cancel()                 # (the filter's text is taken now)
        show_e = self.errors_button.isChecked()
        show_w = self.warnings_button.isChecked()
        needle = self.filter_edit.text().strip().lower()
        e = sum(1 for d in self._diagnostics if d.severity == Severity.ERROR)
        w = sum(1 for d in self._diagnostics if d.severity == Severity.WARNING)
        counts_changed = (e, w) != self._counts
        self._counts = (e, w)
        self._update_buttons()
        expanded = {self.tree.topLevelItem(i).data(0, ROLE_LOCATION)
                    for i in range(self.tree.topLevelItemCount())
                    if not self.tree.topLevelItem(i).isExpanded()}
        self.tree.setUpdatesEnabled(False)
        self.tree.clear()
        groups: dict[str, QTreeWidgetItem] = {}
        shown = 0
        for d in self._diagnostics:
            if d.severity == Severity.ERROR and not show_e:
                continue
            if d.severity != Severity.ERROR and not show_w:
                continue
            file = d.span.file if d.span is not None else PROJECT_GROUP
            name = self.display_name(file)
            if needle and needle not in d.message.lower() and needle not in name.lower() \
                    and needle not in d.code.lower():
                continue
            group = groups.get(file)
            if group is None:
                group = QTreeWidgetItem(self.tree)
                group.setText(0, name)
                group.setIcon(0, icon("file-header" if file.endswith(".h") else
                                      "project" if file == PROJECT_GROUP else "file-plc"))
                group.setData(0, ROLE_LOCATION, file)
                group.setToolTip(0, file)
                f = group.font(0)
                f.setBold(True)
                group.setFont(0, f)
                groups[file] = group
            item = QTreeWidgetItem(group)
            item.setIcon(0, icon("error" if d.severity == Severity.ERROR else "warning"))
            # a related note (a macro's define, a previous definition) is part of the row
            item.setText(0, d.message + "".join(
                f" — {r.message} ({Path(r.span.file).name}:{r.span.line})" for r in d.related))
            item.setText(1, d.code)
            if d.span is not None:
                item.setText(2, f"Ln {d.span.line}, Col {d.span.col}")
                item.setData(0, ROLE_LOCATION, (d.span.file, d.span.line, d.span.col))
            tip = d.message + "".join(f"\nhint: {h}" for h in d.hints) + \
                "".join(f"\nnote: {Path(r.span.file).name}:{r.span.line}: {r.message}"
                        for r in d.related)
            item.setToolTip(0, tip)
            shown += 1
        for file, group in groups.items():
            n = group.childCount()
            group.setText(2, f"{n} problem{'s' * (n != 1)}")
            group.setExpanded(file not in expanded)
        self.tree.setUpdatesEnabled(True)
        if not self._diagnostics:
            self.summary.setText("No problems")
        elif shown != len(self._diagnostics):
            self.summary.setText(f"showing {shown} of {len(self._diagnostics)}")
        else:
            self.summary.setText("")
        if counts_changed:
            self.sig_counts_changed.emit(e, w)

    def _activate(self, item: QTreeWidgetItem, _column: int = 0) -> None:
        loc = item.data(0, ROLE_LOCATION)
        if isinstance(loc, (tuple, list)) and len(loc) == 3:
            file, line, col = loc
            self.sig_open_location.emit(str(file), int(line), int(col))
        elif isinstance(loc, str) and loc != PROJECT_GROUP:
            self.sig_open_location.emit(loc, 1, 1)


def dock_panel(win, key: str):
    """The Problems dock's panel (docks.DOCKS): the window's problems list."""
    return win.problems
