"""``plcbuilder lsp``: the language server for other editors (docs/editors.md).

Speaks the Language Server Protocol on stdin/stdout, or with ``--tcp PORT``
to clients on loopback, each connection its own session (``--host`` to
listen elsewhere: an address other than loopback only with
``--allow-remote``). The server is :mod:`plcbuilder.lsp`; this module only
parses the options.
"""

from __future__ import annotations

import argparse
import ipaddress
import logging
import socket
import sys
from pathlib import Path


def add_parser(subparsers) -> argparse.ArgumentParser:
    p = subparsers.add_parser(
        "lsp", help="the language server for VS Code, Neovim, Helix, Emacs …",
        description="Serve the PLC language over the Language Server Protocol: diagnostics, "
                    "hover, completion, go to definition, references, rename, symbols, "
                    "semantic tokens and inlay hints. stdio by default.")
    p.add_argument("--tcp", type=int, metavar="PORT", default=None,
                   help="listen on this TCP port instead of stdio (0: any free port, printed); "
                        "each connection is a session of its own")
    p.add_argument("--host", default="127.0.0.1",
                   help="the address --tcp listens on (default 127.0.0.1, this machine only)")
    p.add_argument("--allow-remote", action="store_true",
                   help="let --host be an address other machines reach (any client that "
                        "connects reads the files of the workspace it names)")
    p.add_argument("--root", metavar="DIR", action="append", default=None,
                   help="with --tcp: the folder clients' workspaces must be inside (repeat for "
                        "more; default: the current folder)")
    p.add_argument("--log", metavar="FILE", default=None,
                   help="write the server's log to FILE (default: warnings to stderr)")
    return p


def _is_loopback(host: str) -> bool:
    """True when every address ``host`` names is this machine's loopback."""
    if not host:
        return False                                   # every interface
    try:
        return ipaddress.ip_address(host.split("%", 1)[0]).is_loopback
    except ValueError:
        pass
    try:
        infos = socket.getaddrinfo(host, None)
    except (OSError, UnicodeError):
        return False
    addrs = {info[4][0] for info in infos}
    try:
        return bool(addrs) and all(ipaddress.ip_address(a.split("%", 1)[0]).is_loopback
                                   for a in addrs)
    except ValueError:
        return False


def run(args: argparse.Namespace) -> int:
    if args.tcp is not None and not 0 <= args.tcp <= 65535:
        print(f"plcbuilder lsp: --tcp {args.tcp}: a port is 0..65535", file=sys.stderr)
        return 2
    if args.tcp is None and (args.root or args.allow_remote):
        print("plcbuilder lsp: --root and --allow-remote go with --tcp", file=sys.stderr)
        return 2
    roots = [Path(r).absolute() for r in args.root or [Path.cwd()]]
    for r in roots:
        if not r.is_dir():
            print(f"plcbuilder lsp: --root {r}: no such folder", file=sys.stderr)
            return 2
    if args.tcp is not None and not _is_loopback(args.host):
        if not args.allow_remote:
            print(f"plcbuilder lsp: --host {args.host or '(every interface)'} is reachable from "
                  "other machines, and any client that connects can read the files of the "
                  "workspace it names; add --allow-remote to listen there anyway",
                  file=sys.stderr)
            return 2
        print(f"plcbuilder lsp: warning: listening on {args.host or 'every interface'}: other "
              f"machines that reach it can read the files under {', '.join(map(str, roots))}",
              file=sys.stderr, flush=True)
    logging.basicConfig(filename=args.log, level=logging.INFO if args.log else logging.WARNING,
                        format="%(asctime)s %(name)s %(levelname)s %(message)s")
    # pygls logs every message's whole body at INFO: the log keeps ours
    logging.getLogger("pygls").setLevel(logging.WARNING)
    from plcbuilder.lsp import transport
    from plcbuilder.lsp.server import make_server
    if args.tcp is None:
        return transport.serve_stdio(make_server)

    def ready(address):
        print(f"plcbuilder lsp: listening on {address[0]}:{address[1]}", file=sys.stderr,
              flush=True)
    try:
        transport.serve_tcp(lambda: make_server(confine=roots), args.host, args.tcp, ready)
    except OSError as exc:
        print(f"plcbuilder lsp: cannot listen on {args.host}:{args.tcp}: {exc.strerror or exc}",
              file=sys.stderr)
        return 1
    return 0
