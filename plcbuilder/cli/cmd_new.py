"""``plcbuilder new DIR [--name NAME]``: create a project from the example.

The new project holds working hardware procedures (M02, M03, M05, M07, M08,
M09, M71, M80, M81, OFF), software procedures (LUBE, __HANDLER_INIT),
include/pins.h, plc-variables.xml, the default machine (machine.toml) and
plcbuilder.toml. DIR must not exist or be empty. Exit status 1 if the project
cannot be created.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from plcbuilder.cli import term
from plcbuilder.cli.common import guarded, safe_streams


def add_parser(subparsers) -> argparse.ArgumentParser:
    p = subparsers.add_parser(
        "new", help="create a new project from the example project",
        description="Create a PLC Builder project in DIR (which must not exist, or be empty) "
                    "with example hardware and software procedures, include/pins.h, "
                    "plc-variables.xml, the default machine and plcbuilder.toml.")
    p.add_argument("dir", type=Path, metavar="DIR", help="the folder to create")
    p.add_argument("--name", help="the project's name (default: the folder's name)")
    p.add_argument("--target", choices=("mycnc", "huazhong", "tgmotion"), default="mycnc",
                   help="the controller the project is for (docs/targets.md): its example "
                        "program and tests (default: mycnc)")
    term.add_color_argument(p)
    return p


def run(args: argparse.Namespace) -> int:
    safe_streams()
    out = term.Out(args.color)

    def body() -> int:
        from plcbuilder import api
        try:
            project = api.create_project(args.dir, args.name, target=args.target)
        except api.ProjectError as exc:
            out.print(f"plcbuilder new: error: {exc}", err=True)
            return 1
        procs = project.procedures()
        hw = [p.name for p in procs if p.kind.label == "hardware"]
        sw = [p.name for p in procs if p.kind.label == "software"]
        out.print(f"created project {project.name!r} in {args.dir}")
        if args.target != "mycnc":
            out.print(f"  target: {args.target}, program: {' '.join(hw)}")
        else:
            out.print(f"  hardware: {' '.join(hw)}")
            out.print(f"  software: {' '.join(sw)}")
        out.print(f"build it with: plcbuilder build {args.dir}")
        return 0

    return guarded(body, out)
