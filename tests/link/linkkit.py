"""Helpers for the link tests (and tests/cli/test_link_cli.py): real compiled
procedures, a real image, servers on 127.0.0.1 port 0, raw sockets, requests
straight to a service, notifications awaited."""

from __future__ import annotations

import socket
import struct
import time
from typing import Optional

from plcbuilder import api
from plcbuilder.bytecode.program import Kind
from plcbuilder.image.manifest import write_image
from plcbuilder.link import protocol
from plcbuilder.link.service import Session

SOURCES = {
    # name: (kind, source)
    "M03": (Kind.HARDWARE, "main(){ timer=200; do{ timer--; portset(3); }while(timer>0); exit(99); }"),
    "M05": (Kind.HARDWARE, "main(){ portclear(3); exit(99); }"),
    "M02": (Kind.HARDWARE, "main(){ portclear(3); exit(99); }"),
    "OFF": (Kind.HARDWARE, "main(){ portclear(3); portclear(4); exit(99); }"),
    "M88": (Kind.HARDWARE, "main(){ do{ a = portget(5); if (a) { portset(4); } }while(1); }"),
    "LUBE": (Kind.SOFTWARE, "main(){ do{ var02++; }while(1); }"),
    "__HANDLER_GCODE_START": (Kind.SOFTWARE, "main(){ gvarset(20001, 1); exit(99); }"),
    "__HANDLER_EXIT": (Kind.SOFTWARE, "main(){ gvarset(20002, 2); exit(99); }"),
}

#: A hardware procedure whose output 6 toggles every tick (a telemetry change every tick).
TOGGLE = {"TOGGLE": (Kind.HARDWARE, "main(){ do{ if (t) { portclear(6); t = 0; } "
                                   "else { portset(6); t = 1; } }while(1); }")}


def compile_programs(names=None, overrides: Optional[dict] = None, code_limit=None):
    """Compiled Programs (through the real compiler)."""
    progs = []
    src = dict(SOURCES)
    src.update(overrides or {})
    for name in (names or src):
        kind, text = src[name]
        r = api.compile_source(text, f"{name}.plc", api.CompileOptions(kind=kind, code_limit=code_limit))
        assert r.ok, [str(d) for d in r.diagnostics]
        progs.append(r.program)
    return progs


def image_of(programs) -> bytes:
    return write_image([(p.name, p.kind, p.to_bytes()) for p in programs])


# M03 above has line 1 only; this one (M10 in counter_image) has lines to break on
COUNTER = """main()
{
  n = 0;
  do
  {
    n++;
    portset(3);
  }while(n < 100000);
  exit(99);
}
"""


def counter_image() -> bytes:
    """An image of M05, LUBE and COUNTER as the hardware procedure M10."""
    progs = compile_programs(["M05", "LUBE"], overrides={})
    r = api.compile_source(COUNTER, "M10.plc", api.CompileOptions(kind=api.Kind.HARDWARE))
    assert r.ok
    return image_of([*progs, r.program])


def req(svc, mtype, **fields):
    """A request of type mtype straight to a Service (no socket), its answer."""
    return svc.dispatch({"type": mtype, "id": 1, **fields}, Session())


def frame(payload: bytes) -> bytes:
    return struct.pack(">I", len(payload)) + payload


def msg_frame(msg: dict) -> bytes:
    return protocol.encode_frame(msg)


def raw_connect(address, timeout: float = 5.0) -> socket.socket:
    s = socket.create_connection(address, timeout=timeout)
    s.settimeout(timeout)
    return s


def hello(sock: socket.socket, token: str, version: int = protocol.PROTOCOL_VERSION) -> dict:
    sock.sendall(msg_frame({"type": "hello", "id": 0, "version": version, "token": token}))
    return protocol.recv_msg(sock)


def read_until_closed(sock: socket.socket, timeout: float = 5.0) -> tuple[list[dict], bool]:
    """Every message until the server closes the connection (or timeout).
    Returns (messages, closed)."""
    msgs = []
    dec = protocol.FrameDecoder()
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        sock.settimeout(max(0.01, deadline - time.monotonic()))
        try:
            data = sock.recv(65536)
        except socket.timeout:
            break
        except OSError:          # reset by the server: closed
            return msgs, True
        if not data:
            return msgs, True
        for p in dec.feed(data):
            msgs.append(protocol.decode_payload(p, binary=True))
    return msgs, False


def wait_for(pred, timeout: float = 10.0, interval: float = 0.001):
    """Poll pred() until it is truthy; returns its value (AssertionError on timeout)."""
    deadline = time.monotonic() + timeout
    while True:
        v = pred()
        if v:
            return v
        if time.monotonic() > deadline:
            raise AssertionError("condition not met in time")
        time.sleep(interval)


def wait_note(c, kind: str, timeout: float = 10.0) -> dict:
    """The next notification of this kind a Client receives (others are passed over)."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        note = c.next_notification(timeout=end - time.monotonic())
        if note is not None and note["type"] == kind:
            return note
    raise AssertionError(f"no {kind} notification")
