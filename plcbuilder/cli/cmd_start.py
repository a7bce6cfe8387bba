"""``plcbuilder start NAME [--eparam N]``: start a procedure on the running controller.

NAME is a procedure name (``M03``, ``LUBE``, ``__HANDLER_GCODE_START``) or an
M-code number (``3`` starts ``M03``).
"""

from __future__ import annotations

import argparse

from plcbuilder.cli._link_opts import add_link_options, parse_int, run_client


def add_parser(subparsers) -> argparse.ArgumentParser:
    p = subparsers.add_parser(
        "start", help="start a procedure on the running controller",
        description="Start the procedure NAME, or the hardware procedure of an M-code when "
                    "NAME is a number (3 starts M03). A refused start (nothing of that name "
                    "is loaded) prints the controller's reason and exits 1.")
    p.add_argument("name", metavar="NAME", help="procedure name or M-code number")
    p.add_argument("--eparam", type=parse_int, default=0, metavar="N",
                   help="the procedure's eparam (default 0; decimal or 0x hex)")
    add_link_options(p)
    return p


def run(args: argparse.Namespace) -> int:
    name = args.name.strip()

    def body(client, out) -> int:
        if name.isdigit():
            r = client.start(mcode=int(name), eparam=args.eparam)
        else:
            r = client.start(name, eparam=args.eparam)
        out.print(f"started {r.get('started')} (eparam {r.get('eparam')}) at t = "
                  f"{r.get('t_ms')} ms")
        return 0

    return run_client(args, body, "start")
