"""A compiled procedure and its binary file format.

Layout (little-endian)::

    header (20 bytes)
      magic      4s   b"PLCB"
      version    u8   FORMAT_VERSION
      kind       u8   0 hardware, 1 software
      nvars      u8   user variables (slots FIRST_USER_SLOT.. in the VM)
      flags      u8   0 (reserved)
      code_size  u32
      entry      u32  code offset of main()
      crc32      u32  zlib CRC-32 of everything after the header
    code        code_size bytes
    sections    name, files, line table, variable names, procedure table

The code size is what the size limits count. The sections are debug data: the
line table (code offset -> file, line, filled as each instruction is emitted)
names the source line of a runtime fault and drives the disassembler.
"""

from __future__ import annotations

import bisect
import functools
import struct
import zlib

from plcbuilder._support.records import dataclass, field
from plcbuilder.bytecode import abi
from plcbuilder.bytecode.kind import Kind  # defined there, and known here as ever
from plcbuilder.bytecode.opcodes import DecodeError, validate

MAGIC = b"PLCB"
FORMAT_VERSION = 1
HEADER = struct.Struct("<4sBBBBIII")
HEADER_SIZE = HEADER.size
MAX_FILE_SIZE = 1 << 20


class LoadError(ValueError):
    """A compiled procedure that cannot be loaded; the message says why."""


@dataclass(frozen=True)
class LineEntry:
    pc: int
    file: int
    line: int


@dataclass
class Program:
    name: str
    kind: Kind
    code: bytes
    entry: int = 0
    var_names: list[str] = field(default_factory=list)
    files: list[str] = field(default_factory=list)
    lines: list[LineEntry] = field(default_factory=list)
    procs: list[tuple[str, int]] = field(default_factory=list)

    @property
    def nvars(self) -> int:
        return len(self.var_names)

    @property
    def code_size(self) -> int:
        return len(self.code)

    # ------------------------------------------------------------ lookups
    def location(self, pc: int) -> tuple[str, int] | None:
        """(file, line) of the instruction at code offset pc, or None."""
        if not self.lines:
            return None
        i = bisect.bisect_right(self._line_pcs, pc) - 1
        if i < 0:
            return None
        e = self.lines[i]
        f = self.files[e.file] if 0 <= e.file < len(self.files) else "?"
        return f, e.line

    def proc_at(self, pc: int) -> str | None:
        """The name of the procedure whose code holds pc."""
        starts, names = self._proc_starts
        i = bisect.bisect_right(starts, pc) - 1
        return names[i] if i >= 0 else None

    # looked up once per instruction by the disassembler: computed once
    @functools.cached_property
    def _line_pcs(self) -> list[int]:
        return [e.pc for e in self.lines]

    @functools.cached_property
    def _proc_starts(self) -> tuple[list[int], list[str]]:
        ordered = sorted(self.procs, key=lambda p: p[1])
        return [off for _, off in ordered], [name for name, _ in ordered]

    def slot_names(self) -> dict[int, str]:
        """Slot number -> variable name, predefined and user variables."""
        names = {slot: name for name, slot in abi.SLOT_NAMES.items()
                 if name not in ("command", "parameter")}
        if self.kind is Kind.SOFTWARE:
            names[abi.SLOT_PARAM] = "Param"
        for i, n in enumerate(self.var_names):
            names[abi.FIRST_USER_SLOT + i] = n
        return names

    # --------------------------------------------------------- serialise
    def to_bytes(self) -> bytes:
        body = bytearray(self.code)
        _put_str(body, self.name)
        _put_u16(body, len(self.files))
        for f in self.files:
            _put_str(body, f)
        _put_u32(body, len(self.lines))
        for e in self.lines:
            body += struct.pack("<IHI", e.pc, e.file, e.line)
        _put_u16(body, len(self.var_names))
        for v in self.var_names:
            _put_str(body, v)
        _put_u16(body, len(self.procs))
        for name, off in self.procs:
            _put_str(body, name)
            _put_u32(body, off)
        header = HEADER.pack(MAGIC, FORMAT_VERSION, int(self.kind), len(self.var_names), 0,
                             len(self.code), self.entry, zlib.crc32(bytes(body)))
        return header + bytes(body)

    @property
    def crc32(self) -> int:
        return HEADER.unpack_from(self.to_bytes())[7]

    @classmethod
    def from_bytes(cls, data: bytes) -> "Program":
        """Load a compiled procedure; raises LoadError with the reason."""
        if not isinstance(data, (bytes, bytearray, memoryview)):
            raise LoadError("not binary data")
        data = bytes(data)
        if len(data) > MAX_FILE_SIZE:
            raise LoadError(f"file is {len(data)} bytes, more than {MAX_FILE_SIZE}")
        if len(data) < HEADER_SIZE:
            raise LoadError(f"truncated: {len(data)} bytes, the header alone is {HEADER_SIZE}")
        magic, version, kind, nvars, _flags, code_size, entry, crc = HEADER.unpack_from(data)
        if magic != MAGIC:
            raise LoadError(f"not a compiled PLC procedure (magic {magic!r}, expected {MAGIC!r})")
        if version != FORMAT_VERSION:
            raise LoadError(f"format version {version}, this controller reads version {FORMAT_VERSION}")
        if kind not in (0, 1):
            raise LoadError(f"unknown procedure kind {kind}")
        if _flags != 0:
            raise LoadError(f"reserved header flags are 0x{_flags:02x}, must be 0")
        body = data[HEADER_SIZE:]
        if zlib.crc32(body) != crc:
            raise LoadError(f"CRC mismatch: header says {crc:08x}, contents give {zlib.crc32(body):08x}"
                            " (corrupt or truncated)")
        if code_size > len(body):
            raise LoadError(f"truncated: code size {code_size} but only {len(body)} bytes follow the header")
        code = body[:code_size]
        r = _Reader(body, code_size)
        try:
            name = r.str()
            files = [r.str() for _ in range(r.u16())]
            lines = []
            for _ in range(r.u32()):
                pc, fi, ln = r.unpack("<IHI")
                lines.append(LineEntry(pc, fi, ln))
            var_names = [r.str() for _ in range(r.u16())]
            procs = []
            for _ in range(r.u16()):
                pname = r.str()
                procs.append((pname, r.u32()))
        except (struct.error, UnicodeDecodeError, IndexError) as exc:
            raise LoadError(f"damaged debug sections: {exc}") from None
        if r.pos != len(body):
            raise LoadError(f"{len(body) - r.pos} unexpected bytes after the last section")
        if len(var_names) != nvars:
            raise LoadError(f"header says {nvars} variables, the name table has {len(var_names)}")
        if nvars > abi.MAX_USER_VARS:
            raise LoadError(f"{nvars} variables, the limit is {abi.MAX_USER_VARS}")
        try:
            validate(code, entry)
        except DecodeError as exc:
            raise LoadError(f"invalid code: {exc}") from None
        if code and not 0 <= entry < len(code):
            raise LoadError(f"entry point {entry} is outside the code")
        starts = dict(procs)
        if "main" in starts and starts["main"] != entry:
            raise LoadError(f"entry point {entry} is not main() (at {starts['main']})")
        return cls(name, Kind(kind), code, entry, var_names, files, lines, procs)


def _put_u16(buf: bytearray, v: int) -> None:
    buf += struct.pack("<H", v)


def _put_u32(buf: bytearray, v: int) -> None:
    buf += struct.pack("<I", v)


def _put_str(buf: bytearray, s: str) -> None:
    raw = s.encode("utf-8")
    _put_u16(buf, len(raw))
    buf += raw


class _Reader:
    def __init__(self, data: bytes, pos: int):
        self.data, self.pos = data, pos

    def unpack(self, fmt: str):
        st = struct.Struct(fmt)
        vals = st.unpack_from(self.data, self.pos)
        self.pos += st.size
        return vals

    def u16(self) -> int:
        return self.unpack("<H")[0]

    def u32(self) -> int:
        n = self.unpack("<I")[0]
        if n > len(self.data):
            raise IndexError(f"count {n} larger than the file")
        return n

    def str(self) -> str:
        n = self.u16()
        if self.pos + n > len(self.data):
            raise IndexError("string runs past the end")
        s = self.data[self.pos:self.pos + n].decode("utf-8")
        self.pos += n
        return s
