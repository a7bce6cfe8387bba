"""What Build All reports: a :class:`ProcedureBuild` per procedure, a
:class:`BuildResult` for the project.

A result keeps only what the report and the IDE need: the diagnostics (with
the source lines they point at) packed as zlib-compressed JSON until asked
for, the code size and the binary's CRC; the binary's bytes are read back from
build/ when asked for. A large project's report holds a few hundred bytes a
procedure, not the compiler's objects (docs/projects.md, "Build All").

The diagnostics travel as the JSON text of their :meth:`Diagnostic.to_dict`
rows (:func:`dumps`): a worker makes it, the cache stores it as it is, and it
is decoded only when a caller asks for ``diagnostics``.
"""

from __future__ import annotations

import json
import os
import zlib
from pathlib import Path
from typing import Optional

from plcbuilder._support.files import read_bounded
from plcbuilder._support.records import dataclass
from plcbuilder.bytecode.program import MAX_FILE_SIZE, Kind, Program
from plcbuilder.image.manifest import Limits
from plcbuilder.lang import Diagnostic, Severity, error, render_text
from plcbuilder.lang.builtin_headers import source_text
from plcbuilder.project.model import Procedure, Project

BIN_SUFFIX = ".bin"


def dumps(value) -> str:
    """Compact JSON with sorted keys: the text of diagnostics rows and of the cache."""
    return json.dumps(value, sort_keys=True, separators=(",", ":"))


class ProcedureBuild:
    """One procedure's outcome. Its diagnostics (with the source lines they point
    at) are held packed, as zlib-compressed JSON, and decoded when asked for."""

    __slots__ = ("procedure", "size", "limit", "crc32", "cached", "errors", "warnings",
                 "_packed", "_binary", "_bin_path", "_shown")

    def __init__(self, procedure: Procedure, diagnostics, size: Optional[int], limit: int,
                 crc32: Optional[int] = None, cached: bool = False, lines: Optional[dict] = None,
                 binary: Optional[bytes] = None, bin_path: Optional[str | Path] = None,
                 shown: Optional[str] = None):
        self.procedure = procedure
        self.size = size                    # code bytes, None when it did not compile
        self.limit = limit
        self.crc32 = crc32                  # of the binary, None when it did not compile
        self.cached = cached                # reused from build/.cache.json
        self._binary = binary
        self._bin_path = bin_path           # a binary written to (or reused from) build/
        #: the diagnostics rendered as the report shows them without colour (None:
        #: not rendered yet), zlib-compressed unless it is the cache's own string
        self._shown = zlib.compress(shown.encode("utf-8"), 1) if shown and not cached else shown
        if isinstance(diagnostics, Packed):
            self._packed, self.errors, self.warnings = diagnostics
        else:
            rows = [d.to_dict() for d in diagnostics]
            self._packed, self.errors, self.warnings = pack(dumps(rows), *counts(rows), lines)

    @property
    def diagnostics(self) -> list[Diagnostic]:
        if type(self._packed) is str:   # the cache's text: checked as it is decoded
            try:
                rows = json.loads(self._packed)
                if type(rows) is not list:
                    raise ValueError("not a list")
                return [Diagnostic.from_dict(d) for d in rows]
            except (ValueError, RecursionError):
                return [error("build-cache", f"the diagnostics build/.cache.json keeps for "
                                             f"{self.name} are damaged", None,
                              "build again with --no-cache")]
        return [Diagnostic.from_dict(d) for d in _unpack(self._packed)[0]]

    @property
    def lines(self) -> dict:
        """(file, line) -> text of the source lines the diagnostics point at
        (none kept for a cached procedure: they are read from the disk)."""
        if type(self._packed) is str:
            return {}
        return {(f, n): text for f, n, text in _unpack(self._packed)[1]}

    def shown(self) -> str:
        """The diagnostics as ``plcbuilder build`` shows them without colour:
        each :func:`render_text` with :meth:`source_line`, one after another.
        Rendered by the worker that compiled the procedure (or kept in the
        cache with it: its key covers the sources the lines come from), or
        here, once, when neither did."""
        if self._shown is None:
            self._shown = "\n".join(render_text(d, self.source_line) for d in self.diagnostics)
        return self._shown if type(self._shown) is str else \
            zlib.decompress(self._shown).decode("utf-8")

    def shown_if_rendered(self) -> Optional[str]:
        """:meth:`shown` when it is at hand (None: it would be rendered now)."""
        return None if self._shown is None else self.shown()

    def diagnostics_json(self) -> str:
        """The diagnostics as the cache stores them (compact JSON text)."""
        if type(self._packed) is str:
            return self._packed
        return dumps(_unpack(self._packed)[0])

    def __repr__(self) -> str:
        return (f"ProcedureBuild({self.name!r}, size={self.size}, limit={self.limit}, "
                f"errors={self.errors}, warnings={self.warnings}, cached={self.cached})")

    @property
    def name(self) -> str:
        return self.procedure.name

    @property
    def kind(self) -> Kind:
        return self.procedure.kind

    @property
    def path(self) -> Path:
        return self.procedure.path

    @property
    def ok(self) -> bool:
        return self.crc32 is not None and not self.errors

    @property
    def bin_name(self) -> str:
        return self.name + BIN_SUFFIX

    @property
    def binary(self) -> Optional[bytes]:
        """The compiled procedure's bytes; one reused from the cache is read from
        build/ (None if it is no longer there as it was built)."""
        if self._binary is not None or self._bin_path is None:
            return self._binary
        try:
            data = read_bounded(self._bin_path, MAX_FILE_SIZE, "compiled procedure")
        except OSError:
            return None
        return data if zlib.crc32(data) == self.crc32 else None

    def written_to(self, path: Path) -> None:
        """Its binary is now at ``path`` (in build/): the bytes are let go and
        read back from there when asked for."""
        self._binary, self._bin_path = None, path

    def program(self) -> Optional[Program]:
        """The compiled procedure, as the controller loads it (None if it did not compile)."""
        data = self.binary if self.ok else None
        return Program.from_bytes(data) if data is not None else None

    def source_line(self, file: str, line: int) -> Optional[str]:
        """A source line for diagnostics.render_text. (A report asks for one
        line a diagnostic, procedure after procedure: the lines kept with the
        last procedure's diagnostics and the last file read are remembered,
        the file while it is unchanged on disk; an unchanged rebuild of the
        benchmark project read a thousand files 7,300 times.)"""
        global _kept_lines
        packed, kept = _kept_lines
        if packed is not self._packed:
            kept = self.lines
            _kept_lines = (self._packed, kept)
        return kept_line(kept, file, line)


def kept_line(kept: dict, file: str, line: int) -> Optional[str]:
    """A source line for a diagnostic: as kept with it ({(file, line): text}),
    else from the disk. (The worker that renders a procedure's diagnostics for
    the report and ProcedureBuild.source_line find lines alike this way.)"""
    text = kept.get((file, line))
    return text if text is not None else _disk_line(file, line)


#: (the packed diagnostics, their lines) of the procedure source_line last served
_kept_lines: tuple = (None, {})
#: (file, its size and time stamps, its lines) of the file _disk_line last read
_last_file: tuple = (None, None, None)


@dataclass
class BuildResult:
    project: Project
    procedures: list[ProcedureBuild]
    diagnostics: list[Diagnostic]       # the project's own (hardware total, names, image)
    limits: Limits
    hw_total: int                       # code bytes of the hardware procedures that compiled
    image_path: Path
    image_written: bool = False
    image_size: Optional[int] = None
    image_message: str = ""
    compiled: int = 0                   # procedures compiled this time
    reused: int = 0                     # procedures taken from the cache

    @property
    def all_diagnostics(self) -> list[Diagnostic]:
        out = [d for p in self.procedures for d in p.diagnostics]
        return out + list(self.diagnostics)

    @property
    def error_count(self) -> int:
        return sum(p.errors for p in self.procedures) + \
            sum(1 for d in self.diagnostics if d.is_error)

    @property
    def warning_count(self) -> int:
        return sum(p.warnings for p in self.procedures) + \
            sum(1 for d in self.diagnostics if d.severity == Severity.WARNING)

    @property
    def ok(self) -> bool:
        return self.error_count == 0

    def get(self, name: str) -> Optional[ProcedureBuild]:
        for p in self.procedures:
            if p.name == name:
                return p
        return None

    def source_line(self, file: str, line: int) -> Optional[str]:
        """A source line for the project's own diagnostics: as the procedure of
        that file kept it, or from the disk."""
        for p in self.procedures:
            if str(p.path) == file and (p.errors or p.warnings):
                text = p.lines.get((file, line))
                if text is not None:
                    return text
        return _disk_line(file, line)


# ------------------------------------------------------ packed diagnostics

class Packed(tuple):
    """(packed, errors, warnings): diagnostics already packed (by :func:`pack`),
    or their JSON text as the cache file holds it (:func:`cached`: that document
    is in memory for the build anyway, so it is shared, not packed again, and
    decoded only when asked for)."""


def pack(rows_json: str, errors: int, warnings: int, lines=None) -> Packed:
    """Diagnostics as the JSON text of their ``to_dict`` rows, their counts,
    and the source lines they point at ({(file, line): text} or
    [[file, line, text]]), packed for a ProcedureBuild."""
    if rows_json == "[]":
        return Packed((b"", 0, 0))
    if isinstance(lines, dict):
        lines = [[f, n, text] for (f, n), text in lines.items()]
    text = '{"d":' + rows_json + ',"l":' + dumps(lines or []) + "}"
    return Packed((zlib.compress(text.encode("utf-8"), 1), errors, warnings))


def cached(rows_json: str, errors: int, warnings: int) -> Packed:
    """Diagnostics as the cache file holds them: the JSON text of their rows
    (checked as it is decoded) and their counts."""
    return Packed((rows_json if rows_json != "[]" else b"", errors, warnings))


def counts(rows: list) -> tuple[int, int]:
    """(errors, warnings) among diagnostics rows."""
    return (sum(1 for r in rows if r["severity"] == Severity.ERROR),
            sum(1 for r in rows if r["severity"] == Severity.WARNING))


def _unpack(packed: bytes) -> tuple[list, list]:
    """The rows and the lines :func:`pack` packed (a cached procedure's text is
    decoded by ProcedureBuild.diagnostics, with its check)."""
    if not packed:
        return [], []
    doc = json.loads(zlib.decompress(packed))
    return doc["d"], doc["l"]


# ------------------------------------------------------------ source lines

def _disk_lines(file: str) -> Optional[list[str]]:
    """The lines of a file as diagnostics name it (a path, or a built-in header)."""
    try:
        text = source_text(file)
    except (OSError, ValueError):
        return None
    if text is None:
        return None
    return text.replace("\r\n", "\n").replace("\r", "\n").split("\n")


def _disk_line(file: str, line: int) -> Optional[str]:
    """A line of a file as diagnostics name it (a path, or a built-in header)."""
    global _last_file
    try:
        st = os.stat(file)
        stamp = (st.st_size, st.st_mtime_ns, st.st_ctime_ns, st.st_ino)
    except (OSError, ValueError):
        stamp = None                        # a built-in header: it does not change
    name, seen, lines = _last_file
    if name != file or seen != stamp:
        lines = _disk_lines(file)
        _last_file = (file, stamp, lines)
    return lines[line - 1] if lines is not None and 1 <= line <= len(lines) else None
