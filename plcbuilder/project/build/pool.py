"""Compiling Build All's procedures: here, or in worker processes.

When at least :data:`PARALLEL_MIN` procedures need compiling and the machine
has more than one core, worker processes compile them (forked from this
process when it runs a single thread, from a fork server otherwise); fewer are
compiled here, one after another. The outcomes are the same either way, in
the same order.

A job is (source path, CompileOptions, the source's SHA-256 as its cache key
saw it); its outcome is small, flat and picklable, so the parent builds no
objects from it: (the diagnostics' JSON text, errors, warnings, the source
lines they point at, code size, binary, the SHA-256 of the source compiled,
the diagnostics as the report shows them without colour, or None).
The compiler reads each source itself, so the parent never holds a project's
sources.
"""

from __future__ import annotations

import hashlib
import os
import threading
from typing import Callable, Iterator, Optional

from plcbuilder._support.files import read_bounded
from plcbuilder.lang import Span, error, render_text
from plcbuilder.lang.options import CompileOptions
from plcbuilder.lang.source import MAX_SOURCE_BYTES
from plcbuilder.project.build.results import counts, dumps, kept_line

#: Fewer procedures to compile than this: compiled in this process, one after another.
PARALLEL_MIN = 48
MAX_WORKERS = 8

Job = tuple[str, CompileOptions, Optional[str]]


def compile_many(work: list[Job], done: Callable[[int, tuple], None],
                 jobs: Optional[int]) -> None:
    """Compile every job, calling done(index, outcome) in order. ``jobs``:
    worker processes (None: as many as cores, at most :data:`MAX_WORKERS`, when
    there are :data:`PARALLEL_MIN` jobs or more; 1: none). With several workers
    the first job is compiled here (a forked worker then inherits the parser)
    and the rest by the pool; if the pool cannot start or breaks, the rest is
    compiled here."""
    if jobs is None:
        jobs = min(_cores(), MAX_WORKERS) if len(work) >= PARALLEL_MIN else 1
    jobs = max(1, min(jobs, len(work) - 1))
    k = 0
    if jobs > 1:
        done(0, compile_job(work[0]))
        k = 1
        for outcome in _in_workers(work[1:], jobs):
            done(k, outcome)
            k += 1
    for k in range(k, len(work)):
        done(k, compile_job(work[k]))


def compile_job(job: Job) -> tuple:
    """Compile one procedure (in a worker process or here): its outcome (see
    the module docstring). The source is read here."""
    from plcbuilder.lang.pipeline import compile_file     # (an unchanged rebuild: not loaded)
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
        return dumps([diag.to_dict()]), 1, 0, [], None, None, read, None
    binary = r.program.to_bytes() if r.ok and r.program is not None else None
    lines: dict = {}
    for d in r.diagnostics:
        if d.span is not None and (d.span.file, d.span.line) not in lines:
            text = r.source_line(d.span.file, d.span.line)
            if text is not None:
                lines[(d.span.file, d.span.line)] = text
    rows = [d.to_dict() for d in r.diagnostics]
    shown = "\n".join(render_text(d, lambda f, n: kept_line(lines, f, n))   # as the report
                       for d in r.diagnostics)
    return (dumps(rows), *counts(rows), [[f, n, t] for (f, n), t in lines.items()],
            (r.size if binary is not None else None), binary, read, shown)


def _warm() -> None:
    """A worker's start: build the parser (a forked worker has it already)."""
    from plcbuilder.lang.pipeline import compile_source
    compile_source("main() { exit(99); };\n")


def _cores() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        return os.cpu_count() or 1


def _in_workers(work: list[Job], jobs: int) -> Iterator[tuple]:
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
        outcomes = pool.map(compile_job, work, chunksize=chunk)
        while True:
            try:
                outcome = next(outcomes)
            except (StopIteration, BrokenProcessPool, OSError):
                return
            yield outcome
    finally:
        pool.shutdown(wait=True, cancel_futures=True)
