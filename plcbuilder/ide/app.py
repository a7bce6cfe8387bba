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

# No application-wide style sheet: one, even of a single rule, makes Qt style
# every widget through its style-sheet style, and the window took a sixth
# longer to build and paint. The few widgets that have a look of their own
# carry their own sheet (the editor tabs, the status bar, the find bar).

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
    fusion = "Fusion" in QStyleFactory.keys()
    if app is None:
        args = list(argv) if argv is not None else [sys.argv[0]]
        # the style named at construction is the only one made; setStyle()
        # afterwards makes a second, repolishes, and wraps the QStyle for
        # Python (its enums): 11 ms of the start-up
        app = QApplication(args + ["-style", "Fusion"] if fusion else args)
    elif fusion and app.style().name() != "fusion":
        app.setStyle("Fusion")
    app.setOrganizationName(ORGANIZATION)
    app.setApplicationName(APPLICATION)
    app.setApplicationDisplayName(APPLICATION)
    app.setDesktopFileName("plcbuilder")
    app.setWindowIcon(icon("app"))
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
    # widgets a style sheet has polished keep the palette they were polished
    # with: setting their sheet again polishes them with the new one
    sheet = app.styleSheet()
    if sheet:
        app.setStyleSheet("")
        app.setStyleSheet(sheet)
    for w in app.allWidgets():
        own = w.styleSheet()
        if own:
            w.setStyleSheet("")
            w.setStyleSheet(own)


def project_of(file: Path) -> Path:
    """The project folder a file belongs to: the nearest folder above it with a
    plcbuilder.toml, else the one holding its hardware/, software/ or include/
    folder, else its own folder."""
    file = file.resolve()
    for folder in file.parents:
        if (folder / "plcbuilder.toml").is_file():
            return folder
    if file.parent.name in ("hardware", "software", "include"):
        return file.parent.parent
    return file.parent


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
        if project and Path(project).is_file():
            project = str(project_of(Path(project)))
        from plcbuilder.ide import screenshot as shot
        return shot.run(app, settings, project, screenshot, run, after_ms, start_controller,
                        traces=tuple(traces))
    win = MainWindow(settings, start_controller=start_controller)
    win.show()
    if project and Path(project).is_file():     # a file of a project (the desktop's "open")
        folder, file = project_of(Path(project)), Path(project)
        if win.open_project(folder) and file.name != "plcbuilder.toml":
            win.open_file(file)
    elif project:
        win.open_project(project)
    elif win.prefs.open_last_project:
        recent = [p for p in settings.recent_projects() if Path(p).is_dir()]
        if recent:
            win.open_project(recent[0])
    return app.exec()
