"""What typing does in an editor: auto-indent, closing braces, completion and
call tips, comment toggling."""

from __future__ import annotations

from plcbuilder.ide import highlighter as hl
from plcbuilder.ide.offsets import char_to_byte, utf8_len
from plcbuilder.ide.editor.style import COMMENT_PREFIX


class KeysMixin:
    """Typing help, for :class:`~plcbuilder.ide.editor.widget.CodeEditor`."""

    # ============================================================ editing
    def indent_unit(self) -> int:
        return self.tabWidth()

    def toggle_comment(self) -> None:
        """Comment or uncomment the selected lines (or the caret's line) with //."""
        if self.readOnly():
            return
        start_line = self.lineFromPosition(self.selectionStart())
        end_pos = self.selectionEnd()
        end_line = self.lineFromPosition(end_pos)
        if end_line > start_line and end_pos == self.positionFromLine(end_line):
            end_line -= 1                      # a selection ending at a line start
        lines = list(range(start_line, end_line + 1))
        texts = {ln: self.line_text(ln) for ln in lines}
        code = [ln for ln in lines if texts[ln].strip()]
        if not code:
            return
        commented = all(texts[ln].lstrip().startswith(COMMENT_PREFIX) for ln in code)
        self.beginUndoAction()
        try:
            if commented:
                for ln in code:
                    t = texts[ln]
                    i = len(t) - len(t.lstrip())
                    n = len(COMMENT_PREFIX) + (1 if t[i + len(COMMENT_PREFIX):].startswith(" ") else 0)
                    start = self.positionFromLine(ln) + char_to_byte(t, i)
                    self.deleteRange(start, utf8_len(t[i:i + n]))
            else:
                col = min(len(texts[ln]) - len(texts[ln].lstrip()) for ln in code)
                for ln in code:
                    start = self.positionFromLine(ln) + char_to_byte(texts[ln], col)
                    self.insertText(start, COMMENT_PREFIX + " ")
        finally:
            self.endUndoAction()


    # ========================================================== completion
    def show_completions(self, explicit: bool = True) -> bool:
        """Open the completion list for the word before the caret."""
        if self.completion_provider is None:
            return False
        prefix = self.word_before_caret()
        if not explicit and len(prefix) < self.prefs.autocomplete_threshold:
            return False
        items = self.completion_provider(self, prefix)
        low = prefix.lower()
        items = [(n, k) for n, k in items if n.lower().startswith(low)]
        if not explicit and (not items or (len(items) == 1 and items[0][0] == prefix)):
            return False
        if not items:
            return False
        seen = set()
        entries = []
        for name, kind in items:
            if name not in seen:
                seen.add(name)
                entries.append(f"{name}?{kind}" if kind else name)
        self.autoCShow(utf8_len(prefix), " ".join(entries))
        return True

    def _in_comment_or_directive(self, pos: int) -> bool:
        self.highlighter.style_to(pos)
        st = self.styleAt(max(pos - 1, 0))
        return st in (hl.S_COMMENT, hl.S_PREPROC_FILE)

    def _on_char_added(self, ch: int) -> None:
        if ch == 10:
            self._auto_indent()
        elif ch == ord("}"):
            self._dedent_brace()
        elif ch == ord("("):
            self._show_signature()
        elif ch == ord(")"):
            if self.callTipActive():
                self.callTipCancel()
        elif (chr(ch).isalnum() or ch == ord("_")) and ch < 128:
            if self.prefs.autocomplete and not self.autoCActive() \
                    and not self._in_comment_or_directive(self.currentPos()):
                self.show_completions(explicit=False)

    def _show_signature(self) -> None:
        if self.signature_provider is None:
            return
        pos = self.currentPos() - 1
        p = pos
        while p > 0 and self.byte_at(p - 1) in (32, 9):
            p -= 1
        start = self.wordStartPosition(p, True)
        name = self.byte_range_text(start, p)
        if not name:
            return
        tip = self.signature_provider(name)
        if tip:
            self.callTipShow(pos, tip)

    def _auto_indent(self) -> None:
        line0 = self.lineFromPosition(self.currentPos())
        if line0 == 0:
            return
        prev = line0 - 1
        prev_text = self.line_text(prev)
        indent = self.lineIndentation(prev)
        code = prev_text.split("//")[0].rstrip()
        opens = code.endswith("{")
        if opens:
            indent += self.indent_unit()
        rest = self.line_text(line0)
        self.beginUndoAction()
        try:
            self.setLineIndentation(line0, indent)
            caret = self.lineIndentPosition(line0)
            if opens and rest.strip().startswith("}"):
                # Enter between { and }: the } goes one line further down
                self.insertText(caret, "\n")
                self.setLineIndentation(line0 + 1, indent - self.indent_unit())
            self.gotoPos(self.lineIndentPosition(line0))
        finally:
            self.endUndoAction()

    def _dedent_brace(self) -> None:
        pos = self.currentPos() - 1
        line0 = self.lineFromPosition(pos)
        before = self.byte_range_text(self.positionFromLine(line0), pos)
        if before.strip():
            return
        self.highlighter.style_to(self.lineEndPosition(line0))
        match = self.braceMatch(pos, 0)
        if match < 0:
            indent = max(0, self.lineIndentation(line0) - self.indent_unit())
        else:
            indent = self.lineIndentation(self.lineFromPosition(match))
        self.setLineIndentation(line0, indent)
        self.gotoPos(self.lineIndentPosition(line0) + 1)

