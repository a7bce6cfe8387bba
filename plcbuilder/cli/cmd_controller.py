"""``plcbuilder controller``: the simulated controller as a server.

Listens on 127.0.0.1 (``--host`` to change; anything but loopback sends the
token in clear over the network, so a warning says so), on ``--port`` (0, the
default: a free port). A fresh random token is made each time; the address and
token go to the runtime file (0600) where ``plcbuilder upload/start/stop/
input/state`` and the IDE find them, and the file is removed on exit. SIGINT
(Ctrl+C) and SIGTERM run ``__HANDLER_EXIT`` and stop cleanly (exit 0).
"""

from __future__ import annotations

import argparse
import os
import signal
import sys
import time
from pathlib import Path

from plcbuilder.cli._link_opts import EXIT_FAIL, EXIT_USAGE, add_project_option, image_target
from plcbuilder.cli.common import int_in

MAX_LATENCY_MS = 60_000
#: How often the waiting controller looks whether a signal came (it answers
#: Ctrl+C or SIGTERM within this; its parent and server every 0.5 s).
SIGNAL_POLL_S = 0.1


def parse_speed(text: str) -> tuple[str, float]:
    """``--speed``: link.protocol.parse_speed's, for argparse (its error as a usage error)."""
    from plcbuilder.link.protocol import parse_speed as parse
    try:
        mode, factor = parse(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None
    return mode, 1.0 if factor is None else factor


def _loopback(host: str) -> bool:
    import ipaddress
    try:
        return ipaddress.ip_address(host.split("%")[0]).is_loopback
    except ValueError:
        return False


def parse_limits(text: str):
    from plcbuilder.link.server import Limits
    parts = text.split(",")
    try:
        if len(parts) != 3:
            raise ValueError
        lim = Limits(*(int(p, 0) for p in parts))
        lim.check()
    except Exception:  # noqa: BLE001
        raise argparse.ArgumentTypeError(
            f"expected HW_PROC,HW_TOTAL,SW_PROC (bytes, such as 512,8192,16384), got {text!r}"
        ) from None
    return lim


def add_parser(subparsers) -> argparse.ArgumentParser:
    p = subparsers.add_parser(
        "controller", help="run the simulated controller as a server",
        description="Serve the simulated controller over TCP (loopback unless --host says "
                    "otherwise). Its address and a fresh token go to a runtime file only the "
                    "user can read, where the CLI and the IDE find them. Ctrl+C or SIGTERM "
                    "runs __HANDLER_EXIT and stops.")
    p.add_argument("--host", default="127.0.0.1",
                   help="address to listen on (default 127.0.0.1; other addresses expose "
                        "the controller to the network)")
    p.add_argument("--port", type=int_in(0, 65535), default=0, metavar="N",
                   help="TCP port (default 0: a free port, printed and written to the "
                        "runtime file)")
    p.add_argument("--machine", type=Path, metavar="FILE",
                   help="machine description (default: the built-in default machine)")
    p.add_argument("--variables", type=Path, metavar="FILE",
                   help="plc-variables.xml: initial values of var00..var15")
    p.add_argument("--io-dat", type=Path, metavar="FILE", dest="io_dat",
                   help="IO.DAT: softMC presets of the inputs (INP=0x.., DIP=0x..)")
    p.add_argument("--image", type=Path, metavar="FILE",
                   help="an eeprom.rom image to load at start")
    add_project_option(p)
    p.add_argument("--speed", type=parse_speed, default=("realtime", 1.0),
                   metavar="realtime|N|max|pause",
                   help="pace: real time (default), N times real time, as fast as possible, "
                        "or paused")
    p.add_argument("--limits", type=parse_limits, default=None, metavar="HW,TOTAL,SW",
                   help="code size limits an uploaded image is checked against "
                        "(default 512,8192,16384 bytes)")
    p.add_argument("--backend", choices=("fast", "reference"), default="fast",
                   help="the VM implementation (default fast)")
    p.add_argument("--gvarget-latency", type=int_in(0, MAX_LATENCY_MS, "ms"), default=0,
                   metavar="MS",
                   help="host round-trip latency of gvarget on plain registers (default 0)")
    p.add_argument("--runtime-file", type=Path, metavar="FILE",
                   help="where to write the address and token (default: the user's runtime "
                        "folder; see docs/protocol.md)")
    p.add_argument("--state", type=Path, metavar="FILE",
                   help="keep the controller's state (a Huazhong program's B registers) in "
                        "FILE: read at the start, written when it stops (docs/targets.md)")
    p.add_argument("--server-api", type=int_in(0, 65535), default=None, metavar="PORT",
                   help="also answer myCNC's text Server API on PORT (myCNC uses 4266; 0: a "
                        "free port). It has no token, as on myCNC: it listens on 127.0.0.1 "
                        "unless --server-api-host says otherwise. Off by default")
    p.add_argument("--server-api-host", default="127.0.0.1", metavar="HOST",
                   help="the address the Server API listens on (default 127.0.0.1; another "
                        "address lets anyone who reaches it drive the machine)")
    p.add_argument("--parent", type=int_in(1, (1 << 31) - 1), metavar="PID",
                   help="stop (as on SIGTERM) when process PID has ended: the IDE passes its "
                        "own id for the controller it starts")
    return p


def run(args: argparse.Namespace) -> int:
    from plcbuilder.link import runtime
    from plcbuilder.link.server import ConfigError, ControllerServer, make_controller
    from plcbuilder.link.service import Refused

    def say(text: str, err: bool = False) -> None:
        stream = sys.stderr if err else sys.stdout
        try:
            stream.write(text + "\n")
            stream.flush()
        except (OSError, ValueError):
            pass

    if not 0 <= args.port <= 65535:
        say(f"plcbuilder controller: --port must be from 0 to 65535, is {args.port}", True)
        return EXIT_USAGE
    try:
        factory = make_controller(args.machine, args.variables, args.io_dat,
                                  backend=args.backend,
                                  gvarget_latency_ms=max(0, args.gvarget_latency))
    except ConfigError as exc:
        say(f"plcbuilder controller: {exc}", True)
        return EXIT_FAIL
    except OSError as exc:
        say(f"plcbuilder controller: {exc}", True)
        return EXIT_FAIL
    image = image_profile = None
    if args.image is not None:
        from plcbuilder._support.files import read_bounded
        from plcbuilder.link.protocol import MAX_IMAGE
        try:
            image = read_bounded(args.image, MAX_IMAGE, "controller image")
        except OSError as exc:
            say(f"plcbuilder controller: cannot read {args.image}: {exc.strerror or exc}", True)
            return EXIT_FAIL
        from plcbuilder.api import ProjectError
        try:                       # a Huazhong or TG Motion project's image runs as that
            image_profile, _ = image_target(args.image, args.project)
        except ProjectError as exc:
            say(f"plcbuilder controller: {exc}", True)
            return EXIT_FAIL
    path = args.runtime_file or runtime.default_path()
    mode, factor = args.speed
    try:
        api = (args.server_api_host, args.server_api) if args.server_api is not None else None
        srv = ControllerServer(controller_factory=factory, host=args.host, port=args.port,
                               speed=mode, factor=factor, limits=args.limits, image=image,
                               runtime_file=path, server_api=api, image_target=image_profile)
    except Refused as exc:
        say(f"plcbuilder controller: {args.image}: {exc.reason}", True)
        return EXIT_FAIL
    except OSError as exc:
        where = f"{args.host}:{args.port}"
        if api is not None:
            where += f" (or the Server API's {api[0]}:{api[1]})"
        say(f"plcbuilder controller: cannot listen on {where}: {exc.strerror or exc}", True)
        return EXIT_FAIL
    if args.state is not None:
        try:
            srv.service.load_state(args.state)
        except ValueError as exc:
            srv.close(shutdown=False)
            say(f"plcbuilder controller: {exc}", True)
            return EXIT_FAIL
    try:
        old = runtime.read(path)
        if old.pid != os.getpid() and runtime.pid_alive(old.pid):
            say(f"plcbuilder controller: note: the controller of process {old.pid} "
                f"({old.host}:{old.port}) is still running; clients will find this one "
                "instead", True)
    except runtime.RuntimeFileError:
        pass

    ppid = os.getppid()
    received: list[int] = []
    status = 0

    def on_signal(signum, _frame):
        # Only this: a handler runs in the main thread between two of its
        # steps, so one that takes a lock (Event.set does) can interrupt that
        # lock's own holder and wait for it forever: a controller whose IDE had
        # gone hung so on its SIGTERM, and ran on
        received.append(signum)

    previous = {}
    for name in ("SIGINT", "SIGTERM", "SIGHUP"):
        sig = getattr(signal, name, None)
        if sig is not None:
            try:
                previous[sig] = signal.signal(sig, on_signal)
            except (ValueError, OSError):      # not the main thread
                pass
    try:
        try:
            srv.start()
        except OSError as exc:
            srv.close(shutdown=False)
            say(f"plcbuilder controller: cannot write the runtime file {path}: "
                f"{exc.strerror or exc}", True)
            return EXIT_FAIL
        host, port = srv.address
        if not _loopback(host):
            say(f"plcbuilder controller: warning: listening on {host}, not loopback: anyone who "
                "can reach this port and learns the token can drive the controller, and the "
                "token travels unencrypted", True)
        speed = mode if mode != "factor" else f"{factor:g}x real time"
        say(f"plcbuilder controller: listening on {host}:{port} ({speed}); "
            f"runtime file {path}")
        if srv.server_api is not None:
            ahost, aport = srv.server_api.address
            say(f"plcbuilder controller: Server API on {ahost}:{aport} (no token, as on myCNC)")
            if not _loopback(ahost):
                say(f"plcbuilder controller: warning: the Server API listens on {ahost}, not "
                    "loopback, and has no token: anyone who can reach this port can start "
                    "procedures, set outputs and jog the machine", True)
        if image is not None:
            n = len(srv.service.image.procedures) if srv.service.image else 0
            on = f", target {image_profile['name']}" if image_profile else ""
            say(f"plcbuilder controller: loaded {args.image} ({n} procedures{on})")
        say("plcbuilder controller: Ctrl+C or SIGTERM stops it")
        checked = time.monotonic()
        while not received:
            time.sleep(SIGNAL_POLL_S)             # (a signal's handler runs meanwhile)
            if time.monotonic() - checked < 0.5:
                continue
            checked = time.monotonic()
            if args.parent is not None and (not runtime.pid_alive(args.parent) or
                                            (args.parent == ppid and os.getppid() != ppid)):
                say(f"plcbuilder controller: process {args.parent} has ended", True)
                break
            if not srv.sim.running or not (srv.server._thread and srv.server._thread.is_alive()):
                say("plcbuilder controller: the server stopped unexpectedly", True)
                status = EXIT_FAIL
                break
    finally:
        srv.close(shutdown=True)
        t = srv.controller.t_ms
        for sig, handler in previous.items():
            try:
                signal.signal(sig, handler)
            except (ValueError, OSError, TypeError):
                pass
    why = {getattr(signal, "SIGINT", -1): "interrupted", getattr(signal, "SIGTERM", -1):
           "terminated", getattr(signal, "SIGHUP", -2): "hung up"}
    reason = why.get(received[0], "stopped") if received else "stopped"
    say(f"plcbuilder controller: {reason}; ran __HANDLER_EXIT and stopped at t = {t} ms")
    return status
