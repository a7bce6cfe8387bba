"""``plcbuilder desktop-install [--remove]``: PLC Builder in the Linux desktop's
applications menu, with its icon, opening ``*.plc`` files, ``plcbuilder.toml``
and project folders (``cli/desktop.py`` says what it writes, and where)."""

from __future__ import annotations

import argparse
import sys

from plcbuilder.cli.common import guarded, safe_streams
from plcbuilder.cli import term


def add_parser(subparsers) -> argparse.ArgumentParser:
    p = subparsers.add_parser(
        "desktop-install", help="add PLC Builder to the Linux desktop (menu, icon, file types)",
        description="Add PLC Builder to the applications menu of a Linux desktop "
                    "(freedesktop.org): a launcher with the app icon, and *.plc files, "
                    "plcbuilder.toml and project folders opened with it. Writes under "
                    "$XDG_DATA_HOME (~/.local/share) and $XDG_CONFIG_HOME/mimeapps.list.")
    p.add_argument("--remove", action="store_true",
                   help="take the launcher, the icon and the file types away again")
    term.add_color_argument(p)
    return p


def run(args: argparse.Namespace) -> int:
    safe_streams()
    out = term.Out(args.color)

    def body() -> int:
        from plcbuilder.cli import desktop
        if sys.platform != "linux" and not args.remove:
            out.print("plcbuilder desktop-install: error: this is for Linux desktops "
                      "(freedesktop.org)", err=True)
            return 1
        try:
            done = desktop.remove() if args.remove else desktop.install()
        except OSError as exc:
            where = f"{exc.filename}: " if getattr(exc, "filename", None) else ""
            out.print(f"plcbuilder desktop-install: error: {where}{exc.strerror or exc}",
                      err=True)
            return 1
        verb = "removed" if args.remove else "wrote"
        for path in done.files:
            out.print(f"{verb} {path}")
        for line in done.ran:
            out.print(f"ran {line}")
        for note in done.notes:
            out.print(f"note: {note}")
        if not args.remove:
            out.print("PLC Builder is in the applications menu (Development); *.plc files "
                      "and plcbuilder.toml open with it")
        return 0

    return guarded(body, out)
