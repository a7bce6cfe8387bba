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


def apply_theme(app: QApplication, theme: str, *, restyle: bool = True) -> None:
    """The window colours for the editor theme (light: the style's own).
    ``restyle``: set the style sheets of the widgets that have their own
    again (see below); the start passes False, when the only widgets are the
    first frame's, none of which has one (walking them made a Python type for
    each kind of widget Qt made inside them: 12-20 ms after the frame's paint)."""
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
    if not restyle:
        return
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
    from plcbuilder.ide.settings import Settings
    settings = Settings(settings_path)
    prefs = settings.preferences()
    theme = prefs.theme
    if screenshot:
        apply_theme(app, theme)
        if project and Path(project).is_file():
            project = str(project_of(Path(project)))
        from plcbuilder.ide import screenshot as shot
        return shot.run(app, settings, project, screenshot, run, after_ms, start_controller,
                        traces=tuple(traces))
    folder, file = _what_to_open(project, settings)
    opened: list = []                        # the main window, kept while the IDE runs
    failed: list = []
    if folder is not None and prefs.first_frame and _first_frame_fits(app):
        # the light theme is the style's own palette: asking the style for it
        # makes the QStyle type's 540 enum members, after the frame's paint
        if theme != "light":
            apply_theme(app, theme)
        from plcbuilder.ide.first_frame import FirstFrame
        frame = FirstFrame(settings, folder, front=file, font_family=prefs.font_family,
                           font_size=prefs.font_size)

        def make_window() -> None:
            try:
                if theme == "light":
                    apply_theme(app, theme, restyle=False)
                opened.append(_open_window(app, settings, folder, file, start_controller, frame))
            except BaseException as exc:     # (raised below, as without the frame)
                failed.append(exc)
                frame.close()
                app.exit(1)
        frame.after_paint(make_window)
        frame.show()
    else:
        apply_theme(app, theme)
        opened.append(_open_window(app, settings, folder, file, start_controller, None))
    code = app.exec()
    if failed:
        raise failed[0]
    return code


def _what_to_open(project: Optional[str], settings) -> tuple[Optional[Path], Optional[Path]]:
    """The project folder to open (None: none) and a file of it to open with it."""
    if project and Path(project).is_file():     # a file of a project (the desktop's "open")
        file = Path(project)
        return project_of(file), (file if file.name != "plcbuilder.toml" else None)
    if project:
        return Path(project), None
    if settings.preferences().open_last_project:
        recent = [p for p in settings.recent_projects() if Path(p).is_dir()]
        if recent:
            return Path(recent[0]), None
    return None, None


def _first_frame_fits(app: QApplication) -> bool:
    """Whether the first frame can stand where the window will be: not on
    Wayland, where a program does not place its windows (the frame and the
    window could show in two places)."""
    return not app.platformName().startswith("wayland")


def _open_window(app: QApplication, settings, folder: Optional[Path], file: Optional[Path],
                 start_controller: bool, frame):
    """Make the main window, open the project (and file) in it and show it;
    with the first frame, in the frame's place once made (see first_frame)."""
    from plcbuilder.ide.main_window import MainWindow
    win = MainWindow(settings, start_controller=start_controller)
    if frame is None:
        win.show()
    else:
        win.show_when_made()                 # what waits for the paint waits
    if folder is not None and win.open_project(folder) and file is not None:
        win.open_file(file)
    if frame is not None:
        if frame.cancelled:                  # the frame was closed meanwhile: quit
            win.close()
            app.quit()
        else:
            frame.hand_over(win)
    return win
