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
:data:`MAX_UNPACKED` bytes unpacked.
"""

from __future__ import annotations

import io
import json
import struct
import zipfile
from pathlib import Path
from typing import Union

from plcbuilder._support.files import atomic_write, read_bounded
from plcbuilder.controller.history import BIT, INT, TEXT, Trace

FORMAT = "plcbuilder-trace"
VERSION = 1
SUFFIX = ".plctrace"
#: the largest trace file read, and the most it may unpack to
MAX_FILE = 512 * 1024 * 1024
MAX_UNPACKED = 2 * 1024 * 1024 * 1024


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
    """Read a trace file; raises TraceFileError saying what is wrong."""
    path = Path(path)
    try:
        data = read_bounded(path, MAX_FILE, "trace file")
    except OSError as exc:
        raise TraceFileError(f"{path}: cannot read: {exc.strerror or exc}") from None
    try:
        z = zipfile.ZipFile(io.BytesIO(data))
    except zipfile.BadZipFile:
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
        if not isinstance(version, int) or version < 1:
            raise TraceFileError(f"{path}: trace.json: bad version {version!r}")
        if version > VERSION:
            raise TraceFileError(f"{path}: trace format version {version} is newer than this "
                                 f"PLC Builder reads (version {VERSION}); update PLC Builder")
        try:
            t_start, t_end = int(header["t_start"]), int(header["t_end"])
            strings = [str(s) for s in header.get("strings", [])]
            meta = header.get("meta") or {}
            specs = header["signals"]
            if not isinstance(specs, list) or not isinstance(meta, dict):
                raise TypeError("signals must be a list and meta an object")
        except (KeyError, TypeError, ValueError) as exc:
            raise TraceFileError(f"{path}: trace.json: missing or bad field ({exc})") from None
        signals = {}
        for i, spec in enumerate(specs):
            try:
                name, kind, n = str(spec["name"]), spec["kind"], int(spec["changes"])
            except (KeyError, TypeError, ValueError):
                raise TraceFileError(f"{path}: trace.json: signal {i} lacks name, kind or "
                                     f"changes") from None
            if kind not in (BIT, INT, TEXT):
                raise TraceFileError(f"{path}: signal {name!r}: unknown kind {kind!r}")
            raw = _member(z, f"signals/{i}.bin", path)
            if n < 0 or len(raw) != 16 * n:
                raise TraceFileError(f"{path}: signals/{i}.bin ({name}) holds {len(raw)} bytes, "
                                     f"not the {16 * max(n, 0)} its {n} changes need")
            ts = struct.unpack(f"<{n}q", raw[:8 * n])
            vs = struct.unpack(f"<{n}q", raw[8 * n:])
            if any(ts[j] >= ts[j + 1] for j in range(n - 1)):
                raise TraceFileError(f"{path}: signal {name!r}: change times are not increasing")
            if kind == TEXT and any(not 0 <= v < len(strings) for v in vs):
                raise TraceFileError(f"{path}: signal {name!r}: a value names no string")
            signals[name] = (kind, list(zip(ts, vs)))
        events = _json(z, "events.json", path)
        if not isinstance(events, list) or not all(isinstance(e, dict) for e in events):
            raise TraceFileError(f"{path}: events.json is not a list of objects")
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
    raw = _member(z, name, path)
    try:
        return json.loads(raw.decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise TraceFileError(f"{path}: {name} is not valid JSON ({exc})") from None
