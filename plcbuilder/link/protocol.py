"""The wire protocol between the simulated controller (server) and its clients.

Framing
    Every message is one frame: a 4-byte big-endian unsigned length, then that
    many bytes of UTF-8 JSON holding one object; the one exception is
    ``telemetry`` (server -> client), whose payload is a MessagePack map (a JSON
    payload starts with ``{``, a MessagePack map never does). A frame longer
    than :data:`MAX_FRAME` is refused before its payload is read; before the
    hello the server accepts one frame of at most 1 KiB. Binary payloads (the
    image) travel as base64 text.

Messages
    Every message is a JSON object with a string ``type``; a request also has an
    ``id`` (an integer or a short string) that its answer repeats. The first
    message on a connection must be ``hello {version, token}``.

    client -> server (requests):
        hello {version, token}          upload {image: base64, target?}
        start {name | mcode, eparam}    stop {}
        input {pin, value}              adc {channel, value}
        state {}                        variables {}
        registers {addresses: [int]}    (read global registers, at most MAX_REGISTERS)
        recording {}                    (the session as a scenario file: {text, t_ms, actions})
        watch {variables: [PROC.var]}   (record them each tick: "watch" events; [] stops)
        subscribe {samples?, events?}   unsubscribe {}
        speed {mode, factor?}           step {ms}
        reset {}                        event {handler}
        ping {}                         code {letter, value}   (the CNC issues M3, S1200, T5, B2)
        set_breakpoints {file, breakpoints}   debug_state {}      (docs/protocol.md, "Debugging")
        debug_continue {}  debug_pause {}  debug_step {kind, procedure?}  debug_run_to {file, line}
        debug_evaluate {code, procedure?}   (an expression compiled as a condition -> {value})
        debug_step_back {kind: tick|statement}   debug_run_back {}   (SPEC §7: back in time)
        write {target, value}           force {target, value}
        release {target, mode}          release_all {mode}
        forces {}                       (write and force: SPEC §6)

    server -> client:
        welcome {id, version, server, pid, t_ms, speed}   the answer to hello
        result {id, result: {...}}                        a request done
        error {id, code, reason}                          a request refused
        telemetry {t_ms, changes, events, missed, missed_events}   (MessagePack)
        bye {reason}                                      the server is going away
        halted {state}   resumed {t_ms}                   the debugger halted / went on
                                                          (to every subscriber)

    Both ends dispatch a message by its type to a method named ``handle_<type>``
    (server) or ``on_<type>`` (client) after checking the type against the
    catalogue below; nothing is ever evaluated.

Telemetry (version 2)
    Samples travel as changes only: ``changes`` is a list of maps from a field's
    index in ``sample_fields`` (the subscribe answer) to its value, each with
    index 0 (``t_ms``) and the fields that differ from the change before it; a
    sample holds from its ``t_ms`` until the next change, and ``t_ms`` of the
    frame is the tick the controller runs next. The first change after
    subscribing, and after ``missed`` > 0, holds every field.

This module holds what both ends share: constants, the frame encoders and an
incremental decoder, the field checks, and the telemetry change encoding.
"""

from __future__ import annotations

import base64
import binascii
import dataclasses
import enum
import json
import math
import re
import os
import socket
import struct
import sys
from typing import Any, Iterable, Optional

import msgpack

from plcbuilder.controller.events import Sample, from_dict, to_dict
from plcbuilder._support.strictjson import strict_json_loads

#: Bumped on any incompatible change; hello carries it and the server checks it.
#: 2: telemetry in MessagePack, changes only; a 1 KiB frame limit before the hello.
PROTOCOL_VERSION = 2
#: Largest frame accepted before the hello (the hello itself).
MAX_HELLO_FRAME = 1024
#: Changes (and events) in one telemetry frame at most.
TELEMETRY_PER_FRAME = 4000
#: send() and sendall() flags for every socket of the link: a peer that has gone
#: is an error (EPIPE), never SIGPIPE, whatever the process does with that signal
NOSIGNAL = getattr(socket, "MSG_NOSIGNAL", 0)
#: Largest frame payload accepted, in bytes (an image of MAX_IMAGE bytes fits as base64).
MAX_FRAME = 4 * 1024 * 1024
#: Largest image accepted by upload, in bytes (before base64).
MAX_IMAGE = (MAX_FRAME - 4096) // 4 * 3
#: The frame header: payload length, u32 big-endian.
HEADER = struct.Struct(">I")
#: Server name reported in welcome.
SERVER_NAME = "plcbuilder-controller"

_TYPE_RE = re.compile(r"[a-z][a-z_]{0,31}\Z")
_MAX_ID_TEXT = 64

#: Requests a client may send, and the messages a server may send. Dispatch
#: only ever looks a type up in these sets.
REQUESTS = frozenset({"hello", "upload", "start", "stop", "input", "adc", "state", "variables",
                      "subscribe", "unsubscribe", "speed", "step", "reset", "event", "ping",
                      "registers", "recording", "watch", "job", "code"}
                     | {"set_breakpoints", "debug_continue", "debug_pause", "debug_step",
                        "debug_run_to", "debug_state", "debug_evaluate"}
                     | {"debug_step_back", "debug_run_back"})
#: Events that travel as notifications of their own (not inside telemetry).
NOTIFICATIONS = frozenset({"halted", "resumed"})
REPLIES = frozenset({"welcome", "result", "error", "telemetry", "bye"}) | NOTIFICATIONS
#: Write and force (controller/forces.py); their changes also travel as "forces" events.
FORCE_REQUESTS = frozenset({"write", "force", "release", "release_all", "forces"})
REQUESTS = REQUESTS | FORCE_REQUESTS
#: How a release leaves its target: its current value, or the program's (the wiring).
RELEASE_MODES = ("keep", "restore")

#: What the ``job`` request does to the G-code job (controller/job.py)
JOB_VERBS = ("open", "play", "pause", "stop", "reset")
#: The longest G-code program a ``job`` request carries, in characters.
MAX_JOB_TEXT = MAX_FRAME - 8192

#: Addresses one ``registers`` request may read at most.
MAX_REGISTERS = 256

#: Speed modes of the ``speed`` request.
SPEED_MODES = ("realtime", "factor", "max", "pause")
MAX_FACTOR = 10000.0
MIN_FACTOR = 0.001


def parse_speed(speed) -> tuple[str, Optional[float]]:
    """A speed as a user gives it (``controller --speed``, the IDE's Speed box):
    ``realtime`` (also ``1``, ``1x``), ``max``, ``pause``, or a factor of real
    time (``10``, ``10x``, ``2.5×``, or a number) -> (a ``SPEED_MODES`` mode,
    the factor or None). Raises ValueError with a sentence saying what to give."""
    if isinstance(speed, (int, float)) and not isinstance(speed, bool):
        factor = float(speed)
    else:
        text = str(speed).strip().lower()
        if text in ("realtime", "real-time", "real time"):
            return "realtime", None
        if text in ("max", "maximum", "fast"):
            return "max", None
        if text in ("pause", "paused"):
            return "pause", None
        try:
            factor = float(text.rstrip("x×"))
        except ValueError:
            raise ValueError(f"unknown speed {speed!r}: use realtime, max, pause or a factor "
                             f"such as 10") from None
    if not MIN_FACTOR <= factor <= MAX_FACTOR:          # NaN too
        raise ValueError(f"speed factor {factor:g} is out of range ({MIN_FACTOR:g} to "
                         f"{MAX_FACTOR:g})")
    return ("realtime", None) if factor == 1.0 else ("factor", factor)


class ErrorCode(str, enum.Enum):
    """The ``code`` of an error message."""

    BAD_FRAME = "bad_frame"          # framing or JSON: the connection is closed
    UNAUTHORIZED = "unauthorized"    # no hello, or a wrong token: the connection is closed
    VERSION = "version"              # hello with another protocol version: closed
    UNKNOWN_TYPE = "unknown_type"    # a request type this server does not know
    BAD_REQUEST = "bad_request"      # a field missing or of the wrong type or range
    REFUSED = "refused"              # the controller refused (bad image, unknown procedure...)
    BUSY = "busy"                    # too many connections
    INTERNAL = "internal"            # a bug in the server; the request had no effect it knows of

    def __str__(self) -> str:
        return self.value


#: Error codes after which the server closes the connection.
FATAL_CODES = frozenset({ErrorCode.BAD_FRAME, ErrorCode.UNAUTHORIZED, ErrorCode.VERSION,
                         ErrorCode.BUSY})


class ProtocolError(ValueError):
    """A frame that breaks the protocol; ``code`` is the ErrorCode to answer with."""

    def __init__(self, reason: str, code: ErrorCode = ErrorCode.BAD_FRAME):
        super().__init__(reason)
        self.reason = reason
        self.code = code


class BadRequest(ProtocolError):
    """A well-formed request with a missing or wrong field (the connection stays open)."""

    def __init__(self, reason: str):
        super().__init__(reason, ErrorCode.BAD_REQUEST)


# ------------------------------------------------------------------ frames

DEBUG_ENV = "PLCBUILDER_DEBUG"


def debug(text: str) -> None:
    """With ``PLCBUILDER_DEBUG`` set, a line about the link on standard error
    (a developer's switch; nothing is written otherwise)."""
    if os.environ.get(DEBUG_ENV):
        print(text, file=sys.stderr, flush=True)


def _json_default(obj: Any):
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        return dataclasses.asdict(obj)
    if isinstance(obj, enum.Enum):
        return obj.value
    if isinstance(obj, (tuple, set, frozenset)):
        return list(obj)
    if isinstance(obj, (bytes, bytearray, memoryview)):
        return base64.b64encode(bytes(obj)).decode("ascii")
    if hasattr(obj, "item"):          # numpy scalars, should one slip in
        return obj.item()
    raise TypeError(f"{type(obj).__name__} is not JSON serialisable")


def encode_payload(msg: dict) -> bytes:
    """The JSON bytes of one message (compact, no NaN or infinities)."""
    return json.dumps(msg, separators=(",", ":"), ensure_ascii=False, allow_nan=False,
                      default=_json_default).encode("utf-8")


def encode_frame(msg: dict, max_frame: int = MAX_FRAME) -> bytes:
    """Length prefix + payload. Raises ProtocolError when the message is too big."""
    payload = encode_payload(msg)
    if len(payload) > max_frame:
        raise ProtocolError(f"message of {len(payload)} bytes is larger than the "
                            f"{max_frame}-byte frame limit")
    return HEADER.pack(len(payload)) + payload


def encode_binary_frame(msg: dict, max_frame: int = MAX_FRAME) -> bytes:
    """Length prefix + a MessagePack payload (telemetry). Raises ProtocolError
    when the message is too big."""
    payload = msgpack.packb(msg, use_bin_type=True)
    if len(payload) > max_frame:
        raise ProtocolError(f"message of {len(payload)} bytes is larger than the "
                            f"{max_frame}-byte frame limit")
    return HEADER.pack(len(payload)) + payload


def decode_payload(payload: bytes, allowed: Optional[frozenset] = None,
                   binary: bool = False) -> dict:
    """Parse and check one frame's payload. Raises ProtocolError.

    The result is a dict with a valid ``type`` (one of ``allowed`` when given;
    otherwise any well-formed name) and, when present, a valid ``id``. With
    ``binary`` (a client reading the server) a payload that does not start
    with ``{`` is MessagePack; a server never accepts one.
    """
    if binary and payload[:1] != b"{":
        try:
            msg = msgpack.unpackb(payload, raw=False, strict_map_key=False)
        except Exception as exc:  # noqa: BLE001 - msgpack raises several kinds
            raise ProtocolError(f"frame is not valid MessagePack: {exc}") from None
        return _check_message(msg, allowed)
    try:
        text = bytes(payload).decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ProtocolError(f"frame is not UTF-8 (byte {exc.start})") from None
    try:
        msg = strict_json_loads(text)
    except RecursionError:
        raise ProtocolError("frame is not valid JSON: nested too deeply") from None
    except ValueError as exc:
        raise ProtocolError(f"frame is not valid JSON: {exc}") from None
    return _check_message(msg, allowed)


def _check_message(msg: Any, allowed: Optional[frozenset]) -> dict:
    if not isinstance(msg, dict):
        raise ProtocolError(f"a message must be a JSON object, got {type(msg).__name__}")
    mtype = msg.get("type")
    if not isinstance(mtype, str) or not _TYPE_RE.match(mtype):
        raise ProtocolError("a message needs a 'type' naming it (lower-case letters and _)")
    if "id" in msg:
        check_id(msg["id"])
    if allowed is not None and mtype not in allowed:
        raise ProtocolError(f"unknown message type {mtype!r}", ErrorCode.UNKNOWN_TYPE)
    return msg


def check_id(value: Any) -> None:
    if type(value) is int and -(1 << 53) <= value <= 1 << 53:
        return
    if isinstance(value, str) and len(value) <= _MAX_ID_TEXT:
        return
    if value is None:
        return
    raise ProtocolError("a request 'id' must be an integer or a string of at most "
                        f"{_MAX_ID_TEXT} characters")


class FrameDecoder:
    """Incremental frame reader: push bytes as they come, take whole payloads.

    Raises ProtocolError as soon as a length prefix announces more than
    ``max_frame`` bytes, so an oversize frame is never buffered. ``max_frame``
    may change between frames (the server allows only a small hello first);
    :meth:`next_frame` takes one payload at a time, so a caller can stop after
    a few and leave the rest buffered.
    """

    def __init__(self, max_frame: int = MAX_FRAME):
        self.max_frame = max_frame
        self._buf = bytearray()
        self._pos = 0                       # start of the unread bytes in _buf
        self._need: Optional[int] = None

    @property
    def pending(self) -> int:
        """Bytes held that are not taken yet (whole frames and an unfinished one)."""
        return len(self._buf) - self._pos

    def push(self, data: bytes) -> None:
        if self._pos and self._pos >= len(self._buf) // 2:
            del self._buf[:self._pos]       # compact now and then, not on every frame
            self._pos = 0
        self._buf += data

    def next_frame(self) -> Optional[bytes]:
        """One whole payload, or None when none is complete yet."""
        if self._need is None:
            if len(self._buf) - self._pos < HEADER.size:
                return None
            (n,) = HEADER.unpack_from(self._buf, self._pos)
            if n > self.max_frame:
                raise ProtocolError(f"frame of {n} bytes announced, more than the "
                                    f"{self.max_frame}-byte limit")
            self._need = n
            self._pos += HEADER.size
        if len(self._buf) - self._pos < self._need:
            return None
        end = self._pos + self._need
        out = bytes(self._buf[self._pos:end])
        self._pos = end
        self._need = None
        if self._pos == len(self._buf):
            self._buf.clear()
            self._pos = 0
        return out

    @property
    def ready(self) -> bool:
        """True when :meth:`next_frame` would return a payload (or raise)."""
        if self._need is None:
            if len(self._buf) - self._pos < HEADER.size:
                return False
            (n,) = HEADER.unpack_from(self._buf, self._pos)
            return n > self.max_frame or len(self._buf) - self._pos - HEADER.size >= n
        return len(self._buf) - self._pos >= self._need

    def feed(self, data: bytes) -> list[bytes]:
        self.push(data)
        out = []
        while True:
            p = self.next_frame()
            if p is None:
                return out
            out.append(p)

    @property
    def mid_frame(self) -> bool:
        """True when part of a frame (header or payload) has arrived."""
        return len(self._buf) > self._pos or self._need is not None


# -------------------------------------------------------------- non-blocking helpers

def listening_socket(host: str, port: int, backlog: int) -> socket.socket:
    """A non-blocking TCP socket listening on host:port (port 0: a free one)."""
    family, _t, _p, _c, addr = socket.getaddrinfo(host, port, type=socket.SOCK_STREAM)[0]
    lsock = socket.socket(family, socket.SOCK_STREAM)
    try:
        if os.name != "nt":       # (on Windows it would let two servers share the port)
            lsock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        lsock.bind(addr)
        lsock.listen(backlog)
        lsock.setblocking(False)
    except OSError:
        lsock.close()
        raise
    return lsock


def accept_all(lsock: socket.socket):
    """Each connection waiting on a non-blocking listening socket, made
    non-blocking itself, with its peer as ``host:port``: (socket, peer). Ends
    when none is waiting (or accept fails)."""
    while True:
        try:
            sock, addr = lsock.accept()
        except OSError:                 # BlockingIOError and InterruptedError among them
            return
        sock.setblocking(False)
        yield sock, (f"{addr[0]}:{addr[1]}" if isinstance(addr, tuple) else str(addr))


def send_pending(sock: socket.socket, out: bytearray, chunk: int) -> bool:
    """Send what ``out`` holds, at most ``chunk`` bytes a call, taking what went
    out off its front, until it is empty or the socket would block. False when
    the connection failed (the caller drops it)."""
    while out:
        try:
            n = sock.send(out[:chunk], NOSIGNAL)
        except (BlockingIOError, InterruptedError):
            return True
        except OSError:
            return False
        if n <= 0:
            return True
        del out[:n]
    return True


def refuse(sock: socket.socket, data: bytes) -> None:
    """Send ``data`` (the reason) if the socket takes it at once, then close it."""
    try:
        sock.send(data, NOSIGNAL)
    except OSError:
        pass
    sock.close()


# ------------------------------------------------------------------ blocking helpers

def send_msg(sock: socket.socket, msg: dict, max_frame: int = MAX_FRAME) -> None:
    sock.sendall(encode_frame(msg, max_frame), NOSIGNAL)


def _recv_exact(sock: socket.socket, n: int) -> bytes:
    chunks = []
    while n:
        chunk = sock.recv(min(n, 1 << 20))
        if not chunk:
            raise ConnectionError("the connection was closed")
        chunks.append(chunk)
        n -= len(chunk)
    return b"".join(chunks)


def recv_msg(sock: socket.socket, max_frame: int = MAX_FRAME,
             allowed: Optional[frozenset] = None, binary: bool = True) -> dict:
    """Read one whole message from a blocking socket (ConnectionError at EOF);
    a client's read, so MessagePack telemetry is understood."""
    (n,) = HEADER.unpack(_recv_exact(sock, HEADER.size))
    if n > max_frame:
        raise ProtocolError(f"frame of {n} bytes announced, more than the {max_frame}-byte limit")
    return decode_payload(_recv_exact(sock, n), allowed, binary)


# ------------------------------------------------------------------ fields

def field_int(msg: dict, name: str, default: Any = ..., lo: int = -(1 << 31),
              hi: int = (1 << 31) - 1) -> int:
    """An integer field (bool is not an integer here) in [lo, hi]."""
    if name not in msg:
        if default is ...:
            raise BadRequest(f"{msg.get('type')}: missing field {name!r}")
        return default
    v = msg[name]
    if type(v) is not int:
        raise BadRequest(f"{msg.get('type')}: {name!r} must be an integer, is {v!r}"[:200])
    if not lo <= v <= hi:
        raise BadRequest(f"{msg.get('type')}: {name!r} must be from {lo} to {hi}, is {v}")
    return v


def field_str(msg: dict, name: str, default: Any = ..., max_len: int = 128) -> str:
    if name not in msg:
        if default is ...:
            raise BadRequest(f"{msg.get('type')}: missing field {name!r}")
        return default
    v = msg[name]
    if not isinstance(v, str):
        raise BadRequest(f"{msg.get('type')}: {name!r} must be a string")
    if len(v) > max_len:
        raise BadRequest(f"{msg.get('type')}: {name!r} is longer than {max_len} characters")
    return v


def field_int_list(msg: dict, name: str, max_items: int, lo: int = -(1 << 31),
                   hi: int = (1 << 31) - 1) -> list[int]:
    """A list of at most ``max_items`` integers in [lo, hi]."""
    v = msg.get(name)
    if not isinstance(v, list):
        raise BadRequest(f"{msg.get('type')}: {name!r} must be a list of integers")
    if len(v) > max_items:
        raise BadRequest(f"{msg.get('type')}: {name!r} holds more than {max_items} items")
    for x in v:
        if type(x) is not int or not lo <= x <= hi:
            raise BadRequest(f"{msg.get('type')}: {name!r} must hold integers from {lo} to "
                             f"{hi}, holds {x!r}"[:200])
    return list(v)


def field_bool(msg: dict, name: str, default: bool) -> bool:
    v = msg.get(name, default)
    if not isinstance(v, bool):
        raise BadRequest(f"{msg.get('type')}: {name!r} must be true or false")
    return v


def field_number(msg: dict, name: str, lo: float, hi: float) -> float:
    if name not in msg:
        raise BadRequest(f"{msg.get('type')}: missing field {name!r}")
    v = msg[name]
    if type(v) not in (int, float) or not math.isfinite(v) or not lo <= v <= hi:
        raise BadRequest(f"{msg.get('type')}: {name!r} must be a number from {lo:g} to {hi:g}")
    return float(v)


def encode_image(data: bytes) -> str:
    return base64.b64encode(bytes(data)).decode("ascii")


def decode_image(msg: dict, max_image: int = MAX_IMAGE) -> bytes:
    """The image bytes of an upload request (strict base64). Raises BadRequest."""
    text = msg.get("image")
    if not isinstance(text, str):
        raise BadRequest("upload: 'image' must be the image as base64 text")
    if len(text) > (max_image + 2) // 3 * 4:
        raise BadRequest(f"upload: the image is larger than {max_image} bytes")
    try:
        data = base64.b64decode(text.encode("ascii"), validate=True)
    except (binascii.Error, UnicodeEncodeError, ValueError):
        raise BadRequest("upload: 'image' is not valid base64") from None
    if len(data) > max_image:
        raise BadRequest(f"upload: the image is {len(data)} bytes, more than {max_image}")
    return data


#: upload's optional ``target``: the target profile the image is for (docs/targets.md)
TARGET_KEYS = {"name": str, "parameters": list, "cycle_time_us": int,
               "program_periods_us": list, "instruction_ns": int, "scope": list}
#: the target keys whose lists hold strings (TG Motion's oscilloscope signals)
TARGET_TEXT_LISTS = frozenset({"scope"})


def decode_target(msg: dict) -> Optional[dict]:
    """The ``target`` of an upload request, checked for shape (the controller
    checks the values), or None when there is none. Raises BadRequest."""
    t = msg.get("target")
    if t is None:
        return None
    if not isinstance(t, dict) or not isinstance(t.get("name"), str):
        raise BadRequest("upload: 'target' must be an object with a 'name'")
    for key, value in t.items():
        want = TARGET_KEYS.get(key)
        if want is None:
            raise BadRequest(f"upload: unknown target key {key!r}")
        item = str if key in TARGET_TEXT_LISTS else int
        if type(value) is not want or (want is list and len(value) > 100) or \
                (want is list and not all(type(v) is item and
                                          (item is int or len(v) <= 128) for v in value)):
            raise BadRequest(f"upload: target {key!r} has the wrong type")
    return t


# ------------------------------------------------------------------ telemetry encoding

#: The order of a sample's values on the wire (a row per sample).
SAMPLE_FIELDS: tuple[str, ...] = tuple(f.name for f in dataclasses.fields(Sample))


def sample_row(sample: Sample) -> list:
    """A Sample as a compact list in SAMPLE_FIELDS order."""
    return [getattr(sample, name) for name in SAMPLE_FIELDS]


def sample_from_row(row: Iterable, fields: Iterable[str] = SAMPLE_FIELDS) -> Sample:
    """The inverse of :func:`sample_row`; unknown fields (a newer server) are dropped."""
    known = set(SAMPLE_FIELDS)
    d = {k: v for k, v in zip(fields, row) if k in known}
    return from_dict(d)


_MACHINE_FIELDS = SAMPLE_FIELDS[4:]      # inputs .. velocities: the machine's sample dict
_MACHINE_INDEXED = tuple(enumerate(_MACHINE_FIELDS, 4))
_DEFAULTS = {"t_ms": 0, "running": None, "proc": 0, "message": 0}


class ChangeEncoder:
    """One subscriber's telemetry changes: a raw sample row of the controller
    (``t_ms, running, proc, message, fields``) becomes a map of the fields that
    differ from the previous change (all of them after :meth:`reset`)."""

    def __init__(self):
        self._prev: Optional[tuple] = None
        self._prev_fields: Optional[dict] = None

    def reset(self) -> None:
        self._prev = self._prev_fields = None

    def encode(self, row: tuple) -> dict:
        t, running, proc, message, fields = row
        prev = self._prev
        if prev is None:
            d = {1: running, 2: proc, 3: message}
            for i, name in _MACHINE_INDEXED:
                d[i] = fields.get(name, ())
        else:
            d = {}
            if running != prev[0]:
                d[1] = running
            if proc != prev[1]:
                d[2] = proc
            if message != prev[2]:
                d[3] = message
            pf = self._prev_fields
            if fields is not pf:
                # the machine hands out the same tuple for a part that did not
                # change: identity first, values only where it differs
                get, pget = fields.get, pf.get
                for i, name in _MACHINE_INDEXED:
                    v, pv = get(name, ()), pget(name, ())
                    if v is not pv and v != pv:
                        d[i] = v
        d[0] = t
        self._prev, self._prev_fields = (running, proc, message), fields
        return d


class ChangeDecoder:
    """The client's side of :class:`ChangeEncoder`: change maps -> Samples.
    ``fields`` are the server's sample_fields (its indexes); fields this side
    does not know are dropped, fields the server does not send keep defaults."""

    def __init__(self, fields: Iterable[str] = SAMPLE_FIELDS):
        self.set_fields(fields)

    def set_fields(self, fields: Iterable[str]) -> None:
        local = {name: i for i, name in enumerate(SAMPLE_FIELDS)}
        self._map = [local.get(name) for name in fields]
        self.reset()

    def reset(self) -> None:
        self._values = [_DEFAULTS.get(name, ()) for name in SAMPLE_FIELDS]

    def decode(self, change: dict) -> Sample:
        values, mapping = self._values, self._map
        n = len(mapping)
        for k, v in change.items():
            if type(k) is int and 0 <= k < n:
                i = mapping[k]
                if i is not None:
                    values[i] = tuple(v) if type(v) is list else v
        return Sample(*values)


def event_dict(event) -> dict:
    return to_dict(event)


def event_from_dict(d: dict):
    """An Event from its dict, or the dict itself when it is of a kind this side does not know."""
    try:
        return from_dict(d)
    except (TypeError, ValueError, KeyError):
        return d
