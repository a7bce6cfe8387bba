"""What the commands share: the compiling commands' options, printing
diagnostics, turning an internal error into one line, and safe output streams.
(``api`` is imported where it is used: the link commands start without the compiler.)"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

from plcbuilder.cli import term

TYPE_CHECKING = False               # (typing is not imported at run time: start-up)
if TYPE_CHECKING:
    from typing import Callable, Optional

#: Set this environment variable to see the traceback of an internal error.
DEBUG_ENV = "PLCBUILDER_DEBUG"


# ------------------------------------------------------------ shared options

def int_in(lo: int, hi: int, unit: str = ""):
    """An argparse type: a decimal or 0x-hex whole number from lo to hi; outside
    it, argparse says ``argument --OPT: must be from LO to HI, not N`` (exit 2)."""
    from plcbuilder._support.numbers import parse_int_in

    def parse(text: str) -> int:
        try:
            return parse_int_in(text, lo, hi, "")
        except ValueError as exc:
            msg = str(exc)
            if unit:
                msg = msg.replace(f"to {hi},", f"to {hi} {unit},")
            raise argparse.ArgumentTypeError(msg) from None
    parse.__name__ = "whole number"
    return parse


def float_in(lo: float, hi: float, unit: str = ""):
    """An argparse type: a finite number with lo < value <= hi."""
    import math

    def parse(text: str) -> float:
        try:
            v = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"must be a number, not {text[:40]!r}") from None
        if not (math.isfinite(v) and lo < v <= hi):
            raise argparse.ArgumentTypeError(
                f"must be more than {lo:g} and at most {hi:g}{' ' + unit if unit else ''}, "
                f"not {text[:40]}")
        return v
    parse.__name__ = "number"
    return parse


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


def project_of(path: Path, out: Optional[term.Out] = None):
    """The project a file belongs to (it sits in a project's ``hardware/`` or
    ``software/`` folder), or None. A project whose settings cannot be read is
    reported on stderr and ignored (the defaults apply)."""
    from plcbuilder import api
    try:
        return api.Project.find_for(path)
    except (api.ProjectError, OSError) as exc:
        if out is not None:
            out.print(f"plcbuilder: warning: ignoring the project's settings: {exc}", err=True)
        return None


def compile_options(args: argparse.Namespace, path: Path, out: Optional[term.Out] = None):
    """The api.CompileOptions for one file: the command-line options, plus, for a file
    of a project, as Build All compiles it (the project's include folder, size limit
    and strict setting)."""
    from plcbuilder import api
    project = project_of(path, out)
    if project is None:
        return api.CompileOptions(kind=api.kind_of(path, args.software), strict=args.strict,
                                  include_dirs=tuple(args.include))
    return project.compile_options(path, software=args.software, strict=args.strict or None,
                                   extra_includes=tuple(args.include))


def size_text(result) -> str:
    """``120/512 bytes`` (``not compiled (limit 512 bytes)`` when there is no code)."""
    if result.size is None:
        return f"not compiled (limit {result.limit} bytes)"
    return f"{result.size}/{result.limit} bytes"


def print_diagnostics(result, out: term.Out, err: bool = False) -> None:
    """Every diagnostic of a compile result, rendered with its source line and caret."""
    from plcbuilder import api
    colorize = out.colorize(err)
    for d in result.diagnostics:
        out.print(api.render_text(d, result.source_line, colorize), err=err)


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


