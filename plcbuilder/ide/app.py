"""Starting the IDE: the QApplication (names, icon, style) and ``main()``."""

from __future__ import annotations

import os
import sys
from pathlib import Path
from typing import Optional

# PySide6 first: pyqtgraph picks its Qt binding from what is already imported.
os.environ.setdefault("PYQTGRAPH_QT_LIB", "PySide6")
from PySide6.QtGui import QColor, QPalette  # noqa: E402
from PySide6.QtWidgets import QApplication, QStyleFactory  # noqa: E402

from plcbuilder.ide.icons import icon  # noqa: E402
from plcbuilder.ide.settings import APPLICATION, ORGANIZATION  # noqa: E402

STYLE_SHEET = """
QMainWindow::separator { background: palette(window); width: 4px; height: 4px; }
QDockWidget::title { padding: 4px 6px; background: palette(window); }
QTabWidget#editorTabs QTabBar::tab { padding: 5px 10px; }
QTabWidget#editorTabs QTabBar::close-button { image: url(%(close)s); subcontrol-position: right; }
QTabWidget#editorTabs QTabBar::close-button:hover { image: url(%(close_hover)s); }
QStatusBar QLabel { padding: 0 4px; }
QWidget#findBar { border-top: 1px solid palette(mid); }
QLineEdit[notFound="true"] { background: rgba(229, 20, 0, 55); }
"""


def style_sheet() -> str:
    from plcbuilder.ide.icons import icon_path
    return STYLE_SHEET % {"close": icon_path("close"), "close_hover": icon_path("close-hover")}

DARK_COLOURS = {
    QPalette.ColorRole.Window: "#2b2d30", QPalette.ColorRole.WindowText: "#dfe1e5",
    QPalette.ColorRole.Base: "#1e1f22", QPalette.ColorRole.AlternateBase: "#26282b",
    QPalette.ColorRole.Text: "#dfe1e5", QPalette.ColorRole.Button: "#2b2d30",
    QPalette.ColorRole.ButtonText: "#dfe1e5", QPalette.ColorRole.Highlight: "#2f65ca",
    QPalette.ColorRole.HighlightedText: "#ffffff", QPalette.ColorRole.ToolTipBase: "#2b2d30",
    QPalette.ColorRole.ToolTipText: "#dfe1e5", QPalette.ColorRole.PlaceholderText: "#8c8f94",
    QPalette.ColorRole.Mid: "#43454a", QPalette.ColorRole.Link: "#589df6",
}


def create_application(argv: Optional[list] = None) -> QApplication:
    """The QApplication (an existing one is reused), named and styled."""
    app = QApplication.instance()
    if app is None:
        app = QApplication(list(argv) if argv is not None else [sys.argv[0]])
    app.setOrganizationName(ORGANIZATION)
    app.setApplicationName(APPLICATION)
    app.setApplicationDisplayName(APPLICATION)
    app.setDesktopFileName("plcbuilder")
    app.setWindowIcon(icon("app"))
    if "Fusion" in QStyleFactory.keys():
        app.setStyle("Fusion")
    app.setStyleSheet(style_sheet())
    return app


def apply_theme(app: QApplication, theme: str) -> None:
    """The window colours for the editor theme (light: the style's own)."""
    if theme == "dark":
        pal = QPalette()
        for role, colour in DARK_COLOURS.items():
            pal.setColor(role, QColor(colour))
        pal.setColor(QPalette.ColorGroup.Disabled, QPalette.ColorRole.Text, QColor("#6f737a"))
        pal.setColor(QPalette.ColorGroup.Disabled, QPalette.ColorRole.ButtonText, QColor("#6f737a"))
        app.setPalette(pal)
    else:
        app.setPalette(app.style().standardPalette())
    # widgets the style sheet has polished keep the palette they were polished
    # with: setting the sheet again polishes every widget with the new one
    sheet = app.styleSheet()
    if sheet:
        app.setStyleSheet("")
        app.setStyleSheet(sheet)


def main(project: Optional[str] = None, *, screenshot: Optional[str] = None,
         run: Optional[str] = None, after_ms: int = 1000, settings_path: Optional[str] = None,
         start_controller: bool = True, traces: tuple = ()) -> int:
    """Run the IDE (``plcbuilder gui``); in screenshot mode save a PNG and exit."""
    app = create_application()
    from plcbuilder.ide.main_window import MainWindow
    from plcbuilder.ide.settings import Settings
    settings = Settings(settings_path)
    apply_theme(app, settings.preferences().theme)
    if screenshot:
        from plcbuilder.ide import screenshot as shot
        return shot.run(app, settings, project, screenshot, run, after_ms, start_controller,
                        traces=tuple(traces))
    win = MainWindow(settings, start_controller=start_controller)
    win.show()
    if project:
        win.open_project(project)
    elif win.prefs.open_last_project:
        recent = [p for p in settings.recent_projects() if Path(p).is_dir()]
        if recent:
            win.open_project(recent[0])
    return app.exec()
