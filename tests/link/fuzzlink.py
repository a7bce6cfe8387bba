"""Hostile traffic for the controller server: random, mutated and truncated
frames, frames of the wrong encoding, and requests with random fields, on
connections with and without a hello. Used by tests/link/test_link_fuzz.py
(a few seconds) and scripts/attack_link.py (longer)."""

from __future__ import annotations

import json
import random
import socket
import struct
import time
from typing import Callable, Optional

import msgpack

from plcbuilder.link import protocol

_TYPES = sorted(protocol.REQUESTS) + ["welcome", "telemetry", "bye", "x", "PING", ""]
_NAMES = ["M03", "M05", "OFF", "LUBE", "__HANDLER_EXIT", "", "x" * 200, "../etc", "M\x00"]


def random_value(rng: random.Random, depth: int = 0):
    kind = rng.randrange(10 if depth < 3 else 6)
    if kind == 0:
        return rng.choice([0, 1, -1, 1 << 31, -(1 << 31) - 1, 1 << 64, 2 ** 53 + 1])
    if kind == 1:
        return rng.randint(-1000, 100_000)
    if kind == 2:
        return rng.choice(_NAMES)
    if kind == 3:
        return rng.choice([True, False, None])
    if kind == 4:
        return rng.choice([0.5, -1e308, 1e308, 3.0, 1e-9])
    if kind == 5:
        return "".join(chr(rng.randrange(0x20, 0x3000)) for _ in range(rng.randrange(8)))
    if kind in (6, 7):
        return [random_value(rng, depth + 1) for _ in range(rng.randrange(4))]
    return {rng.choice(["a", "type", "id", "name", "pin"]): random_value(rng, depth + 1)
            for _ in range(rng.randrange(4))}


def random_request(rng: random.Random) -> dict:
    msg = {"type": rng.choice(_TYPES)}
    if rng.random() < 0.8:
        msg["id"] = rng.choice([rng.randrange(1 << 20), "x", None, [1], 1.5])
    for key in rng.sample(["name", "mcode", "eparam", "pin", "value", "channel", "mode",
                           "factor", "ms", "samples", "events", "queue", "lossless",
                           "handler", "image", "token", "version"], rng.randrange(4)):
        msg[key] = random_value(rng)
    if msg["type"] == "step":
        msg["ms"] = rng.randrange(1, 50)           # keep a case short
    return msg


def _frame(payload: bytes) -> bytes:
    return struct.pack(">I", len(payload)) + payload


def hostile_bytes(rng: random.Random) -> bytes:
    """One piece of hostile traffic (maybe several frames)."""
    kind = rng.randrange(9)
    if kind == 0:
        return bytes(rng.randrange(256) for _ in range(rng.randrange(1, 300)))
    if kind == 1:
        return struct.pack(">I", rng.choice([protocol.MAX_FRAME + 1, 0xFFFFFFFF, 1 << 20,
                                             2000])) + b"{" * rng.randrange(100)
    if kind == 2:                                  # a valid frame, mutated
        data = bytearray(_frame(json.dumps(random_request(rng)).encode()))
        for _ in range(rng.randrange(1, 4)):
            data[rng.randrange(len(data))] = rng.randrange(256)
        return bytes(data)
    if kind == 3:                                  # truncated
        data = _frame(json.dumps(random_request(rng)).encode())
        return data[:rng.randrange(len(data))]
    if kind == 4:                                  # MessagePack from a client
        try:
            return _frame(msgpack.packb(random_request(rng)))
        except (OverflowError, ValueError, TypeError):
            return _frame(b"\x81\xa4type\xa4ping")
    if kind == 5:                                  # JSON oddities
        return _frame(rng.choice([b"[" * 3000, b'{"type":"ping","id":1,"x":NaN}',
                                  b'{"type":"ping","type":"state"}', b"\xff\xfe{}", b"null",
                                  '{"type":"ping","id":"é"}'.encode()]))
    if kind == 6:                                  # many pipelined requests
        return b"".join(_frame(json.dumps(random_request(rng)).encode())
                        for _ in range(rng.randrange(1, 200)))
    return _frame(json.dumps(random_request(rng)).encode())


def _drain(sock: socket.socket, seconds: float) -> tuple[list[dict], bool]:
    """Messages read within ``seconds``, and whether the server closed."""
    dec = protocol.FrameDecoder()
    msgs: list[dict] = []
    end = time.monotonic() + seconds
    while True:
        left = end - time.monotonic()
        if left <= 0:
            return msgs, False
        sock.settimeout(left)
        try:
            data = sock.recv(1 << 16)
        except socket.timeout:
            return msgs, False
        except OSError:
            return msgs, True
        if not data:
            return msgs, True
        try:
            for p in dec.feed(data):
                msgs.append(protocol.decode_payload(p, binary=True))
        except protocol.ProtocolError:
            return msgs, True


def hello(sock: socket.socket, token: str) -> bool:
    sock.sendall(_frame(json.dumps({"type": "hello", "id": 0, "token": token,
                                    "version": protocol.PROTOCOL_VERSION}).encode()))
    msgs, _closed = _first(sock)
    return bool(msgs) and msgs[0].get("type") == "welcome"


def _first(sock: socket.socket) -> tuple[list[dict], bool]:
    sock.settimeout(5.0)
    try:
        return [protocol.recv_msg(sock)], False
    except (OSError, protocol.ProtocolError, ConnectionError):
        return [], True


def fuzz(address, token: str, seconds: float, seed: int = 0,
         alive: Optional[Callable[[], bool]] = None, wait: float = 0.05) -> dict:
    """Hostile cases against a server for ``seconds``. Returns counts: tried,
    refused (an error answer or the connection closed), accepted (a result),
    crashed (``alive()`` said no afterwards: the server stopped answering)."""
    rng = random.Random(seed)
    out = {"tried": 0, "refused": 0, "accepted": 0, "crashed": 0}
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        out["tried"] += 1
        try:
            s = socket.create_connection(address, timeout=5)
        except OSError:
            out["crashed"] += 1
            break
        try:
            if rng.random() < 0.5 and not hello(s, token):
                out["refused"] += 1
                continue
            try:
                s.sendall(hostile_bytes(rng))
            except OSError:
                out["refused"] += 1
                continue
            msgs, closed = _drain(s, wait)
            if any(m.get("type") == "result" for m in msgs):
                out["accepted"] += 1
            else:
                out["refused"] += 1
        finally:
            s.close()
        if alive is not None and not alive():
            out["crashed"] += 1
            break
    return out
