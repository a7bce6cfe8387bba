"""Which project a file belongs to, and how the project compiles it.

A file's project is the folder of the nearest ``plcbuilder.toml`` above it
(the file's own folder first), else, as Build All finds it, a ``hardware/`` or
``software/`` folder beside an ``include/`` folder. The project gives the
include path, the size limits, strict mode and the procedure's kind; outside
a project a file compiles as ``plcbuilder check`` compiles it (hardware,
unless its folder is ``software/``). A settings file that cannot be read is
reported (:attr:`Context.problem`) and the defaults are used meanwhile.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Optional

from plcbuilder.lang.pipeline import CompileOptions
from plcbuilder.project.model import SETTINGS_FILE, Project, ProjectError, kind_of

HEADER_SUFFIXES = (".h",)


@dataclass(frozen=True)
class Context:
    """How one file is compiled."""
    project: Optional[Project]
    options: CompileOptions
    software: bool
    header: bool
    problem: Optional[ProjectError] = None

    @property
    def include_dirs(self) -> tuple:
        return tuple(self.options.include_dirs)


class Projects:
    """Finds and caches projects (a settings file is read again when it changes)."""

    def __init__(self):
        self._cache: dict[Path, tuple[Optional[float], Project]] = {}

    def settings_file(self, path: Path) -> Optional[Path]:
        """The nearest plcbuilder.toml above ``path``."""
        for folder in path.parents:
            candidate = folder / SETTINGS_FILE
            try:
                if candidate.is_file():
                    return candidate
            except OSError:
                continue
        return None

    def project_for(self, path: Optional[Path]) -> tuple[Optional[Project], Optional[ProjectError]]:
        if path is None:
            return None, None
        settings = self.settings_file(path)
        try:
            if settings is not None:
                return self._open(settings.parent, settings), None
            return Project.find_for(path), None
        except ProjectError as exc:
            return None, exc

    def context(self, path: Optional[Path], find_project: bool = True) -> Context:
        """How ``path`` compiles (``find_project`` False: with the defaults, its
        project's settings not read)."""
        header = path is not None and path.suffix.lower() in HEADER_SUFFIXES
        project, problem = self.project_for(path) if find_project else (None, None)
        software = path is not None and kind_of(path).label == "software"
        if project is not None and path is not None:
            options = project.compile_options(path)
        else:
            options = CompileOptions(kind=kind_of(path) if path is not None else CompileOptions().kind)
        return Context(project, options, software, header, problem)

    def _open(self, root: Path, settings: Path) -> Project:
        try:
            stamp: Optional[float] = settings.stat().st_mtime_ns
        except OSError:
            stamp = None
        hit = self._cache.get(root)
        if hit is not None and hit[0] == stamp and stamp is not None:
            return hit[1]
        project = Project.open(root)
        self._cache[root] = (stamp, project)
        return project
