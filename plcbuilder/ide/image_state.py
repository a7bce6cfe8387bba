"""Is what the controller runs what the editors show? (issue 13.3)

Three things can differ before a Start: an editor with unsaved changes, a
source whose content changed since ``build/eeprom.rom`` was built (not
built: compared by SHA-256 with what the build read), and an image
on the controller other than the project's (not uploaded). :func:`stale_reasons`
names each, for the warning that offers "Build, Upload and Start".
"""

from __future__ import annotations

import zlib
from pathlib import Path
from typing import Iterable, Optional

from plcbuilder._support.files import read_bounded
from plcbuilder.lang.source import MAX_SOURCE_BYTES
from plcbuilder.link.protocol import MAX_IMAGE


def image_crc(path) -> Optional[str]:
    """The CRC-32 (8 hex digits, as the controller reports it) of an image
    file, None when it cannot be read."""
    try:
        return f"{zlib.crc32(read_bounded(path, MAX_IMAGE, 'controller image')):08x}"
    except OSError:
        return None


def sources(project) -> list[Path]:
    """The project's procedures and headers."""
    out = [p.path for p in project.procedures()]
    for d in project.include_dirs():
        try:
            out += sorted(p for p in d.iterdir() if p.suffix == ".h" and p.is_file())
        except OSError:
            continue
    return out


def newer_sources(project) -> list[Path]:
    """Sources that changed since the image was built (all of them when there
    is none). A file saved after it is compared by content with what the last
    Build All read (build/.cache.json, when it describes this image): saved
    again with the bytes that were built, it has not changed; one the build did
    not read, or without a cache, counts as changed by its time alone."""
    import hashlib

    from plcbuilder.project.build.cache import built_from
    try:
        built = project.image_path.stat().st_mtime
    except OSError:
        return sources(project)
    hashes = None
    out = []
    for p in sources(project):
        try:
            if p.stat().st_mtime <= built:
                continue
            if hashes is None:
                hashes = built_from(project.build_dir, project.image_path) or {}
            was = hashes.get(str(p))
            if was is None or hashlib.sha256(
                    read_bounded(p, MAX_SOURCE_BYTES, "source")).hexdigest() != was:
                out.append(p)
        except OSError:
            continue
    return out


def stale_reasons(project, unsaved: Iterable[str], loaded_crc: Optional[str]) -> list[str]:
    """Why Start would run something other than what the editors show (empty:
    it runs exactly that)."""
    reasons = []
    names = sorted(Path(p).name for p in unsaved)
    if names:
        reasons.append(f"unsaved changes in {', '.join(names)}")
    if not project.image_path.exists():
        reasons.append("the project has not been built (no build/eeprom.rom)")
        return reasons
    newer = [p.name for p in newer_sources(project)]
    if newer:
        reasons.append(f"{', '.join(newer[:4])}{' …' if len(newer) > 4 else ''} "
                       f"changed since the last Build All")
    crc = image_crc(project.image_path)
    if loaded_crc is None:
        reasons.append("the controller has no image loaded")
    elif crc is not None and crc != loaded_crc:
        reasons.append("the controller runs another image than build/eeprom.rom "
                       "(not uploaded since the last Build All)")
    return reasons
