"""The runtime file: where a running controller tells its clients how to reach it.

``plcbuilder controller`` writes ``{"host", "port", "token", "pid"}`` (JSON) to
:func:`default_path`:

- ``$XDG_RUNTIME_DIR/plcbuilder/controller.json`` when ``XDG_RUNTIME_DIR`` names
  a folder (a per-user tmpfs on most Linux desktops), else
- ``$XDG_CACHE_HOME/plcbuilder/run/controller.json`` (``~/.cache/...``), or on
  Windows ``%LOCALAPPDATA%\\plcbuilder\\run\\controller.json``.

``PLCBUILDER_CONTROLLER_FILE`` overrides the path for servers and clients alike.
The folder is created 0700 and the file 0600 (only the user can read the
token), written atomically (a private temporary file, then ``os.replace``), and
removed when the server exits, if it still holds that server's data.
"""

from __future__ import annotations

import json
import os
import secrets
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


def write(endpoint: Endpoint, path: Optional[Path] = None) -> Path:
    """Write the runtime file atomically, readable by the user only. Returns its path."""
    path = Path(path) if path is not None else default_path()
    folder = path.parent
    folder.mkdir(mode=0o700, parents=True, exist_ok=True)
    data = (json.dumps(endpoint.as_dict(), sort_keys=True) + "\n").encode("utf-8")
    atomic_write(path, data, mode=0o600)
    return path


def read(path: Optional[Path] = None) -> Endpoint:
    """The endpoint in the runtime file. Raises RuntimeFileError saying why not."""
    path = Path(path) if path is not None else default_path()
    try:
        raw = read_bounded(path, MAX_SIZE, "runtime file")
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


def remove(endpoint: Endpoint, path: Optional[Path] = None) -> bool:
    """Remove the runtime file if it still describes ``endpoint`` (another server
    may have replaced it since). Returns whether it was removed."""
    path = Path(path) if path is not None else default_path()
    try:
        current = read(path)
    except RuntimeFileError:
        return False
    if current != endpoint:
        return False
    try:
        os.unlink(path)
    except OSError:
        return False
    return True
