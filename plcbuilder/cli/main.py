"""``plcbuilder``: the command line. Thin: each subcommand is a module of this
package with ``add_parser(subparsers)`` and ``run(args) -> int``."""

from __future__ import annotations

import argparse
import importlib
import sys

#: Subcommand modules, in the order ``--help`` lists them.
COMMANDS = ("gui", "check", "compile", "disasm", "run", "test", "new", "build",
            "controller", "upload", "start", "stop", "input", "state", "trace", "lsp", "dap",
            "desktop")


def build_parser(only: tuple[str, ...] | None = None) -> argparse.ArgumentParser:
    """The command line's parser: every command, or ``only`` those named (a
    command starts without importing the others' modules)."""
    parser = argparse.ArgumentParser(
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
    argv = list(sys.argv[1:] if argv is None else argv)
    if argv and argv[0].startswith("-") and argv[0].split("=", 1)[0] not in TOP_LEVEL_OPTIONS:
        argv.insert(0, "gui")           # `plcbuilder --settings F`: the default command's options
    first = argv[0] if argv else "gui"
    # only the command asked for is loaded; --help and a mistyped command see them all
    parser = build_parser((first,) if first in COMMANDS else () if first == "--version" else None)
    args = parser.parse_args(argv)
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
