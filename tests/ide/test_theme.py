"""The dark theme applies to every widget, plots included, and back again
(issue 13, defect 4: the tree, the plots and Build Output stayed white, the
status bar and dock toolbars went dark grey on black)."""

import dataclasses

import pytest
from PySide6.QtGui import QPalette
from PySide6.QtWidgets import QApplication, QLabel

from plcbuilder.ide.looks import text_colour
from tests.ide.test_docks_fit import prompts_off, runwin  # noqa: F401 - fixtures

Role = QPalette.ColorRole


def _lightness(widget, role) -> int:
    return widget.palette().color(role).lightness()


def _plot_background(plot_widget) -> int:
    return plot_widget.backgroundBrush().color().lightness()


def _axis_text(plot_item) -> int:
    return plot_item.getAxis("bottom").textPen().color().lightness()


def _look(w) -> dict:
    rp = w.run_panels
    status_labels = [lab for lab in w.statusBar().findChildren(QLabel)
                     if lab.isVisible() and not text_colour(lab)]      # not the coloured ones
    return {
        "tree": _lightness(w.tree.viewport() if hasattr(w.tree, "viewport")
                           else w.tree, Role.Base),
        "build output": _lightness(w.build_panel.text, Role.Base),
        "problems": _lightness(w.problems, Role.Window),
        "status text": min(_lightness(lab, Role.WindowText) for lab in status_labels),
        "status back": _lightness(w.statusBar(), Role.Window),
        "outputs plot": _plot_background(rp.lanes.widget),
        "proc plot": _plot_background(rp.proc.widget),
        "proc axis text": _axis_text(rp.proc.plot),
        "toolbar": _lightness(rp.lanes.toolbar, Role.Window),
        "toolbar text": _lightness(rp.lanes.toolbar.follow, Role.ButtonText),
    }


@pytest.mark.parametrize("first", ["light", "dark"])
def test_switching_the_theme_restyles_every_widget(runwin, qtbot, first):  # noqa: F811
    w, _conn = runwin
    app = QApplication.instance()
    try:
        for theme in (first, "dark" if first == "light" else "light", first):
            w.apply_preferences(dataclasses.replace(w.prefs, theme=theme))
            qtbot.wait(30)
            look = _look(w)
            dark = theme == "dark"
            backs = {k: v for k, v in look.items() if "text" not in k}
            texts = {k: v for k, v in look.items() if "text" in k}
            if dark:
                assert all(v < 90 for v in backs.values()), (theme, backs)
                assert all(v > 160 for v in texts.values()), (theme, texts)
            else:
                assert all(v > 180 for v in backs.values()), (theme, backs)
                assert all(v < 110 for v in texts.values()), (theme, texts)
    finally:
        from plcbuilder.ide.app import apply_theme
        apply_theme(app, "light")
