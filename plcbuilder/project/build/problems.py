"""The problems Build All finds before it compiles: a procedure whose name
cannot be one (or that another file has too), a file its target does not run,
a source file that is a link out of the project, and a build/ folder that
leads out of it. Each is a diagnostic; a procedure with one is not compiled
(its file is not even read), and a build/ out of the project is not written.
"""

from __future__ import annotations

import os
import stat
from functools import lru_cache
from pathlib import Path
from typing import Optional

from plcbuilder.bytecode.program import Kind
from plcbuilder.image.manifest import valid_name
from plcbuilder.lang import Diagnostic, Span, error
from plcbuilder.project.build.results import ProcedureBuild
from plcbuilder.project.model import Procedure, Project

#: the codes of a procedure's problems: the procedure was not compiled
CODES = frozenset(("procedure-name", "duplicate-procedure", "source-outside-project",
                   "target-project"))


def procedure_problem(project: Project, proc: Procedure, procs: list[Procedure],
                      seen: dict[str, Procedure], root: Path) -> Optional[Diagnostic]:
    """Why ``proc`` is not compiled, or None. ``seen``: the procedures before
    it by name (the caller adds each); ``root``: the project's real path."""
    return (_outside_problem(proc, root) or _name_problem(proc, seen)
            or _target_problem(project, proc, procs))


def is_procedure_problem(pb: ProcedureBuild) -> bool:
    """Whether the procedure was not compiled because of such a problem."""
    return any(d.code in CODES for d in pb.diagnostics)


def real(p: Path) -> Path:
    """A path with its links resolved (as far as they go: a link loop is left)."""
    try:
        return p.resolve()
    except (OSError, RuntimeError):     # a link loop
        return p.absolute()


def build_dir_problem(project: Project) -> Optional[Diagnostic]:
    """build/ (or something in the way of it) leading out of the project."""
    build_dir = project.build_dir
    if not os.path.lexists(build_dir):
        return None
    where, root = real(build_dir), real(project.root)
    if where.is_relative_to(root) and where != root:
        return None
    return error("build-outside-project",
                 f"{build_dir} leads to {where}, outside the project; Build All writes only "
                 "inside the project", None,
                 f"remove the link {build_dir} (Build All makes the folder)")


@lru_cache(maxsize=64)
def _folder_inside(folder: str, root: Path, stamp) -> bool:
    """Whether a folder really lies in the project (``root``, its real path,
    and ``stamp``, the folder's identity, in the key: either changed, it is
    resolved again)."""
    return real(Path(folder)).is_relative_to(root)


def _outside_problem(proc: Procedure, root: Path) -> Optional[Diagnostic]:
    """A source file that is a link out of the project: an error, and it is not
    read (its lines would be echoed in diagnostics)."""
    path = str(proc.path)
    try:
        # a file that is no link lies where its folder really is: one lstat of
        # each, not a walk of every folder of its path (a thousand procedures)
        folder = os.path.dirname(path)
        st = os.lstat(folder)
        if stat.S_ISLNK(st.st_mode) or stat.S_ISLNK(os.lstat(path).st_mode):
            raise OSError
        if _folder_inside(folder, root, (st.st_ino, st.st_dev, st.st_mtime_ns)):
            return None
        where = real(Path(folder)) / proc.path.name
    except OSError:
        where = real(proc.path)
        if where.is_relative_to(root):
            return None
    return error("source-outside-project",
                 f"{proc.path} is a link to {where}, outside the project; Build All compiles "
                 "only files inside the project", None,     # no span: its lines are not shown
                 "copy the file into the project instead of linking to it")


def _name_problem(proc: Procedure, seen: dict[str, Procedure]) -> Optional[Diagnostic]:
    at = Span.point(str(proc.path), 1, 1)
    if not valid_name(proc.name):
        return error("procedure-name",
                     f"'{proc.name}' cannot be a procedure name: use letters, digits, '_' and "
                     "'-' (at most 64), as in M03 or __HANDLER_INIT", at,
                     "rename the file")
    other = seen.get(proc.name)
    if other is not None:
        return error("duplicate-procedure",
                     f"there is a {other.kind.label} procedure named {proc.name} too "
                     f"({other.path}); names must be unique in a project (they share build/ "
                     "and the image)", at, "rename one of the files")
    return None


def _target_problem(project: Project, proc: Procedure,
                    procs: list[Procedure]) -> Optional[Diagnostic]:
    """A target other than mycnc runs one program: one .plc file in hardware/
    (docs/targets.md)."""
    target = project.target
    if target == "mycnc":
        return None
    at = Span.point(str(proc.path), 1, 1)
    if proc.kind is Kind.SOFTWARE:
        return error("target-project", f"the {target} target has no software PLC: "
                                       f"{proc.path.name} in software/ is not run", at,
                     "move its procedures into the program in hardware/, or remove the file")
    first = next(p for p in procs if p.kind is Kind.HARDWARE)
    if first is not proc:
        return error("target-project", f"the {target} target runs one program, "
                                       f"{first.path.name}; this is a second one", at,
                     f"put its procedures into {first.path.name}, or remove the file")
    return None
