"""Build All's steps: compile every procedure, write build/ and the image.

1. Every ``hardware/*.plc`` and ``software/*.plc`` is compiled (going on past
   errors) as :meth:`Project.compile_options` says: the project's include folder
   and size limits; each procedure's diagnostics and size against its limit are
   in the result (:func:`compile_all`). A procedure with a problem
   (:mod:`.problems`) is not compiled; one the cache (:mod:`.cache`) has is
   not compiled again; the rest are compiled here or by workers (:mod:`.pool`).
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
"""

from __future__ import annotations

import os
import zlib
from contextlib import contextmanager
from pathlib import Path
from typing import Callable, Iterator, Optional

from plcbuilder._support import gcpause
from plcbuilder._support.files import atomic_write, remove_temp_files
from plcbuilder.bytecode.program import Kind
from plcbuilder.image.manifest import ImageError, iter_image, valid_name
from plcbuilder.lang import error
from plcbuilder.lang.options import CompileOptions
from plcbuilder.project.build.cache import Cache, image_key
from plcbuilder.project.build.pool import compile_many
from plcbuilder.project.build.problems import (build_dir_problem, is_procedure_problem,
                                               procedure_problem, real)
from plcbuilder.project.build.results import (BIN_SUFFIX, BuildResult, ProcedureBuild, pack)
from plcbuilder.project.model import Procedure, Project, not_a_project

try:
    import fcntl
except ImportError:          # Windows
    fcntl = None
try:
    import msvcrt
except ImportError:          # everything but Windows
    msvcrt = None

LOCK_FILE = ".lock"

#: progress(done, total, name): called after each procedure is compiled (or found
#: unchanged); first with done=0 before any work.
Progress = Callable[[int, int, str], None]


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
    outside = build_dir_problem(project)
    if outside is not None:          # write nothing there: compile, report, keep the image
        result = BuildResult(project, compile_all(project, progress, strict=strict, jobs=jobs),
                             [outside], project.limits, 0, project.image_path)
        result.compiled = sum(1 for p in result.procedures if not is_procedure_problem(p))
        result.image_message = (f"{project.image_path} not written: {build_dir} is outside "
                                "the project")
        return result
    build_dir.mkdir(parents=True, exist_ok=True)
    with _locked(build_dir / LOCK_FILE), gcpause.paused():
        # (the cache's document and the builds are a few objects a diagnostic
        # and a procedure, none in a cycle: the collector went through them
        # again and again, a sixth of an unchanged rebuild)
        remove_temp_files(build_dir)
        return _build(project, progress, strict, use_cache, jobs)


def _build(project: Project, progress: Optional[Progress], strict: Optional[bool],
           use_cache: bool, jobs: Optional[int]) -> BuildResult:
    limits = project.limits
    build_dir = project.build_dir
    cache = Cache(build_dir, use_cache)
    result = BuildResult(project, [], [], limits, 0, project.image_path)
    result.procedures = _procedure_builds(project, progress, strict, (), jobs, cache)
    result.reused = sum(1 for p in result.procedures if p.cached)
    result.compiled = sum(1 for p in result.procedures
                          if not p.cached and not is_procedure_problem(p))

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


def _procedure_builds(project: Project, progress: Optional[Progress], strict: Optional[bool],
                      extra_includes: tuple, jobs: Optional[int],
                      cache: Optional[Cache]) -> list[ProcedureBuild]:
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
    root = real(project.root)           # resolved once, not once a procedure
    for i, proc in enumerate(procs):
        folder = proc.path.parent
        if folder not in options_for:
            options_for[folder] = project.compile_options(proc.path, strict=strict,
                                                          extra_includes=extra_includes)
        options = options_for[folder]
        problem = procedure_problem(project, proc, procs, by_name, root)
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
        rows_json, errors, warnings, lines, size, binary, read, shown = outcome
        if read != work[k][2]:
            key = None           # the source changed after its key was made: not cached
        pb = ProcedureBuild(procs[i], pack(rows_json, errors, warnings, lines), size,
                            options.limit, zlib.crc32(binary) if binary is not None else None,
                            False, None, binary, shown=shown)
        if cache is not None:
            cache.compiled(pb, key, rows_json)
        finished(i, pb)

    work = [(str(procs[i].path), options, cache.source_hash(procs[i]) if cache else None)
            for i, options, _key in pending]
    compile_many(work, compiled, jobs)
    return out   # type: ignore[return-value]  - every slot is filled


# ------------------------------------------------------------------ image

def _write_the_image(result: BuildResult, cache: Cache) -> None:
    """Write build/eeprom.rom unless it holds these binaries already."""
    path, limits = result.image_path, result.limits
    key = image_key(result.procedures, limits)
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


def _safe_bin_name(name: str) -> bool:
    return name.endswith(BIN_SUFFIX) and "/" not in name and "\\" not in name \
        and valid_name(name[:-len(BIN_SUFFIX)])
