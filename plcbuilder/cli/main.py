"""``plcbuilder``: the command line. Thin: each subcommand is a module of this
package with ``add_parser(subparsers)`` and ``run(args) -> int``."""

from __future__ import annotations

import argparse
import gc
import importlib
import os
import sys

#: Subcommand modules, in the order ``--help`` lists them.
COMMANDS = ("gui", "check", "compile", "disasm", "run", "test", "new", "build",
            "controller", "upload", "start", "stop", "input", "state", "trace", "lsp", "dap",
            "desktop")


def _columns() -> int:
    """The terminal's width, as ``shutil.get_terminal_size`` finds it."""
    try:
        cols = int(os.environ.get("COLUMNS", "0"))
    except ValueError:
        cols = 0
    if cols <= 0:
        try:
            cols = os.get_terminal_size(sys.__stdout__.fileno()).columns
        except (AttributeError, ValueError, OSError):
            cols = 0
    return cols or 80


class _Formatter(argparse.HelpFormatter):
    """argparse's, told the width: argparse asks ``shutil`` for it, and
    importing shutil (with its compression modules) is a tenth of a bare
    Python start, paid by every command for a help text it rarely prints."""

    def __init__(self, prog, indent_increment=2, max_help_position=24, width=None):
        super().__init__(prog, indent_increment, max_help_position,
                         _columns() - 2 if width is None else width)


class _Parser(argparse.ArgumentParser):
    """The parser of the command line and of each command (the subcommands'
    parsers are of the parent's class): with :class:`_Formatter`."""

    def __init__(self, *args, **kwargs):
        kwargs.setdefault("formatter_class", _Formatter)
        super().__init__(*args, **kwargs)


def build_parser(only: tuple[str, ...] | None = None) -> argparse.ArgumentParser:
    """The command line's parser: every command, or ``only`` those named (a
    command starts without importing the others' modules)."""
    parser = _Parser(
        prog="plcbuilder",
        description="PLC Builder: edit, compile and simulate myCNC PLC procedures.")
    from plcbuilder import __version__
    parser.add_argument("--version", action="version", version=f"plcbuilder {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in COMMANDS if only is None else only:
        try:
            mod = importlib.import_module(f"plcbuilder.cli.cmd_{name}")
        except ModuleNotFoundError as exc:
            if exc.name == f"plcbuilder.cli.cmd_{name}":
                continue
            raise
        p = mod.add_parser(sub)
        p.set_defaults(_run=mod.run)
    return parser


#: options of the parser itself; any other leading option is the IDE's
TOP_LEVEL_OPTIONS = ("-h", "--help", "--version")


def main(argv: list[str] | None = None) -> int:
    """The command line: ``argv``, or (None) the program's own arguments.

    Run as the program, the collector waits while the command line starts:
    what starting makes (modules, classes, the command's parser) lives to the
    end, and the collector went through it in a tenth of a short command's
    time. Once the arguments are read those objects are frozen (``gc.freeze``:
    no later pass, the last one at exit included, goes through them again) and
    the collector runs as usual for the command itself."""
    program = argv is None
    if program:
        gc.disable()
    argv = list(sys.argv[1:] if argv is None else argv)
    if argv and argv[0].startswith("-") and argv[0].split("=", 1)[0] not in TOP_LEVEL_OPTIONS:
        argv.insert(0, "gui")           # `plcbuilder --settings F`: the default command's options
    first = argv[0] if argv else "gui"
    # only the command asked for is loaded; --help and a mistyped command see them all
    parser = build_parser((first,) if first in COMMANDS else () if first == "--version" else None)
    args = parser.parse_args(argv)
    if program:
        gc.freeze()
        gc.enable()
    if getattr(args, "_run", None) is None:
        try:
            mod = importlib.import_module("plcbuilder.cli.cmd_gui")
        except ModuleNotFoundError:
            parser.print_help()
            return 2
        return mod.run(parser.parse_args(["gui"]))
    try:
        return int(args._run(args) or 0)
    except KeyboardInterrupt:
        return 130
    except BrokenPipeError:
        return 0
