"""Writing files so that a reader never sees half of one."""

from __future__ import annotations

import os
import re
import secrets
from pathlib import Path
from typing import Optional, Union


#: The name atomic_write gives its temporary file beside ``NAME``: ``.NAME.XXXXXXXX.tmp``.
TEMP_NAME = re.compile(r"\..+\.[0-9a-f]{8}\.tmp\Z", re.DOTALL)


def atomic_write(path: Union[str, Path], data: Union[bytes, str], *,
                 mode: Optional[int] = None, sync: bool = True) -> None:
    """Replace path's contents all at once: write a temporary file in the same
    folder, fsync it, ``os.replace`` it over path, then fsync the folder.
    Readers see the old file or the new one, never a half-written one. str is
    written as UTF-8. The file keeps its permissions when it existed, unless
    ``mode`` is given: then it has exactly that mode, whatever the umask (the
    temporary file is created with it, so the data is never readable by more).
    ``sync=False`` skips both fsyncs: still all-or-nothing for readers, but a
    power cut may lose the new contents (for files a checksum guards anyway)."""
    path = Path(path)
    if isinstance(data, str):
        data = data.encode("utf-8")
    elif not isinstance(data, (bytes, bytearray, memoryview)):
        raise TypeError(f"atomic_write takes bytes or str, not {type(data).__name__}")
    keep = None
    if mode is None:
        try:
            keep = path.stat().st_mode & 0o7777
        except FileNotFoundError:
            pass
    tmp = path.with_name(f".{path.name}.{secrets.token_hex(4)}.tmp")   # TEMP_NAME
    flags = (os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_BINARY", 0)
             | getattr(os, "O_NOFOLLOW", 0))
    fd = os.open(tmp, flags, 0o666 if mode is None else mode)
    try:
        if mode is not None and hasattr(os, "fchmod"):
            os.fchmod(fd, mode)
        with os.fdopen(fd, "wb") as f:
            f.write(data)
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
