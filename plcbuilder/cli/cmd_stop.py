"""``plcbuilder stop``: press Stop on the running controller (first M02, then OFF)."""

from __future__ import annotations

import argparse

from plcbuilder.cli._link_opts import add_link_options, run_client


def add_parser(subparsers) -> argparse.ArgumentParser:
    p = subparsers.add_parser(
        "stop", help="press Stop on the running controller",
        description="Press Stop: the first press starts M02, the second OFF (where the image "
                    "has them; otherwise the running hardware procedure just ends). Outputs "
                    "stay as the procedures left them.")
    add_link_options(p)
    return p


def run(args: argparse.Namespace) -> int:
    def body(client, out) -> int:
        r = client.stop()
        if r.get("started"):
            out.print(f"stop: started {r['started']} at t = {r.get('t_ms')} ms")
        else:
            out.print(f"stop: no stop procedure loaded; the running hardware procedure "
                      f"ended at t = {r.get('t_ms')} ms")
        return 0

    return run_client(args, body, "stop")
