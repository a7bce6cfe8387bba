"""Diagnostics in an editor: squiggles, margin markers and hover text."""

from __future__ import annotations

from typing import Iterable, Optional

from plcbuilder.api import Diagnostic, Severity
from plcbuilder.ide.editor.style import (IND_ERROR, IND_WARNING, MARGIN_SYMBOLS, MK_COVERED,
                                         MK_ERROR, MK_UNCOVERED, MK_WARNING)


class DiagnosticsMixin:
    """Diagnostics and hover, for :class:`~plcbuilder.ide.editor.widget.CodeEditor`."""

    # ======================================================== diagnostics
    def set_diagnostics(self, diagnostics: Iterable[Diagnostic]) -> None:
        """Show these diagnostics (already filtered to this file): squiggles,
        margin markers, and hover text."""
        self.clear_indicator(IND_ERROR)
        self.clear_indicator(IND_WARNING)
        self.markerDeleteAll(MK_ERROR)
        self.markerDeleteAll(MK_WARNING)
        ranges = []
        marked: dict[int, int] = {}
        for d in diagnostics:
            s = d.span
            if s is None:
                continue
            start, end = self.diagnostic_range(d)
            ranges.append((start, end, d))
            ind = IND_ERROR if d.severity == Severity.ERROR else IND_WARNING
            self.setIndicatorCurrent(ind)
            if end > start:
                self.indicatorFillRange(start, end - start)
            line0 = self.lineFromPosition(start)
            mk = MK_ERROR if d.severity == Severity.ERROR else MK_WARNING
            if line0 not in marked or (marked[line0] == MK_WARNING and mk == MK_ERROR):
                if line0 in marked:
                    self.markerDelete(line0, marked[line0])
                self.markerAdd(line0, mk)
                marked[line0] = mk
        self._diag_ranges = ranges

    def set_coverage(self, covered: Iterable[int], uncovered: Iterable[int]) -> None:
        """Mark test coverage in the margin: a green bar beside the lines that
        ran, a red one beside the lines with code that did not (1-based lines;
        both empty: no marks)."""
        from pyside6_scintilla import Scintilla
        for mk, colour in ((MK_COVERED, 0x3A9E3A), (MK_UNCOVERED, 0x2626D9)):   # BGR
            self.markerDefine(mk, int(Scintilla.MarkerSymbol.LeftRect))
            self.markerSetBack(mk, colour)
            self.markerDeleteAll(mk)
        self.setMarginMaskN(MARGIN_SYMBOLS, self.marginMaskN(MARGIN_SYMBOLS)
                            | (1 << MK_COVERED) | (1 << MK_UNCOVERED))
        for mk, lines in ((MK_COVERED, covered), (MK_UNCOVERED, uncovered)):
            for line in lines:
                if 1 <= line <= self.lineCount():
                    self.markerAdd(line - 1, mk)

    def diagnostic_range(self, d: Diagnostic) -> tuple[int, int]:
        """The byte range a diagnostic's span covers in this document (at least
        one character, so that a point at a line's end still shows)."""
        s = d.span
        start = self.position_of(s.line, s.col)
        end = self.position_of(s.end_line, s.end_col) if (s.end_line, s.end_col) > (s.line, s.col) \
            else start
        if end <= start:
            # a point: the whole word there, or the one it follows ("expected ';'
            # after '1'"), not one character (nor an invisible space)
            line_end = self.lineEndPosition(self.lineFromPosition(start))
            word_start = self.wordStartPosition(start, True)
            word_end = self.wordEndPosition(start, True)
            if word_end > start:
                start, end = word_start, word_end
            elif word_start < start:
                end = start
                start = word_start
            elif start < line_end:
                end = self.positionAfter(start)
            elif start > self.positionFromLine(self.lineFromPosition(start)):
                start = self.positionBefore(start)      # at a line end: the char before
                end = line_end
            else:
                end = start
        return start, end

    def diagnostics_at(self, pos: int) -> list[Diagnostic]:
        out = []
        for s, e, d in self._diag_ranges:
            if s <= pos < e or (s == e == pos):
                out.append(d)
        if not out:
            line0 = self.lineFromPosition(pos)
            for s, e, d in self._diag_ranges:
                if self.lineFromPosition(s) == line0 and s <= pos <= e:
                    out.append(d)
        return out

    def diagnostic_lines(self) -> dict[int, int]:
        """{1-based line: marker} of the diagnostics shown (for tests)."""
        out = {}
        line = self.markerNext(0, (1 << MK_ERROR) | (1 << MK_WARNING))
        while line >= 0:
            bits = self.markerGet(line)
            out[line + 1] = MK_ERROR if bits & (1 << MK_ERROR) else MK_WARNING
            line = self.markerNext(line + 1, (1 << MK_ERROR) | (1 << MK_WARNING))
        return out

    def indicator_ranges(self, indicator: int) -> list[tuple[int, int]]:
        """Every (start, end) byte range where indicator is set."""
        out = []
        pos = 0
        length = self.length()
        while pos < length:
            if self.indicatorValueAt(indicator, pos):
                end = self.indicatorEnd(indicator, pos)
                out.append((pos, end))
                pos = max(end, pos + 1)
            else:
                nxt = self.indicatorEnd(indicator, pos)
                if nxt <= pos:
                    break
                pos = nxt
        return out

    # =============================================================== hover
    def hover_text_at(self, pos: int) -> Optional[str]:
        """What hovering over pos shows: the diagnostics there, then help."""
        parts = []
        for d in self.diagnostics_at(pos):
            label = "error" if d.severity == Severity.ERROR else d.severity.label
            parts.append(f"{label}: {d.message}")
            parts.extend(f"  hint: {h}" for h in d.hints)
            parts.extend(f"  note: {r.span.file.rsplit('/', 1)[-1]}:{r.span.line}: {r.message}"
                         for r in d.related)
        if self.hover_provider is not None and self.prefs.hover:
            try:
                extra = self.hover_provider(self, pos)
            except Exception:  # noqa: BLE001 - hover help must never break the editor
                extra = None
            if extra:
                if parts:
                    parts.append("")
                parts.append(extra)
        return "\n".join(parts) if parts else None

    def _on_dwell_start(self, x: int, y: int) -> None:
        if self.autoCActive():
            return
        pos = self.charPositionFromPointClose(x, y)
        if pos < 0:
            return
        text = self.hover_text_at(pos)
        if text:
            self.callTipShow(pos, text)
