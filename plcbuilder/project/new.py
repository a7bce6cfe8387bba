"""``plcbuilder new DIR``: a new project made from the example project.

The example (package data, ``resources/example_project``) holds working
hardware procedures (M02, M03, M05, M07, M08, M09, M71, M80, M81, OFF),
software procedures (LUBE, __HANDLER_INIT), scenario tests of them
(``tests/*.toml``, run by ``plcbuilder test``) and a plc-variables.xml. The new
project also gets ``include/pins.h`` (the built-in default pin map), the
default machine as ``machine.toml`` and a ``plcbuilder.toml``.

The project is assembled in a temporary folder beside DIR and renamed into
place, so a failure never leaves half a project behind.
"""

from __future__ import annotations

import os
import secrets
import shutil
from importlib import resources
from importlib.resources.abc import Traversable
from pathlib import Path
from typing import Optional, Union

from plcbuilder._support.files import atomic_write
from plcbuilder.project.model import (DEFAULT_MACHINE, HARDWARE_DIR, INCLUDE_DIR, SETTINGS_FILE,
                                      SOFTWARE_DIR, Project, ProjectError, Settings)

EXAMPLE = ("resources", "example_project")
#: the example project of each target (docs/targets.md)
EXAMPLES = {"mycnc": EXAMPLE, "huazhong": ("resources", "example_huazhong"),
            "tgmotion": ("resources", "example_tgmotion")}
#: settings an example sets beyond the defaults: what TG Motion's oscilloscope samples,
#: and a housekeeping Program_01 slower than the seed's "10 000 μs (the upper value is
#: not limited)"
EXAMPLE_SETTINGS = {"tgmotion": {"oscilloscope": ("in 9", "out 7", "Program.target_x"),
                                 "program_periods_us": (20000, 1000, 1000)}}
PINS = ("resources", "include", "pins.h")
MACHINE = ("resources", "machine", "default.toml")


def _resource(parts: tuple[str, ...]) -> Traversable:
    ref = resources.files("plcbuilder")
    for p in parts:
        ref = ref / p
    return ref


def _copy_tree(src: Traversable, dest: Path) -> None:
    dest.mkdir(parents=True, exist_ok=True)
    for entry in sorted(src.iterdir(), key=lambda e: e.name):
        if entry.name.startswith(".") or entry.name == "__pycache__":
            continue
        if entry.is_dir():
            _copy_tree(entry, dest / entry.name)
        else:
            (dest / entry.name).write_bytes(entry.read_bytes())


def create_project(dest: Union[str, Path], name: Optional[str] = None,
                   target: str = "mycnc") -> Project:
    """Create a project at dest (which must not exist, or be an empty folder)
    for ``target`` (mycnc, huazhong or tgmotion: that target's example).
    Raises ProjectError when it cannot."""
    dest = Path(dest)
    if target not in EXAMPLES:
        raise ProjectError(f"unknown target {target!r} (one of {', '.join(EXAMPLES)})")
    if dest.exists():
        if not dest.is_dir():
            raise ProjectError("exists and is a file", dest)
        if any(dest.iterdir()):
            raise ProjectError("exists and is not empty; choose a new folder", dest)
    parent = dest.parent
    if not parent.is_dir():
        raise ProjectError("no such folder", parent)
    example, pins, machine = _resource(EXAMPLES[target]), _resource(PINS), _resource(MACHINE)
    for ref, what in ((example, "the example project"), (pins, "the default pins.h"),
                      (machine, "the default machine")):
        if not (ref.is_dir() if ref is example else ref.is_file()):
            raise ProjectError(f"{what} is missing from this PLC Builder installation", ref)
    project_name = name or dest.resolve().name
    tmp = parent / f".{dest.name}.{secrets.token_hex(4)}.new"
    try:
        _copy_tree(example, tmp)
        (tmp / INCLUDE_DIR).mkdir(exist_ok=True)
        (tmp / INCLUDE_DIR / "pins.h").write_bytes(pins.read_bytes())
        (tmp / DEFAULT_MACHINE).write_bytes(machine.read_bytes())
        (tmp / SETTINGS_FILE).write_text(Settings(name=project_name, target=target,
                                                  **EXAMPLE_SETTINGS.get(target, {})).to_toml(),
                                         encoding="utf-8")
        try:
            os.replace(tmp, dest)          # POSIX: also replaces an empty folder
        except OSError:
            if dest.is_dir() and not any(dest.iterdir()):
                dest.rmdir()
                os.replace(tmp, dest)
            else:
                raise
    except OSError as exc:
        shutil.rmtree(tmp, ignore_errors=True)
        raise ProjectError(f"cannot create the project: {exc.strerror or exc}", dest) from None
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return Project.open(dest)


def init_project(dest: Union[str, Path], name: Optional[str] = None) -> Project:
    """Make the folder dest (which holds other files) a project: add what is
    missing of hardware/, software/, include/pins.h, machine.toml and
    plcbuilder.toml, and change nothing that is there. Raises ProjectError."""
    dest = Path(dest)
    if not dest.is_dir():
        raise ProjectError("no such folder", dest)
    pins, machine = _resource(PINS), _resource(MACHINE)
    try:
        for sub in (HARDWARE_DIR, SOFTWARE_DIR, INCLUDE_DIR):
            (dest / sub).mkdir(exist_ok=True)
        for target, ref in ((dest / INCLUDE_DIR / "pins.h", pins), (dest / DEFAULT_MACHINE, machine)):
            if not target.exists():
                atomic_write(target, ref.read_bytes())
        settings = dest / SETTINGS_FILE
        if not settings.exists():
            atomic_write(settings, Settings(name=name or dest.resolve().name).to_toml())
    except OSError as exc:
        raise ProjectError(f"cannot make it a project: {exc.strerror or exc}", dest) from None
    return Project.open(dest)
