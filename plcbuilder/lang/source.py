"""Source files: reading them safely, and the set of files one compilation saw.

A file that is not text, is huge, or cannot be read becomes a diagnostic,
never an exception. Line endings are normalised to ``\\n`` and a UTF-8 BOM is
dropped, so columns are the same for every stage.
"""

from __future__ import annotations

import errno
from pathlib import Path

from plcbuilder._support.records import dataclass, field
from plcbuilder._support.files import FileRefused, read_bounded
from plcbuilder.diagnostics import Diagnostic, Span, error, warning

TYPE_CHECKING = False               # (typing is not imported at run time: start-up)
if TYPE_CHECKING:
    from typing import Optional

MAX_SOURCE_BYTES = 1 << 20  # 1 MiB: a procedure is at most 16 KiB of code


@dataclass
class SourceFile:
    name: str            # the name diagnostics show (relative where possible)
    path: Optional[Path]  # None for text given directly or built-in headers read from resources
    text: str

    def __post_init__(self):
        self._lines: list[str] | None = None

    @property
    def lines(self) -> list[str]:
        if self._lines is None:
            self._lines = self.text.split("\n")
        return self._lines

    def line(self, n: int) -> Optional[str]:
        lines = self.lines
        return lines[n - 1] if 1 <= n <= len(lines) else None


def normalise(text: str) -> str:
    if text.startswith("\ufeff"):
        text = text[1:]
    if "\r" in text:
        text = text.replace("\r\n", "\n").replace("\r", "\n")
    return text


def decode_source(data: bytes, name: str) -> tuple[Optional[str], list[Diagnostic]]:
    """Bytes -> text, or None and a diagnostic saying why this is not a source file."""
    at = Span.point(name, 1, 1)
    if len(data) > MAX_SOURCE_BYTES:
        return None, [error("file-too-large",
                            f"{name} is {len(data)} bytes; a PLC source file is at most "
                            f"{MAX_SOURCE_BYTES} bytes", at)]
    if b"\x00" in data:
        return None, [error("file-binary", f"{name} is not a text file (it contains NUL bytes)", at,
                            "a compiled procedure (.bin) is read with 'plcbuilder disasm'")]
    try:
        return normalise(data.decode("utf-8")), []
    except UnicodeDecodeError as exc:
        line = data[:exc.start].count(b"\n") + 1
        text = normalise(data.decode("latin-1"))
        return text, [warning("file-encoding",
                              f"{name} is not valid UTF-8 (byte 0x{data[exc.start]:02x} on line {line});"
                              " read as Latin-1", Span.point(name, line, 1))]


def read_source(path: Path, name: str) -> tuple[Optional[str], list[Diagnostic]]:
    """Read a source file; (None, [diagnostic]) when it cannot be used: missing,
    unreadable, over MAX_SOURCE_BYTES, or not a regular file (a folder, a FIFO, a
    device: never opened for reading, so a FIFO cannot hang the compiler)."""
    at = Span.point(name, 1, 1)
    try:
        data = read_bounded(path, MAX_SOURCE_BYTES, "PLC source file")
    except FileRefused as exc:
        if exc.errno == errno.EISDIR:
            return None, [error("file-unreadable", f"{name} is a folder, not a source file", at)]
        code = "file-too-large" if exc.errno == errno.EFBIG else "file-unreadable"
        return None, [error(code, f"{name} {exc.reason}", at)]
    except FileNotFoundError:
        return None, [error("file-not-found", f"{name}: no such file", at)]
    except OSError as exc:
        return None, [error("file-unreadable", f"cannot read {name}: {exc.strerror or exc}", at)]
    return decode_source(data, name)


@dataclass
class SourceSet:
    """Every file one compilation read, by display name (for rendering diagnostics)."""
    files: dict[str, SourceFile] = field(default_factory=dict)

    def add(self, f: SourceFile) -> None:
        self.files.setdefault(f.name, f)

    def line(self, name: str, n: int) -> Optional[str]:
        f = self.files.get(name)
        return f.line(n) if f else None
