"""Dock tab titles that are never cut: whole where they fit, shortened ("…")
where they do not.

Qt elides the titles of docks tabbed together as soon as they are a little
short of room ("Ou…", "Disasse…", issue 23.15); with elision off, a bar too
narrow for its tabs scrolls, and the tab before the current one is cut at the
bar's edge (a narrow left dock read "kpoints | Outline"). :func:`fit_titles`
keeps a bar's titles whole while they fit its width and shortens them all
evenly (each tab's tooltip says its whole title) when they do not; a bar too
narrow even for the shortened titles scrolls, its current tab whole.
"""

from __future__ import annotations

from PySide6.QtCore import QEvent, QObject, Qt, QTimer
from PySide6.QtWidgets import QTabBar

_WHOLE, _SHORT = Qt.TextElideMode.ElideNone, Qt.TextElideMode.ElideRight


class _Fitter(QObject):
    """Watches one tab bar's size and tabs; sets its elide mode to fit."""

    def __init__(self, bar: QTabBar):
        super().__init__(bar)
        self.bar = bar
        self._due = False
        bar.installEventFilter(self)
        bar.setUsesScrollButtons(True)      # (only when even short titles do not fit)
        self.fit()

    def eventFilter(self, obj, event) -> bool:  # noqa: N802 - Qt override
        if event.type() in (QEvent.Type.Resize, QEvent.Type.Show,
                            QEvent.Type.LayoutRequest) and not self._due:
            self._due = True                 # once the bar has its new size and tabs
            QTimer.singleShot(0, self, self.fit)
        return False

    def fit(self) -> None:
        self._due = False
        bar = self.bar
        n = bar.count()
        for i in range(n):
            if bar.tabToolTip(i) != bar.tabText(i):
                bar.setTabToolTip(i, bar.tabText(i))
        # what the tabs take with whole titles (the size hint is the whole
        # title's, whatever the elide mode)
        fm = bar.fontMetrics()
        hints = [bar.tabSizeHint(i).width() for i in range(n)]
        # shortened, a tab is at least two characters and "..." wide (Qt's rule)
        short = sum(h - fm.horizontalAdvance(bar.tabText(i))
                    + fm.horizontalAdvance(bar.tabText(i)[:2] + "...")
                    for i, h in enumerate(hints))
        # too narrow even for those: whole titles, scrolled to the current tab
        # (shortened and scrolled, the current tab read "O…")
        mode = _WHOLE if sum(hints) <= bar.width() or short > bar.width() else _SHORT
        if bar.elideMode() != mode:
            bar.setElideMode(mode)


def fit_titles(bar: QTabBar) -> None:
    """Whole titles on ``bar`` where they fit, evenly shortened where they do
    not (from now on, as it is resized and gets tabs)."""
    if bar.findChild(_Fitter) is None:
        _Fitter(bar)
