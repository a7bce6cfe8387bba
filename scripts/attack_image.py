#!/usr/bin/env python3
"""Attacks on the image loader and the build folder (issue 17, items 9 and 11),
run against the real code.

    python scripts/attack_image.py          # prints one row per attack

``ATTACKS`` is a list of (name, callable); each callable takes no arguments and
returns ``{"tried", "refused", "accepted", "crashed"}``. For an attack on the
loader, *refused* is an ImageError with a reason, *accepted* an image that was
read anyway, *crashed* any other exception. Two rows say "(must be accepted)":
there accepted is the good outcome. For the build folder, tried counts the
temporary files killed builds left, refused those the next build removed,
accepted those it left, crashed the builds that did not end as they should.
``scripts/attack.py`` prints these rows with the others.
"""

from __future__ import annotations

import dataclasses
import json
import os
import random
import subprocess
import sys
import tempfile
import zlib
from pathlib import Path
from typing import Callable

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from plcbuilder.bytecode.program import Kind, Program  # noqa: E402
from plcbuilder.image import ImageError, read_image, read_romfs, write_romfs  # noqa: E402
from plcbuilder.image.manifest import (MANIFEST_NAME, MAX_PROCEDURES, Limits,  # noqa: E402
                                       manifest_text, write_image)
from plcbuilder.lang.compiler import CompileOptions, compile_source  # noqa: E402

Outcome = dict


def _tally() -> Outcome:
    return {"tried": 0, "refused": 0, "accepted": 0, "crashed": 0}


def _read(out: Outcome, image: bytes) -> None:
    out["tried"] += 1
    try:
        read_image(image)
    except ImageError:
        out["refused"] += 1
    except Exception:  # noqa: BLE001 - that is what is counted
        out["crashed"] += 1
    else:
        out["accepted"] += 1


_TEMPLATE: dict[Kind, Program] = {}


def _binary(name: str, kind: Kind) -> bytes:
    """A real compiled procedure, named name (compiled once per kind)."""
    if kind not in _TEMPLATE:
        r = compile_source("main() { a=portget(3); if (a) { portset(7); }; exit(99); };\n",
                           "T.plc", CompileOptions(kind=kind))
        _TEMPLATE[kind] = r.program
    return dataclasses.replace(_TEMPLATE[kind], name=name).to_bytes()


def _sample() -> list[tuple[str, Kind, bytes]]:
    names = [("M03", Kind.HARDWARE), ("M05", Kind.HARDWARE), ("M80", Kind.HARDWARE),
             ("OFF", Kind.HARDWARE), ("LUBE", Kind.SOFTWARE), ("__HANDLER_INIT", Kind.SOFTWARE)]
    return [(n, k, _binary(n, k)) for n, k in names]


def _files() -> dict[str, bytes]:
    return read_romfs(write_image(_sample())).files()


# ------------------------------------------------------------ 17.9: manifest

def manifest_bit_flips() -> Outcome:
    """Every single bit of the MANIFEST flipped, the ROMFS made valid around it."""
    out = _tally()
    files = _files()
    raw = files[MANIFEST_NAME]
    for bit in range(len(raw) * 8):
        buf = bytearray(raw)
        buf[bit // 8] ^= 1 << (bit % 8)
        _read(out, write_romfs({**files, MANIFEST_NAME: bytes(buf)}, "plcbuilder"))
    return out


def manifest_limit_digit() -> Outcome:
    """The reported case: "hw_proc": 512 -> 532 (one bit), and every other digit
    of every limit changed to every other digit."""
    out = _tally()
    files = _files()
    raw = files[MANIFEST_NAME]
    head_end = raw.index(b'"procedures"')
    for i in range(head_end):
        if not 0x30 <= raw[i] <= 0x39:
            continue
        for d in b"0123456789":
            if d != raw[i]:
                buf = bytearray(raw)
                buf[i] = d
                _read(out, write_romfs({**files, MANIFEST_NAME: bytes(buf)}, "plcbuilder"))
    return out


def manifest_out_of_order() -> Outcome:
    """Procedures listed in another order than by name, each manifest otherwise
    well formed with its own CRC right (what a forger would write)."""
    out = _tally()
    files = _files()
    doc = json.loads(files[MANIFEST_NAME])
    entries, limits = doc["procedures"], Limits(**doc["limits"])
    rng = random.Random(17)
    orders = {tuple(range(len(entries)))}
    tried = []
    for i in range(len(entries) - 1):          # every adjacent swap, and reversed
        o = list(range(len(entries)))
        o[i], o[i + 1] = o[i + 1], o[i]
        tried.append(o)
    tried.append(list(reversed(range(len(entries)))))
    while len(tried) < 60:
        o = list(range(len(entries)))
        rng.shuffle(o)
        if tuple(o) not in orders:
            tried.append(o)
    for o in tried:
        if tuple(o) in orders:
            continue
        orders.add(tuple(o))
        text = manifest_text([entries[i] for i in o], limits)
        _read(out, write_romfs({**files, MANIFEST_NAME: text}, "plcbuilder"))
    return out


def _many(n: int) -> list[tuple[str, Kind, bytes]]:
    return [(name, Kind.SOFTWARE, _binary(name, Kind.SOFTWARE))
            for name in (f"{i:05d}".ljust(64, "p") for i in range(n))]


def max_procedures_fit() -> Outcome:
    """Exactly 4,096 procedures with the longest names (64 characters): written
    and read back (must be accepted)."""
    out = _tally()
    out["tried"] += 1
    try:
        image = write_image(_many(MAX_PROCEDURES))
    except ImageError:
        out["refused"] += 1
        return out
    except Exception:  # noqa: BLE001
        out["crashed"] += 1
        return out
    out["tried"] -= 1
    _read(out, image)
    return out


def over_max_procedures() -> Outcome:
    """4,097 procedures: the writer refuses them, and so does the reader an
    image forged with all 4,097 (and a manifest with its CRC right)."""
    out = _tally()
    progs = _many(MAX_PROCEDURES + 1)
    out["tried"] += 1
    try:
        write_image(progs)
    except ImageError:
        out["refused"] += 1
    except Exception:  # noqa: BLE001
        out["crashed"] += 1
    else:
        out["accepted"] += 1
    files = {name + ".bin": data for name, _k, data in progs}
    entries = [{"name": n, "kind": "software", "file": n + ".bin",
                "code_size": Program.from_bytes(d).code_size, "file_size": len(d),
                "crc32": f"{zlib.crc32(d):08x}"} for n, _k, d in progs]
    files[MANIFEST_NAME] = manifest_text(entries, Limits())
    _read(out, write_romfs(files, "plcbuilder"))
    return out


# ------------------------------------------------- 17.11: killed builds

_KILLED = """
import os, sys
from plcbuilder.project import Project, build_project
real, count = os.replace, [0]
def die(src, dst):           # killed between writing a temporary file and renaming it
    count[0] += 1
    if count[0] == int(sys.argv[2]):
        os._exit(9)
    real(src, dst)
os.replace = die
build_project(Project.open(sys.argv[1]), use_cache=False)
"""


def killed_builds_leave_temp_files() -> Outcome:
    """Builds killed at their 1st..8th rename (a kill -9 between writing a
    temporary file and renaming it); then one normal build. Its temporary
    files must all be gone, and the image must read."""
    from plcbuilder.project import Project, build_project, create_project
    out = _tally()
    with tempfile.TemporaryDirectory(prefix="attack-image-") as tmp:
        project = create_project(Path(tmp) / "proj")
        env = dict(os.environ, PYTHONPATH=str(ROOT))
        left: set[str] = set()
        for k in range(1, 9):
            for p in project.build_dir.glob("*.bin"):
                p.unlink()            # so that the build writes every binary again
            rc = subprocess.run([sys.executable, "-c", _KILLED, str(project.root), str(k)],
                                env=env, cwd=tmp).returncode
            if rc not in (9, 0):
                out["crashed"] += 1
            left |= {p.name for p in project.build_dir.iterdir() if p.name.endswith(".tmp")}
        out["tried"] = len(left)
        try:
            r = build_project(Project.open(project.root))
            read_image(project.image_path.read_bytes())
            if not r.ok:
                out["crashed"] += 1
        except Exception:  # noqa: BLE001
            out["crashed"] += 1
        after = {p.name for p in project.build_dir.iterdir() if p.name.endswith(".tmp")}
        out["accepted"] = len(left & after)
        out["refused"] = len(left - after)
    return out


ATTACKS: list[tuple[str, Callable[[], Outcome]]] = [
    ("17.9 manifest: every single bit flipped", manifest_bit_flips),
    ("17.9 manifest: a digit of a limit changed (512 -> 532 ...)", manifest_limit_digit),
    ("17.9 manifest: procedures out of name order", manifest_out_of_order),
    ("17.9 4,096 procedures, 64-char names (must be accepted)", max_procedures_fit),
    ("17.9 4,097 procedures (writer, forged image)", over_max_procedures),
    ("17.11 temporary files of killed builds, next build", killed_builds_leave_temp_files),
]


def main() -> int:
    width = max(len(n) for n, _f in ATTACKS)
    print(f"{'attack':<{width}}  {'tried':>6} {'refused':>8} {'accepted':>9} {'crashed':>8}")
    for name, attack in ATTACKS:
        r = attack()
        print(f"{name:<{width}}  {r['tried']:>6} {r['refused']:>8} {r['accepted']:>9} "
              f"{r['crashed']:>8}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
