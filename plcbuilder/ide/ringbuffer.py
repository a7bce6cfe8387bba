"""Preallocated ring buffers for live plots.

A :class:`RingBuffer` holds the last ``capacity`` rows of ``width`` columns in
one numpy array allocated once. Every row is written twice, at ``i`` and at
``i + capacity``, so the newest ``n`` rows are always one contiguous slice and
:meth:`RingBuffer.view` hands plots a zero-copy, chronological view (the
"doubled buffer" trick: one extra write per row instead of a copy per frame).

No Qt here: the buffers are filled by the run model, outside any widget, and
the plots only read views of them.
"""

from __future__ import annotations

import numpy as np

__all__ = ["RingBuffer"]


class RingBuffer:
    """The last ``capacity`` rows of ``width`` values of one dtype.

    Columns are stored as rows of a ``(width, 2 * capacity)`` array so that a
    column's view is contiguous in memory (what pyqtgraph likes best).
    """

    def __init__(self, capacity: int, width: int = 1, dtype=np.float64):
        if capacity < 1 or width < 1:
            raise ValueError("capacity and width must be at least 1")
        self.capacity = int(capacity)
        self.width = int(width)
        self._data = np.zeros((self.width, 2 * self.capacity), dtype=dtype)
        self._head = 0          # rows written since the last clear

    # ------------------------------------------------------------------ info
    def __len__(self) -> int:
        return min(self._head, self.capacity)

    @property
    def total(self) -> int:
        """Rows written since the last clear (including those overwritten)."""
        return self._head

    @property
    def dtype(self):
        return self._data.dtype

    # ----------------------------------------------------------------- write
    def clear(self) -> None:
        self._head = 0

    def append(self, row) -> None:
        """Append one row (``width`` values, or a scalar when width is 1)."""
        i = self._head % self.capacity
        self._data[:, i] = row
        self._data[:, i + self.capacity] = row
        self._head += 1

    def extend(self, rows) -> None:
        """Append many rows at once: an array of shape ``(n, width)`` (or ``(n,)``
        when width is 1). Only the last ``capacity`` of them are kept."""
        rows = np.asarray(rows, dtype=self._data.dtype)
        if rows.ndim == 1:
            rows = rows.reshape(-1, 1) if self.width == 1 else rows.reshape(1, -1)
        n = rows.shape[0]
        if n == 0:
            return
        if rows.shape[1] != self.width:
            raise ValueError(f"expected rows of {self.width} values, got {rows.shape[1]}")
        if n > self.capacity:
            skipped = n - self.capacity
            rows = rows[skipped:]
            self._head += skipped
            n = self.capacity
        cols = rows.T
        start = self._head % self.capacity
        first = min(n, self.capacity - start)
        # first part: from start to the end of the first copy
        self._data[:, start:start + first] = cols[:, :first]
        self._data[:, start + self.capacity:start + self.capacity + first] = cols[:, :first]
        rest = n - first
        if rest:
            self._data[:, :rest] = cols[:, first:]
            self._data[:, self.capacity:self.capacity + rest] = cols[:, first:]
        self._head += n

    def repeat_last(self, n: int) -> None:
        """Append the newest row ``n`` times more (a held value; rows must
        have been written before)."""
        if n <= 0 or not self._head:
            return
        row = self._data[:, (self._head - 1) % self.capacity].copy()[:, None]
        if n > self.capacity:
            self._head += n - self.capacity
            n = self.capacity
        start = self._head % self.capacity
        first = min(n, self.capacity - start)
        self._data[:, start:start + first] = row
        self._data[:, start + self.capacity:start + self.capacity + first] = row
        rest = n - first
        if rest:
            self._data[:, :rest] = row
            self._data[:, self.capacity:self.capacity + rest] = row
        self._head += n

    # ------------------------------------------------------------------ read
    def _span(self, last: int | None) -> tuple[int, int]:
        n = len(self) if last is None else max(0, min(int(last), len(self)))
        s = (self._head - n) % self.capacity if n else 0
        return s, s + n

    def view(self, column: int = 0, last: int | None = None) -> np.ndarray:
        """The newest ``last`` values (all kept values by default) of one column,
        oldest first, as a read-only view that stays valid until the next write."""
        a, b = self._span(last)
        v = self._data[column, a:b]
        v.flags.writeable = False
        return v

    def views(self, last: int | None = None) -> np.ndarray:
        """Every column at once: a read-only ``(width, n)`` view."""
        a, b = self._span(last)
        v = self._data[:, a:b]
        v.flags.writeable = False
        return v

    def latest(self):
        """The newest row (a copy), or None when empty."""
        if not self._head:
            return None
        i = (self._head - 1) % self.capacity
        return self._data[:, i].copy()
