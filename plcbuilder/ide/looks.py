"""A widget's text colour and weight, given through its palette and font.

Not through a style sheet: a sheet is parsed, re-polishes the widget each
time it is set (the status bar's labels change five times a second while a
procedure runs) and makes the widget draw through the style-sheet style; one
set before the window's first paint made that paint wait for the parser.
"""

from __future__ import annotations

from typing import Optional

from PySide6.QtGui import QColor, QFont, QPalette

#: the property that names a widget's own text colour ("" for the theme's)
COLOUR_PROPERTY = "textColour"


def set_text_colour(widget, colour: Optional[str], bold: bool = False) -> None:
    """The widget's text in ``colour`` (None: the theme's own), semi-bold or not."""
    if (widget.property(COLOUR_PROPERTY) or None) == colour and is_bold(widget) == bold:
        return
    # a palette with nothing else set: every other role still comes from the
    # parent, and follows a change of theme
    pal = QPalette()
    if colour is not None:
        pal.setColor(QPalette.ColorRole.WindowText, QColor(colour))
    widget.setPalette(pal)
    font = widget.font()
    font.setWeight(QFont.Weight.DemiBold if bold else QFont.Weight.Normal)
    widget.setFont(font)
    widget.setProperty(COLOUR_PROPERTY, colour or "")


def is_bold(widget) -> bool:
    return widget.font().weight() > QFont.Weight.Normal


def text_colour(widget) -> Optional[str]:
    """The colour :func:`set_text_colour` gave the widget (None: the theme's)."""
    return widget.property(COLOUR_PROPERTY) or None
