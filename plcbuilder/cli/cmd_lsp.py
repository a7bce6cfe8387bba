"""``plcbuilder lsp``: the language server for other editors (docs/editors.md).

Speaks the Language Server Protocol on stdin/stdout, or with ``--tcp PORT``
to one client at a time on loopback (``--host`` to listen elsewhere). The
server is :mod:`plcbuilder.lsp`; this module only parses the options.
"""

from __future__ import annotations

import argparse
import logging
import sys


def add_parser(subparsers) -> argparse.ArgumentParser:
    p = subparsers.add_parser(
        "lsp", help="the language server for VS Code, Neovim, Helix, Emacs …",
        description="Serve the PLC language over the Language Server Protocol: diagnostics, "
                    "hover, completion, go to definition, references, rename, symbols, "
                    "semantic tokens and inlay hints. stdio by default.")
    p.add_argument("--tcp", type=int, metavar="PORT", default=None,
                   help="listen on this TCP port instead of stdio (0: any free port, printed)")
    p.add_argument("--host", default="127.0.0.1",
                   help="the address --tcp listens on (default 127.0.0.1, this machine only)")
    p.add_argument("--log", metavar="FILE", default=None,
                   help="write the server's log to FILE (default: warnings to stderr)")
    return p


def run(args: argparse.Namespace) -> int:
    if args.tcp is not None and not 0 <= args.tcp <= 65535:
        print(f"plcbuilder lsp: --tcp {args.tcp}: a port is 0..65535", file=sys.stderr)
        return 2
    logging.basicConfig(filename=args.log, level=logging.INFO if args.log else logging.WARNING,
                        format="%(asctime)s %(name)s %(levelname)s %(message)s")
    from plcbuilder.lsp import server
    if args.tcp is None:
        server.serve_stdio()
        return 0

    def ready(address):
        print(f"plcbuilder lsp: listening on {address[0]}:{address[1]}", file=sys.stderr,
              flush=True)
    try:
        server.serve_tcp(args.host, args.tcp, ready)
    except OSError as exc:
        print(f"plcbuilder lsp: cannot listen on {args.host}:{args.tcp}: {exc.strerror or exc}",
              file=sys.stderr)
        return 1
    return 0
