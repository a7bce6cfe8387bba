"""``plcbuilder disasm FILE``: show a compiled procedure's code.

FILE is a compiled binary (``.bin``, or any file that starts with the binary's
magic) or a source file, which is compiled first. Source lines are shown beside
the code when the sources can be found: for a source file always; for a binary
when the files it names still exist (they are named relative to the procedure's
folder: looked for beside the binary, in ``../hardware`` or ``../software`` for
a project's ``build/`` folder, then in the current folder). Sources that
changed since the compile are shown as they are now. A binary that cannot be loaded prints the
reason and exits 1; so does a source file with errors (its diagnostics go to
stderr; a source file's warnings are left to ``check``).
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Callable, Optional

from plcbuilder import api
from plcbuilder._support.files import read_bounded
from plcbuilder.cli import term
from plcbuilder.cli.common import (add_compile_options, compile_options, guarded,
                                      print_diagnostics, safe_streams)

MAX_SOURCE_FILE = 1 << 20


def add_parser(subparsers) -> argparse.ArgumentParser:
    p = subparsers.add_parser(
        "disasm", help="disassemble a compiled procedure (or a source file)",
        description="Print the code of a compiled procedure FILE.bin, or of a source file "
                    "compiled first, with the source lines where they are available.")
    p.add_argument("file", type=Path, metavar="FILE", help="a .bin binary or a .plc source file")
    add_compile_options(p)
    return p


def is_binary(path: Path) -> bool:
    """A .bin name, or contents that start with the binary's magic."""
    if path.suffix.lower() == ".bin":
        return True
    try:      # not a regular file, or too large: compiling it says why
        return read_bounded(path, MAX_SOURCE_FILE).startswith(api.MAGIC)
    except OSError:
        return False


def source_reader(bases: list[Path]) -> Callable[[str, int], Optional[str]]:
    """source_line(file, line) over files found on disk, relative to one of bases."""
    cache: dict[str, Optional[list[str]]] = {}

    def load(name: str) -> Optional[list[str]]:
        if name.startswith(api.BUILTIN_PREFIX):
            text = api.builtin_header(name[len(api.BUILTIN_PREFIX):])
            return text.split("\n") if text is not None else None
        if name.startswith("<"):
            return None
        p = Path(name)
        candidates = [p] if p.is_absolute() else [b / p for b in bases]
        for c in candidates:
            try:
                text = read_bounded(c, MAX_SOURCE_FILE).decode("utf-8", errors="replace")
            except OSError:
                continue
            return text.replace("\r\n", "\n").replace("\r", "\n").split("\n")
        return None

    def source_line(name: str, line: int) -> Optional[str]:
        if name not in cache:
            cache[name] = load(name)
        lines = cache[name]
        if lines is None or not 1 <= line <= len(lines):
            return None
        return lines[line - 1]

    return source_line


def _highlighted(source_line, out: term.Out):
    if source_line is None or not out.color:
        return source_line

    def wrapped(name: str, line: int) -> Optional[str]:
        text = source_line(name, line)
        return None if text is None else out.highlight(text.strip())

    return wrapped


def run(args: argparse.Namespace) -> int:
    safe_streams()
    out = term.Out(args.color)

    def body() -> int:
        path: Path = args.file
        if is_binary(path):
            try:
                program = api.load_program(path)
            except api.LoadError as exc:
                out.print(f"{out.paint('location', str(path) + ':', err=True)} "
                          f"{out.paint('error', 'error:', err=True)} {exc}", err=True)
                return 1
            except OSError as exc:
                out.print(f"{path}: error: cannot read: {exc.strerror or exc}", err=True)
                return 1
            # the binary names its sources relative to the procedure's folder: the
            # binary's own folder (compile), or a project's hardware/ or software/ (build/)
            folder = "software" if program.kind == api.Kind.SOFTWARE else "hardware"
            bases = [path.parent, path.parent.parent / folder, Path.cwd()]
            source_line = source_reader(bases)
        else:
            result = api.compile_file(path, compile_options(args, path, out))
            if not result.ok or result.program is None:
                print_diagnostics(result, out, err=True)   # warnings only matter then too
                return 1
            program, source_line = result.program, result.source_line
        text = api.disassemble(program, _highlighted(source_line, out))
        out.print(text.rstrip("\n"))
        return 0

    return guarded(body, out)
