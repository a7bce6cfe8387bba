"""``plcbuilder start NAME [--eparam N]``: start a procedure on the running controller.

NAME is a procedure name (``M03``, ``LUBE``, ``__HANDLER_GCODE_START``) or an
M-code number (``3`` starts ``M03``).
"""

from __future__ import annotations

import argparse

from plcbuilder._support.numbers import WORD32, parse_int_in, to_int32
from plcbuilder.cli._link_opts import EXIT_USAGE, add_link_options, run_client
from plcbuilder.cli.common import int_in

MAX_MCODE = 1_000_000


def add_parser(subparsers) -> argparse.ArgumentParser:
    p = subparsers.add_parser(
        "start", help="start a procedure on the running controller",
        description="Start the procedure NAME, or the hardware procedure of an M-code when "
                    "NAME is a number (3 starts M03). A refused start (nothing of that name "
                    "is loaded) prints the controller's reason and exits 1.")
    p.add_argument("name", metavar="NAME", help="procedure name or M-code number")
    p.add_argument("--eparam", type=int_in(*WORD32), default=0, metavar="N",
                   help="the procedure's eparam (default 0; a 32-bit value, -2147483648 to "
                        "4294967295, decimal or 0x hex)")
    add_link_options(p)
    return p


def run(args: argparse.Namespace) -> int:
    import sys
    name = args.name.strip()
    eparam = to_int32(args.eparam)              # the protocol carries it signed
    mcode = None
    if name.isdigit():
        try:
            mcode = parse_int_in(name, 0, MAX_MCODE, "an M-code number")
        except ValueError as exc:
            print(f"plcbuilder start: {exc}", file=sys.stderr)
            return EXIT_USAGE

    def body(client, out) -> int:
        if mcode is not None:
            r = client.start(mcode=mcode, eparam=eparam)
        else:
            r = client.start(name, eparam=eparam)
        out.print(f"started {r.get('started')} (eparam {r.get('eparam')}) at t = "
                  f"{r.get('t_ms')} ms")
        return 0

    return run_client(args, body, "start")
