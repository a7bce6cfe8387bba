"""``plcbuilder dap``: the debug adapter for other editors (docs/editors.md).

Speaks the Debug Adapter Protocol on stdin/stdout; the adapter is
:mod:`plcbuilder.dap`. An editor starts it (VS Code: a launch.json
configuration of type ``plcbuilder``, through a debug adapter description).
"""

from __future__ import annotations

import argparse


def add_parser(subparsers) -> argparse.ArgumentParser:
    return subparsers.add_parser(
        "dap", help="the debug adapter for VS Code and other editors",
        description="Serve the Debug Adapter Protocol on stdin/stdout: launch (build, upload, "
                    "start a procedure) or attach to a controller, breakpoints with conditions, "
                    "hit counts and logpoints, stepping, variables, write and evaluate.")


def run(args: argparse.Namespace) -> int:
    from plcbuilder.dap import session
    return session.serve_stdio()
