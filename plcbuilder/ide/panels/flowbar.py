"""A bar of controls that never widens its dock: one row where there is room
for it, two rows where there is not (issue 23.6: the Watch's bar, wider than
the right-hand docks, widened them when the run panels loaded)."""

from __future__ import annotations

from PySide6 import QtWidgets


class FlowBar(QtWidgets.QWidget):
    """``first`` and ``second`` are ((widget, stretch), …): side by side on one
    row when the bar is at least as wide as they need, else ``second`` under
    ``first``. The bar asks for no width of its own (its dock decides)."""

    def __init__(self, first, second, parent=None, margins=(4, 2, 4, 2), spacing: int = 6):
        super().__init__(parent)
        self._first, self._second = list(first), list(second)
        outer = QtWidgets.QVBoxLayout(self)
        outer.setContentsMargins(*margins)
        outer.setSpacing(2)
        self._rows = (QtWidgets.QHBoxLayout(), QtWidgets.QHBoxLayout())
        for row in self._rows:
            row.setSpacing(spacing)
            outer.addLayout(row)
        self.two_rows = None
        self._flow(False)
        self.setSizePolicy(QtWidgets.QSizePolicy.Policy.Ignored,
                           QtWidgets.QSizePolicy.Policy.Fixed)
        self.setMinimumWidth(0)

    def one_row_width(self) -> int:
        """The width everything needs on one row."""
        items = self._first + self._second
        m = self.layout().contentsMargins()
        return (sum(w.sizeHint().width() for w, _s in items if not w.isHidden())
                + self._rows[0].spacing() * len(items) + m.left() + m.right())

    def _flow(self, two_rows: bool) -> None:
        if two_rows == self.two_rows:
            return
        self.two_rows = two_rows
        first, second = self._rows
        for row in self._rows:
            while row.count():
                row.takeAt(0)
        for w, stretch in self._first:
            first.addWidget(w, stretch)
        for w, stretch in self._second:
            (second if two_rows else first).addWidget(w, stretch)
        if two_rows:
            second.addStretch(1)
        self.updateGeometry()

    def resizeEvent(self, event) -> None:  # noqa: N802 - Qt's name
        self._flow(event.size().width() < self.one_row_width())
        super().resizeEvent(event)
