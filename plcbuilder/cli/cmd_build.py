"""``plcbuilder build PROJECT [--strict] [--quiet]``: Build All.

Compiles every procedure of the project (going on past errors) and prints each
one's diagnostics and a line with its size against its limit, then the
hardware total against its limit, what happened to ``build/eeprom.rom`` (only
written when there is no error; otherwise the previous image is kept) and a
summary. ``--quiet`` prints only the diagnostics and the summary. Exit status
1 if there is any error (in a procedure, in the totals, or in the project
settings), else 0. A folder that is not a project (no plcbuilder.toml,
hardware/ or software/) is refused with exit status 1, and nothing is written
there.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from plcbuilder import api
from plcbuilder.cli import term
from plcbuilder.cli.common import guarded, safe_streams


def add_parser(subparsers) -> argparse.ArgumentParser:
    p = subparsers.add_parser(
        "build", help="Build All: compile a project and write build/eeprom.rom",
        description="Compile every procedure of PROJECT (hardware/*.plc, software/*.plc), "
                    "print the diagnostics and sizes, write build/NAME.bin and, when there "
                    "is no error, the image build/eeprom.rom. Exit status 1 on any error.")
    p.add_argument("project", type=Path, metavar="PROJECT", nargs="?", default=Path("."),
                   help="the project folder (default: the current folder)")
    p.add_argument("--strict", action="store_true",
                   help="controller compatibility: report every construct the myCNC manual "
                        "does not show as an error (also set by [build] strict in "
                        "plcbuilder.toml)")
    p.add_argument("-q", "--quiet", action="store_true",
                   help="print only the diagnostics and the summary line")
    p.add_argument("--no-cache", action="store_true",
                   help="recompile every procedure (ignore build/.cache.json)")
    term.add_color_argument(p)
    return p


class _Progress:
    """``[done/total] name`` on one line of a terminal's stderr, for large projects."""

    def __init__(self, enabled: bool):
        self.enabled = enabled
        self.width = 0

    def __call__(self, done: int, total: int, name: str) -> None:
        if not self.enabled or total == 0:
            return
        text = f"[{done}/{total}] {name}"[:78]
        sys.stderr.write("\r" + text.ljust(self.width))
        sys.stderr.flush()
        self.width = len(text)

    def clear(self) -> None:
        if self.enabled and self.width:
            sys.stderr.write("\r" + " " * self.width + "\r")
            sys.stderr.flush()


def _procedure_line(pb, out: term.Out) -> str:
    status = out.paint("ok", "ok") if pb.ok else out.paint("bad", "failed")
    used = "-" if pb.size is None else str(pb.size)
    note = " (unchanged)" if pb.cached else ""
    return (f"{out.paint('location', str(pb.path) + ':')} {status}: "
            f"{api.summary_counts(pb.errors, pb.warnings)}; "
            f"{pb.kind.label} procedure {pb.name}, {used}/{pb.limit} bytes{note}")


def run(args: argparse.Namespace) -> int:
    safe_streams()
    out = term.Out(args.color)

    def body() -> int:
        try:
            project = api.Project.open(args.project, existing=True)
        except api.ProjectError as exc:
            out.print(f"plcbuilder build: error: {exc}", err=True)
            return 1
        progress = _Progress(not args.quiet and _isatty(sys.stderr))
        try:
            result = api.build_project(project, progress, strict=args.strict or None,
                                       use_cache=not args.no_cache)
        except OSError as exc:
            progress.clear()
            out.print(f"plcbuilder build: error: cannot write {getattr(exc, 'filename', '')}: "
                      f"{exc.strerror or exc}", err=True)
            return 1
        progress.clear()
        report(result, out, args.quiet)
        return 0 if result.ok else 1

    return guarded(body, out)


def _isatty(stream) -> bool:
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError, OSError):
        return False


def report(result, out: term.Out, quiet: bool = False) -> None:
    """Print a BuildResult the way `plcbuilder build` does."""
    colorize = out.colorize()
    for pb in result.procedures:
        if colorize is None:            # as the compiler rendered them (or the cache kept them)
            shown = pb.shown()
            if shown:
                out.print(shown)
        else:
            for d in pb.diagnostics:
                out.print(api.render_text(d, pb.source_line, colorize))
        if not quiet:
            out.print(_procedure_line(pb, out))
    for d in result.diagnostics:
        out.print(api.render_text(d, result.source_line, colorize))
    hw = [p for p in result.procedures if p.kind.label == "hardware"]
    sw = [p for p in result.procedures if p.kind.label == "software"]
    if not quiet:
        over = result.hw_total > result.limits.hw_total
        total = f"{result.hw_total}/{result.limits.hw_total} bytes"
        failed = sum(1 for p in hw if not p.ok)
        note = f", {failed} not compiled" if failed else ""
        out.print(f"hardware total: {out.paint('bad', total) if over else total} "
                  f"({len(hw)} procedure{'s' * (len(hw) != 1)}{note}); software: "
                  f"{sum(p.size or 0 for p in sw)} bytes ({len(sw)} procedure{'s' * (len(sw) != 1)})")
        out.print(result.image_message)
    elif not result.image_written:
        out.print(result.image_message)
    n = len(result.procedures)
    counts = api.summary_counts(result.error_count, result.warning_count)
    status = out.paint("ok", "Build All ok") if result.ok else out.paint("bad", "Build All failed")
    out.print(f"{status}: {n} procedure{'s' * (n != 1)}, {counts} "
              f"({result.compiled} compiled, {result.reused} unchanged)")
