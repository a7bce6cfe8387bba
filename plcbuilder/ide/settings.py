"""What the IDE remembers between sessions (QSettings): recent projects, the
window's geometry and dock layout, open files, and the preferences.

Tests (and ``PLCBUILDER_SETTINGS=FILE``) use an INI file of their own, so a
test run never touches the user's settings.
"""

from __future__ import annotations

import json
import os
from dataclasses import asdict, dataclass, fields, replace
from pathlib import Path
from typing import Optional

from PySide6.QtCore import QByteArray, QSettings

from plcbuilder.ide.editor import EditorPrefs

ORGANIZATION = "PLC Builder"
APPLICATION = "PLC Builder"
SETTINGS_ENV = "PLCBUILDER_SETTINGS"
RECOVERY_ENV = "PLCBUILDER_RECOVERY_DIR"
MAX_RECENT = 10
#: the parts of the window's sketch (Settings.frame_sketch) and their numbers
SKETCH_SHAPES = {"size": 2, "tree": 4, "editor": 4, "text": 2}


@dataclass(frozen=True)
class Preferences(EditorPrefs):
    """Everything the Preferences dialog edits: the editor's own preferences and more."""
    autosave_seconds: int = 5           # recovery autosave interval
    save_before_build: bool = True
    reload_unmodified: bool = True      # reload files changed on disk when not edited
    build_before_upload: bool = True
    open_last_project: bool = True
    first_frame: bool = True            # show the project at once while the window is made

    def editor_prefs(self) -> EditorPrefs:
        names = {f.name for f in fields(EditorPrefs)}
        return EditorPrefs(**{k: v for k, v in asdict(self).items() if k in names})

    def with_changes(self, **changes) -> "Preferences":
        return replace(self, **changes)


class Settings:
    """A thin, typed layer over QSettings."""

    def __init__(self, path: Optional[str] = None):
        path = path or os.environ.get(SETTINGS_ENV)
        self.explicit = bool(path)
        if path:
            self.qs = QSettings(str(path), QSettings.Format.IniFormat)
        else:
            self.qs = QSettings(QSettings.Format.IniFormat, QSettings.Scope.UserScope,
                                ORGANIZATION, APPLICATION)
        self.path = self.qs.fileName()

    # ------------------------------------------------------------ recent
    def recent_projects(self) -> list[str]:
        value = self.qs.value("recent/projects", [])
        if isinstance(value, str):
            value = [value] if value else []
        return [str(v) for v in (value or []) if v]

    def add_recent_project(self, path) -> list[str]:
        path = str(Path(path).resolve())
        items = [p for p in self.recent_projects() if p != path]
        items.insert(0, path)
        del items[MAX_RECENT:]
        self.qs.setValue("recent/projects", items)
        return items

    def remove_recent_project(self, path) -> None:
        items = [p for p in self.recent_projects() if p != str(path)]
        self.qs.setValue("recent/projects", items)

    def clear_recent_projects(self) -> None:
        self.qs.setValue("recent/projects", [])

    # ------------------------------------------------------------ folders
    def last_folder(self, kind: str, default=None) -> Path:
        """The folder a file dialog of ``kind`` (projects, traces, recordings)
        was last left in, when it still exists; else ``default`` (or home)."""
        value = str(self.qs.value(f"folders/{kind}", "") or "")
        if value and Path(value).is_dir():
            return Path(value)
        return Path(default) if default is not None else Path.home()

    def set_last_folder(self, kind: str, folder) -> None:
        self.qs.setValue(f"folders/{kind}", str(folder))

    # ------------------------------------------------- the project's run
    def project_value(self, project, key: str, default=None):
        """A value remembered for one project (its last eparam, its speed)."""
        value = self.qs.value(f"session/{_key(project)}/{key}", None)
        return default if value is None else value

    def set_project_value(self, project, key: str, value) -> None:
        self.qs.setValue(f"session/{_key(project)}/{key}", value)

    # ------------------------------------------------------------ window
    def window_state(self) -> tuple[Optional[QByteArray], Optional[QByteArray]]:
        geom = self.qs.value("window/geometry")
        state = self.qs.value("window/state")
        return (geom if isinstance(geom, QByteArray) else None,
                state if isinstance(state, QByteArray) else None)

    def save_window_state(self, geometry: QByteArray, state: QByteArray, docks: list) -> None:
        """The window's geometry and dock layout (``state``), with the names of
        the docks the layout has (``docks``: see :meth:`window_docks`)."""
        self.qs.setValue("window/geometry", geometry)
        self.qs.setValue("window/state", state)
        self.qs.setValue("window/docks", " ".join(docks))

    def window_docks(self) -> Optional[set]:
        """The object names of the docks the saved layout has (a window without
        a controller has no run docks), None when not known."""
        value = self.qs.value("window/docks", None)
        return set(value.split()) if isinstance(value, str) else None

    def frame_sketch(self) -> Optional[dict]:
        """Where the window had its parts when it was last closed, for the
        first frame (plcbuilder.ide.first_frame): ``{"size": (w, h), "tree":
        (x, y, w, h), "editor": (x, y, w, h), "text": (x, line height)}`` in
        the window's coordinates (text: where the front editor's text starts,
        after its margins, and the height of its lines; (0, 0) when unknown);
        None when not kept or not readable."""
        value = self.qs.value("window/sketch", None)
        try:
            parts = dict(p.split("=", 1) for p in str(value).split(";")) if value else {}
            sketch = {k: tuple(int(v) for v in parts[k].split(","))
                      for k in SKETCH_SHAPES if k in parts or k != "text"}
        except (KeyError, ValueError):
            return None
        if any(len(v) != SKETCH_SHAPES[k] or any(n < 0 for n in v[-2:]) for k, v in sketch.items()):
            return None
        sketch.setdefault("text", (0, 0))
        return sketch

    def save_frame_sketch(self, sketch: Optional[dict]) -> None:
        if sketch is None:
            self.qs.remove("window/sketch")
        else:
            self.qs.setValue("window/sketch", ";".join(
                f"{k}={','.join(str(int(n)) for n in sketch[k])}" for k in SKETCH_SHAPES
                if k in sketch))

    def splitter_sizes(self, name: str) -> Optional[list[int]]:
        """A panel's splitter sizes as the user left them (None: never moved)."""
        value = self.qs.value(f"window/splitters/{name}", None)
        try:
            sizes = [int(v) for v in str(value).split(",")] if value else []
        except ValueError:
            return None
        return sizes if sizes and all(s >= 0 for s in sizes) else None

    def save_splitter_sizes(self, name: str, sizes: list[int]) -> None:
        self.qs.setValue(f"window/splitters/{name}", ",".join(str(int(s)) for s in sizes))

    def forget_splitter_sizes(self) -> None:
        """Every panel's splitter sizes (View › Reset Layout)."""
        self.qs.remove("window/splitters")

    def open_files(self, project) -> list[str]:
        value = self.qs.value(f"session/{_key(project)}/files", [])
        if isinstance(value, str):
            value = [value] if value else []
        return [str(v) for v in (value or [])]

    def current_file(self, project) -> str:
        return str(self.qs.value(f"session/{_key(project)}/current", "") or "")

    def save_session(self, project, files: list[str], current: str) -> None:
        self.qs.setValue(f"session/{_key(project)}/files", list(files))
        self.qs.setValue(f"session/{_key(project)}/current", current or "")

    def breakpoints(self, project) -> list:
        """The project's breakpoints as saved (dicts, paths relative to the project)."""
        raw = self.qs.value(f"session/{_key(project)}/breakpoints", "")
        try:
            value = json.loads(str(raw)) if raw else []
        except ValueError:
            return []
        return value if isinstance(value, list) else []

    def save_breakpoints(self, project, items: list) -> None:
        self.qs.setValue(f"session/{_key(project)}/breakpoints", json.dumps(items))

    # ------------------------------------------------------- preferences
    def preferences(self) -> Preferences:
        d = Preferences()
        values = {}
        for f in fields(Preferences):
            raw = self.qs.value(f"preferences/{f.name}", None)
            if raw is None:
                continue
            default = getattr(d, f.name)
            try:
                if isinstance(default, bool):
                    values[f.name] = raw if isinstance(raw, bool) else str(raw).lower() in ("1", "true", "yes")
                elif isinstance(default, int):
                    values[f.name] = int(raw)
                else:
                    values[f.name] = str(raw)
            except (TypeError, ValueError):
                continue
        return replace(d, **values)

    def save_preferences(self, prefs: Preferences) -> None:
        for k, v in asdict(prefs).items():
            self.qs.setValue(f"preferences/{k}", v)

    # ---------------------------------------------------------- recovery
    def recovery_dir(self) -> Path:
        env = os.environ.get(RECOVERY_ENV)
        if env:
            return Path(env)
        custom = self.qs.value("recovery/dir", "")
        if custom:
            return Path(str(custom))
        if self.explicit:                   # a settings file of its own: recovery beside it
            return Path(self.path).parent / "recovery"
        new = data_dir() / "recovery"
        # (before 23.14: the organisation and the application, both "PLC Builder")
        old = data_dir().parent / ORGANIZATION / APPLICATION / "recovery"
        if not new.exists() and old.is_dir() and any(old.iterdir()):
            return old                      # a crash's copies there are still offered
        return new

    def set_recovery_dir(self, path) -> None:
        self.qs.setValue("recovery/dir", str(path))

    def example_dir(self) -> Path:
        """Where "Open Example Project" creates its project when the user does not pick."""
        if self.explicit:
            return Path(self.path).parent / "examples"
        return data_dir() / "examples"

    def sync(self) -> None:
        self.qs.sync()


def data_dir() -> Path:
    """The IDE's data folder: ``~/.local/share/PLC Builder`` on Linux (the
    application's name once, not the organisation's and the application's)."""
    from PySide6.QtCore import QStandardPaths      # (its enums: only when asked)
    base = QStandardPaths.writableLocation(QStandardPaths.StandardLocation.GenericDataLocation)
    return Path(base or Path.home() / ".local" / "share") / APPLICATION


def _key(project) -> str:
    return str(Path(str(project)).resolve()).replace("/", "|").replace("\\", "|")

