"""``plcbuilder compile FILE [-o OUT]``: compile one procedure to a binary.

Diagnostics go to stderr; on success one line on stdout names the file written
and its size against its limit. The binary is written atomically (a temporary
file in the same folder, then ``os.replace``), so a failed or interrupted
compile never leaves a half-written OUT. With errors nothing is written.
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
        "compile", help="compile a PLC source file to a binary",
        description="Compile FILE to a binary procedure (default: FILE with the suffix .bin). "
                    "Diagnostics go to stderr; exit status 1 on errors, and then nothing "
                    "is written.")
    p.add_argument("file", type=Path, metavar="FILE", help="a .plc source file")
    p.add_argument("-o", "--output", type=Path, metavar="OUT",
                   help="where to write the binary (a folder: OUT/NAME.bin)")
    add_compile_options(p)
    return p


def output_path(src: Path, out: Path | None, name: str) -> Path:
    if out is None:
        return src.with_suffix(".bin")
    if out.is_dir():
        return out / f"{name}.bin"
    return out


def _same_file(a: Path, b: Path) -> bool:
    try:
        return a.resolve() == b.resolve()
    except OSError:
        return False


def run(args: argparse.Namespace) -> int:
    safe_streams()
    out = term.Out(args.color)

    def body() -> int:
        src: Path = args.file
        result = api.compile_file(src, compile_options(args, src, out))
        print_diagnostics(result, out, err=True)
        if not result.ok or result.program is None:
            out.print(f"{out.paint('location', str(src) + ':', err=True)} "
                      f"{out.paint('bad', 'not compiled', err=True)}: {api.summary(result.diagnostics)}",
                      err=True)
            return 1
        dest = output_path(src, args.output, result.name)
        if _same_file(dest, src):
            out.print(f"plcbuilder compile: error: the output {dest} is the source file itself; "
                      f"choose another with -o", err=True)
            return 1
        try:
            api.atomic_write(dest, result.program.to_bytes())
        except OSError as exc:
            out.print(f"plcbuilder compile: error: cannot write {dest}: {exc.strerror or exc}",
                      err=True)
            return 1
        out.print(f"{out.paint('location', str(dest) + ':')} {result.kind.label} procedure "
                  f"{result.name}, {size_text(result)}")
        return 0

    return guarded(body, out)
