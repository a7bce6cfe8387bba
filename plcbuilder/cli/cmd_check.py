"""``plcbuilder check FILE…``: compile each file and report its diagnostics.

Every diagnostic is printed the way compilers do (``file:line:col: error: text``,
the source line, a caret under the span, hints), then one summary line per
file with the procedure's size against its limit. Exit status: 0 when no file
has an error, 1 when one has (a missing or unreadable file is an error on that
file), 2 on bad usage.

This module also holds what the three compiling commands (check, compile,
disasm) share: their options and how a file's procedure kind is decided.
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path
from typing import Callable, Optional

from plcbuilder.bytecode.program import Kind
from plcbuilder.cli import term
from plcbuilder.diagnostics import render_text, summary

#: Set this environment variable to see the traceback of an internal error.
DEBUG_ENV = "PLCBUILDER_DEBUG"


# ------------------------------------------------------------ shared options

def add_compile_options(p: argparse.ArgumentParser) -> None:
    """--strict, --software, --include DIR (repeatable) and --color."""
    p.add_argument("--strict", action="store_true",
                   help="controller compatibility: report every construct the myCNC manual "
                        "does not show (else, while, unary operators, %%, ^, &&, ||, /* */) "
                        "as an error")
    p.add_argument("--software", action="store_true",
                   help="compile as a software procedure (16384-byte limit, Param); the default "
                        "is hardware unless the file is in a folder named 'software'")
    p.add_argument("-I", "--include", dest="include", action="append", default=[],
                   metavar="DIR", type=Path,
                   help="search DIR for #include files (after the procedure's own folder; "
                        "repeatable)")
    term.add_color_argument(p)


def procedure_kind(path: Path, software: bool = False) -> Kind:
    """--software, or software when the file's parent folder is named ``software``."""
    from plcbuilder import api
    return api.kind_for_path(path, software)


def project_of(path: Path, out: Optional[term.Out] = None):
    """The project a file belongs to (it sits in a project's ``hardware/`` or
    ``software/`` folder), or None. A project whose settings cannot be read is
    reported on stderr and ignored (the defaults apply)."""
    if path.parent.name not in ("hardware", "software"):
        return None
    from plcbuilder import api
    root = path.parent.parent
    if not (root / "plcbuilder.toml").is_file() and not (root / "include").is_dir():
        return None
    try:
        return api.Project.open(root)
    except (api.ProjectError, OSError) as exc:
        if out is not None:
            out.print(f"plcbuilder: warning: ignoring the project's settings: {exc}", err=True)
        return None


def include_dirs(path: Path, extra: list[Path]) -> tuple[Path, ...]:
    """The --include folders, then the project's include folder when the file sits
    in a project's ``hardware/`` or ``software/`` folder (as Build All searches it).
    (Used by other commands too: keep the signature.)"""
    dirs = list(extra)
    project = project_of(path)
    if project is not None:
        dirs += [d for d in project.include_dirs() if d not in dirs]
    return tuple(dirs)


def compile_options(args: argparse.Namespace, path: Path, out: Optional[term.Out] = None):
    """The api.CompileOptions for one file: the command-line options, plus, for a file
    of a project, the project's include folder, size limit and strict setting."""
    from plcbuilder import api
    kind = procedure_kind(path, args.software)
    dirs = list(args.include)
    strict = args.strict
    limit = None
    project = project_of(path, out)
    if project is not None:
        dirs += [d for d in project.include_dirs() if d not in dirs]
        limit = project.limits.proc_limit(kind)
        strict = strict or bool(getattr(project.settings, "strict", False))
    return api.CompileOptions(kind=kind, strict=strict, include_dirs=tuple(dirs),
                              code_limit=limit)


def size_text(result) -> str:
    """``120/512 bytes`` (``not compiled (limit 512 bytes)`` when there is no code)."""
    if result.size is None:
        return f"not compiled (limit {result.limit} bytes)"
    return f"{result.size}/{result.limit} bytes"


def print_diagnostics(result, out: term.Out, err: bool = False) -> None:
    """Every diagnostic of a compile result, rendered with its source line and caret."""
    colorize = out.colorize(err)
    for d in result.diagnostics:
        out.print(render_text(d, result.source_line, colorize), err=err)


def guarded(fn: Callable[[], int], out: term.Out) -> int:
    """Run a command body; an internal error becomes one line and exit 1, not a traceback."""
    try:
        return fn()
    except (KeyboardInterrupt, BrokenPipeError):
        raise
    except Exception as exc:  # noqa: BLE001 - the user gets a message, not a traceback
        if os.environ.get(DEBUG_ENV):
            raise
        out.print(f"plcbuilder: internal error: {type(exc).__name__}: {exc} "
                  f"(set {DEBUG_ENV}=1 to see the traceback)", err=True)
        return 1


def safe_streams() -> None:
    """Never fail on a character the terminal's encoding cannot show."""
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.reconfigure(errors="backslashreplace")
        except (AttributeError, ValueError, OSError):
            pass


# ------------------------------------------------------------ the command

def add_parser(subparsers) -> argparse.ArgumentParser:
    p = subparsers.add_parser(
        "check", help="report the diagnostics of PLC source files",
        description="Compile each FILE and print its errors and warnings as "
                    "file:line:col: error|warning: text, the source line and a caret, "
                    "then one summary line per file with its size against its limit. "
                    "Exit status 1 if any file has an error.")
    p.add_argument("files", nargs="+", type=Path, metavar="FILE", help="a .plc source file")
    add_compile_options(p)
    return p


def check_file(path: Path, args: argparse.Namespace, out: term.Out) -> bool:
    """Check one file, print its report; True when it has no error."""
    from plcbuilder import api
    result = api.compile_file(path, compile_options(args, path, out))
    print_diagnostics(result, out)
    out.print(summary_line(path, result, out))
    return result.ok


def summary_line(path: Path, result, out: term.Out) -> str:
    counts = summary(result.diagnostics)
    status = out.paint("ok", "ok") if result.ok else out.paint("bad", "failed")
    return f"{out.paint('location', str(path) + ':')} {status}: {counts}; " \
           f"{result.kind.label} procedure {result.name}, {size_text(result)}"


def run(args: argparse.Namespace) -> int:
    safe_streams()
    out = term.Out(args.color)

    def body() -> int:
        ok = True
        for path in args.files:
            ok = check_file(path, args, out) and ok
        return 0 if ok else 1

    return guarded(body, out)
