"""Linux desktop integration (``plcbuilder desktop-install``): PLC Builder in the
applications menu, with its icon, and ``*.plc`` files, ``plcbuilder.toml`` and
project folders opened with it.

It writes, under the user's data folder (``$XDG_DATA_HOME``, by default
``~/.local/share``), following the freedesktop.org specifications:

- ``applications/plcbuilder.desktop``: the launcher (Desktop Entry 1.4), which
  runs this installation's Python with ``-m plcbuilder gui`` on the file or
  folder given;
- ``icons/hicolor/scalable/apps/plcbuilder.svg``: the application's icon;
- ``mime/packages/plcbuilder.xml``: two file types (shared MIME-info): a PLC
  procedure (``*.plc``, ``text/x-plcbuilder-plc``) and a project's settings
  (``plcbuilder.toml``, ``application/x-plcbuilder-project``);

and in ``$XDG_CONFIG_HOME/mimeapps.list`` (by default ``~/.config``) makes PLC
Builder the default application of those two types. A folder (``inode/directory``)
is offered too, in the file manager's "Open With", never made the default.
Then it refreshes the desktop's caches with ``update-mime-database`` and
``update-desktop-database`` where they are installed (it says when they are
not). ``remove`` takes everything away again.

The standard library and ``_support`` only: the command line uses it without Qt.
"""

from __future__ import annotations

import os
import shlex
import shutil
import subprocess
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Optional, Sequence

from plcbuilder._support.files import atomic_write
from plcbuilder._support.package_data import data_folder

APP_ID = "plcbuilder"
DESKTOP_FILE = f"{APP_ID}.desktop"
PLC_TYPE = "text/x-plcbuilder-plc"
PROJECT_TYPE = "application/x-plcbuilder-project"
#: the types the launcher opens: its own two are made its default
MIME_TYPES = (PLC_TYPE, PROJECT_TYPE, "inode/directory")
DEFAULT_FOR = (PLC_TYPE, PROJECT_TYPE)

MIME_XML = f"""<?xml version="1.0" encoding="UTF-8"?>
<mime-info xmlns="http://www.freedesktop.org/standards/shared-mime-info">
  <mime-type type="{PLC_TYPE}">
    <comment>PLC procedure</comment>
    <sub-class-of type="text/plain"/>
    <glob pattern="*.plc"/>
  </mime-type>
  <mime-type type="{PROJECT_TYPE}">
    <comment>PLC Builder project</comment>
    <sub-class-of type="text/plain"/>
    <glob pattern="plcbuilder.toml" weight="60"/>
  </mime-type>
</mime-info>
"""


@dataclass
class Installed:
    """What :func:`install` or :func:`remove` did: the files written (or
    removed), the tools run and the notes (a tool that is missing)."""
    files: list[Path] = field(default_factory=list)
    ran: list[str] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)


def data_home(env: Optional[dict] = None) -> Path:
    env = os.environ if env is None else env
    return Path(env.get("XDG_DATA_HOME") or Path.home() / ".local" / "share")


def config_home(env: Optional[dict] = None) -> Path:
    env = os.environ if env is None else env
    return Path(env.get("XDG_CONFIG_HOME") or Path.home() / ".config")


def command(python: Optional[str] = None) -> list[str]:
    """The command the launcher runs (then ``%f``): this installation's Python."""
    return [python or sys.executable, "-m", APP_ID, "gui"]


def _exec_arg(arg: str) -> str:
    """One argument of a desktop entry's Exec key (its own quoting rules)."""
    if arg and not any(c in arg for c in ' \t\n"\'\\><~|&;$*?#()`'):
        return arg
    return '"' + "".join("\\" + c if c in '"`$\\' else c for c in arg) + '"'


def desktop_entry(cmd: Sequence[str]) -> str:
    """The launcher's text (Desktop Entry Specification 1.4: what desktop-file-validate
    knows)."""
    exec_line = " ".join(_exec_arg(a) for a in cmd) + " %f"
    return "\n".join([
        "[Desktop Entry]",
        "Type=Application",
        "Version=1.4",
        "Name=PLC Builder",
        "GenericName=PLC IDE",
        "Comment=Write, build, simulate and debug PLC procedures for myCNC controllers",
        f"TryExec={cmd[0]}",
        f"Exec={exec_line}",
        f"Icon={APP_ID}",
        "Terminal=false",
        "StartupNotify=true",
        f"StartupWMClass={APP_ID}",
        "Categories=Development;IDE;",
        "Keywords=PLC;CNC;myCNC;controller;simulator;",
        "MimeType=" + "".join(f"{t};" for t in MIME_TYPES),
        "",
    ])


def _paths(data: Path) -> dict[str, Path]:
    return {"desktop": data / "applications" / DESKTOP_FILE,
            "icon": data / "icons" / "hicolor" / "scalable" / "apps" / f"{APP_ID}.svg",
            "mime": data / "mime" / "packages" / f"{APP_ID}.xml"}


def install(env: Optional[dict] = None, python: Optional[str] = None,
            refresh: bool = True) -> Installed:
    """Write the launcher, the icon and the file types, make PLC Builder the
    default application of its file types, and refresh the desktop's caches.
    Raises OSError naming the file that could not be written."""
    data, out = data_home(env), Installed()
    p = _paths(data)
    icon = data_folder("resources", "icons").joinpath("app.svg").read_bytes()
    for key, content in (("desktop", desktop_entry(command(python))), ("icon", icon),
                         ("mime", MIME_XML)):
        p[key].parent.mkdir(parents=True, exist_ok=True)
        atomic_write(p[key], content)
        out.files.append(p[key])
    out.files.append(_set_defaults(config_home(env) / "mimeapps.list", DEFAULT_FOR))
    if refresh:
        _refresh(data, out)
    return out


def remove(env: Optional[dict] = None, refresh: bool = True) -> Installed:
    """Take away what :func:`install` wrote (files that are not there are skipped)."""
    data, out = data_home(env), Installed()
    for path in _paths(data).values():
        if path.exists():
            path.unlink()
            out.files.append(path)
    mimeapps = config_home(env) / "mimeapps.list"
    if mimeapps.is_file() and _drop_defaults(mimeapps, DEFAULT_FOR):
        out.files.append(mimeapps)
    if refresh:
        _refresh(data, out)
    return out


# ------------------------------------------------------------- mimeapps.list

def _set_defaults(path: Path, types: Sequence[str]) -> Path:
    """Make ``plcbuilder.desktop`` the default of ``types`` in a mimeapps.list,
    keeping every other line as it was."""
    lines = path.read_text(encoding="utf-8").splitlines() if path.is_file() else []
    lines = _without(lines, types)
    section = "[Default Applications]"
    entries = [f"{t}={DESKTOP_FILE};" for t in types]
    if section in lines:
        i = lines.index(section) + 1
        lines[i:i] = entries
    else:
        if lines and lines[-1].strip():
            lines.append("")
        lines += [section, *entries]
    path.parent.mkdir(parents=True, exist_ok=True)
    atomic_write(path, "\n".join(lines) + "\n")
    return path


def _drop_defaults(path: Path, types: Sequence[str]) -> bool:
    lines = path.read_text(encoding="utf-8").splitlines()
    kept = _without(lines, types)
    if kept == lines:
        return False
    if [s.strip() for s in kept if s.strip()] in ([], ["[Default Applications]"]):
        path.unlink()                   # nothing but what install wrote: gone with it
    else:
        atomic_write(path, "\n".join(kept) + "\n")
    return True


def _without(lines: list[str], types: Sequence[str]) -> list[str]:
    """The lines without a ``[Default Applications]`` entry of ``types`` that
    names PLC Builder (another application's entries stay)."""
    out, section = [], ""
    for line in lines:
        s = line.strip()
        if s.startswith("[") and s.endswith("]"):
            section = s
        key, eq, value = s.partition("=")
        if section == "[Default Applications]" and eq and key.strip() in types \
                and DESKTOP_FILE in value:
            continue
        out.append(line)
    return out


# ------------------------------------------------------------------- caches

def _refresh(data: Path, out: Installed) -> None:
    for tool, folder in (("update-mime-database", data / "mime"),
                         ("update-desktop-database", data / "applications")):
        exe = shutil.which(tool)
        if exe is None:
            out.notes.append(f"{tool} is not installed: the desktop sees the change when it "
                             f"next reads its files (log in again)")
            continue
        if not folder.is_dir():
            continue
        r = subprocess.run([exe, str(folder)], capture_output=True, text=True, timeout=60)
        out.ran.append(shlex.join([tool, str(folder)]))
        if r.returncode != 0:
            out.notes.append(f"{tool} {folder}: {(r.stderr or r.stdout).strip()}")
