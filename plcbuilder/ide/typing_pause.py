"""A filter field over a long list filters once typing pauses.

Filtering a long list (the run log's 20,000 rows, thousands of problems) at
each key typed into its field held every key up for a tenth of a second or
more. :class:`TypingPause` runs the filter at each key while the list is
short, and once typing pauses (:data:`PAUSE_MS`) while it is long; Enter runs
it at once.
"""

from __future__ import annotations

from typing import Callable

from PySide6.QtCore import QObject, QTimer
from PySide6.QtWidgets import QLineEdit

PAUSE_MS = 150


class TypingPause(QObject):
    """Runs ``run`` when the text of ``edit`` changes: at once, or once typing
    pauses while ``long()`` says the list is long."""

    def __init__(self, edit: QLineEdit, run: Callable[[], None], long: Callable[[], bool]):
        super().__init__(edit)
        self.run, self.long = run, long
        self.timer = QTimer(self)
        self.timer.setSingleShot(True)
        self.timer.timeout.connect(self.now)
        edit.textChanged.connect(self._typed)
        edit.returnPressed.connect(self.now)

    def _typed(self, _text: str) -> None:
        if self.long():
            self.timer.start(PAUSE_MS)
        else:
            self.now()

    def now(self) -> None:
        """Run the filter now (what was waiting for the pause included)."""
        self.timer.stop()
        self.run()

    def cancel(self) -> None:
        """The filter ran by other means: nothing waits for the pause."""
        self.timer.stop()
