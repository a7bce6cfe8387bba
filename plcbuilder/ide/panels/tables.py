"""A bounded, append-only table model for logs that grow fast.

Rows are queued with :meth:`RowsModel.queue` (cheap, from any signal handler)
and inserted in one batch by :meth:`RowsModel.flush`, which the panels' redraw
timer calls; the oldest rows are dropped in chunks past ``limit``.
"""

from __future__ import annotations

from typing import Any, Callable, Optional, Sequence

from PySide6 import QtCore, QtGui

Qt = QtCore.Qt


class RowsModel(QtCore.QAbstractTableModel):
    """Rows are tuples; ``columns`` names the first ``len(columns)`` items of
    each, any items after those are hidden payload (see :meth:`row`)."""

    def __init__(self, columns: Sequence[str], limit: int = 20000,
                 colour: Optional[Callable[[tuple], Optional[str]]] = None,
                 tooltip: Optional[Callable[[tuple], Optional[str]]] = None,
                 align_right: Sequence[int] = (), parent=None):
        super().__init__(parent)
        self._columns = list(columns)
        self._rows: list[tuple] = []
        self._pending: list[tuple] = []
        self.limit = int(limit)
        self._colour = colour
        self._tooltip = tooltip
        self._right = set(align_right)
        self._brushes: dict[str, QtGui.QBrush] = {}
        self.dropped = 0

    # ------------------------------------------------------------------- rows
    def queue(self, row: tuple) -> None:
        self._pending.append(row)
        if len(self._pending) > 4 * self.limit:          # never flushed: stay bounded
            del self._pending[:len(self._pending) - self.limit]

    def flush(self) -> int:
        """Insert the queued rows; returns how many were added."""
        if not self._pending:
            return 0
        new, self._pending = self._pending, []
        if len(new) > self.limit:
            self.dropped += len(new) - self.limit
            new = new[-self.limit:]
        over = len(self._rows) + len(new) - self.limit
        if over > 0:
            drop = min(len(self._rows), max(over, self.limit // 10))
            self.beginRemoveRows(QtCore.QModelIndex(), 0, drop - 1)
            del self._rows[:drop]
            self.endRemoveRows()
            self.dropped += drop
        first = len(self._rows)
        self.beginInsertRows(QtCore.QModelIndex(), first, first + len(new) - 1)
        self._rows.extend(new)
        self.endInsertRows()
        return len(new)

    def clear(self) -> None:
        self.beginResetModel()
        self._rows.clear()
        self._pending.clear()
        self.dropped = 0
        self.endResetModel()

    def replace(self, rows: list) -> list[tuple]:
        """Show ``rows`` instead (at most ``limit``, the newest); returns the
        rows shown until now, those queued included."""
        old = self._rows + self._pending
        self.beginResetModel()
        self._rows = list(rows)[-self.limit:] if self.limit else list(rows)
        self._pending = []
        self.endResetModel()
        return old

    def row(self, i: int) -> tuple:
        return self._rows[i]

    def rows(self) -> list[tuple]:
        return list(self._rows)

    # ------------------------------------------------------------- Qt model
    def rowCount(self, parent=QtCore.QModelIndex()) -> int:  # noqa: N802
        return 0 if parent.isValid() else len(self._rows)

    def columnCount(self, parent=QtCore.QModelIndex()) -> int:  # noqa: N802
        return 0 if parent.isValid() else len(self._columns)

    def headerData(self, section, orientation, role=Qt.ItemDataRole.DisplayRole):  # noqa: N802
        if role == Qt.ItemDataRole.DisplayRole and orientation == Qt.Orientation.Horizontal:
            return self._columns[section]
        return None

    def data(self, index, role=Qt.ItemDataRole.DisplayRole) -> Any:
        if not index.isValid():
            return None
        row = self._rows[index.row()]
        if role == Qt.ItemDataRole.DisplayRole:
            v = row[index.column()]
            return "" if v is None else str(v)
        if role == Qt.ItemDataRole.ForegroundRole and self._colour is not None:
            c = self._colour(row)
            if c:
                b = self._brushes.get(c)
                if b is None:
                    b = self._brushes[c] = QtGui.QBrush(QtGui.QColor(c))
                return b
        if role == Qt.ItemDataRole.ToolTipRole and self._tooltip is not None:
            return self._tooltip(row)
        if role == Qt.ItemDataRole.TextAlignmentRole and index.column() in self._right:
            return int(Qt.AlignmentFlag.AlignRight | Qt.AlignmentFlag.AlignVCenter)
        return None
