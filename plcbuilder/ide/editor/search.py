"""Find, replace and highlight matches in an editor (the find bar's engine)."""

from __future__ import annotations

from typing import Optional

from plcbuilder.ide.offsets import utf8_len
from plcbuilder.ide.editor.style import (FIND_CXX11REGEX, FIND_MATCHCASE, FIND_REGEXP,
                                         FIND_WHOLEWORD, IND_FIND)


class SearchMixin:
    """Find and replace, for :class:`~plcbuilder.ide.editor.widget.CodeEditor`."""

    @staticmethod
    def search_flags(case: bool = False, whole: bool = False, regex: bool = False) -> int:
        f = 0
        if case:
            f |= FIND_MATCHCASE
        if whole:
            f |= FIND_WHOLEWORD
        if regex:
            f |= FIND_REGEXP | FIND_CXX11REGEX
        return f

    def find(self, text: str, flags: int = 0, *, forward: bool = True, wrap: bool = True,
             from_pos: Optional[int] = None) -> bool:
        """Select the next (or previous) match of text; False when there is none."""
        if not text:
            return False
        n = utf8_len(text)
        length = self.length()
        if forward:
            start = self.selectionEnd() if from_pos is None else from_pos
            ranges = [(start, length)] + ([(0, start)] if wrap else [])
        else:
            start = self.selectionStart() if from_pos is None else from_pos
            ranges = [(start, 0)] + ([(length, start)] if wrap else [])
        self.setSearchFlags(flags)
        for a, b in ranges:
            self.setTargetRange(a, b)
            found = self.searchInTarget(n, text)
            if found >= 0:
                s, e = self.targetStart(), self.targetEnd()
                self.ensureVisible(self.lineFromPosition(s))
                self.setSel(s, e)
                self.scrollRange(e, s)
                return True
        return False

    def _matches_selection(self, text: str, flags: int) -> bool:
        s, e = self.selectionStart(), self.selectionEnd()
        if s == e:
            return False
        self.setSearchFlags(flags)
        self.setTargetRange(s, e)
        return self.searchInTarget(utf8_len(text), text) == s and self.targetEnd() == e

    def replace(self, text: str, replacement: str, flags: int = 0) -> bool:
        """Replace the selected match (if the selection is one) and find the next."""
        if self.readOnly() or not text:
            return False
        if self._matches_selection(text, flags):
            if flags & FIND_REGEXP:
                self.replaceTargetRE(utf8_len(replacement), replacement)
            else:
                self.replaceTarget(utf8_len(replacement), replacement)
            self.setSel(self.targetEnd(), self.targetEnd())
        return self.find(text, flags)

    def replace_all(self, text: str, replacement: str, flags: int = 0) -> int:
        """Replace every match; returns how many (one undo step)."""
        if self.readOnly() or not text:
            return 0
        count = 0
        pos = 0
        n = utf8_len(text)
        rn = utf8_len(replacement)
        self.setSearchFlags(flags)
        self.beginUndoAction()
        try:
            while True:
                self.setTargetRange(pos, self.length())
                if self.searchInTarget(n, text) < 0:
                    break
                start, end = self.targetStart(), self.targetEnd()
                if flags & FIND_REGEXP:
                    self.replaceTargetRE(rn, replacement)
                else:
                    self.replaceTarget(rn, replacement)
                count += 1
                pos = self.targetEnd()
                if end == start:           # an empty regex match: step on
                    pos += 1
                if pos > self.length():
                    break
        finally:
            self.endUndoAction()
        return count

    def highlight_matches(self, text: str, flags: int = 0, limit: int = 5000) -> int:
        """Mark every match with the find indicator; returns the count."""
        self.clear_indicator(IND_FIND)
        if not text:
            return 0
        count = 0
        pos = 0
        n = utf8_len(text)
        self.setSearchFlags(flags)
        self.setIndicatorCurrent(IND_FIND)
        while count < limit:
            self.setTargetRange(pos, self.length())
            if self.searchInTarget(n, text) < 0:
                break
            s, e = self.targetStart(), self.targetEnd()
            if e > s:
                self.indicatorFillRange(s, e - s)
            count += 1
            pos = max(e, s + 1)
        return count

    def clear_indicator(self, indicator: int) -> None:
        self.setIndicatorCurrent(indicator)
        self.indicatorClearRange(0, self.length())
