"""What the commands that talk to a running controller share (upload, start,
stop, input, state): the ``--controller HOST:PORT`` and ``--token`` options,
connecting, and turning link errors into one clear line and an exit status.

Exit status: 0 done, 1 refused by the controller or no controller to talk to,
2 bad usage.
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path
from typing import Callable

from plcbuilder.cli import term
from plcbuilder.cli.common import DEBUG_ENV, float_in, safe_streams

MAX_TIMEOUT_S = 86_400.0

EXIT_OK, EXIT_FAIL, EXIT_USAGE = 0, 1, 2


def add_link_options(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("controller")
    g.add_argument("--controller", metavar="HOST:PORT",
                   help="the controller's address (default: from the runtime file that "
                        "'plcbuilder controller' writes)")
    g.add_argument("--token", metavar="TOKEN",
                   help="the controller's token (default: from the runtime file)")
    g.add_argument("--runtime-file", type=Path, metavar="FILE",
                   help="read the address and token from FILE instead of the default "
                        "runtime file")
    g.add_argument("--timeout", type=float_in(0.0, MAX_TIMEOUT_S, "s"), default=30.0,
                   metavar="S",
                   help="seconds to wait for each answer (default 30)")
    term.add_color_argument(p)


def add_project_option(p: argparse.ArgumentParser) -> None:
    p.add_argument("--project", type=Path, metavar="DIR",
                   help="the project the image is of: the controller runs it on the "
                        "project's target (docs/targets.md). Default: the project whose "
                        "build/eeprom.rom the image is; none (myCNC) for an image elsewhere")


def image_target(image: Path, project: "Path | None") -> "tuple[dict | None, str]":
    """The target profile to load ``image`` with, as the IDE sends it, and the
    target's name: that of the project DIR (``--project``), else of the project
    whose ``build/eeprom.rom`` the image is; (None, "mycnc") for a myCNC project or
    an image outside a project. Raises ProjectError for a project that cannot be
    read (a bad plcbuilder.toml or parameters file names the line)."""
    from plcbuilder.api import Project
    if project is None:
        root = Path(image).resolve().parent.parent
        if not (root / "plcbuilder.toml").is_file():
            return None, "mycnc"
        found = Project.open(root)
        if found.image_path.resolve() != Path(image).resolve():
            return None, "mycnc"
    else:
        found = Project.open(project)
    target = found.target_settings()
    if target.get("name") == "mycnc":
        return None, "mycnc"
    return {k: list(v) if isinstance(v, tuple) else v for k, v in target.items()}, target["name"]


def connect(args: argparse.Namespace):
    """A connected Client from the options (link errors propagate)."""
    from plcbuilder.link.client import Client, parse_address
    host = port = None
    if args.controller:
        host, port = parse_address(args.controller)
    return Client.connect(host, port, args.token, timeout=args.timeout,
                          runtime_file=args.runtime_file)


def run_client(args: argparse.Namespace, body: Callable, what: str) -> int:
    """Connect, run ``body(client, out)``, close; link errors become one line on
    stderr and exit status 1 (2 for a bad --controller)."""
    from plcbuilder.link.client import LinkError, NotRunningError, RefusedError
    safe_streams()
    out = term.Out(getattr(args, "color", "auto"))
    try:
        client = connect(args)
    except ValueError as exc:
        out.print(f"plcbuilder {what}: --controller: {exc}", err=True)
        return EXIT_USAGE
    except NotRunningError as exc:
        out.print(f"plcbuilder {what}: {exc}", err=True)
        return EXIT_FAIL
    except RefusedError as exc:
        out.print(f"plcbuilder {what}: the controller refused the connection: {exc.reason}",
                  err=True)
        return EXIT_FAIL
    except LinkError as exc:
        out.print(f"plcbuilder {what}: {exc}", err=True)
        return EXIT_FAIL
    try:
        return int(body(client, out) or 0)
    except RefusedError as exc:
        out.print(f"plcbuilder {what}: refused: {exc.reason}", err=True)
        return EXIT_FAIL
    except LinkError as exc:
        out.print(f"plcbuilder {what}: {exc}", err=True)
        return EXIT_FAIL
    except (KeyboardInterrupt, BrokenPipeError):
        raise
    except Exception as exc:  # noqa: BLE001 - a message, not a traceback
        if os.environ.get(DEBUG_ENV):
            raise
        out.print(f"plcbuilder {what}: internal error: {type(exc).__name__}: {exc} "
                  f"(set {DEBUG_ENV}=1 to see the traceback)", err=True)
        return EXIT_FAIL
    finally:
        client.close()


def parse_int(text: str) -> int:
    """A decimal or 0x-hex integer (argparse type)."""
    try:
        return int(text.strip(), 0)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not an integer: {text!r}") from None
