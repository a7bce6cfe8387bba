"""Find in Files (Ctrl+Shift+F): a text or regular expression searched in
every source and header of the project — the open editors' text, unsaved
changes included — with the matches listed by file; a click opens the line.

:func:`search` is pure (texts in, matches out) so it is tested without widgets.
"""

from __future__ import annotations

import re
from typing import Callable, Mapping, Optional

from PySide6.QtCore import Qt, Signal
from PySide6.QtWidgets import (QCheckBox, QHBoxLayout, QLabel, QLineEdit, QToolButton,
                               QVBoxLayout, QWidget)

from plcbuilder.ide.icons import icon
from plcbuilder.ide.panels.results import Hit, ResultsTree

#: Matches listed at most (the summary says when there were more).
MAX_HITS = 5000


class SearchError(ValueError):
    """The pattern is not a valid regular expression (the message says why)."""


def compile_pattern(text: str, *, regex: bool = False, case: bool = False,
                    whole_word: bool = False) -> re.Pattern:
    """The pattern to search for; raises SearchError for a bad regular expression."""
    flags = 0 if case else re.IGNORECASE
    body = text if regex else re.escape(text)
    try:
        pattern = re.compile(body, flags)      # alone first: wrapped, a stray [ could close
    except re.error as exc:
        raise SearchError(f"not a valid regular expression: {exc}") from None
    if whole_word:
        pattern = re.compile(rf"(?<![A-Za-z0-9_])(?:{body})(?![A-Za-z0-9_])", flags)
    return pattern


def search(sources: Mapping[str, str], text: str, *, regex: bool = False, case: bool = False,
           whole_word: bool = False, limit: int = MAX_HITS) -> tuple[list[Hit], bool]:
    """Every match of ``text`` in the texts, file by file, line by line:
    (hits, whether the limit cut the list short). Empty matches are skipped."""
    if not text:
        return [], False
    pattern = compile_pattern(text, regex=regex, case=case, whole_word=whole_word)
    hits: list[Hit] = []
    for path, body in sources.items():
        for n, line in enumerate(body.replace("\r\n", "\n").replace("\r", "\n").split("\n"), 1):
            for m in pattern.finditer(line):
                if m.end() == m.start():
                    continue
                if len(hits) >= limit:
                    return hits, True
                hits.append(Hit(path, n, m.start() + 1, m.end() + 1, line))
    return hits, False


class FindInFilesPanel(QWidget):
    """The search row (pattern, Regex, Match case, Whole word) over the results."""

    sig_open_location = Signal(str, int, int)
    """Open a match: file, line, column."""

    def __init__(self, parent=None):
        super().__init__(parent)
        #: () -> {path: text} of the files to search (set by the window)
        self.sources_provider: Optional[Callable[[], Mapping[str, str]]] = None
        self.pattern = QLineEdit(self)
        self.pattern.setPlaceholderText("Find in the project's files…")
        self.pattern.setClearButtonEnabled(True)
        self.pattern.returnPressed.connect(self.run_search)
        self.regex = QCheckBox("Regex", self)
        self.case = QCheckBox("Match case", self)
        self.whole_word = QCheckBox("Whole word", self)
        for box in (self.regex, self.case, self.whole_word):
            box.toggled.connect(lambda _on: self.pattern.text() and self.run_search())
        go = QToolButton(self)
        go.setIcon(icon("find"))
        go.setToolTip("Search (Enter)")
        go.clicked.connect(self.run_search)
        self.summary = QLabel("", self)
        self.summary.setTextInteractionFlags(Qt.TextInteractionFlag.TextSelectableByMouse)
        self.tree = ResultsTree(self)
        self.tree.sig_open_location.connect(self.sig_open_location)
        row = QHBoxLayout()
        row.setContentsMargins(4, 3, 4, 0)
        row.addWidget(self.pattern, 1)
        row.addWidget(go)
        for w in (self.regex, self.case, self.whole_word):
            row.addWidget(w)
        lay = QVBoxLayout(self)
        lay.setContentsMargins(0, 0, 0, 0)
        lay.setSpacing(2)
        lay.addLayout(row)
        lay.addWidget(self.summary)
        lay.addWidget(self.tree, 1)
        self.summary.setContentsMargins(6, 0, 6, 0)

    def focus_pattern(self, text: str = "") -> None:
        """Put the caret in the search box (with ``text``, e.g. the editor's
        selection, when given) and select it."""
        if text:
            self.pattern.setText(text)
        self.pattern.setFocus(Qt.FocusReason.ShortcutFocusReason)
        self.pattern.selectAll()

    def run_search(self) -> int:
        """Search now; returns the number of matches listed."""
        text = self.pattern.text()
        sources = dict(self.sources_provider()) if self.sources_provider else {}
        try:
            hits, more = search(sources, text, regex=self.regex.isChecked(),
                                case=self.case.isChecked(),
                                whole_word=self.whole_word.isChecked())
        except SearchError as exc:
            self.tree.clear()
            self.summary.setText(str(exc))
            self.summary.setStyleSheet("color: #c62828;")
            return 0
        self.summary.setStyleSheet("")
        n = self.tree.set_hits(hits)
        files = len({h.file for h in hits})
        if not text:
            self.summary.setText("")
        elif not hits:
            self.summary.setText(f"No match for “{text}” in {len(sources)} files")
        else:
            self.summary.setText(f"{n}{'+' if more else ''} match{'es' * (n != 1)} in "
                                 f"{files} file{'s' * (files != 1)}"
                                 + (f" (only the first {n} are listed)" if more else ""))
        return n
