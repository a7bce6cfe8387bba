"""``plcbuilder check FILE…``: compile each file and report its diagnostics.

Every diagnostic is printed the way compilers do (``file:line:col: error: text``,
the source line, a caret under the span, hints), then one summary line per
file with the procedure's size against its limit. Exit status: 0 when no file
has an error, 1 when one has (a missing or unreadable file is an error on that
file), 2 on bad usage.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from plcbuilder import api
from plcbuilder.cli import term
from plcbuilder.cli.common import (add_compile_options, compile_options, guarded,
                                   print_diagnostics, safe_streams, size_text)


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
    result = api.compile_file(path, compile_options(args, path, out))
    print_diagnostics(result, out)
    out.print(summary_line(path, result, out))
    return result.ok


def summary_line(path: Path, result, out: term.Out) -> str:
    counts = api.summary(result.diagnostics)
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
