"""Reading and writing the product's files safely.

    read_bounded   read a regular file of at most ``limit`` bytes (never a FIFO,
                   a device or a folder; never more than the limit)
    atomic_write   replace a regular file all at once (never a device or a FIFO)

Both raise :class:`FileRefused` (an ``OSError``: its ``strerror`` is the reason,
its ``filename`` the file) for what they will not touch, so a caller that
already reports ``OSError`` as ``cannot read FILE: strerror`` needs no change.
"""

from __future__ import annotations

import errno
import os
import re
import stat
from collections.abc import Iterable as _Iterable
from contextlib import contextmanager
from pathlib import Path

from .lazy import Pattern

TYPE_CHECKING = False               # (typing is not imported at run time: start-up)
if TYPE_CHECKING:
    from typing import BinaryIO, Iterable, Iterator, Optional, Union

#: What a file that is not a regular file is, for messages.
_KINDS = ((stat.S_ISDIR, "a folder"), (stat.S_ISCHR, "a character device"),
          (stat.S_ISBLK, "a block device"), (stat.S_ISFIFO, "a FIFO (named pipe)"),
          (stat.S_ISSOCK, "a socket"))


class FileRefused(OSError):
    """A file that is refused: not a regular file, or over its size limit.
    ``strerror`` says why (``is a FIFO (named pipe), not a regular file``),
    ``filename`` is the file; ``str()`` reads ``FILE: why``."""

    def __init__(self, path: Union[str, Path], reason: str, code: int = errno.EINVAL):
        super().__init__(code, reason, str(path))
        self.path = str(path)
        self.reason = reason

    def __str__(self) -> str:
        return f"{self.path}: {self.reason}"


def kind_of_mode(mode: int) -> str:
    """What a file of this ``st_mode`` is (``a FIFO (named pipe)``, ``a folder``…)."""
    for test, word in _KINDS:
        if test(mode):
            return word
    return "a regular file" if stat.S_ISREG(mode) else "not a regular file"


def size_text(n: int) -> str:
    """``1 MiB``, ``64 KiB``, ``300 bytes``: a limit as a reader would write it."""
    for unit, shift in (("GiB", 30), ("MiB", 20), ("KiB", 10)):
        if n >= 1 << shift and n % (1 << shift) == 0:
            return f"{n >> shift} {unit}"
    return f"{n} bytes"


def read_bounded(path: Union[str, Path], limit: int, what: str = "file") -> bytes:
    """The bytes of the regular file at ``path`` (symbolic links followed), at
    most ``limit`` of them. ``what`` names the kind of file in messages
    (``"machine description"``).

    Raises :class:`FileRefused` for a folder, a device, a FIFO or a socket
    (opened without blocking and never read, so a FIFO cannot hang the caller)
    and for a file over ``limit`` bytes (never read past ``limit + 1``);
    ``FileNotFoundError`` and the other ``OSError`` as ``open`` does."""
    path = Path(path)
    flags = os.O_RDONLY | getattr(os, "O_BINARY", 0) | getattr(os, "O_NONBLOCK", 0)
    fd = os.open(path, flags)
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode):
            raise FileRefused(path, f"is {kind_of_mode(st.st_mode)}, not a regular file; "
                                    f"a {what} must be a regular file",
                              errno.EISDIR if stat.S_ISDIR(st.st_mode) else errno.EINVAL)
        if st.st_size > limit:
            raise FileRefused(path, _too_large(st.st_size, limit, what), errno.EFBIG)
        chunks, total = [], 0
        while total <= limit:
            chunk = os.read(fd, min(1 << 20, limit + 1 - total))
            if not chunk:
                break
            chunks.append(chunk)
            total += len(chunk)
        if total > limit:               # it grew while we read it
            raise FileRefused(path, _too_large(total, limit, what, at_least=True), errno.EFBIG)
        return b"".join(chunks)
    finally:
        os.close(fd)


def _too_large(size: int, limit: int, what: str, at_least: bool = False) -> str:
    more = "more than " if at_least else ""
    return (f"is {more}{size} bytes; a {what} is at most {size_text(limit)} "
            f"({limit} bytes)")


def check_replaceable(path: Union[str, Path]) -> None:
    """Raise :class:`FileRefused` unless ``path`` is missing or a regular file
    (a symbolic link is judged by what it points to)."""
    try:
        st = os.stat(path)
    except (FileNotFoundError, NotADirectoryError):
        return
    except OSError:
        return                           # let the write itself say why
    if not stat.S_ISREG(st.st_mode):
        raise FileRefused(path, f"is {kind_of_mode(st.st_mode)}, not a regular file; "
                                "refusing to replace it (write to a regular file)",
                          errno.EISDIR if stat.S_ISDIR(st.st_mode) else errno.EINVAL)


#: The name atomic_write gives its temporary file beside ``NAME``: ``.NAME.XXXXXXXX.tmp``
#: (compiled when first used: not at every start).
TEMP_NAME = Pattern(r"\..+\.[0-9a-f]{8}\.tmp\Z", re.DOTALL)


def atomic_write(path: Union[str, Path], data: Union[bytes, str, Iterable[bytes]], *,
                 mode: Optional[int] = None, sync: bool = True,
                 unless_same: bool = False) -> bool:
    """Replace path's contents all at once: write a temporary file in the same
    folder, fsync it, ``os.replace`` it over path, then fsync the folder.
    Readers see the old file or the new one, never a half-written one. str is
    written as UTF-8. The file keeps its permissions when it existed, unless
    ``mode`` is given: then it has exactly that mode, whatever the umask (the
    temporary file is created with it, so the data is never readable by more).
    Raises :class:`FileRefused` when path exists and is not a regular file (a
    device, a FIFO, a folder: ``/dev/full`` stays a device), before writing
    anything. ``sync=False`` skips both fsyncs: still all-or-nothing for
    readers, but a power cut may lose the new contents (for files a checksum
    guards anyway).

    ``data`` may also be an iterable of bytes chunks, written as they come (a
    large file is never whole in memory). With ``unless_same`` the file is
    left alone when it already holds exactly these bytes (compared as they are
    written, the old file read alongside). Returns whether it replaced path."""
    path = Path(path)
    if isinstance(data, str):
        data = data.encode("utf-8")
    if isinstance(data, (bytes, bytearray, memoryview)):
        chunks: Iterable = (data,)
    elif isinstance(data, _Iterable):
        chunks = data
    else:
        raise TypeError(f"atomic_write takes bytes, str or chunks of bytes, not {type(data).__name__}")
    check_replaceable(path)
    keep = None
    if mode is None:
        try:
            keep = path.stat().st_mode & 0o7777
        except FileNotFoundError:
            pass
    tmp = path.with_name(f".{path.name}.{os.urandom(4).hex()}.tmp")   # TEMP_NAME
    flags = (os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_BINARY", 0)
             | getattr(os, "O_NOFOLLOW", 0))
    fd = os.open(tmp, flags, 0o666 if mode is None else mode)
    try:
        if mode is not None and hasattr(os, "fchmod"):
            os.fchmod(fd, mode)
        with os.fdopen(fd, "wb") as f, _old_contents(path if unless_same else None) as old:
            same = old is not None
            for chunk in chunks:
                f.write(chunk)
                if same:
                    same = old.read(len(chunk)) == chunk
            if same and old.read(1) == b"":
                f.close()
                os.unlink(tmp)
                return False
            f.flush()
            if sync:
                os.fsync(f.fileno())
        if keep is not None:
            os.chmod(tmp, keep)
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise
    if sync:
        _fsync_dir(path.parent)
    return True


@contextmanager
def _old_contents(path: Optional[Path]) -> Iterator[Optional[BinaryIO]]:
    """The file at path open for reading, or None (no path, or unreadable)."""
    if path is None:
        yield None
        return
    try:
        f = open(path, "rb")
    except OSError:
        yield None
        return
    with f:
        yield f


def remove_temp_files(folder: Union[str, Path]) -> list[str]:
    """Remove the temporary files atomic_write left in ``folder`` (its writer was
    killed between creating one and renaming it): regular files named as
    :data:`TEMP_NAME` says, nothing else. The caller makes sure no writer is at
    work in the folder. Returns the names removed."""
    removed = []
    try:
        entries = list(os.scandir(folder))
    except OSError:
        return removed
    for entry in entries:
        try:
            if TEMP_NAME.match(entry.name) and entry.is_file(follow_symlinks=False):
                os.unlink(entry.path)
                removed.append(entry.name)
        except OSError:
            pass
    return sorted(removed)


def _fsync_dir(folder: Path) -> None:
    """Make a rename in ``folder`` durable (where the platform can)."""
    if not hasattr(os, "O_DIRECTORY"):
        return
    try:
        fd = os.open(folder, os.O_RDONLY | os.O_DIRECTORY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)
