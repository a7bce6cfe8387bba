"""The system libraries Qt's X11 (xcb) platform plugin needs, and the
``apt-get install`` line for the missing ones.

PySide6 wheels bring Qt but not the X11 libraries of the desktop: on a fresh
Debian or Ubuntu, ``libxcb-cursor0`` and a few others are often missing, and Qt
then stops with "could not load the Qt platform plugin xcb". ``ldd`` on the
plugin names every library the loader cannot find (its own and those of the
libraries it links). Run as ``python -m plcbuilder.cli.qt_libs``: prints the
line and exits 1 when something is missing (``scripts/run`` does this before
starting the IDE). Importing this module does not load Qt.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from importlib.util import find_spec
from pathlib import Path
from typing import Optional

#: shared library (soname) -> the Debian/Ubuntu package that has it
PACKAGES = {
    "libxcb-cursor.so.0": "libxcb-cursor0",
    "libxcb-icccm.so.4": "libxcb-icccm4",
    "libxcb-image.so.0": "libxcb-image0",
    "libxcb-keysyms.so.1": "libxcb-keysyms1",
    "libxcb-render-util.so.0": "libxcb-render-util0",
    "libxcb-xkb.so.1": "libxcb-xkb1",
    "libxkbcommon-x11.so.0": "libxkbcommon-x11-0",
    "libxkbcommon.so.0": "libxkbcommon0",
    "libxcb-randr.so.0": "libxcb-randr0",
    "libxcb-shape.so.0": "libxcb-shape0",
    "libxcb-xinerama.so.0": "libxcb-xinerama0",
    "libxcb-shm.so.0": "libxcb-shm0",
    "libxcb-sync.so.1": "libxcb-sync1",
    "libxcb-xfixes.so.0": "libxcb-xfixes0",
    "libxcb-render.so.0": "libxcb-render0",
    "libxcb-xinput.so.0": "libxcb-xinput0",
    "libxcb-util.so.1": "libxcb-util1",
    "libxcb.so.1": "libxcb1",
    "libX11-xcb.so.1": "libx11-xcb1",
    "libX11.so.6": "libx11-6",
    "libEGL.so.1": "libegl1",
    "libGL.so.1": "libgl1",
    "libGLX.so.0": "libglx0",
    "libOpenGL.so.0": "libopengl0",
    "libfontconfig.so.1": "libfontconfig1",
    "libfreetype.so.6": "libfreetype6",
    "libdbus-1.so.3": "libdbus-1-3",
    "libglib-2.0.so.0": "libglib2.0-0",
    "libgthread-2.0.so.0": "libglib2.0-0",
    "libSM.so.6": "libsm6",
    "libICE.so.6": "libice6",
}

_NOT_FOUND = re.compile(r"^\s*(\S+)\s*=>\s*not found", re.MULTILINE)


def xcb_plugin() -> Optional[Path]:
    """The xcb platform plugin of the installed PySide6 (None: none found)."""
    spec = find_spec("PySide6")
    if spec is None or not spec.submodule_search_locations:
        return None
    for base in spec.submodule_search_locations:
        plugin = Path(base) / "Qt" / "plugins" / "platforms" / "libqxcb.so"
        if plugin.is_file():
            return plugin
    return None


def missing_in(ldd_output: str) -> list[str]:
    """The libraries ``ldd`` could not find, each once, in its order."""
    seen: list[str] = []
    for name in _NOT_FOUND.findall(ldd_output):
        if name not in seen:
            seen.append(name)
    return seen


class Check:
    """``ldd`` on the xcb plugin, running: :meth:`missing` waits for its answer
    (the IDE starts it first and imports Qt meanwhile)."""

    def __init__(self, plugin: Optional[Path] = None):
        plugin = plugin or xcb_plugin()
        ldd = os.environ.get("PLCBUILDER_LDD") or shutil.which("ldd")
        self.proc: Optional[subprocess.Popen] = None
        if plugin is None or not ldd:
            return
        try:
            self.proc = subprocess.Popen([ldd, str(plugin)], stdout=subprocess.PIPE,
                                         stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                                         text=True)
        except OSError:
            self.proc = None

    def missing(self) -> list[str]:
        """The libraries the xcb plugin needs that the system lacks. Empty when
        nothing is missing or it cannot tell (no plugin, no ldd)."""
        if self.proc is None:
            return []
        try:
            out, _ = self.proc.communicate(timeout=20)
        except (OSError, subprocess.SubprocessError):
            self.proc.kill()
            return []
        return missing_in(out or "")


def start_check(plugin: Optional[Path] = None) -> Check:
    """Start looking for the xcb plugin's missing libraries (see :class:`Check`)."""
    return Check(plugin)


def missing_libraries(plugin: Optional[Path] = None) -> list[str]:
    """The libraries the xcb plugin needs that the system lacks (``ldd``;
    ``PLCBUILDER_LDD`` names another command, for tests). Empty when nothing
    is missing or it cannot tell (no plugin, no ldd)."""
    return Check(plugin).missing()


def packages_for(libraries: list[str]) -> list[str]:
    """The packages to install for these libraries, each once (an unknown
    library is named as it is: the user finds its package with apt-file)."""
    out: list[str] = []
    for lib in libraries:
        pkg = PACKAGES.get(lib, lib)
        if pkg not in out:
            out.append(pkg)
    return out


def apt_line(libraries: list[str]) -> str:
    return "sudo apt-get install -y " + " ".join(packages_for(libraries))


def report(libraries: list[str]) -> str:
    """What to tell the user when libraries are missing."""
    return ("PLC Builder's window needs system libraries that Qt's X11 platform plugin "
            f"cannot find: {', '.join(libraries)}.\n"
            "On Debian or Ubuntu, install them with:\n\n"
            f"    {apt_line(libraries)}\n")


def main() -> int:
    libs = missing_libraries()
    if libs:
        print(report(libs), file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
