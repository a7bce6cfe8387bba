"""Trace files (``.plctrace``): a capture or a whole session, saved and reopened.

The format (version 1) is a ZIP archive holding:

``trace.json``
    ``{"format": "plcbuilder-trace", "version": 1, "t_start", "t_end",
    "tick_ms": 1, "strings": [...], "meta": {...},
    "signals": [{"name", "kind": "bit"|"int"|"text", "changes": N}, ...]}``
``signals/<i>.bin``
    signal i's changes: N little-endian int64 times, then N int64 values
    (a text signal's values index ``strings``)
``events.json``
    the events of the time span (started, ended, message, print, fault, note),
    as ``plcbuilder run --json`` shows them

Saving is atomic (the previous file stays whole until the new one is
complete). Reading refuses, with the reason, a file that is not such an
archive, a newer version, sizes that do not add up, or more than
:data:`MAX_UNPACKED` bytes unpacked; and, naming the member and the field,
every value out of its range or of the wrong type (a time that is not a whole
number of ms from 0 to :data:`MAX_TIME`, NaN, Infinity, a bit that is not 0
or 1, a name twice…) and JSON nested more than :data:`MAX_DEPTH` deep.
"""

from __future__ import annotations

import io
import json
import math
import re
import struct
import zipfile
from collections import deque
from pathlib import Path
from typing import Union

from plcbuilder._support.files import atomic_write, read_bounded
from plcbuilder._support.strictjson import no_duplicate_keys
from plcbuilder.controller.history import BIT, INT, TEXT, Trace

FORMAT = "plcbuilder-trace"
VERSION = 1
SUFFIX = ".plctrace"
#: the largest trace file read, and the most it may unpack to
MAX_FILE = 512 * 1024 * 1024
MAX_UNPACKED = 2 * 1024 * 1024 * 1024
#: the largest time (ms) a trace may name: 2^53, the largest a JSON reader keeps exact
MAX_TIME = 1 << 53
#: how deeply trace.json and events.json may nest lists and objects
MAX_DEPTH = 32
#: at most this many changes a signal, events, strings; names and texts this long
MAX_CHANGES = MAX_UNPACKED // 16
MAX_EVENTS = 10_000_000
MAX_STRINGS = 1_000_000
MAX_NAME = 256
MAX_TEXT = 65_536
_CONTROL = re.compile(r"[\x00-\x1f\x7f-\x9f]")


class TraceFileError(Exception):
    """A trace file that cannot be read or written; the message names it and why."""


def save(trace: Trace, path: Union[str, Path]) -> None:
    """Write ``trace`` to ``path`` atomically; raises TraceFileError."""
    path = Path(path)
    buf = io.BytesIO()
    header = {"format": FORMAT, "version": VERSION, "t_start": trace.t_start,
              "t_end": trace.t_end, "tick_ms": 1, "strings": list(trace.strings),
              "meta": trace.meta, "signals": []}
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED, compresslevel=6) as z:
        for i, (name, (kind, changes)) in enumerate(trace.signals.items()):
            n = len(changes)
            header["signals"].append({"name": name, "kind": kind, "changes": n})
            data = struct.pack(f"<{n}q", *(t for t, _ in changes)) + \
                struct.pack(f"<{n}q", *(v for _, v in changes))
            z.writestr(f"signals/{i}.bin", data)
        z.writestr("events.json", json.dumps(trace.events, separators=(",", ":")))
        z.writestr("trace.json", json.dumps(header, indent=1))
    try:
        atomic_write(path, buf.getvalue())
    except OSError as exc:
        raise TraceFileError(f"{path}: cannot write the trace: {exc.strerror or exc}") from None


def load(path: Union[str, Path]) -> Trace:
    """Read a trace file; raises TraceFileError saying what is wrong (the file,
    and the member and field)."""
    path = Path(path)
    try:
        data = read_bounded(path, MAX_FILE, "trace file")
    except OSError as exc:
        raise TraceFileError(f"{path}: cannot read: {exc.strerror or exc}") from None
    try:
        z = zipfile.ZipFile(io.BytesIO(data))
    except (zipfile.BadZipFile, OSError, EOFError, ValueError):
        raise TraceFileError(f"{path}: not a trace file (not a ZIP archive; truncated or "
                             f"another kind of file)") from None
    with z:
        total = sum(i.file_size for i in z.infolist())
        if total > MAX_UNPACKED:
            raise TraceFileError(f"{path}: unpacks to {total} bytes, more than the "
                                 f"{MAX_UNPACKED} a trace may hold")
        header = _json(z, "trace.json", path)
        if not isinstance(header, dict) or header.get("format") != FORMAT:
            raise TraceFileError(f"{path}: trace.json does not say format "
                                 f"'{FORMAT}': not a PLC Builder trace")
        version = header.get("version")
        if not _is_int(version) or version < 1:
            raise TraceFileError(f"{path}: trace.json: bad version {_shown(version)}")
        if version > VERSION:
            raise TraceFileError(f"{path}: trace format version {version} is newer than this "
                                 f"PLC Builder reads (version {VERSION}); update PLC Builder")
        head = _Fields(path, "trace.json")
        t_start = head.time(header, "t_start")
        t_end = head.time(header, "t_end")
        if t_end < t_start:
            head.bad("t_end", f"{t_end} is before t_start ({t_start})")
        strings = head.get(header, "strings", list, default=[])
        if len(strings) > MAX_STRINGS:
            head.bad("strings", f"{len(strings)} strings, more than {MAX_STRINGS}")
        for i, s in enumerate(strings):
            if not isinstance(s, str) or len(s) > MAX_TEXT:
                head.bad(f"strings[{i}]", f"must be a text of at most {MAX_TEXT} characters, "
                                          f"not {_shown(s)}")
        meta = header.get("meta")
        meta = {} if meta is None else meta
        if not isinstance(meta, dict):
            head.bad("meta", f"must be an object, not {_shown(meta)}")
        _check_trigger(head, meta)
        specs = head.get(header, "signals", list)
        signals: dict = {}
        for i, spec in enumerate(specs):
            field = f"signals[{i}]"
            if not isinstance(spec, dict):
                head.bad(field, f"must be an object {{name, kind, changes}}, not {_shown(spec)}")
            name = head.get(spec, "name", str, field)
            if not name or len(name) > MAX_NAME or _CONTROL.search(name):
                head.bad(f"{field}.name", f"must be 1 to {MAX_NAME} characters without "
                                          f"control characters, not {_shown(name)}")
            if name in signals:
                head.bad(f"{field}.name", f"{name!r} is named twice")
            kind = spec.get("kind")
            if kind not in (BIT, INT, TEXT):
                head.bad(f"{field}.kind", f"signal {name!r}: unknown kind {_shown(kind)} "
                                          f"(bit, int or text)")
            n = spec.get("changes")
            if not _is_int(n) or not 0 <= n <= MAX_CHANGES:
                head.bad(f"{field}.changes", f"signal {name!r}: must be a whole number from 0 "
                                             f"to {MAX_CHANGES}, not {_shown(n)}")
            raw = _member(z, f"signals/{i}.bin", path)
            if len(raw) != 16 * n:
                raise TraceFileError(f"{path}: signals/{i}.bin ({name}) holds {len(raw)} bytes, "
                                     f"not the {16 * n} its {n} changes need")
            ts = struct.unpack(f"<{n}q", raw[:8 * n])
            vs = struct.unpack(f"<{n}q", raw[8 * n:])
            if any(ts[j] >= ts[j + 1] for j in range(n - 1)):
                raise TraceFileError(f"{path}: signal {name!r}: change times are not increasing")
            if n and not (0 <= ts[0] and ts[-1] <= MAX_TIME):
                raise TraceFileError(f"{path}: signals/{i}.bin ({name}): a change time is "
                                     f"outside 0..{MAX_TIME} ms")
            if kind == TEXT and any(not 0 <= v < len(strings) for v in vs):
                raise TraceFileError(f"{path}: signal {name!r}: a value names no string")
            if kind == BIT and any(v not in (0, 1) for v in vs):
                raise TraceFileError(f"{path}: signal {name!r}: a bit signal holds a value "
                                     f"other than 0 and 1")
            signals[name] = (kind, list(zip(ts, vs)))
        events = _json(z, "events.json", path)
        _check_events(path, events)
    return Trace(t_start, t_end, signals, strings, events, meta)


def _member(z: zipfile.ZipFile, name: str, path: Path) -> bytes:
    try:
        return z.read(name)
    except KeyError:
        raise TraceFileError(f"{path}: {name} is missing") from None
    except (zipfile.BadZipFile, OSError, EOFError, ValueError) as exc:
        raise TraceFileError(f"{path}: {name} is damaged ({exc})") from None
    except Exception as exc:  # noqa: BLE001 - zlib.error and the like from a damaged member
        raise TraceFileError(f"{path}: {name} is damaged ({exc})") from None


def _json(z: zipfile.ZipFile, name: str, path: Path):
    """A member's JSON: no key twice, nested at most :data:`MAX_DEPTH` deep,
    every number finite (NaN, Infinity and 1e400 are refused, naming the field)."""
    raw = _member(z, name, path)
    try:
        value = json.loads(raw.decode("utf-8"), object_pairs_hook=no_duplicate_keys,
                           parse_constant=_NonFinite)
    except RecursionError:
        raise TraceFileError(f"{path}: {name}: nested too deeply (at most {MAX_DEPTH} "
                             f"levels)") from None
    except (UnicodeDecodeError, ValueError) as exc:     # JSONDecodeError is a ValueError
        raise TraceFileError(f"{path}: {name} is not valid JSON ({exc})") from None
    deepest, odd = _walk(value)
    if deepest > MAX_DEPTH:
        raise TraceFileError(f"{path}: {name}: nested too deeply (at most {MAX_DEPTH} levels)")
    if odd:
        where, v = _find_non_finite(value)
        raise TraceFileError(f"{path}: {name}: {where}: {_shown(v)} is not a number a trace "
                             f"may hold")
    return value


class _NonFinite(str):
    """NaN, Infinity or -Infinity as the JSON said it (refused once its field is known)."""


def _odd(v) -> bool:
    return isinstance(v, _NonFinite) or (isinstance(v, float) and not math.isfinite(v))


def _walk(value) -> tuple[int, bool]:
    """How deeply lists and objects nest in ``value``, and whether a number in
    it is not finite."""
    if not isinstance(value, (dict, list)):
        return 0, _odd(value)
    deepest, odd = 0, False
    todo = [(value, 1)]
    while todo:
        v, d = todo.pop()
        v = v.values() if isinstance(v, dict) else v
        deepest = max(deepest, d)
        if d > MAX_DEPTH:
            break
        for x in v:
            if isinstance(x, (dict, list)):
                todo.append((x, d + 1))
            elif _odd(x):
                odd = True
    return deepest, odd


def _find_non_finite(value) -> tuple[str, object]:
    """Where the first number that is not finite is: ``signals[2].changes``."""
    todo = deque([(value, "")])
    while todo:
        v, where = todo.popleft()
        items = v.items() if isinstance(v, dict) else enumerate(v) \
            if isinstance(v, list) else ()
        for k, x in items:
            at = f"{where}.{k}" if isinstance(k, str) and where else \
                k if isinstance(k, str) else f"{where}[{k}]"
            if _odd(x):
                return at, x
            if isinstance(x, (dict, list)):
                todo.append((x, at))
    return "(the whole)", value


def _is_int(v) -> bool:
    return isinstance(v, int) and not isinstance(v, bool)


def _shown(v) -> str:
    """A value as a message shows it: short."""
    if isinstance(v, _NonFinite):
        return str.__str__(v)
    text = json.dumps(v) if isinstance(v, (int, float, str, bool, type(None))) else \
        ("an object" if isinstance(v, dict) else "a list" if isinstance(v, list) else repr(v))
    return text if len(text) <= 40 else text[:37] + "..."


_MISSING = object()


class _Fields:
    """Checks the fields of one member; a bad one raises TraceFileError naming
    the file, the member and the field."""

    def __init__(self, path: Path, member: str):
        self.path, self.member = path, member

    def bad(self, field: str, why: str):
        raise TraceFileError(f"{self.path}: {self.member}: {field}: {why}")

    def get(self, obj: dict, key: str, kind: type, parent: str = "", default=_MISSING):
        field = f"{parent}.{key}" if parent else key
        if key not in obj or (obj[key] is None and default is not _MISSING):
            if default is _MISSING:
                self.bad(field, "missing")
            return default
        v = obj[key]
        if not isinstance(v, kind) or isinstance(v, bool):
            self.bad(field, f"must be {_KIND_WORDS[kind]}, not {_shown(v)}")
        return v

    def time(self, obj: dict, key: str, parent: str = "", default=_MISSING) -> int:
        field = f"{parent}.{key}" if parent else key
        if key not in obj and default is not _MISSING:
            return default
        v = obj.get(key, _MISSING)
        if v is _MISSING:
            self.bad(field, "missing")
        if not _is_int(v) or not 0 <= v <= MAX_TIME:
            self.bad(field, f"must be a whole number of ms from 0 to {MAX_TIME}, not {_shown(v)}")
        return v


_KIND_WORDS = {str: "a text", list: "a list", dict: "an object", int: "a whole number"}


def _check_trigger(head: _Fields, meta: dict) -> None:
    """``meta.trigger`` (what a capture says of its trigger), when there is one."""
    trig = meta.get("trigger")
    if trig is None:
        return
    if not isinstance(trig, dict):
        head.bad("meta.trigger", f"must be an object, not {_shown(trig)}")
    spec = head.get(trig, "spec", str, "meta.trigger")
    if len(spec) > MAX_TEXT:
        head.bad("meta.trigger.spec", f"longer than {MAX_TEXT} characters")
    head.time(trig, "t_ms", "meta.trigger")
    for key in ("pre_ms", "post_ms"):
        head.time(trig, key, "meta.trigger", None)
    if trig.get("mode") is not None:
        head.get(trig, "mode", str, "meta.trigger")


#: The fields of each event the controller writes, and their types (None: may be null).
_EVENT_FIELDS = {
    "started": {"name": str, "kind": str, "eparam": int},
    "ended": {"name": str, "kind": str, "exit_code": int, "exit_name": (str, None),
              "vexit": int},
    "message": {"message": int, "name": (str, None), "command": int, "parameter": int,
                "source": str},
    "print": {"register": int, "value": int, "source": str},
    "fault": {"source": str, "file": (str, None), "line": (int, None), "text": str,
              "calls": list},
    "note": {"text": str, "level": str},
    "log": {"source": str, "text": str},
    "halted": {"state": dict},
    "resumed": {},
    "forces": {"forces": list},
    "watch": {"name": str, "value": int},
}
_INT64 = (-(1 << 63), (1 << 63) - 1)


def _check_events(path: Path, events) -> None:
    """``events.json``: a list of objects, each with its ``type`` and ``t_ms``,
    and the fields of the events the controller writes of their types."""
    ev = _Fields(path, "events.json")
    if not isinstance(events, list):
        raise TraceFileError(f"{path}: events.json is not a list of objects")
    if len(events) > MAX_EVENTS:
        raise TraceFileError(f"{path}: events.json: {len(events)} events, more than "
                             f"{MAX_EVENTS}")
    for i, e in enumerate(events):
        where = f"[{i}]"
        if not isinstance(e, dict):
            raise TraceFileError(f"{path}: events.json is not a list of objects "
                                 f"(event {i} is {_shown(e)})")
        kind = ev.get(e, "type", str, where)
        ev.time(e, "t_ms", where)
        for key, want in _EVENT_FIELDS.get(kind, {}).items():
            if key not in e:
                continue
            v = e[key]
            types = want if isinstance(want, tuple) else (want,)
            if v is None and None in types:
                continue
            ok = any(isinstance(v, t) and not isinstance(v, bool) for t in types if t)
            if not ok:
                words = " or ".join(_KIND_WORDS[t] for t in types if t)
                ev.bad(f"{where}.{key}", f"must be {words}, not {_shown(v)}")
            if _is_int(v) and not _INT64[0] <= v <= _INT64[1]:
                ev.bad(f"{where}.{key}", f"{_shown(v)} is beyond a 64-bit number")
            if isinstance(v, str) and len(v) > MAX_TEXT:
                ev.bad(f"{where}.{key}", f"longer than {MAX_TEXT} characters")
