"""Back and Forward (Alt+Left / Alt+Right) over the places the caret jumped from.

A place is remembered when the caret leaves it by a jump: go to definition,
a click on a problem, a match, a reference, an outline entry or a disassembly
line, Go to Line, and a switch to another editor tab. Back returns to the
last place remembered (remembering where it was for Forward); a new jump
forgets the Forward list, as in a web browser. Places of files that are gone
are skipped.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Optional

from PySide6.QtCore import QObject, Signal

from plcbuilder.ide.editor import file_key

#: Places remembered at most.
LIMIT = 100


@dataclass(frozen=True)
class Location:
    path: str
    line: int
    col: int = 1

    def same_line(self, other: Optional["Location"]) -> bool:
        return other is not None and file_key(self.path) == file_key(other.path) and \
            self.line == other.line


class NavigationHistory(QObject):
    """The Back and Forward lists of one window's editors (an EditorStack)."""

    sig_changed = Signal(bool, bool)
    """Back / Forward became possible or not: (can go back, can go forward)."""

    def __init__(self, editors, parent=None):
        super().__init__(parent)
        self.editors = editors
        self.back_list: list[Location] = []
        self.forward_list: list[Location] = []
        self._moving = False
        self._last_editor = None
        editors.sig_current_changed.connect(self.on_current_changed)

    # ------------------------------------------------------------ public
    def here(self, ed=None) -> Optional[Location]:
        """The caret's place in ``ed`` (default: the current editor)."""
        ed = ed if ed is not None else self.editors.current_editor()
        if ed is None:
            return None
        try:
            line, col = ed.cursor_line_col()
        except RuntimeError:            # the editor's widget is gone
            return None
        return Location(ed.path, line, col)

    def record(self, where: Optional[Location] = None) -> None:
        """Remember ``where`` (default: the caret's place) before a jump."""
        if self._moving:
            return
        where = where or self.here()
        if where is None:
            return
        if not where.same_line(self.back_list[-1] if self.back_list else None):
            self.back_list.append(where)
            del self.back_list[:-LIMIT]
        self.forward_list.clear()
        self._emit()

    def can_go_back(self) -> bool:
        return bool(self.back_list)

    def can_go_forward(self) -> bool:
        return bool(self.forward_list)

    def back(self) -> bool:
        """Go to the last place remembered; False when there is none."""
        return self._go(self.back_list, self.forward_list)

    def forward(self) -> bool:
        return self._go(self.forward_list, self.back_list)

    def forget_file(self, path: str) -> None:
        """A file was deleted: its places go."""
        k = file_key(path)
        self.back_list = [loc for loc in self.back_list if file_key(loc.path) != k]
        self.forward_list = [loc for loc in self.forward_list if file_key(loc.path) != k]
        self._emit()

    def clear(self) -> None:
        self.back_list.clear()
        self.forward_list.clear()
        self._last_editor = None
        self._emit()

    # ------------------------------------------------------------ signals
    def on_current_changed(self, ed) -> None:
        """Another tab: the place left in the tab before is remembered."""
        prev, self._last_editor = self._last_editor, ed
        if prev is None or prev is ed or self._moving:
            return
        if prev not in self.editors.editors():
            return                      # closed
        where = self.here(prev)
        if where is not None:
            self.record(where)

    # ------------------------------------------------------------ private
    def _go(self, source: list[Location], other: list[Location]) -> bool:
        here = self.here()
        while source:
            target = source.pop()
            if target.same_line(here):
                continue
            if not target.path.startswith("<") and not Path(target.path).exists() and \
                    self.editors.editor_for(target.path) is None:
                continue
            if here is not None and not here.same_line(other[-1] if other else None):
                other.append(here)
            self._moving = True
            try:
                ed = self.editors.open_file(target.path, target.line, target.col)
                self._last_editor = self.editors.current_editor()
            finally:
                self._moving = False
            self._emit()
            return ed is not None
        self._emit()
        return False

    def _emit(self) -> None:
        self.sig_changed.emit(self.can_go_back(), self.can_go_forward())
