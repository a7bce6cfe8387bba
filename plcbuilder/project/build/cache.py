"""The incremental build cache, ``build/.cache.json``: what the last Build All
compiled, from what, so the next one compiles only what changed.

The format (this is its one description). One JSON object, written as
``json.dumps(doc, sort_keys=True, separators=(",", ":"))`` plus a newline::

    {"version": 3,                        CACHE_VERSION
     "compiler": "<hex>",                 compiler_fingerprint(): its version and sources
     "procedures": {"<kind>/<name>": {    kind "hardware" or "software"
         "key": "<hex>",                  the procedure's key (below)
         "diagnostics": "<JSON text>",    its Diagnostic.to_dict() rows, as compact JSON
         "errors": int, "warnings": int,  how many of them are errors, warnings
         "shown": "<text>" | null,        those rows as the report shows them
         "check": int,                    CRC-32 of diagnostics, errors, warnings, shown
         "bin": "<name>.bin" | null,      the binary in build/ (null: it did not compile)
         "bin_stat": stat | null,         that binary's stat when it was written
         "crc32": int | null,             its CRC-32
         "size": int | null},             its code bytes
       ...},
     "files": {"<path>": [size, mtime_ns, inode, "<sha256>", ["<#include target>", ...],
                          trusted],       every source and header the keys read
       ...},
     "image": {"key": "<hex>", "stat": stat} | {}}    what build/eeprom.rom was made from

where a stat is ``[size, mtime_ns, inode]``. A file's ``trusted`` is false
when it was modified less than :data:`RACY_NS` (2 s) before the build that
recorded it: a same-size edit could then hide in the timestamp's resolution,
so such a file is read again however its stat looks; a trusted file whose stat
is unchanged is not read at all. Its #include targets are every ``#include``
line's (an over-approximation: commented or inactive ones count too, which
only costs a rebuild).

A procedure's **key** is a SHA-256 of length-prefixed parts: the cache
version, the compiler fingerprint, the kind, the compile options (strict,
target, size limit, include folders, root), the source's path, the working
folder (diagnostics name headers relative to it) and SHA-256; then, following
the #include targets breadth first and resolving each as the preprocessor
does (the including file's folder, the include folders, the built-in
headers), each target with the folder it is named from and the header found
(its path and SHA-256, a built-in header's SHA-256, or "missing"). A procedure
with more than 256 such targets, or one that cannot be read, has no key and is
not cached. The image's key is a SHA-256 of the image format's version, the
limits and every procedure's (name, kind, CRC, size).

A procedure whose key is unchanged and whose binary is still there, unchanged
(same stat, or else same CRC), is not compiled; its diagnostics are reported
from the cache. Its ``"shown"`` is what ``plcbuilder build`` printed for them
without colour (each ``render_text`` with the source lines, joined by
newlines; null when the compiler did not render them): the key covers every
file those lines come from, and the compiler fingerprint covers the renderer,
so it is printed as it is. The diagnostics stay text until something asks
for them (the IDE's Problems, a report in colour); an entry whose ``"check"``
does not match its text is compiled again, and text that does not decode to
diagnostics then gives one ``build-cache`` error in their place. An image
whose key and stat are unchanged is not made again. A cache of another version
or compiler is used only to remove the binaries it names; one larger than
:data:`MAX_CACHE_BYTES` or not a JSON object is ignored, as is any entry of
the wrong shape. The outputs are the same either way.

The file is read once at the start of a build and written at its end, only
when it changed, atomically and flushed to the disk. An entry compiled in this
build is held as its JSON text, zlib-compressed (:class:`RawJSON`), and
written out as it is; the document is written in chunks, never whole in
memory (:func:`_json_chunks`).
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import time
import zlib
from functools import lru_cache
from pathlib import Path
from typing import Iterator, Optional

import plcbuilder
from plcbuilder._support.files import atomic_write, read_bounded
from plcbuilder.bytecode.program import MAX_FILE_SIZE
from plcbuilder.image.manifest import VERSION as IMAGE_VERSION
from plcbuilder.image.manifest import Limits
from plcbuilder.lang.options import COMPILER_VERSION, CompileOptions
from plcbuilder.lang.builtin_headers import builtin_header
from plcbuilder.lang.source import MAX_SOURCE_BYTES
from plcbuilder.project.build.results import BIN_SUFFIX, ProcedureBuild, cached, dumps
from plcbuilder.project.model import Procedure

CACHE_FILE = ".cache.json"
MAX_CACHE_BYTES = 64 << 20      # a larger build/.cache.json is not ours: it is ignored
CACHE_VERSION = 3
#: A file modified less than this before a build is read again by the next one.
RACY_NS = 2_000_000_000
_MAX_DEPS = 256


@lru_cache(maxsize=1)
def compiler_fingerprint() -> str:
    """A hash of the compiler (its version and its own source files, and the
    diagnostics' renderer), so that a changed compiler never reuses a cached build."""
    h = hashlib.sha256()
    h.update(f"plcbuilder {plcbuilder.__version__} compiler {COMPILER_VERSION}".encode())
    pkg = Path(plcbuilder.__file__).parent
    # the renderer too: the cache keeps the diagnostics as rendered ("shown")
    try:
        h.update(b"diagnostics.py\0" + (pkg / "diagnostics.py").read_bytes() + b"\0")
    except OSError:
        pass
    for sub in ("lang", "bytecode"):
        folder = pkg / sub
        try:
            files = sorted(p for p in folder.iterdir() if p.suffix in (".py", ".lark"))
        except OSError:
            continue
        for p in files:
            try:
                h.update(p.name.encode() + b"\0" + p.read_bytes() + b"\0")
            except OSError:
                pass
    return h.hexdigest()


def image_key(procs: list[ProcedureBuild], limits: Limits) -> str:
    """What an image is made from: the format, the limits, each procedure's binary."""
    rows = sorted((p.name, p.kind.label, p.crc32, p.size) for p in procs)
    return hashlib.sha256(json.dumps([IMAGE_VERSION, limits.as_dict(), rows]).encode()).hexdigest()


class Cache:
    """build/.cache.json: read once at the start of a build, written at its end
    only when it changed; meanwhile it reads and hashes each source and header at
    most once (not at all when its stat is unchanged and trusted)."""

    def __init__(self, build_dir: Path, use: bool):
        self.build_dir = build_dir
        self.build_dir_name = str(build_dir)
        self.fingerprint = compiler_fingerprint()
        self.start_ns = time.time_ns()
        try:
            self.cwd = os.getcwd()      # diagnostics name headers relative to it
        except OSError:
            self.cwd = ""
        self.doc = _load(build_dir)
        procs = self.doc.get("procedures")
        procs = {k: v for k, v in procs.items() if isinstance(v, dict)} \
            if isinstance(procs, dict) else {}
        #: binaries the last build wrote, whatever compiler wrote them (to remove stale ones)
        self.old_bins = {e.get("bin") for e in procs.values() if isinstance(e.get("bin"), str)}
        current = use and self.doc.get("version") == CACHE_VERSION \
            and self.doc.get("compiler") == self.fingerprint
        self.old = procs if current else {}
        files, image = self.doc.get("files"), self.doc.get("image")
        self.old_files = files if current and isinstance(files, dict) else {}
        self.old_image = image if current and isinstance(image, dict) else {}
        self.procs: dict[str, dict] = {}
        self.files: dict[str, list] = {}
        self.image: dict = {}
        self.found: dict[tuple, Optional[str]] = {}    # include resolutions, this build
        self.include_parts: dict[tuple, Optional[bytes]] = {}   # see _includes
        self.fixed: dict[tuple, tuple] = {}     # (kind, options) -> a key's fixed parts

    # ------------------------------------------------------------ files
    def info(self, path: Path) -> Optional[tuple[str, list]]:
        """(SHA-256, #include targets) of a file; None when it cannot be read."""
        name = str(path)
        rec = self.files.get(name)
        if rec is not None:
            return rec[3], rec[4]
        stat = _stat(name)
        if stat is None:
            return None
        old = self.old_files.get(name)
        if (isinstance(old, list) and len(old) == 6 and old[:3] == stat and old[5] is True
                and isinstance(old[3], str) and isinstance(old[4], list)):
            self.files[name] = old
            return old[3], old[4]
        try:
            data = read_bounded(path, MAX_SOURCE_BYTES)
        except OSError:
            return None
        trusted = stat[1] <= self.start_ns - RACY_NS
        rec = [stat[0], stat[1], stat[2], hashlib.sha256(data).hexdigest(),
               _include_targets(data.decode("utf-8", "replace")), trusted]
        self.files[name] = rec
        return rec[3], rec[4]

    def source_hash(self, proc: Procedure) -> Optional[str]:
        """The SHA-256 of the source as its key saw it (the compiler reads the
        file again, and a build that compiled other bytes does not cache them)."""
        rec = self.files.get(str(proc.path))
        return rec[3] if rec is not None else None

    def _resolve(self, target: str, folder: Optional[str], dirs: tuple[str, ...]) -> Optional[str]:
        """The header #include target names from folder (None: a built-in one)."""
        memo = (target, folder, dirs)
        found = self.found.get(memo, self)
        if found is self:
            path = next((p for p in (Path(d) / target for d in
                                     ((folder,) if folder is not None else ()) + dirs)
                         if p.is_file()), None)
            found = self.found[memo] = str(path) if path is not None else None
        return found

    def key(self, proc: Procedure, options: CompileOptions) -> Optional[str]:
        """The SHA-256 that decides whether a cached build is still good, or None
        when the sources cannot be read (then the compiler reports why)."""
        source = self.info(proc.path)
        if source is None:
            return None
        fixed = self.fixed.get((proc.kind, id(options)))
        if fixed is None or fixed[0] is not options:   # the parts the same for a folder
            dirs = tuple(str(Path(d)) for d in options.include_dirs)
            fixed = self.fixed[(proc.kind, id(options))] = (
                options, dirs,
                _framed((CACHE_VERSION, self.fingerprint, proc.kind.label, options.strict,
                         options.target, options.limit)),
                _framed((self.cwd,)), _framed((str(options.root), len(dirs)) + dirs))
        _options, dirs, head, cwd, tail = fixed
        path = str(proc.path)
        includes = self._includes(tuple(source[1]), os.path.dirname(path), dirs)
        if includes is None:
            return None
        return hashlib.sha256(b"".join((head, _framed((path,)), cwd,
                                        _framed((source[0],)), tail, includes))).hexdigest()

    def _includes(self, targets: tuple[str, ...], folder: str,
                  dirs: tuple[str, ...]) -> Optional[bytes]:
        """The part of a key that follows a source's #include targets (named
        from ``folder``), framed as _framed frames it; None when a header
        cannot be read or there are too many. Resolved as the preprocessor
        does: the including file's folder, then the include folders, then the
        built-in headers. The same targets from the same folder give the same
        part within a build (its files are read at most once), so it is made
        once a build, not once a procedure."""
        memo = (targets, folder, dirs)
        if memo in self.include_parts:
            return self.include_parts[memo]
        parts: list = []
        todo = [(t, folder) for t in targets]
        seen: set[tuple[str, Optional[str]]] = set()
        done: Optional[bytes] = None
        while todo:
            target, where = todo.pop(0)
            if (target, where) in seen:
                continue
            seen.add((target, where))
            if len(seen) > _MAX_DEPS:
                break
            parts += ("include", target, str(where))
            found = self._resolve(target, where, dirs)
            if found is not None:
                header = self.info(Path(found))
                if header is None:
                    break
                parts += ("file", found, header[0])
                todo.extend((t, str(Path(found).parent)) for t in header[1])
                continue
            builtin = _builtin_info(target)
            if builtin is not None:
                parts += ("builtin", builtin[0])
                todo.extend((t, None) for t in builtin[1])
            else:
                parts.append("missing")
        else:
            done = _framed(parts)
        self.include_parts[memo] = done
        return done

    # ------------------------------------------------------- procedures
    def lookup(self, proc: Procedure, options: CompileOptions,
               key: str) -> Optional[ProcedureBuild]:
        """The procedure as the last build left it, if its key and binary still hold."""
        cache_id = f"{proc.kind.label}/{proc.name}"
        entry = self.old.get(cache_id)
        if not entry or entry.get("key") != key:
            return None
        try:
            rows, errors, warnings = entry["diagnostics"], entry["errors"], entry["warnings"]
            shown = entry["shown"]
            if type(rows) is not str or type(errors) is not int or type(warnings) is not int \
                    or not (shown is None or type(shown) is str) \
                    or entry["check"] != _check(rows, errors, warnings, shown):
                return None
            size, crc = entry.get("size"), entry.get("crc32")
            path = None
            if entry.get("bin"):
                if entry["bin"] != proc.name + BIN_SUFFIX or type(size) is not int \
                        or type(crc) is not int:
                    return None
                path = os.path.join(self.build_dir_name, entry["bin"])
                stat = _stat(path)
                if stat is None:
                    return None
                if stat != entry.get("bin_stat"):      # touched since: check its bytes
                    try:
                        data = read_bounded(path, MAX_FILE_SIZE, "compiled procedure")
                    except OSError:
                        return None
                    if zlib.crc32(data) != crc:
                        return None
                    del data
                    entry = dict(entry, bin_stat=stat)
            elif errors:
                size = crc = None
            else:
                return None
        except (OSError, KeyError, TypeError, ValueError):
            return None
        self.procs[cache_id] = entry
        # only name, size and CRC are kept: the bytes are read from build/ when needed
        return ProcedureBuild(proc, cached(rows, errors, warnings), size, options.limit, crc,
                              True, None, None, path, shown=shown)

    def compiled(self, pb: ProcedureBuild, key: Optional[str], rows_json: str) -> None:
        """A procedure compiled now: write its binary and remember it. Once
        written, the ProcedureBuild keeps only its name, size and CRC: the bytes
        are read again from build/ when needed, so a large project's binaries
        are never all in memory."""
        path = self.build_dir / pb.bin_name
        binary = pb.binary if pb.ok else None
        if binary is not None:
            _write_if_changed(path, binary, sync=False)
            pb.written_to(path)
        if key is None:
            return
        # kept as its JSON text (written out as it is), the diagnostics as the
        # compiler's JSON text (``rows_json``), a string in it: never decoded here
        shown = pb.shown_if_rendered()
        self.procs[f"{pb.kind.label}/{pb.name}"] = RawJSON.packed(dumps({
            "bin": pb.bin_name if binary is not None else None,
            "bin_stat": _stat(path) if binary is not None else None,
            "check": _check(rows_json, pb.errors, pb.warnings, shown),
            "crc32": pb.crc32 if binary is not None else None,
            "diagnostics": rows_json, "errors": pb.errors, "key": key, "shown": shown,
            "size": pb.size, "warnings": pb.warnings}))

    # ------------------------------------------------------------ image
    def unchanged_image(self, path: Path, key: str) -> Optional[int]:
        """The image's size when it is the one made from these binaries and
        limits and is still there, unchanged; None otherwise."""
        stat = _stat(path)
        if stat is not None and self.old_image.get("key") == key \
                and self.old_image.get("stat") == stat:
            self.image = self.old_image
            return stat[0]
        return None

    def image_written(self, path: Path, key: str) -> None:
        stat = _stat(path)
        self.image = {"key": key, "stat": stat} if stat is not None else {}

    def save(self) -> None:
        doc = {"version": CACHE_VERSION, "compiler": self.fingerprint,
               "procedures": dict(sorted(self.procs.items())),
               "files": dict(sorted(self.files.items())), "image": self.image}
        if doc == self.doc:
            return
        try:
            atomic_write(self.build_dir / CACHE_FILE, _json_chunks(doc), unless_same=True)
        except OSError:
            pass   # a cache that cannot be written only costs time next build


class RawJSON(bytes):
    """A value of the cache's tables already as its JSON text, zlib-compressed
    until it is written out (see _json_chunks)."""

    @classmethod
    def packed(cls, text: str) -> "RawJSON":
        return cls(zlib.compress(text.encode("utf-8"), 1))

    def text(self) -> str:
        return zlib.decompress(self).decode("utf-8")


def _json_chunks(doc: dict, big: tuple = ("files", "procedures")) -> Iterator[bytes]:
    """json.dumps(doc, sort_keys=True, compact) + newline, byte for byte, as
    chunks of about 64 KiB: the two large tables are encoded an entry at a time,
    so the whole text is never in memory; an entry that is a RawJSON is its
    own text."""
    def text(value) -> str:
        return value.text() if isinstance(value, RawJSON) else dumps(value)

    def pieces() -> Iterator[str]:
        yield "{"
        for n, k in enumerate(sorted(doc)):
            yield ("," if n else "") + text(k) + ":"
            if k in big and isinstance(doc[k], dict):
                yield "{"
                for m, sub in enumerate(sorted(doc[k])):
                    yield ("," if m else "") + text(sub) + ":" + text(doc[k][sub])
                yield "}"
            else:
                yield text(doc[k])
        yield "}\n"

    batch: list[str] = []
    held = 0
    for piece in pieces():
        batch.append(piece)
        held += len(piece)
        if held >= 1 << 16:
            yield "".join(batch).encode("utf-8")
            batch, held = [], 0
    yield "".join(batch).encode("utf-8")


def built_from(build_dir: Path, image_path: Path) -> Optional[dict[str, str]]:
    """{path: SHA-256} of each source and header the image at ``image_path``
    was made from, as the last Build All read them; None when the cache does
    not describe that image (no cache, another compiler, the image not written
    by the build that wrote the cache, or changed since). The IDE compares
    content with it to tell whether a source changed since the last Build All
    (a save that only touched the file's time does not count)."""
    doc = _load(build_dir)
    image, files = doc.get("image"), doc.get("files")
    if doc.get("version") != CACHE_VERSION or not isinstance(image, dict) \
            or not isinstance(files, dict):
        return None
    stat = _stat(image_path)
    if stat is None or image.get("stat") != stat:
        return None
    return {name: rec[3] for name, rec in files.items()
            if isinstance(rec, list) and len(rec) == 6 and isinstance(rec[3], str)}


def _load(build_dir: Path) -> dict:
    try:
        doc = json.loads(read_bounded(build_dir / CACHE_FILE, MAX_CACHE_BYTES).decode("utf-8"))
    except (OSError, ValueError, RecursionError):
        return {}
    return doc if isinstance(doc, dict) else {}


_INCLUDE_RE = re.compile(r"^[ \t]*#[ \t]*include\b(.*)$", re.MULTILINE)


def _include_targets(text: str) -> list[str]:
    """Every #include target named in text (an over-approximation: includes in
    comments or inactive #ifdef branches count too, which only costs a rebuild)."""
    out = []
    for m in _INCLUDE_RE.finditer(text):
        arg = re.sub(r"//.*|/\*.*?\*/", "", m.group(1)).strip()
        mm = re.fullmatch(r'"([^"]+)"|<([^>]+)>|([^\s"<>]+)', arg)
        if mm:
            out.append(next(g for g in mm.groups() if g))
    return out


def _check(rows_json: str, errors: int, warnings: int, shown: Optional[str]) -> int:
    """The CRC-32 an entry's ``"check"`` holds: of its diagnostics' text,
    their counts and ``shown`` (a damaged entry is compiled again)."""
    crc = zlib.crc32(f"{errors},{warnings},{shown is None:d}:".encode())
    crc = zlib.crc32(rows_json.encode("utf-8", "surrogatepass"), crc)
    return zlib.crc32((shown or "").encode("utf-8", "surrogatepass"), crc)


def _framed(parts) -> bytes:
    """Each part as its UTF-8 bytes (a str of it) after their length, 8 bytes
    little-endian: the text a key's SHA-256 is taken of."""
    out = []
    for part in parts:
        b = part if type(part) is bytes else str(part).encode("utf-8", "surrogatepass")
        out += (len(b).to_bytes(8, "little"), b)
    return b"".join(out)


def _stat(path) -> Optional[list]:
    """What tells a file changed without reading it: [size, mtime_ns, inode]."""
    try:
        st = os.stat(path)
    except OSError:
        return None
    return [st.st_size, st.st_mtime_ns, st.st_ino]


@lru_cache(maxsize=None)
def _builtin_info(target: str) -> Optional[tuple[str, tuple[str, ...]]]:
    text = builtin_header(target)
    if text is None:
        return None
    return hashlib.sha256(text.encode("utf-8")).hexdigest(), tuple(_include_targets(text))


def _write_if_changed(path: Path, data: bytes, sync: bool = True) -> bool:
    """Write data atomically unless path already holds it; whether it wrote."""
    try:
        if read_bounded(path, len(data)) == data:
            return False
    except OSError:       # missing, different, or not a regular file (atomic_write says so)
        pass
    atomic_write(path, data, sync=sync)
    return True
