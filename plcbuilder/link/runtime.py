"""The runtime file: where a running controller tells its clients how to reach it.

``plcbuilder controller`` writes ``{"host", "port", "token", "pid"}`` (JSON) to
:func:`default_path`:

- ``$XDG_RUNTIME_DIR/plcbuilder/controller.json`` when ``XDG_RUNTIME_DIR`` names
  a folder (a per-user tmpfs on most Linux desktops), else
- ``$XDG_CACHE_HOME/plcbuilder/run/controller.json`` (``~/.cache/...``), or on
  Windows ``%LOCALAPPDATA%\\plcbuilder\\run\\controller.json``.

``PLCBUILDER_CONTROLLER_FILE`` overrides the path for servers and clients alike.
The folder is created 0700 and the file 0600 (only the user can read the
token), written atomically (a private temporary file, then ``os.replace``).
On POSIX a runtime file, or its folder, that another user owns or that other
users can write is refused (someone else could point the clients at their
own server), both when writing and when reading. When the server exits it
removes the file if it still holds that server's data; if it replaced the
file of a controller that is still running, it puts that one's back instead.
"""

from __future__ import annotations

import json
import os
import secrets
import stat
import sys
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Optional

from plcbuilder._support.files import atomic_write, read_bounded
from plcbuilder._support.procs import pid_alive

__all__ = ["Endpoint", "RuntimeFileError", "default_path", "new_token", "pid_alive", "read",
           "remove", "write"]

ENV_FILE = "PLCBUILDER_CONTROLLER_FILE"
FILE_NAME = "controller.json"
MAX_SIZE = 64 * 1024


class RuntimeFileError(OSError):
    """The runtime file is missing, unreadable or damaged."""


@dataclass(frozen=True)
class Endpoint:
    host: str
    port: int
    token: str
    pid: int

    def as_dict(self) -> dict:
        return asdict(self)


def default_path(environ: Optional[dict] = None) -> Path:
    env = os.environ if environ is None else environ
    if env.get(ENV_FILE):
        return Path(env[ENV_FILE])
    run = env.get("XDG_RUNTIME_DIR")
    if run and os.path.isabs(run) and os.path.isdir(run):
        return Path(run) / "plcbuilder" / FILE_NAME
    if sys.platform == "win32" and env.get("LOCALAPPDATA"):
        base = Path(env["LOCALAPPDATA"])
    elif env.get("XDG_CACHE_HOME") and os.path.isabs(env["XDG_CACHE_HOME"]):
        base = Path(env["XDG_CACHE_HOME"])
    else:
        base = Path.home() / ".cache"
    return base / "plcbuilder" / "run" / FILE_NAME


def new_token() -> str:
    """A fresh random token (256 bits, URL-safe text)."""
    return secrets.token_urlsafe(32)


def _check_owner(path: Path, st: os.stat_result, what: str) -> None:
    """Refuse (RuntimeFileError) what another user owns or other users can write."""
    if os.name != "posix":
        return
    uid = os.getuid()
    if st.st_uid != uid:
        raise RuntimeFileError(f"refusing {what} {path}: it belongs to user {st.st_uid}, "
                               f"not to you (user {uid})")
    if st.st_mode & 0o022:
        raise RuntimeFileError(f"refusing {what} {path}: other users can write it (mode "
                               f"{stat.S_IMODE(st.st_mode):04o}); make it private (chmod 700)")


def check_folder(folder: Path) -> None:
    """The runtime file's folder must be the user's own and not writable by others."""
    try:
        st = os.stat(folder)
    except OSError as exc:
        raise RuntimeFileError(f"cannot use the folder {folder}: {exc.strerror or exc}") from None
    _check_owner(folder, st, "the runtime folder")


def write(endpoint: Endpoint, path: Optional[Path] = None) -> Path:
    """Write the runtime file atomically, readable by the user only. Returns its
    path. Raises RuntimeFileError (an OSError) for a folder that is not safe."""
    path = Path(path) if path is not None else default_path()
    folder = path.parent
    folder.mkdir(mode=0o700, parents=True, exist_ok=True)
    check_folder(folder)
    data = (json.dumps(endpoint.as_dict(), sort_keys=True) + "\n").encode("utf-8")
    atomic_write(path, data, mode=0o600)
    return path


def read(path: Optional[Path] = None) -> Endpoint:
    """The endpoint in the runtime file. Raises RuntimeFileError saying why not."""
    path = Path(path) if path is not None else default_path()
    try:
        st = os.stat(path)
        if stat.S_ISREG(st.st_mode):    # whose it is, before reading a byte of it
            _check_owner(path, st, "the runtime file")
            check_folder(path.parent)
        raw = read_bounded(path, MAX_SIZE, "runtime file")   # refuses what is not a regular file
    except FileNotFoundError:
        raise RuntimeFileError(f"no runtime file {path}") from None
    except OSError as exc:
        raise RuntimeFileError(f"cannot read {path}: {exc.strerror or exc}") from None
    try:
        d = json.loads(raw.decode("utf-8"))
        ep = Endpoint(host=d["host"], port=d["port"], token=d["token"], pid=d["pid"])
    except (ValueError, KeyError, TypeError, UnicodeDecodeError, RecursionError):
        raise RuntimeFileError(f"{path} is damaged (expected host, port, token and pid)") from None
    if not (isinstance(ep.host, str) and type(ep.port) is int and 0 < ep.port < 65536
            and isinstance(ep.token, str) and type(ep.pid) is int):
        raise RuntimeFileError(f"{path} is damaged (expected host, port, token and pid)")
    return ep


def remove(endpoint: Endpoint, path: Optional[Path] = None,
           previous: Optional[Endpoint] = None) -> bool:
    """Remove the runtime file if it still describes ``endpoint`` (another server
    may have replaced it since). When ``previous`` (the file this server
    replaced) names a controller that is still running, it is written back
    instead, so that clients find that one again. Returns whether the file
    stopped describing ``endpoint``."""
    path = Path(path) if path is not None else default_path()
    try:
        current = read(path)
    except RuntimeFileError:
        return False
    if current != endpoint:
        return False
    if previous is not None and previous.pid != endpoint.pid and pid_alive(previous.pid):
        try:
            write(previous, path)
            return True
        except OSError:
            pass
    try:
        os.unlink(path)
    except OSError:
        return False
    return True
