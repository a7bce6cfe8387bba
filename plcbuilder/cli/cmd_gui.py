"""``plcbuilder gui [PROJECT]``: the IDE.

``--screenshot FILE`` opens the project, builds it, optionally runs a
procedure (``--run NAME[:EPARAM]`` for ``--after MS`` of simulated time),
saves a PNG of the main window and exits. Importing this module does not
load Qt: the IDE is imported when the command runs.
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

from plcbuilder.cli.common import int_in


def _has_display() -> bool:
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")
                or sys.platform in ("win32", "darwin"))


def _uses_xcb() -> bool:
    """Qt will load its X11 platform plugin (Linux, an X display, no other platform asked)."""
    platform = os.environ.get("QT_QPA_PLATFORM", "")
    if platform:
        return platform.startswith("xcb")
    return sys.platform.startswith("linux") and bool(os.environ.get("DISPLAY")) \
        and not os.environ.get("WAYLAND_DISPLAY")


def add_parser(subparsers) -> argparse.ArgumentParser:
    p = subparsers.add_parser(
        "gui", help="the IDE (the default command)",
        description="Open the PLC Builder IDE, with PROJECT when given (else the last "
                    "project). With --screenshot, save a PNG of the window and exit.")
    p.add_argument("project", nargs="?", type=Path, metavar="PROJECT",
                   help="a project folder to open, or a file of one (a .plc, a header, "
                        "its plcbuilder.toml: the project opens with the file)")
    p.add_argument("--screenshot", type=Path, metavar="FILE",
                   help="open PROJECT, build it, save a PNG of the main window to FILE, exit")
    p.add_argument("--run", metavar="NAME[:EPARAM]",
                   help="with --screenshot: upload the image and start this procedure first")
    p.add_argument("--after", type=int_in(0, 7 * 24 * 3600 * 1000, "ms"), default=1000,
                   metavar="MS",
                   help="with --screenshot: simulated milliseconds to run (with --run), or "
                        "milliseconds to wait (default 1000)")
    p.add_argument("--trace", action="append", default=[], type=Path, metavar="FILE",
                   help="with --screenshot: show this .plctrace in the run panels; a second "
                        "--trace is compared with it (drawn dashed over it)")
    p.add_argument("--settings", type=Path, metavar="FILE",
                   help="keep the IDE's settings in this INI file instead of the user's")
    p.add_argument("--no-controller", action="store_true",
                   help="do not start the embedded simulated controller")
    return p


def run(args: argparse.Namespace) -> int:
    if getattr(args, "run", None) and not getattr(args, "screenshot", None):
        print("plcbuilder gui: --run needs --screenshot", file=sys.stderr)
        return 2
    traces = list(getattr(args, "trace", None) or [])
    if traces and not getattr(args, "screenshot", None):
        print("plcbuilder gui: --trace needs --screenshot", file=sys.stderr)
        return 2
    if len(traces) > 2:
        print("plcbuilder gui: --trace at most twice (a trace, and one to compare with it)",
              file=sys.stderr)
        return 2
    if getattr(args, "after", 1000) < 0:
        print("plcbuilder gui: --after must not be negative", file=sys.stderr)
        return 2
    project = getattr(args, "project", None)
    if project is not None and not project.exists():
        print(f"plcbuilder gui: {project}: no such project folder or file", file=sys.stderr)
        return 2
    if "QT_QPA_PLATFORM" not in os.environ and not _has_display():
        if getattr(args, "screenshot", None):
            os.environ["QT_QPA_PLATFORM"] = "offscreen"     # a picture needs no screen
        else:
            print("plcbuilder gui: no display (DISPLAY is not set); run it on a desktop, or "
                  "use --screenshot FILE, or set QT_QPA_PLATFORM=offscreen", file=sys.stderr)
            return 1
    check = None
    if _uses_xcb():
        from plcbuilder.cli import qt_libs
        check = qt_libs.start_check()   # (ldd runs while the IDE's modules load)
    try:
        from plcbuilder.ide.app import main
    except ImportError as exc:
        print(f"plcbuilder gui: the IDE cannot start: {exc}", file=sys.stderr)
        return 1
    if check is not None:
        missing = check.missing()
        if missing:                     # Qt would stop with "could not load ... xcb"
            print("plcbuilder gui: " + qt_libs.report(missing), file=sys.stderr)
            return 1
    settings = getattr(args, "settings", None)
    return main(str(project) if project else None,
                screenshot=str(args.screenshot) if getattr(args, "screenshot", None) else None,
                run=getattr(args, "run", None), after_ms=getattr(args, "after", 1000),
                settings_path=str(settings) if settings else None,
                start_controller=not getattr(args, "no_controller", False),
                traces=tuple(str(t) for t in traces))
