"""Build All: compile every procedure of a project, write build/ and the image.

    compile_all(project) -> [ProcedureBuild]     compile, write nothing (also ``run``'s)
    build_project(project, progress) -> BuildResult

1. Every ``hardware/*.plc`` and ``software/*.plc`` is compiled (going on past
   errors) as :meth:`Project.compile_options` says: the project's include folder
   and size limits; each procedure's diagnostics and size against its limit are
   in the result (:func:`compile_all`).
2. Each procedure that compiles is written to ``build/NAME.bin``; the binary of
   a procedure that no longer compiles (or no longer exists) is removed, so
   ``build/`` never holds a stale binary.
3. The hardware procedures' total is checked against its limit (8 KiB).
4. Only when there is no error at all is ``build/eeprom.rom`` written (a ROMFS
   image with a manifest, see plcbuilder.image); otherwise the previous image
   is kept, and the result says so.

A folder that is not a project (no plcbuilder.toml, hardware/ or software/:
:func:`~plcbuilder.project.model.not_a_project`) is not built: the result is
that one error, and nothing is written there (no build/, no image).

Every file is written atomically, and only when its contents change. The image
and the cache are flushed to the disk before they replace the old ones; the
binaries are not (one a power cut loses fails its CRC check at the next build
and is compiled again). A build holds ``build/.lock`` while it runs, so two
builds never interleave, and first removes the temporary files a killed build
left in ``build/`` (only those named as atomic_write names them). The same
sources give byte-identical outputs.

Compiling uses every core: when at least :data:`PARALLEL_MIN` procedures need
compiling and the machine has more than one core, worker processes compile
them (forked from this process when it runs a single thread, from a fork server
otherwise); fewer are compiled here, one after another. The results are the
same either way, in the same order. Each result keeps only what the report and
the IDE need: the diagnostics (with the source lines they point at, packed as
compressed JSON until asked for), the code size and the binary's CRC (its bytes
are read back from build/). The compiler reads each source it compiles itself,
so a build never holds the project's sources; one whose bytes changed after
its key was made is not cached.

Incremental builds: ``build/.cache.json`` remembers, per procedure, a key (a
SHA-256 of the source, of every header it may include as the search order
resolves it, of the compile options and of the compiler itself) with the
diagnostics, the CRC and the stat of the binary; per source and header file,
its stat (size, modification time, inode), SHA-256 and #include targets; and
what the image was made from. A file whose stat is unchanged is not read again
(unless it was modified less than 2 s before the build that recorded it: a
same-size edit could then hide in the timestamp's resolution). A procedure
whose key is unchanged and whose binary is still there, unchanged, is not
recompiled, and its warnings are reported again from the cache; an image made
from the same binaries and limits that is still there, unchanged, is not made
again. The outputs are the same either way.
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import threading
import time
import zlib
from contextlib import contextmanager
from functools import lru_cache
from pathlib import Path
from typing import Callable, Iterator, Optional

import plcbuilder
from plcbuilder.bytecode.program import MAX_FILE_SIZE, Kind, Program
from plcbuilder.lang import Diagnostic, Related, Severity, Span, error
from plcbuilder.image.manifest import VERSION as IMAGE_VERSION
from plcbuilder.image.manifest import ImageError, Limits, iter_image, valid_name
from plcbuilder.lang import pipeline as _compiler
from plcbuilder.lang.pipeline import CompileOptions, compile_file, compile_source
from plcbuilder.lang.source import MAX_SOURCE_BYTES
from plcbuilder.lang.builtin_headers import source_text
from plcbuilder.lang.preprocess import builtin_header
from plcbuilder._support.files import atomic_write, read_bounded, remove_temp_files
from plcbuilder._support.records import dataclass
from plcbuilder.project.model import Procedure, Project, not_a_project

try:
    import fcntl
except ImportError:          # Windows
    fcntl = None
try:
    import msvcrt
except ImportError:          # everything but Windows
    msvcrt = None

CACHE_FILE = ".cache.json"
LOCK_FILE = ".lock"
MAX_CACHE_BYTES = 64 << 20      # a larger build/.cache.json is not ours: it is ignored
CACHE_VERSION = 2
BIN_SUFFIX = ".bin"
#: Fewer procedures to compile than this: compiled in this process, one after another.
PARALLEL_MIN = 48
MAX_WORKERS = 8
#: A file modified less than this before a build is read again by the next one.
RACY_NS = 2_000_000_000

#: progress(done, total, name): called after each procedure is compiled (or found
#: unchanged); first with done=0 before any work.
Progress = Callable[[int, int, str], None]


# ------------------------------------------------------------------ results

class ProcedureBuild:
    """One procedure's outcome. Its diagnostics (with the source lines they point
    at) are held packed, as zlib-compressed JSON, and decoded when asked for:
    a large project's report holds a few hundred bytes a procedure, not the
    objects (docs/projects.md, "Build All")."""

    __slots__ = ("procedure", "size", "limit", "crc32", "cached", "errors", "warnings",
                 "_packed", "_binary", "_bin_path")

    def __init__(self, procedure: Procedure, diagnostics, size: Optional[int], limit: int,
                 crc32: Optional[int] = None, cached: bool = False, lines: Optional[dict] = None,
                 binary: Optional[bytes] = None, bin_path: Optional[Path] = None):
        self.procedure = procedure
        self.size = size                    # code bytes, None when it did not compile
        self.limit = limit
        self.crc32 = crc32                  # of the binary, None when it did not compile
        self.cached = cached                # reused from build/.cache.json
        self._binary = binary
        self._bin_path = bin_path           # a binary written to (or reused from) build/
        if isinstance(diagnostics, _Packed):
            self._packed, self.errors, self.warnings = diagnostics
        else:
            rows = [_diag_to_json(d) for d in diagnostics]
            self._packed, self.errors, self.warnings = _pack(_dumps(rows), *_counts(rows), lines)

    @property
    def diagnostics(self) -> list[Diagnostic]:
        return [_diag_from_json(d) for d in _unpack(self._packed)[0]]

    @property
    def lines(self) -> dict:
        """(file, line) -> text of the source lines the diagnostics point at."""
        return {(f, n): text for f, n, text in _unpack(self._packed)[1]}

    def diagnostics_json(self) -> str:
        """The diagnostics as the cache stores them (compact JSON text)."""
        return _dumps(_unpack(self._packed)[0])

    def __repr__(self) -> str:
        return (f"ProcedureBuild({self.name!r}, size={self.size}, limit={self.limit}, "
                f"errors={self.errors}, warnings={self.warnings}, cached={self.cached})")

    @property
    def name(self) -> str:
        return self.procedure.name

    @property
    def kind(self) -> Kind:
        return self.procedure.kind

    @property
    def path(self) -> Path:
        return self.procedure.path

    @property
    def ok(self) -> bool:
        return self.crc32 is not None and not self.errors

    @property
    def bin_name(self) -> str:
        return self.name + BIN_SUFFIX

    @property
    def binary(self) -> Optional[bytes]:
        """The compiled procedure's bytes; one reused from the cache is read from
        build/ (None if it is no longer there as it was built)."""
        if self._binary is not None or self._bin_path is None:
            return self._binary
        try:
            data = read_bounded(self._bin_path, MAX_FILE_SIZE, "compiled procedure")
        except OSError:
            return None
        return data if zlib.crc32(data) == self.crc32 else None

    def program(self) -> Optional[Program]:
        """The compiled procedure, as the controller loads it (None if it did not compile)."""
        data = self.binary if self.ok else None
        return Program.from_bytes(data) if data is not None else None

    def source_line(self, file: str, line: int) -> Optional[str]:
        """A source line for diagnostics.render_text. (A report asks for one
        line a diagnostic, procedure after procedure: the lines kept with the
        last procedure's diagnostics and the last file read are remembered,
        the file while it is unchanged on disk; an unchanged rebuild of the
        benchmark project read a thousand files 7,300 times.)"""
        global _kept_lines
        packed, kept = _kept_lines
        if packed is not self._packed:
            kept = self.lines
            _kept_lines = (self._packed, kept)
        text = kept.get((file, line))
        return text if text is not None else _disk_line(file, line)


#: (the packed diagnostics, their lines) of the procedure source_line last served
_kept_lines: tuple = (None, {})
#: (file, its size and time stamps, its lines) of the file _disk_line last read
_last_file: tuple = (None, None, None)


class _Packed(tuple):
    """(packed, errors, warnings): diagnostics already packed (by _pack), or the
    rows of the cache file as it was read (:func:`_cached`: that document is in
    memory for the build anyway, so they are shared, not packed again)."""


def _pack(rows_json: str, errors: int, warnings: int, lines=None) -> _Packed:
    """Diagnostics as the JSON text of their ``_diag_to_json`` rows, their
    counts, and the source lines they point at ({(file, line): text} or
    [[file, line, text]]), packed for a ProcedureBuild."""
    if rows_json == "[]":
        return _Packed((b"", 0, 0))
    if isinstance(lines, dict):
        lines = [[f, n, text] for (f, n), text in lines.items()]
    text = '{"d":' + rows_json + ',"l":' + _dumps(lines or []) + "}"
    return _Packed((zlib.compress(text.encode("utf-8"), 1), errors, warnings))


def _cached(rows: list) -> _Packed:
    """Diagnostics rows as the cache file holds them (checked by the caller)."""
    return _Packed((rows if rows else b"", *_counts(rows)))


def _counts(rows: list) -> tuple[int, int]:
    return (sum(1 for r in rows if r["severity"] == Severity.ERROR),
            sum(1 for r in rows if r["severity"] == Severity.WARNING))


def _unpack(packed) -> tuple[list, list]:
    if isinstance(packed, list):                 # a cached procedure's rows (_cached)
        return packed, []
    if not packed:
        return [], []
    doc = json.loads(zlib.decompress(packed))
    return doc["d"], doc["l"]


@dataclass
class BuildResult:
    project: Project
    procedures: list[ProcedureBuild]
    diagnostics: list[Diagnostic]       # the project's own (hardware total, names, image)
    limits: Limits
    hw_total: int                       # code bytes of the hardware procedures that compiled
    image_path: Path
    image_written: bool = False
    image_size: Optional[int] = None
    image_message: str = ""
    compiled: int = 0                   # procedures compiled this time
    reused: int = 0                     # procedures taken from the cache

    @property
    def all_diagnostics(self) -> list[Diagnostic]:
        out = [d for p in self.procedures for d in p.diagnostics]
        return out + list(self.diagnostics)

    @property
    def error_count(self) -> int:
        return sum(p.errors for p in self.procedures) + \
            sum(1 for d in self.diagnostics if d.is_error)

    @property
    def warning_count(self) -> int:
        return sum(p.warnings for p in self.procedures) + \
            sum(1 for d in self.diagnostics if d.severity == Severity.WARNING)

    @property
    def ok(self) -> bool:
        return self.error_count == 0

    def get(self, name: str) -> Optional[ProcedureBuild]:
        for p in self.procedures:
            if p.name == name:
                return p
        return None

    def source_line(self, file: str, line: int) -> Optional[str]:
        """A source line for the project's own diagnostics: as the procedure of
        that file kept it, or from the disk."""
        for p in self.procedures:
            if str(p.path) == file and (p.errors or p.warnings):
                text = p.lines.get((file, line))
                if text is not None:
                    return text
        return _disk_line(file, line)


# -------------------------------------------------------------- build all

def compile_all(project: Project, progress: Optional[Progress] = None, *,
                strict: Optional[bool] = None, extra_includes: tuple = (),
                jobs: Optional[int] = None) -> list[ProcedureBuild]:
    """Compile every procedure of the project, going on past errors; writes
    nothing. A name that cannot be a procedure's, or that two files share, is an
    error of that procedure. ``jobs``: worker processes (None: as many as cores
    when there is enough to compile; 1: none)."""
    return _procedure_builds(project, progress, strict, extra_includes, jobs, None)


def build_project(project: Project, progress: Optional[Progress] = None, *,
                  strict: Optional[bool] = None, use_cache: bool = True,
                  jobs: Optional[int] = None) -> BuildResult:
    """Build All (see the module docstring); ``strict`` None: as the project's
    settings say; ``jobs`` as :func:`compile_all`'s. Never raises for problems in
    the sources; an unwritable build folder raises OSError."""
    build_dir = project.build_dir
    why = not_a_project(project.root)
    if why is not None:              # write nothing: not even build/
        result = BuildResult(project, [], [error("not-a-project", f"{project.root}: {why}",
                                                 None)],
                             project.limits, 0, project.image_path)
        result.image_message = f"{project.image_path} not written: {project.root} is not a project"
        return result
    outside = _build_dir_problem(project)
    if outside is not None:          # write nothing there: compile, report, keep the image
        result = BuildResult(project, compile_all(project, progress, strict=strict, jobs=jobs),
                             [outside], project.limits, 0, project.image_path)
        result.compiled = sum(1 for p in result.procedures if not _is_name_problem(p))
        result.image_message = (f"{project.image_path} not written: {build_dir} is outside "
                                "the project")
        return result
    build_dir.mkdir(parents=True, exist_ok=True)
    with _locked(build_dir / LOCK_FILE):
        remove_temp_files(build_dir)
        return _build(project, progress, strict, use_cache, jobs)


def _build(project: Project, progress: Optional[Progress], strict: Optional[bool],
           use_cache: bool, jobs: Optional[int]) -> BuildResult:
    limits = project.limits
    build_dir = project.build_dir
    cache = _Cache(build_dir, use_cache)
    result = BuildResult(project, [], [], limits, 0, project.image_path)
    result.procedures = _procedure_builds(project, progress, strict, (), jobs, cache)
    result.reused = sum(1 for p in result.procedures if p.cached)
    result.compiled = sum(1 for p in result.procedures
                          if not p.cached and not _is_name_problem(p))

    # binaries: those compiled are written already; remove what no longer compiles
    good = {p.bin_name for p in result.procedures if p.ok}
    stale = cache.old_bins | {p.bin_name for p in result.procedures}
    for name in sorted(n for n in stale if n and n not in good and _safe_bin_name(n)):
        try:
            (build_dir / name).unlink()
        except FileNotFoundError:
            pass

    hw = [(p.size, p.name) for p in result.procedures if p.ok and p.kind is Kind.HARDWARE]
    result.hw_total = sum(s for s, _ in hw)
    if result.hw_total > limits.hw_total:
        biggest = ", ".join(f"{n} {s}" for s, n in sorted(hw, key=lambda x: (-x[0], x[1]))[:5])
        result.diagnostics.append(error(
            "size-limit",
            f"hardware procedures together are {result.hw_total} bytes of code; the limit is "
            f"{limits.hw_total} ({result.hw_total}/{limits.hw_total} bytes; largest: {biggest})",
            None, "move work into software procedures, or remove procedures you do not use"))

    if result.ok:
        _write_the_image(result, cache)
    if not result.image_written:
        n = result.error_count
        keep = (f"the previous {project.image_path.name} is kept"
                if project.image_path.exists() else f"there is no {project.image_path.name} yet")
        result.image_message = (f"{project.image_path} not written: {n} error{'s' * (n != 1)}; "
                                f"{keep}")
    cache.save()
    return result


def _write_the_image(result: BuildResult, cache: "_Cache") -> None:
    """Write build/eeprom.rom unless it holds these binaries already."""
    path, limits = result.image_path, result.limits
    key = _image_key(result.procedures, limits)
    changed = False
    size = cache.unchanged_image(path, key)
    if size is None:
        # streamed: each binary is read from build/ to check it, then again as
        # the image is written; neither the binaries nor the image are kept whole
        programs = [(p.name, p.kind, _reader(p)) for p in result.procedures]
        # compiled in this build: the binaries are this compiler's output, not
        # decoded again (a tenth of a cold Build All); a cached one is checked
        checked = {p.name: (p.kind, p.crc32, p.size) for p in result.procedures
                   if not p.cached and p.crc32 is not None and p.size is not None}
        try:
            changed = atomic_write(path, iter_image(programs, limits, checked),
                                   unless_same=True)
            size = path.stat().st_size
        except _Lost as lost:
            result.diagnostics.append(error(
                "image", f"cannot make the image: build/{lost}{BIN_SUFFIX} changed during "
                "the build", None, "build again"))
            return
        except ImageError as exc:
            result.diagnostics.append(error("image", f"cannot make the image: {exc}", None))
            return
        cache.image_written(path, key)
    result.image_written = True
    result.image_size = size
    n = len(result.procedures)
    result.image_message = (f"{'wrote' if changed else 'up to date:'} {path} "
                            f"({size} bytes, {n} procedure{'s' * (n != 1)})")


class _Lost(Exception):
    """A binary no longer in build/ as it was built (its procedure's name)."""


def _reader(pb: ProcedureBuild) -> Callable[[], bytes]:
    def read() -> bytes:
        data = pb.binary
        if data is None:
            raise _Lost(pb.name)
        return data
    return read


def _image_key(procs: list[ProcedureBuild], limits: Limits) -> str:
    rows = sorted((p.name, p.kind.label, p.crc32, p.size) for p in procs)
    return hashlib.sha256(json.dumps([IMAGE_VERSION, limits.as_dict(), rows]).encode()).hexdigest()


def _procedure_builds(project: Project, progress: Optional[Progress], strict: Optional[bool],
                      extra_includes: tuple, jobs: Optional[int],
                      cache: Optional["_Cache"]) -> list[ProcedureBuild]:
    """Every procedure's ProcedureBuild, in the project's order: from the cache
    when it has it, compiled (in worker processes when there are many) otherwise."""
    procs = project.procedures()
    total = len(procs)
    out: list[Optional[ProcedureBuild]] = [None] * total
    by_name: dict[str, Procedure] = {}
    options_for: dict[Path, CompileOptions] = {}
    pending: list[tuple[int, CompileOptions, Optional[str]]] = []   # (index, options, key)
    done = 0

    def finished(i: int, pb: ProcedureBuild) -> None:
        nonlocal done
        out[i] = pb
        done += 1
        if progress:
            progress(done, total, pb.name)

    if progress:
        progress(0, total, "")
    root = _real(project.root)          # resolved once, not once a procedure
    for i, proc in enumerate(procs):
        folder = proc.path.parent
        if folder not in options_for:
            options_for[folder] = project.compile_options(proc.path, strict=strict,
                                                          extra_includes=extra_includes)
        options = options_for[folder]
        problem = (_outside_problem(proc, root) or _name_problem(proc, by_name)
                   or _target_problem(project, proc, procs))
        by_name.setdefault(proc.name, proc)
        if problem is not None:
            finished(i, ProcedureBuild(proc, [problem], None, options.limit))
            continue
        key = cache.key(proc, options) if cache is not None else None
        reused = cache.lookup(proc, options, key) if key is not None else None
        if reused is not None:
            finished(i, reused)
        else:
            pending.append((i, options, key))

    def compiled(k: int, outcome: tuple) -> None:
        i, options, key = pending[k]
        rows_json, errors, warnings, lines, size, binary, read = outcome
        if read != work[k][2]:
            key = None           # the source changed after its key was made: not cached
        pb = ProcedureBuild(procs[i], _pack(rows_json, errors, warnings, lines), size,
                            options.limit, zlib.crc32(binary) if binary is not None else None,
                            False, None, binary)
        if cache is not None:
            cache.compiled(pb, key, rows_json)
        finished(i, pb)

    work = [(str(procs[i].path), options, cache.source_hash(procs[i]) if cache else None)
            for i, options, _key in pending]
    _compile_many(work, compiled, jobs)
    return out   # type: ignore[return-value]  - every slot is filled


# ------------------------------------------------------------ compiling

def _compile_job(job: tuple[str, CompileOptions, Optional[str]]) -> tuple:
    """Compile one procedure (in a worker process or here): (the diagnostics'
    JSON text, errors, warnings, the source lines they point at, size, binary,
    the SHA-256 of the source compiled), small, flat and picklable: the parent
    builds no objects from it. The source is read here, so the parent never
    holds a project's sources."""
    path, options, _hash = job
    try:
        data = read_bounded(path, MAX_SOURCE_BYTES)
    except OSError:
        data = None                     # the compiler reads it and says why not
    read = hashlib.sha256(data).hexdigest() if data is not None else None
    try:
        r = compile_file(path, options, data=data)
    except Exception as exc:  # noqa: BLE001 - one procedure must not stop Build All
        diag = error("internal", f"internal compiler error: {type(exc).__name__}: {exc}",
                     Span.point(path, 1, 1))
        rows = [_diag_to_json(diag)]
        return _dumps(rows), 1, 0, [], None, None, read
    binary = r.program.to_bytes() if r.ok and r.program is not None else None
    lines: dict = {}
    for d in r.diagnostics:
        if d.span is not None and (d.span.file, d.span.line) not in lines:
            text = r.source_line(d.span.file, d.span.line)
            if text is not None:
                lines[(d.span.file, d.span.line)] = text
    rows = [_diag_to_json(d) for d in r.diagnostics]
    return (_dumps(rows), *_counts(rows), [[f, n, t] for (f, n), t in lines.items()],
            (r.size if binary is not None else None), binary, read)


def _warm() -> None:
    """A worker's start: build the parser (a forked worker has it already)."""
    compile_source("main() { exit(99); };\n")


def _cores() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        return os.cpu_count() or 1


def _compile_many(work: list, done: Callable[[int, tuple], None], jobs: Optional[int]) -> None:
    """Compile every job, calling done(index, outcome) in order. With several
    workers the first job is compiled here (a forked worker then inherits the
    parser) and the rest by the pool; if the pool cannot start or breaks, the
    rest is compiled here."""
    if jobs is None:
        jobs = min(_cores(), MAX_WORKERS) if len(work) >= PARALLEL_MIN else 1
    jobs = max(1, min(jobs, len(work) - 1))
    k = 0
    if jobs > 1:
        done(0, _compile_job(work[0]))
        k = 1
        for outcome in _in_workers(work[1:], jobs):
            done(k, outcome)
            k += 1
    for k in range(k, len(work)):
        done(k, _compile_job(work[k]))


def _in_workers(work: list, jobs: int) -> Iterator[tuple]:
    """The outcomes of work in order, from a pool of worker processes, for as
    long as the pool works (the caller compiles what is left)."""
    import multiprocessing              # (an unchanged rebuild starts no worker: not loaded)
    from concurrent.futures import ProcessPoolExecutor
    from concurrent.futures.process import BrokenProcessPool
    methods = multiprocessing.get_all_start_methods()
    if "fork" in methods and threading.active_count() == 1:
        ctx = multiprocessing.get_context("fork")    # inherits everything loaded here
    elif "forkserver" in methods:                    # forking a threaded process is unsafe
        ctx = multiprocessing.get_context("forkserver")
        ctx.set_forkserver_preload([__name__])
    else:
        ctx = multiprocessing.get_context("spawn")
    chunk = max(1, min(16, len(work) // (jobs * 8)))
    try:
        pool = ProcessPoolExecutor(jobs, mp_context=ctx, initializer=_warm)
    except (OSError, ValueError, NotImplementedError):
        return
    try:
        outcomes = pool.map(_compile_job, work, chunksize=chunk)
        while True:
            try:
                outcome = next(outcomes)
            except (StopIteration, BrokenProcessPool, OSError):
                return
            yield outcome
    finally:
        pool.shutdown(wait=True, cancel_futures=True)


# ------------------------------------------------------------ build folder

@contextmanager
def _locked(path: Path) -> Iterator[None]:
    """Hold an exclusive lock on path (created if missing) while the block runs."""
    fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o666)
    try:
        if fcntl is not None:
            fcntl.flock(fd, fcntl.LOCK_EX)
        elif msvcrt is not None:
            msvcrt.locking(fd, msvcrt.LK_LOCK, 1)
        yield
    finally:
        os.close(fd)       # releases the lock


def _real(p: Path) -> Path:
    try:
        return p.resolve()
    except (OSError, RuntimeError):     # a link loop
        return p.absolute()


@lru_cache(maxsize=64)
def _real_folder(folder: Path, root: Path, stamp) -> Path:
    """A folder's real path (``root``, the project's, and ``stamp``, the
    folder's identity, in the key: either changed, it is resolved again)."""
    return _real(folder)


def _outside_problem(proc: Procedure, root: Path) -> Optional[Diagnostic]:
    """A source file that is a link out of the project: an error, and it is not
    read (its lines would be echoed in diagnostics)."""
    path = proc.path
    try:
        # a file that is no link lies where its folder really is: one lstat,
        # not a walk of every folder of its path (a thousand procedures)
        folder = path.parent
        st = os.lstat(folder)
        if os.path.islink(path) or os.path.islink(folder):
            raise OSError
        real = _real_folder(folder, root, (st.st_ino, st.st_dev, st.st_mtime_ns)) / path.name
    except OSError:
        real = _real(path)
    if real.is_relative_to(root):
        return None
    return error("source-outside-project",
                 f"{proc.path} is a link to {real}, outside the project; Build All compiles "
                 "only files inside the project", None,     # no span: its lines are not shown
                 "copy the file into the project instead of linking to it")


def _build_dir_problem(project: Project) -> Optional[Diagnostic]:
    """build/ (or something in the way of it) leading out of the project."""
    build_dir = project.build_dir
    if not os.path.lexists(build_dir):
        return None
    real, root = _real(build_dir), _real(project.root)
    if real.is_relative_to(root) and real != root:
        return None
    return error("build-outside-project",
                 f"{build_dir} leads to {real}, outside the project; Build All writes only "
                 "inside the project", None,
                 f"remove the link {build_dir} (Build All makes the folder)")


def _name_problem(proc: Procedure, seen: dict[str, Procedure]) -> Optional[Diagnostic]:
    at = Span.point(str(proc.path), 1, 1)
    if not valid_name(proc.name):
        return error("procedure-name",
                     f"'{proc.name}' cannot be a procedure name: use letters, digits, '_' and "
                     "'-' (at most 64), as in M03 or __HANDLER_INIT", at,
                     "rename the file")
    other = seen.get(proc.name)
    if other is not None:
        return error("duplicate-procedure",
                     f"there is a {other.kind.label} procedure named {proc.name} too "
                     f"({other.path}); names must be unique in a project (they share build/ "
                     "and the image)", at, "rename one of the files")
    return None


def _target_problem(project: Project, proc: Procedure,
                    procs: list[Procedure]) -> Optional[Diagnostic]:
    """A target other than mycnc runs one program: one .plc file in hardware/
    (docs/targets.md)."""
    target = project.target
    if target == "mycnc":
        return None
    at = Span.point(str(proc.path), 1, 1)
    if proc.kind is Kind.SOFTWARE:
        return error("target-project", f"the {target} target has no software PLC: "
                                       f"{proc.path.name} in software/ is not run", at,
                     "move its procedures into the program in hardware/, or remove the file")
    first = next(p for p in procs if p.kind is Kind.HARDWARE)
    if first is not proc:
        return error("target-project", f"the {target} target runs one program, "
                                       f"{first.path.name}; this is a second one", at,
                     f"put its procedures into {first.path.name}, or remove the file")
    return None


def _is_name_problem(pb: ProcedureBuild) -> bool:
    return any(d.code in ("procedure-name", "duplicate-procedure", "source-outside-project",
                          "target-project")
               for d in pb.diagnostics)


def _write_if_changed(path: Path, data: bytes, sync: bool = True) -> bool:
    """Write data atomically unless path already holds it; whether it wrote."""
    try:
        if read_bounded(path, len(data)) == data:
            return False
    except OSError:       # missing, different, or not a regular file (atomic_write says so)
        pass
    atomic_write(path, data, sync=sync)
    return True


def _safe_bin_name(name: str) -> bool:
    return name.endswith(BIN_SUFFIX) and "/" not in name and "\\" not in name \
        and valid_name(name[:-len(BIN_SUFFIX)])


# ------------------------------------------------------------------ cache

@lru_cache(maxsize=1)
def compiler_fingerprint() -> str:
    """A hash of the compiler (its version and its own source files), so that a
    changed compiler never reuses a cached build."""
    h = hashlib.sha256()
    h.update(f"plcbuilder {plcbuilder.__version__} compiler {_compiler.COMPILER_VERSION}".encode())
    pkg = Path(plcbuilder.__file__).parent
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


_INCLUDE_RE = re.compile(r"^[ \t]*#[ \t]*include\b(.*)$", re.MULTILINE)
_MAX_DEPS = 256


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


class _Cache:
    """build/.cache.json: read once at the start of a build, written at its end
    only when it changed; meanwhile it reads and hashes each source and header at
    most once (not at all when its stat is unchanged, see the module docstring)."""

    def __init__(self, build_dir: Path, use: bool):
        self.build_dir = build_dir
        self.fingerprint = compiler_fingerprint()
        self.start_ns = time.time_ns()
        try:
            self.cwd = os.getcwd()      # diagnostics name headers relative to it
        except OSError:
            self.cwd = ""
        self.doc = _load_cache(build_dir)
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
        self.found: dict[tuple, Optional[Path]] = {}   # include resolutions, this build

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
               _include_targets(_text(data)), trusted]
        self.files[name] = rec
        return rec[3], rec[4]

    def source_hash(self, proc: Procedure) -> Optional[str]:
        """The SHA-256 of the source as its key saw it (the compiler reads the
        file again, and a build that compiled other bytes does not cache them)."""
        rec = self.files.get(str(proc.path))
        return rec[3] if rec is not None else None

    def _resolve(self, target: str, folder: Optional[Path], dirs: list[Path]) -> Optional[Path]:
        """The header #include target names from folder (None: a built-in one)."""
        memo = (target, folder, tuple(dirs))
        if memo not in self.found:
            self.found[memo] = next((d / target for d in ([folder] if folder else []) + dirs
                                     if (d / target).is_file()), None)
        return self.found[memo]

    def key(self, proc: Procedure, options: CompileOptions) -> Optional[str]:
        """The SHA-256 that decides whether a cached build is still good, or None
        when the sources cannot be read (then the compiler reports why)."""
        h = hashlib.sha256()

        def put(*parts) -> None:
            for part in parts:
                b = part if isinstance(part, bytes) else str(part).encode("utf-8", "surrogatepass")
                h.update(len(b).to_bytes(8, "little") + b)

        source = self.info(proc.path)
        if source is None:
            return None
        put(CACHE_VERSION, self.fingerprint, proc.kind.label, options.strict, options.target,
            options.limit, str(proc.path), self.cwd, source[0], str(options.root))
        dirs = [Path(d) for d in options.include_dirs]
        put(len(dirs), *[str(d) for d in dirs])
        # Resolve includes as the preprocessor does: the including file's folder,
        # then the include folders, then the built-in headers.
        todo = [(t, proc.path.parent) for t in source[1]]
        seen: set[tuple[str, str]] = set()
        while todo:
            target, folder = todo.pop(0)
            if (target, str(folder)) in seen:
                continue
            seen.add((target, str(folder)))
            if len(seen) > _MAX_DEPS:
                return None
            put("include", target, str(folder))
            found = self._resolve(target, folder, dirs)
            if found is not None:
                header = self.info(found)
                if header is None:
                    return None
                put("file", str(found), header[0])
                todo.extend((t, found.parent) for t in header[1])
                continue
            builtin = _builtin_info(target)
            if builtin is not None:
                put("builtin", builtin[0])
                todo.extend((t, None) for t in builtin[1])
            else:
                put("missing")
        return h.hexdigest()

    # ------------------------------------------------------- procedures
    def lookup(self, proc: Procedure, options: CompileOptions,
               key: str) -> Optional[ProcedureBuild]:
        """The procedure as the last build left it, if its key and binary still hold."""
        cache_id = f"{proc.kind.label}/{proc.name}"
        entry = self.old.get(cache_id)
        if not entry or entry.get("key") != key:
            return None
        try:
            rows = entry["diagnostics"]
            if type(rows) is not list:
                return None
            for row in rows:
                _check_row(row)
            size, crc = entry.get("size"), entry.get("crc32")
            path = None
            if entry.get("bin"):
                if entry["bin"] != proc.name + BIN_SUFFIX or type(size) is not int \
                        or type(crc) is not int:
                    return None
                path = self.build_dir / entry["bin"]
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
            elif _counts(rows)[0]:
                size = crc = None
            else:
                return None
        except (OSError, KeyError, TypeError, ValueError):
            return None
        self.procs[cache_id] = entry
        # only name, size and CRC are kept: the bytes are read from build/ when needed
        return ProcedureBuild(proc, _cached(rows), size, options.limit, crc, True, None, None,
                              path)

    def compiled(self, pb: ProcedureBuild, key: Optional[str], rows_json: str) -> None:
        """A procedure compiled now: write its binary (or remove the old one)
        and remember it. Once written, the ProcedureBuild keeps only its name,
        size and CRC: the bytes are read again from build/ when needed, so a
        large project's binaries are never all in memory."""
        path = self.build_dir / pb.bin_name
        binary = pb.binary if pb.ok else None
        if binary is not None:
            _write_if_changed(path, binary, sync=False)
            pb._binary, pb._bin_path = None, path
        if key is None:
            return
        # kept as its JSON text (written out as it is), the diagnostics as the
        # compiler's JSON text (``rows_json``): never decoded here
        first = _dumps({
            "bin": pb.bin_name if binary is not None else None,
            "bin_stat": _stat(path) if binary is not None else None,
            "crc32": pb.crc32 if binary is not None else None,
        })
        last = _dumps({"key": key, "size": pb.size})
        # the text _dumps would give for the whole entry (keys sorted), packed
        self.procs[f"{pb.kind.label}/{pb.name}"] = _RawJSON.packed(
            first[:-1] + ',"diagnostics":' + rows_json + "," + last[1:])

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


class _RawJSON(bytes):
    """A value of the cache's tables already as its JSON text, zlib-compressed
    until it is written out (see _json_chunks)."""

    @classmethod
    def packed(cls, text: str) -> "_RawJSON":
        return cls(zlib.compress(text.encode("utf-8"), 1))

    def text(self) -> str:
        return zlib.decompress(self).decode("utf-8")


def _dumps(value) -> str:
    return json.dumps(value, sort_keys=True, separators=(",", ":"))


def _json_chunks(doc: dict, big: tuple = ("files", "procedures")) -> Iterator[bytes]:
    """json.dumps(doc, sort_keys=True, compact) + newline, byte for byte, as
    chunks of about 64 KiB: the two large tables are encoded an entry at a time,
    so the whole text is never in memory; an entry that is a _RawJSON is its
    own text."""
    def dumps(value) -> str:
        return value.text() if isinstance(value, _RawJSON) else _dumps(value)

    def pieces() -> Iterator[str]:
        yield "{"
        for n, k in enumerate(sorted(doc)):
            yield ("," if n else "") + dumps(k) + ":"
            if k in big and isinstance(doc[k], dict):
                yield "{"
                for m, sub in enumerate(sorted(doc[k])):
                    yield ("," if m else "") + dumps(sub) + ":" + dumps(doc[k][sub])
                yield "}"
            else:
                yield dumps(doc[k])
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


def _text(data: bytes) -> str:
    return data.decode("utf-8", "replace")


def _load_cache(build_dir: Path) -> dict:
    try:
        doc = json.loads(read_bounded(build_dir / CACHE_FILE, MAX_CACHE_BYTES).decode("utf-8"))
    except (OSError, ValueError, RecursionError):
        return {}
    return doc if isinstance(doc, dict) else {}


def _span_to_json(s: Optional[Span]):
    return None if s is None else [s.file, s.line, s.col, s.end_line, s.end_col]


def _span_from_json(v) -> Optional[Span]:
    if v is None:
        return None
    f, a, b, c, d = v
    if not isinstance(f, str) or not all(type(x) is int for x in (a, b, c, d)):
        raise ValueError("bad span")
    return Span(f, a, b, c, d)


def _diag_to_json(d: Diagnostic) -> dict:
    return {"severity": int(d.severity), "code": d.code, "message": d.message,
            "span": _span_to_json(d.span), "hints": list(d.hints),
            "related": [[_span_to_json(r.span), r.message] for r in d.related]}


def _diag_from_json(v: dict) -> Diagnostic:
    if not isinstance(v["code"], str) or not isinstance(v["message"], str):
        raise ValueError("bad diagnostic")
    return Diagnostic(Severity(v["severity"]), v["code"], v["message"], _span_from_json(v["span"]),
                      tuple(str(h) for h in v["hints"]),
                      tuple(Related(_span_from_json(s), str(m)) for s, m in v["related"]))


_SEVERITIES = frozenset(int(s) for s in Severity)


def _check_row(v) -> None:
    """Raise ValueError unless ``v`` is a diagnostic row as ``_diag_to_json``
    makes it (what ``_diag_from_json`` reads), without making the objects."""
    if type(v) is not dict or v.get("severity") not in _SEVERITIES \
            or type(v.get("code")) is not str or type(v.get("message")) is not str \
            or type(v.get("hints")) is not list or type(v.get("related")) is not list \
            or not all(type(h) is str for h in v["hints"]):
        raise ValueError("bad diagnostic")
    _check_span(v.get("span"))
    for rel in v["related"]:
        if type(rel) is not list or len(rel) != 2 or type(rel[1]) is not str:
            raise ValueError("bad diagnostic")
        _check_span(rel[0])


def _check_span(v) -> None:
    if v is not None and (type(v) is not list or len(v) != 5 or type(v[0]) is not str
                          or not all(type(x) is int for x in v[1:])):
        raise ValueError("bad span")


def _disk_lines(file: str) -> Optional[list[str]]:
    """The lines of a file as diagnostics name it (a path, or a built-in header)."""
    try:
        text = source_text(file)
    except (OSError, ValueError):
        return None
    if text is None:
        return None
    return text.replace("\r\n", "\n").replace("\r", "\n").split("\n")


def _disk_line(file: str, line: int) -> Optional[str]:
    """A line of a file as diagnostics name it (a path, or a built-in header)."""
    global _last_file
    try:
        st = os.stat(file)
        stamp = (st.st_size, st.st_mtime_ns, st.st_ctime_ns, st.st_ino)
    except (OSError, ValueError):
        stamp = None                        # a built-in header: it does not change
    name, seen, lines = _last_file
    if name != file or seen != stamp:
        lines = _disk_lines(file)
        _last_file = (file, stamp, lines)
    return lines[line - 1] if lines is not None and 1 <= line <= len(lines) else None
