"""A label for status text that never widens its dock: it asks for the room its
text needs, takes what the layout gives, and elides ("…") what does not fit,
the whole text in its tooltip."""

from __future__ import annotations

from PySide6.QtCore import QSize, Qt
from PySide6.QtGui import QPainter, QTextDocument
from PySide6.QtGui import Qt as QtGuiNs
from PySide6.QtWidgets import QLabel, QSizePolicy, QStyleOption

#: the least a status label shrinks to, in average characters ("Idle · …")
MIN_CHARS = 6


class ShownText:
    """For a QLabel subclass whose ``setText`` keeps ``_full`` (the text as
    set) and ``_plain`` (without markup), and which sets ``_pending = None``
    in its ``__init__``: a text that changes often is set when it can be seen."""

    _full: str
    _plain: str
    _pending: "str | None"

    def set_text_when_shown(self, text: str) -> None:
        """Set a text that changes often (a status with the time in it): at once
        when the label is visible and the text differs, else when it shows.
        A label's new text lays its window out again (and repaints it), which
        costs the IDE CPU while the label cannot even be seen (a dock tabbed
        away). :meth:`full_text` and :meth:`plain_text` give the new text at once."""
        text = text or ""
        if text == self._full:
            return
        if self.isVisible():
            self.setText(text)
            return
        self._pending = text
        self._full = text
        self._plain = _plain_of(text)

    def showEvent(self, event) -> None:  # noqa: N802 - Qt override
        if self._pending is not None:
            text, self._pending = self._pending, None
            self.setText(text)
        super().showEvent(event)

    def full_text(self) -> str:
        """The text as set (rich or plain)."""
        return self._full

    def plain_text(self) -> str:
        """The text without markup."""
        return self._plain


class ElidedLabel(ShownText, QLabel):
    """A one-line QLabel (plain or rich text) whose minimum width is a few
    characters: when the text is wider than the label it is drawn as plain
    text, elided at the right, and the full text is the tooltip."""

    def __init__(self, text: str = "", parent=None, *, min_chars: int = MIN_CHARS):
        super().__init__(parent)
        self._full = ""
        self._plain = ""
        self._min_chars = min_chars
        self._own_tip = ""
        self._pending: str | None = None     # a text to show when the label shows
        self.setSizePolicy(QSizePolicy.Policy.Preferred, QSizePolicy.Policy.Preferred)
        self.setWordWrap(False)
        self.setText(text)

    # QLabel API -----------------------------------------------------------
    def setText(self, text: str) -> None:  # noqa: N802 - Qt override
        self._pending = None
        self._full = text or ""
        self._plain = _plain_of(self._full)
        super().setText(self._full)
        self._update_tip()

    def setToolTip(self, tip: str) -> None:  # noqa: N802 - Qt override
        self._own_tip = tip or ""
        self._update_tip()

    def is_elided(self) -> bool:
        """True when the label is too narrow for its text."""
        return self._text_width() > self.contentsRect().width()

    def minimumSizeHint(self) -> QSize:  # noqa: N802 - Qt override
        hint = super().minimumSizeHint()
        w = self.fontMetrics().averageCharWidth() * self._min_chars
        m = self.contentsMargins()
        return QSize(min(hint.width(), w + m.left() + m.right()), hint.height())

    def paintEvent(self, event) -> None:  # noqa: N802 - Qt override
        if not self.is_elided():
            super().paintEvent(event)
            return
        p = QPainter(self)
        opt = QStyleOption()
        opt.initFrom(self)
        rect = self.contentsRect()
        text = self.fontMetrics().elidedText(self._plain, Qt.TextElideMode.ElideRight,
                                             rect.width())
        self.style().drawItemText(p, rect, int(self.alignment() | Qt.AlignmentFlag.AlignVCenter),
                                  opt.palette, self.isEnabled(), text, self.foregroundRole())
        p.end()

    def resizeEvent(self, event) -> None:  # noqa: N802 - Qt override
        super().resizeEvent(event)
        self._update_tip()

    # ------------------------------------------------------------ helpers
    def _text_width(self) -> int:
        return self.fontMetrics().horizontalAdvance(self._plain)

    def _update_tip(self) -> None:
        tip = self._own_tip
        if not tip and self._plain and self.is_elided():
            tip = self._plain
        QLabel.setToolTip(self, tip)


def _plain_of(text: str) -> str:
    """The text without markup."""
    if QtGuiNs.mightBeRichText(text):
        doc = QTextDocument()
        doc.setHtml(text)
        return doc.toPlainText()
    return text
