"""Which files the language server may read.

A client names files by URI, and the server must not become a way to read any
file of the user's (over ``--tcp`` any local program can be the client). It
reads only

- files inside the workspace folders the client gave at ``initialize`` (and
  later with ``workspace/didChangeWorkspaceFolders``); with none given, the
  folder the server was started in;
- files inside the include folders of the projects those files belong to, as
  each project's settings give them (``include/`` and ``[build] include``),
  and the project's ``plcbuilder.toml``;
- the documents the client opened (their text is the client's, never read
  from disk);
- the built-in headers (the package's own ``resources/include``).

Paths are compared after links are resolved: a link inside a workspace folder
that points outside it is outside. A server that serves TCP is also given
``confine`` (the folders it was started for, ``--root``): a workspace folder
outside them is not accepted.
"""

from __future__ import annotations

import logging
import os
from pathlib import Path
from typing import Iterable, Optional

log = logging.getLogger(__name__)


def real(p: Path) -> Path:
    """A path with links resolved (as far as it exists)."""
    try:
        return Path(os.path.realpath(p))
    except (OSError, ValueError):
        return Path(os.path.abspath(p))


def inside(path: Path, folders: Iterable[Path]) -> bool:
    return any(path == f or path.is_relative_to(f) for f in folders)


def _builtin_folder() -> Optional[Path]:
    from plcbuilder._support.package_data import data_folder
    folder = data_folder("resources", "include")
    return real(folder) if isinstance(folder, Path) else None


class Access:
    """The folders the server reads (see the module docstring)."""

    def __init__(self, confine: Optional[Iterable[Path]] = None, default: Optional[Path] = None):
        self.confine = [real(Path(p)) for p in confine] if confine is not None else None
        self.default = real(default or Path.cwd())
        self.folders: list[Path] = []
        self._given = False
        self.includes: dict[Path, tuple[Path, ...]] = {}   # project root -> its include folders
        self.opened: set[Path] = set()
        self.builtin = _builtin_folder()

    # ------------------------------------------------------------ folders
    def set_folders(self, paths: Iterable[Path]) -> list[Path]:
        """The workspace folders (replacing those before); returns those refused
        (outside ``confine``)."""
        accepted, refused = [], []
        for p in paths:
            r = real(p)
            if self.confine is not None and not inside(r, self.confine):
                refused.append(r)
            elif r not in accepted:
                accepted.append(r)
        self.folders = accepted
        self._given = True
        self.includes = {}               # found again as the workspace's files are checked
        for r in refused:
            log.warning("workspace folder %s refused: it is outside the folders this server "
                        "serves (%s)", r, ", ".join(map(str, self.confine or ())))
        return refused

    def change_folders(self, added: Iterable[Path], removed: Iterable[Path]) -> list[Path]:
        gone = {real(p) for p in removed}
        keep = [f for f in self.folders if f not in gone]
        return self.set_folders(keep + list(added))

    def roots(self) -> list[Path]:
        """The workspace folders, or the default folder when the client gave none."""
        if self._given and self.folders:
            return self.folders
        if self._given and not self.folders and self.confine is not None:
            return []                               # every folder given was refused
        if self.confine is not None and not inside(self.default, self.confine):
            return []
        return [self.default]

    # ------------------------------------------------------------ projects
    def in_workspace(self, path: Path) -> bool:
        return inside(real(path), self.roots())

    def add_project(self, root: Path, include_dirs: Iterable[Path]) -> None:
        """A project whose file is in the workspace: its include folders may be read."""
        self.includes[real(root)] = tuple(real(Path(d)) for d in include_dirs)

    # ------------------------------------------------------------ documents
    def open(self, path: Path) -> None:
        self.opened.add(real(path))

    def close(self, path: Path) -> None:
        self.opened.discard(real(path))

    # ------------------------------------------------------------ the rule
    def may_read(self, path: Path) -> bool:
        """True when the server may read ``path`` from disk."""
        r = real(path)
        if r in self.opened or self.builtin is not None and inside(r, (self.builtin,)):
            return True
        roots = self.roots()
        if inside(r, roots):
            return True
        return any(inside(r, dirs) for dirs in list(self.includes.values()))

    def refusal(self, path: Path) -> str:
        return (f"{path} is outside the workspace folders and their projects' include "
                "folders: the language server does not read it")
