"""The mouse wheel never changes a value in a dock (issue 23 point 1).

Qt gives a slider, a spin box or a combo box the wheel events over it, and
each changes its value: scrolling a dock with the wheel moved an ADC slider as
it came under the pointer, and that forced the channel. Here every such widget
of the window's docks (and the toolbar's speed box) gets one event filter that
takes the wheel from it and gives it to the scroll area it is in (the Inputs
dock's, a table's), or to nothing: the dock scrolls, the value stays. Values
change only by a click, a drag, a key or a typed value. The widgets also lose
Qt's "wheel focus", so a wheel does not focus them either.

    guard = WheelGuard(window)
    guard.watch_docks(window)   # every dock, now and whenever it shows
    guard.guard(widget)         # one more widget (tree) by hand

The filter is installed after the window's first paint and only on those
widgets, so nothing else pays for it.
"""

from __future__ import annotations

from PySide6.QtCore import QEvent, QObject, QPointF, Qt
from PySide6.QtGui import QWheelEvent
from PySide6.QtWidgets import (QAbstractScrollArea, QAbstractSlider, QAbstractSpinBox,
                               QApplication, QComboBox, QDockWidget, QScrollBar, QWidget)

#: What the wheel would change.
VALUE_WIDGETS = (QAbstractSlider, QAbstractSpinBox, QComboBox)
#: The property a guarded widget has (True).
GUARDED = "wheelGuarded"


def is_value_widget(w: QWidget) -> bool:
    return isinstance(w, VALUE_WIDGETS) and not isinstance(w, QScrollBar)


class WheelGuard(QObject):
    """Takes wheel events from value widgets and scrolls what they are in."""

    def guard(self, root: QWidget) -> int:
        """Guard ``root`` and every value widget in it (those already guarded
        are left as they are); returns how many were new."""
        new = 0
        for w in [root, *root.findChildren(QWidget)]:
            if is_value_widget(w) and not w.property(GUARDED):
                w.setProperty(GUARDED, True)
                if w.focusPolicy() == Qt.FocusPolicy.WheelFocus:
                    w.setFocusPolicy(Qt.FocusPolicy.StrongFocus)
                w.installEventFilter(self)
                new += 1
        return new

    def watch_docks(self, window) -> None:
        """Guard every dock of ``window`` now, and again whenever one shows (a
        dock's panel may be made when it first shows)."""
        for dock in window.findChildren(QDockWidget):
            self.guard(dock)
            if not dock.property(GUARDED):
                dock.setProperty(GUARDED, True)
                dock.visibilityChanged.connect(lambda on, d=dock: on and self.guard(d))

    def eventFilter(self, obj, event) -> bool:  # noqa: N802 - Qt override
        if event.type() == QEvent.Type.Wheel:
            _scroll_instead(obj, event)
            return True
        return False


def _scroll_instead(widget: QWidget, event: QWheelEvent) -> None:
    """Give the wheel event to the scroll area ``widget`` is in, if any."""
    area = widget.parentWidget()
    while area is not None and not isinstance(area, QAbstractScrollArea):
        area = area.parentWidget()
    if area is None:
        return
    viewport = area.viewport()
    glob = event.globalPosition()
    pos = QPointF(viewport.mapFromGlobal(glob.toPoint()))
    QApplication.sendEvent(viewport, QWheelEvent(
        pos, glob, event.pixelDelta(), event.angleDelta(), event.buttons(), event.modifiers(),
        event.phase(), event.inverted()))
