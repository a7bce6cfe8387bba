"""``eeprom.rom``: the ROMFS image of a built project, and its manifest.

The image holds, in its root directory, one file per compiled procedure,
``NAME.bin`` (the binary of :mod:`plcbuilder.bytecode.program`), and a file
``MANIFEST``: UTF-8 JSON, keys sorted, one procedure a line::

    {"format": "plcbuilder-image", "limits": {"hw_proc": 512, "hw_total": 8192, "sw_proc": 16384}, "manifest_crc32": "5b0e3c1d", "version": 2,
     "procedures": [
     {"code_size": 90, "crc32": "ca7ed3a4", "file": "LUBE.bin", "file_size": 172, "kind": "software", "name": "LUBE"},
     {"code_size": 57, "crc32": "1c291ca3", "file": "M03.bin", "file_size": 312, "kind": "hardware", "name": "M03"}
    ]}

Procedures are sorted by name (strictly: no name twice). The reader accepts the
manifest only in exactly this form (it regenerates the text and compares), so a
damaged byte that would still parse as the same JSON (a tab for a space) is
refused too. ``manifest_crc32`` makes the manifest check itself: it is the
CRC-32 of the manifest's own bytes with those 8 digits written as
``00000000``, so a damaged byte that still reads as valid JSON in the canonical
form (``"hw_proc": 512`` turned ``532``) is refused as well.

``crc32`` is the zlib CRC-32 of the whole ``.bin`` file, as 8 lower-case hex
digits (ROMFS checksums protect the headers only, so these CRCs are what
protects the code). ``limits`` are the size limits the image was built for.

:func:`read_image` accepts an image only whole and valid: the ROMFS structure,
the manifest, every listed file (present, size, CRC, loadable, kind, code
size) and the size limits; nothing else may be in the image. Any failure
raises :class:`ImageError` naming the procedure where there is one.
"""

from __future__ import annotations

import json
import re
import zlib
from plcbuilder._support.records import dataclass, field
from typing import Callable, Iterable, Iterator, Mapping, Optional, Sequence, Union

from plcbuilder._support.strictjson import strict_json_loads
from plcbuilder.bytecode.program import Kind, LoadError, Program
from plcbuilder.image.limits import MAX_LIMIT, Limits
from plcbuilder.image.romfs import REGULAR, ImageError, LazyFile, iter_romfs, read_romfs

MANIFEST_NAME = "MANIFEST"
FORMAT = "plcbuilder-image"
VERSION = 2
VOLUME = "plcbuilder"
SUFFIX = ".bin"
MAX_PROCEDURES = 4096
MAX_NAME = 64
MAX_FILE_SIZE = 1 << 32
NAME_RE = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_\-]{0,63}\Z")
_KINDS = {"hardware": Kind.HARDWARE, "software": Kind.SOFTWARE}
_ENTRY_KEYS = {"name", "kind", "file", "code_size", "file_size", "crc32"}
_TOP_KEYS = {"format", "version", "limits", "manifest_crc32", "procedures"}
_SELF_CRC = "manifest_crc32"

__all__ = ["ImageError", "Limits", "Image", "ImageProcedure", "write_image", "iter_image", "read_image",
           "valid_name", "MANIFEST_NAME"]


@dataclass(frozen=True)
class ImageProcedure:
    name: str
    kind: Kind
    code_size: int
    file_size: int
    crc32: int
    data: bytes = field(repr=False)
    program: Program = field(repr=False)

    @property
    def file(self) -> str:
        return self.name + SUFFIX


@dataclass(frozen=True)
class Image:
    limits: Limits                          # the limits the image was checked against
    built_for: Limits                       # the limits its manifest names
    procedures: tuple[ImageProcedure, ...]  # sorted by name
    volume: str = VOLUME

    def get(self, name: str) -> ImageProcedure | None:
        for p in self.procedures:
            if p.name == name:
                return p
        return None

    def names(self, kind: Kind | None = None) -> list[str]:
        return [p.name for p in self.procedures if kind is None or p.kind is kind]

    @property
    def hw_total(self) -> int:
        return sum(p.code_size for p in self.procedures if p.kind is Kind.HARDWARE)


def valid_name(name: str) -> bool:
    """Whether a procedure name can go into an image (letters, digits, _ and -)."""
    return isinstance(name, str) and bool(NAME_RE.match(name))


def _kind_label(kind: Kind) -> str:
    return Kind(kind).label


def _check_limits(procs: Sequence[tuple[str, Kind, int]], limits: Limits) -> None:
    """Per-procedure and hardware-total limits; procs are (name, kind, code_size)."""
    for name, kind, size in procs:
        limit = limits.proc_limit(kind)
        if size > limit:
            raise ImageError(f"procedure {name} ({_kind_label(kind)}): code is {size} bytes, "
                             f"over the {limit}-byte limit of a {_kind_label(kind)} procedure")
    hw = [(size, name) for name, kind, size in procs if kind is Kind.HARDWARE]
    total = sum(s for s, _ in hw)
    if total > limits.hw_total:
        biggest = ", ".join(f"{n} {s}" for s, n in sorted(hw, key=lambda x: (-x[0], x[1]))[:3])
        raise ImageError(f"hardware procedures together are {total} bytes, over the "
                         f"{limits.hw_total}-byte limit (largest: {biggest})")


def _load(name: str, kind: Kind, data: bytes) -> Program:
    try:
        program = Program.from_bytes(data)
    except LoadError as exc:
        raise ImageError(f"procedure {name}: {name}{SUFFIX} does not load: {exc}") from None
    except Exception as exc:  # a loader bug must still read as a refused image
        raise ImageError(f"procedure {name}: {name}{SUFFIX} does not load: "
                         f"{type(exc).__name__}: {exc}") from None
    if program.name != name:
        raise ImageError(f"procedure {name}: {name}{SUFFIX} holds the procedure "
                         f"{program.name!r}")
    if program.kind is not kind:
        raise ImageError(f"procedure {name}: the manifest says {_kind_label(kind)}, "
                         f"{name}{SUFFIX} is a {_kind_label(program.kind)} procedure")
    return program


def _manifest_bytes(entries: Iterable[dict], limits: Limits, crc: str) -> bytes:
    head = json.dumps({"format": FORMAT, "version": VERSION, "limits": limits.as_dict(),
                       _SELF_CRC: crc}, sort_keys=True)
    lines = [json.dumps(e, sort_keys=True) for e in entries]
    body = ",\n ".join(lines)
    text = head[:-1] + ',\n "procedures": [' + ("\n " + body + "\n" if lines else "") + "]}\n"
    return text.encode("utf-8")


def manifest_crc(entries: Iterable[dict], limits: Limits) -> str:
    """``manifest_crc32``: the CRC-32 of the canonical manifest written with
    ``00000000`` in its place, as 8 lower-case hex digits."""
    return f"{zlib.crc32(_manifest_bytes(entries, limits, '0' * 8)):08x}"


def manifest_text(entries: Iterable[dict], limits: Limits) -> bytes:
    """The MANIFEST file: deterministic JSON, one procedure a line, checking
    itself with its own CRC-32 (entries in the order given: write_image sorts)."""
    return _manifest_bytes(entries, limits, manifest_crc(entries, limits))


def _worst_manifest_size() -> int:
    """Bytes of the largest manifest write_image can give: MAX_PROCEDURES entries,
    every name MAX_NAME characters, every number as long as it may be."""
    name = "W" * MAX_NAME
    entry = {"name": name, "kind": "hardware", "file": name + SUFFIX, "code_size": MAX_LIMIT,
             "file_size": MAX_FILE_SIZE, "crc32": "f" * 8}
    big = Limits(MAX_LIMIT, MAX_LIMIT, MAX_LIMIT)
    one = len(_manifest_bytes([entry], big, "f" * 8))
    two = len(_manifest_bytes([entry, entry], big, "f" * 8))
    return one + (two - one) * (MAX_PROCEDURES - 1)


#: The largest MANIFEST the reader accepts: exactly what the largest image
#: write_image can make needs (MAX_PROCEDURES procedures), so the two limits agree.
MAX_MANIFEST = _worst_manifest_size()


#: (name, kind, binary): the binary as bytes, or a function reading it (then it
#: is read once to check it and once more to write it, never kept).
ProgramInput = tuple[str, Union[Kind, str], Union[bytes, Callable[[], bytes]]]


def write_image(programs: Sequence[ProgramInput], limits: Limits | None = None) -> bytes:
    """The eeprom.rom image of compiled procedures: [(name, kind, bin_bytes)].

    Checks everything read_image checks (names, loadable binaries, kinds,
    limits, the number of procedures) and raises ImageError instead of writing
    an image the controller would refuse; each binary is decoded once. The output depends only on the inputs (sorted by name).
    """
    return b"".join(iter_image(programs, limits))


def iter_image(programs: Sequence[ProgramInput], limits: Limits | None = None,
               checked: Optional[Mapping[str, tuple[Kind, int, int]]] = None
               ) -> Iterator[bytes]:
    """write_image's image as chunks in order, for writing straight to a file:
    with binaries given as functions, no binary is held longer than it takes to
    check or write it. Every check is done before the first chunk; a binary
    that reads otherwise the second time raises ImageError while writing.

    ``checked`` names binaries the caller's compiler made just now: name ->
    (kind, CRC-32, code size). A binary of that name, kind and CRC is not
    decoded again (Build All's own output; the controller still checks every
    binary it loads); any other is loaded and checked in full."""
    limits = limits or Limits()
    limits.check()
    if len(programs) > MAX_PROCEDURES:
        raise ImageError(f"{len(programs)} procedures, at most {MAX_PROCEDURES} fit an image")
    seen: set[str] = set()
    rows = []
    for item in programs:
        try:
            name, kind, data = item
        except (TypeError, ValueError):
            raise ImageError(f"expected (name, kind, bin_bytes), got {item!r}") from None
        if not valid_name(name):
            raise ImageError(f"procedure name {name!r} cannot go into an image: use letters, "
                             "digits, '_' and '-' (at most 64)")
        if name in seen:
            raise ImageError(f"procedure {name} is given twice")
        seen.add(name)
        if isinstance(kind, str):
            if kind not in _KINDS:
                raise ImageError(f"procedure {name}: unknown kind {kind!r}")
            kind = _KINDS[kind]
        kind = Kind(kind)
        read = data if callable(data) else None
        if read is not None:
            data = read()
        if not isinstance(data, (bytes, bytearray)):
            raise ImageError(f"procedure {name}: the binary must be bytes")
        data = bytes(data)
        crc = zlib.crc32(data)
        known = checked.get(name) if checked else None
        if known is not None and known[0] is kind and known[1] == crc:
            code_size = known[2]
        else:
            code_size = _load(name, kind, data).code_size    # the decoded program is not kept
        stored = LazyFile(len(data), _reread(name, read, crc)) if read is not None else data
        rows.append((name, kind, stored, code_size, len(data), crc))
    rows.sort(key=lambda r: r[0])
    _check_limits([(r[0], r[1], r[3]) for r in rows], limits)
    files: dict = {r[0] + SUFFIX: r[2] for r in rows}
    files[MANIFEST_NAME] = manifest_text(_Entries(rows), limits)
    # Each binary was loaded (validated) once above, and the layout is what
    # read_image reads (the tests write and read back every kind of image), so
    # the image is not decoded a second time here.
    return iter_romfs(files, VOLUME)


class _Entries:
    """The manifest's entries of write_image's rows, made as they are read (the
    manifest is made twice, for its CRC and then with it; no list is kept)."""

    def __init__(self, rows: list):
        self.rows = rows

    def __iter__(self) -> Iterator[dict]:
        for n, k, _d, size, length, crc in self.rows:
            yield {"name": n, "kind": _kind_label(k), "file": n + SUFFIX, "code_size": size,
                   "file_size": length, "crc32": f"{crc:08x}"}


def _reread(name: str, read: Callable[[], bytes], crc: int) -> Callable[[], bytes]:
    def again() -> bytes:
        data = read()
        if not isinstance(data, (bytes, bytearray)) or zlib.crc32(data) != crc:
            raise ImageError(f"procedure {name}: {name}{SUFFIX} changed while the image "
                             "was written")
        return bytes(data)
    return again


# ------------------------------------------------------------------ reading

def _int(value, what: str, lo: int = 0, hi: int = 1 << 32) -> int:
    if type(value) is not int or not lo <= value <= hi:
        raise ImageError(f"manifest: {what} must be a whole number from {lo} to {hi}, is {value!r}")
    return value


def parse_manifest(raw: bytes) -> tuple[Limits, list[dict]]:
    """Validate the MANIFEST file; returns (limits, entries)."""
    if len(raw) > MAX_MANIFEST:
        raise ImageError(f"manifest is {len(raw)} bytes, more than {MAX_MANIFEST}")
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ImageError(f"manifest is not UTF-8 text (byte {exc.start})") from None
    try:
        doc = strict_json_loads(text)
    except (ValueError, RecursionError) as exc:
        raise ImageError(f"manifest is not valid JSON: {exc}") from None
    if not isinstance(doc, dict):
        raise ImageError("manifest: expected a JSON object")
    if "format" in doc and doc["format"] != FORMAT:
        raise ImageError(f"manifest: format is {doc['format']!r}, expected {FORMAT!r}")
    if "version" in doc and (type(doc["version"]) is not int or doc["version"] != VERSION):
        raise ImageError(f"manifest: format version {doc['version']!r}, this reader reads "
                         f"version {VERSION}")
    if set(doc) != _TOP_KEYS:
        extra, missing = sorted(set(doc) - _TOP_KEYS), sorted(_TOP_KEYS - set(doc))
        raise ImageError(f"manifest: unexpected keys {extra}" if extra else
                         f"manifest: missing keys {missing}")
    lim = doc["limits"]
    if not isinstance(lim, dict) or set(lim) != {"hw_proc", "hw_total", "sw_proc"}:
        raise ImageError("manifest: limits must hold exactly hw_proc, hw_total and sw_proc")
    limits = Limits(**{k: _int(v, f"limits.{k}", 1, MAX_LIMIT) for k, v in lim.items()})
    procs = doc["procedures"]
    if not isinstance(procs, list):
        raise ImageError("manifest: procedures must be a list")
    if len(procs) > MAX_PROCEDURES:
        raise ImageError(f"manifest lists {len(procs)} procedures, at most {MAX_PROCEDURES}")
    previous = None
    for i, e in enumerate(procs):
        if not isinstance(e, dict):
            raise ImageError(f"manifest: procedure #{i + 1} is not an object")
        name = e.get("name")
        label = f"procedure {name}" if isinstance(name, str) else f"procedure #{i + 1}"
        if set(e) != _ENTRY_KEYS:
            extra, missing = sorted(set(e) - _ENTRY_KEYS), sorted(_ENTRY_KEYS - set(e))
            raise ImageError(f"manifest: {label}: unexpected keys {extra}" if extra else
                             f"manifest: {label}: missing keys {missing}")
        if not valid_name(name):
            raise ImageError(f"manifest: {label}: invalid procedure name {name!r}")
        if previous is not None and name <= previous:
            raise ImageError(f"manifest: procedure {name} is listed twice" if name == previous
                             else f"manifest: procedure {name} comes after {previous}; the "
                             "procedures must be in name order (the canonical form)")
        previous = name
        if e["kind"] not in _KINDS:
            raise ImageError(f"manifest: {label}: unknown kind {e['kind']!r}")
        if e["file"] != name + SUFFIX:
            raise ImageError(f"manifest: {label}: file is {e['file']!r}, expected {name + SUFFIX!r}")
        _int(e["code_size"], f"{label}: code_size")
        _int(e["file_size"], f"{label}: file_size")
        crc = e["crc32"]
        if not isinstance(crc, str) or not re.fullmatch(r"[0-9a-f]{8}", crc):
            raise ImageError(f"manifest: {label}: crc32 must be 8 lower-case hex digits, is {crc!r}")
    own = doc[_SELF_CRC]
    if not isinstance(own, str) or not re.fullmatch(r"[0-9a-f]{8}", own):
        raise ImageError(f"manifest: {_SELF_CRC} must be 8 lower-case hex digits, is {own!r}")
    if _manifest_bytes(procs, limits, own) != raw:
        # Same meaning, other bytes (a tab for a space, an escaped letter): the
        # manifest was not written by write_image, or a byte of it was damaged.
        raise ImageError("manifest is not in the canonical form write_image gives it "
                         "(damaged or edited)")
    crc = manifest_crc(procs, limits)
    if crc != own:
        raise ImageError(f"manifest: its CRC-32 is {crc}, it says {own} (damaged or edited)")
    return limits, procs


def read_image(data: bytes | bytearray | memoryview, limits: Limits | None = None) -> Image:
    """Validate a whole eeprom.rom image and load its procedures.

    limits: the controller's limits; None checks against the limits the
    manifest names. Raises ImageError with the reason, naming the procedure.
    """
    if limits is not None:
        limits.check()
    fs = read_romfs(data, strict=True)
    if fs.volume != VOLUME:
        raise ImageError(f"volume name is {fs.volume!r}, a PLC Builder image has {VOLUME!r}")
    files: dict[str, bytes] = {}
    for node in fs.root.entries():
        if node.type != REGULAR:
            raise ImageError(f"unexpected {node.type_name} {node.name!r} in the image "
                             "(only procedure files and the manifest belong there)")
        files[node.name] = node.data
    if MANIFEST_NAME not in files:
        raise ImageError(f"no {MANIFEST_NAME} in the image")
    built_for, entries = parse_manifest(files.pop(MANIFEST_NAME))
    procedures = []
    for e in entries:
        name, kind = e["name"], _KINDS[e["kind"]]
        blob = files.pop(e["file"], None)
        if blob is None:
            raise ImageError(f"procedure {name}: the manifest lists {e['file']}, "
                             "the image has no such file")
        if len(blob) != e["file_size"]:
            raise ImageError(f"procedure {name}: {e['file']} is {len(blob)} bytes, "
                             f"the manifest says {e['file_size']}")
        crc = zlib.crc32(blob)
        if f"{crc:08x}" != e["crc32"]:
            raise ImageError(f"procedure {name}: CRC-32 of {e['file']} is {crc:08x}, "
                             f"the manifest says {e['crc32']} (corrupt file)")
        program = _load(name, kind, blob)
        if program.code_size != e["code_size"]:
            raise ImageError(f"procedure {name}: code is {program.code_size} bytes, "
                             f"the manifest says {e['code_size']}")
        procedures.append(ImageProcedure(name, kind, program.code_size, len(blob), crc,
                                         blob, program))
    if files:
        raise ImageError(f"file {sorted(files)[0]!r} in the image is not in the manifest")
    check = limits or built_for
    _check_limits([(p.name, p.kind, p.code_size) for p in procedures], check)
    procedures.sort(key=lambda p: p.name)
    return Image(check, built_for, tuple(procedures), fs.volume)
