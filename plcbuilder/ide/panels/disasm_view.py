"""The Disassembly dock: the code of the current editor's procedure, as
``plcbuilder disasm`` prints it, from the disassembler's records
(:func:`plcbuilder.api.instructions`) of the last check of the file.

Each procedure of the program lists the source lines it compiled, each with
its bytes and its instructions (offset, bytes, opcode, operand) under it. A
double-click on a line opens it; the line at the editor's caret is selected
as the caret moves. The header says the code size against the limit.
"""

from __future__ import annotations

from pathlib import Path
from typing import Callable, Optional

from PySide6.QtCore import Qt, Signal
from PySide6.QtGui import QBrush, QColor, QFont, QFontDatabase
from PySide6.QtWidgets import (QHeaderView, QLabel, QTreeWidget, QTreeWidgetItem, QVBoxLayout,
                               QWidget)

from plcbuilder.ide.code_bytes import instructions_of, resolve
from plcbuilder.ide.editor import file_key

ROLE_LOCATION = Qt.ItemDataRole.UserRole + 1


class DisasmView(QWidget):
    """The disassembly of one procedure with its source lines beside it."""

    sig_open_location = Signal(str, int, int)
    """Open this source line: file, line, column."""

    def __init__(self, parent=None):
        super().__init__(parent)
        #: (path, line) -> the line's text (an open editor's text first); set by the window
        self.source_line: Optional[Callable[[str, int], Optional[str]]] = None
        self.path: Optional[str] = None
        self.header = QLabel("No procedure open", self)
        self.header.setContentsMargins(6, 3, 6, 3)
        self.header.setWordWrap(True)
        self.tree = QTreeWidget(self)
        self.tree.setColumnCount(4)
        self.tree.setHeaderLabels(["Offset", "Bytes", "Instruction", "Operand"])
        self.tree.setUniformRowHeights(True)
        self.tree.setAlternatingRowColors(True)
        self.tree.header().setStretchLastSection(True)
        self.tree.header().setSectionResizeMode(QHeaderView.ResizeMode.Interactive)
        mono = QFontDatabase.systemFont(QFontDatabase.SystemFont.FixedFont)
        self.tree.setFont(mono)
        self.tree.itemActivated.connect(self._on_item)
        self.tree.itemDoubleClicked.connect(self._on_item)
        lay = QVBoxLayout(self)
        lay.setContentsMargins(0, 0, 0, 0)
        lay.setSpacing(0)
        lay.addWidget(self.header)
        lay.addWidget(self.tree)
        self._line_items: dict[tuple[str, int], QTreeWidgetItem] = {}
        self._bytes: dict[int, int] = {}          # id(line item) -> its bytes

    # ------------------------------------------------------------ public
    def clear_view(self, why: str) -> None:
        self.tree.clear()
        self._line_items = {}
        self.header.setText(why)

    def show_result(self, path: str, result) -> int:
        """Show the program of a procedure's last check (a CompileResult);
        returns the number of instructions listed."""
        self.path = path
        instrs = instructions_of(result)
        self.tree.clear()
        self._line_items = {}
        name = Path(path).name
        if not instrs:
            errors = len(getattr(result, "errors", []) or [])
            why = (f"{name} has {errors} error{'s' * (errors != 1)}: no code to show"
                   if errors else f"{name}: no code yet")
            self.clear_view(why)
            return 0
        size, limit = getattr(result, "size", None), getattr(result, "limit", None)
        over = size is not None and limit is not None and size > limit
        text = f"<b>{name}</b>: {size} of {limit} bytes" if limit else f"<b>{name}</b>: {size} bytes"
        if over:
            text += (f" — <span style='color:#c62828'>{size - limit} bytes over the limit</span>; "
                     "the bytes of each line are beside it")
        self.header.setText(text)
        bold = QFont(self.tree.font())
        bold.setBold(True)
        grey = QBrush(QColor("#7f7f7f"))
        proc_item = line_item = None
        last = None
        self._bytes = {}
        groups: list[tuple[QTreeWidgetItem, str]] = []     # line items and their text
        procs: list[tuple[QTreeWidgetItem, list]] = []
        for d in instrs:
            if d.starts_proc or proc_item is None:
                proc_item = QTreeWidgetItem([f"{d.proc or 'main'}()", "", "", ""])
                proc_item.setFont(0, bold)
                self.tree.addTopLevelItem(proc_item)
                procs.append((proc_item, []))
                last = None
            f = resolve(d.file, path)
            if (f, d.line) != last or line_item is None:
                last = (f, d.line)
                src = self._line_text(f, d.line)
                where = f"{Path(f).name}:{d.line}" if f else "?"
                line_item = QTreeWidgetItem(["", "", "", ""])
                line_item.setFont(0, bold)
                line_item.setData(0, ROLE_LOCATION, (f, d.line or 1, 1))
                line_item.setToolTip(0, f"{where}: {src}")
                proc_item.addChild(line_item)
                procs[-1][1].append(line_item)
                groups.append((line_item, f"{where}  {src}"))
                self._bytes[id(line_item)] = 0
                if f is not None and d.line is not None:
                    self._line_items.setdefault((file_key(f), d.line), line_item)
            self._bytes[id(line_item)] += d.size
            ins = QTreeWidgetItem([f"{d.offset:5d}", d.raw.hex(" "), d.op.name, d.operand])
            ins.setForeground(1, grey)
            ins.setData(0, ROLE_LOCATION, (f, d.line or 1, 1))
            line_item.addChild(ins)
        for item, text in groups:
            n = self._bytes[id(item)]
            item.setText(0, f"{n:3d} B  {text}")
            item.setFirstColumnSpanned(True)
        for top, lines in procs:
            total = sum(self._bytes[id(i)] for i in lines)
            top.setText(0, f"{top.text(0)}   {total} bytes")
            top.setFirstColumnSpanned(True)
        self.tree.expandAll()
        fm = self.tree.fontMetrics()
        head = self.tree.header().fontMetrics()
        titles = self.tree.headerItem()
        # wide enough for the code's text and for the column's title ("Instructio")
        for col, width in enumerate((self.tree.indentation() * 3 + fm.horizontalAdvance("000000"),
                                     fm.horizontalAdvance("00 00 00 00 00 00"),
                                     fm.horizontalAdvance("GVARSET000"))):
            self.tree.setColumnWidth(col, max(width, head.horizontalAdvance(titles.text(col)) + 16))
        return len(instrs)

    def follow(self, path: str, line: int) -> None:
        """Select the source line ``line`` of ``path`` when it made code."""
        item = self._line_items.get((file_key(path), line))
        if item is not None and self.tree.currentItem() is not item:
            self.tree.setCurrentItem(item)
            self.tree.scrollToItem(item, QTreeWidget.ScrollHint.PositionAtCenter)

    def line_bytes(self) -> dict[tuple[str, int], int]:
        """{(file key, line): bytes} as listed (for tests)."""
        return {k: self._bytes[id(item)] for k, item in self._line_items.items()}

    # ------------------------------------------------------------ private
    def _line_text(self, f: Optional[str], line: Optional[int]) -> str:
        if f is None or line is None or self.source_line is None:
            return ""
        text = self.source_line(f, line)
        return text.strip() if text else ""

    def _on_item(self, item: QTreeWidgetItem, _col: int = 0) -> None:
        loc = item.data(0, ROLE_LOCATION)
        if loc and loc[0]:
            self.sig_open_location.emit(*loc)
