"""Diagnostics while typing: compile on a worker thread, debounced.

Each edit of a file restarts that file's debounce timer (:data:`DEBOUNCE_MS`);
when it fires the text is handed to one worker thread, which compiles it
with the file's options and reports back through a queued signal. Every
request carries a generation number per file: a result older than the
newest request for its file is dropped, so the editor never shows
diagnostics of text that is no longer there. While the worker is busy, new
requests for the same file replace the waiting one (only the newest text is
compiled).

Each file's compiles share one :class:`~plcbuilder.lang.incremental.Incremental`,
so a keystroke costs what it changed, not the whole file: headers are not
tokenized again and only the procedures around the edit are parsed again
(the result is the same as a compile from scratch). Closing the file
(:meth:`DiagnosticsWorker.cancel`) drops it.

Python's cyclic garbage collector is paused from the start of a compile until
its result has been handed to the window, and the young generations are
collected then, on the window's thread, while the Problems panel waits for
its refresh: a compile leaves tens of thousands of new objects, and the
collection of them that followed at once was a tenth of a keystroke's time
before its diagnostics (the language server does the same,
:mod:`plcbuilder.lsp.checks`).
"""

from __future__ import annotations

import gc
import sys
import threading
import traceback
from dataclasses import dataclass
from typing import TYPE_CHECKING, Callable, Optional

from PySide6.QtCore import QObject, QTimer, Signal

from plcbuilder import api
from plcbuilder._support import gcpause
from plcbuilder.api import Span, error
# the compiler (lark and the stages) loads on the worker thread with its first
# job, not with the main window: the IDE paints before it is there
if TYPE_CHECKING:
    from plcbuilder.lang.incremental import Incremental

DEBOUNCE_MS = 200          # + compile time: results land well within 300 ms for normal files
#: how often the interpreter hands the GIL from the compiling thread to the
#: window's: at Python's default (5 ms) every Qt callback of a keystroke waited
#: up to that long, and typing during the compile of a 2.7 MB file queued for
#: seconds (median 2.5 s a key); at 0.5 ms, about 0.1 s
GIL_SWITCH_S = 0.0005


@dataclass
class Job:
    key: str                     # the file (file_key)
    generation: int
    path: str                    # the name diagnostics use (the file's path)
    text: Optional[str]          # None: compile the file from disk
    options: api.CompileOptions
    gc_held: bool = False        # the collector is paused for it until its result is handled


def _release_gc() -> None:
    if gcpause.release():
        gc.collect(1)            # the compile's young objects (see the module docstring)


class DiagnosticsWorker(QObject):
    """Compiles files in the background; see the module docstring."""

    sig_result = Signal(str, object)
    """A fresh result: (file key, CompileResult)."""

    sig_busy = Signal(bool)
    """The worker started (True) or finished (False) compiling."""

    _sig_done = Signal(object, object)   # worker thread -> GUI thread: (Job, result)

    def __init__(self, parent=None, debounce_ms: int = DEBOUNCE_MS):
        super().__init__(parent)
        self.debounce_ms = debounce_ms
        self._generation: dict[str, int] = {}
        self._timers: dict[str, QTimer] = {}
        self._pending_text: dict[str, Callable[[], tuple]] = {}
        self._queue: dict[str, Job] = {}
        self._incremental: dict[str, Incremental] = {}   # per file, used by the worker thread
        self._cond = threading.Condition()
        self._stopped = False
        self._held = False
        self._busy = False
        #: jobs the worker thread took whose result the GUI thread has not
        #: handled yet (compiling, or the result waiting in the event queue):
        #: with an empty queue the worker is idle only when this is 0
        self._taken = 0
        self._sig_done.connect(self._on_done)
        if sys.getswitchinterval() > GIL_SWITCH_S:
            sys.setswitchinterval(GIL_SWITCH_S)
        self._thread = threading.Thread(target=self._run, name="plcbuilder-diagnostics",
                                        daemon=True)
        self._thread.start()

    # ---------------------------------------------------------------- public
    def schedule(self, key: str, request: Callable[[], tuple],
                 delay_ms: Optional[int] = None) -> None:
        """Compile a file once typing stops (``delay_ms`` after the last edit;
        default: the debounce). ``request()`` is called when the timer fires
        and returns (path, text or None, CompileOptions)."""
        self._generation[key] = self._generation.get(key, 0) + 1
        self._pending_text[key] = request
        timer = self._timers.get(key)
        if timer is None:
            timer = QTimer(self)
            timer.setSingleShot(True)
            timer.timeout.connect(lambda k=key: self._fire(k))
            self._timers[key] = timer
        timer.start(self.debounce_ms if delay_ms is None else max(self.debounce_ms, delay_ms))

    def submit(self, key: str, path: str, text: Optional[str], options: api.CompileOptions) -> int:
        """Compile now (no debounce); returns the request's generation."""
        gen = self._generation.get(key, 0) + 1
        self._generation[key] = gen
        timer = self._timers.get(key)
        if timer is not None:
            timer.stop()
        self._pending_text.pop(key, None)
        self._enqueue(Job(key, gen, path, text, options))
        return gen

    def hold(self, held: bool) -> None:
        """While held, requests wait in the queue and nothing is compiled (the
        main window holds it until its first paint: a compile on this thread
        takes the interpreter from the window, and its first one loads the
        compiler)."""
        with self._cond:
            self._held = bool(held)
            self._cond.notify_all()

    def cancel(self, key: str) -> None:
        """Forget a file (closed): drop its pending request and any result."""
        self._generation[key] = self._generation.get(key, 0) + 1
        timer = self._timers.pop(key, None)
        if timer is not None:
            timer.stop()
            timer.deleteLater()
        self._pending_text.pop(key, None)
        with self._cond:
            self._queue.pop(key, None)
            self._incremental.pop(key, None)

    def pending(self) -> bool:
        """True while anything is waiting for its timer, queued or compiling."""
        with self._cond:
            queued = bool(self._queue) or self._taken > 0
        return queued or self._busy or any(t.isActive() for t in self._timers.values())

    def generation(self, key: str) -> int:
        return self._generation.get(key, 0)

    def shutdown(self) -> None:
        for t in self._timers.values():
            t.stop()
        with self._cond:
            self._stopped = True
            self._queue.clear()
            self._cond.notify_all()
        self._thread.join(timeout=2)

    # --------------------------------------------------------------- private
    def _fire(self, key: str) -> None:
        request = self._pending_text.pop(key, None)
        if request is None:
            return
        try:
            path, text, options = request()
        except Exception:  # noqa: BLE001 - the editor went away meanwhile
            return
        self._enqueue(Job(key, self._generation.get(key, 0), path, text, options))

    def _enqueue(self, job: Job) -> None:
        with self._cond:
            self._queue[job.key] = job           # a newer request replaces a waiting one
            self._cond.notify()
        if not self._busy:
            self._busy = True
            self.sig_busy.emit(True)

    def _run(self) -> None:
        while True:
            with self._cond:
                while (not self._queue or self._held) and not self._stopped:
                    self._cond.wait()
                if self._stopped:
                    return
                key = next(iter(self._queue))
                job = self._queue.pop(key)
                self._taken += 1
                incremental = self._incremental.get(key) if job.text is not None else None
            if job.text is not None and incremental is None:
                # (loaded outside the lock: the GUI thread queues requests under it)
                from plcbuilder.lang.incremental import Incremental
                incremental = Incremental()
                with self._cond:
                    incremental = self._incremental.setdefault(key, incremental)
            gcpause.hold()
            job.gc_held = True
            try:
                if job.text is None:
                    result = api.compile_file(job.path, job.options)
                else:
                    result = api.compile_source(job.text, job.path, job.options,
                                                incremental=incremental)
            except Exception as exc:  # noqa: BLE001 - an internal error becomes a diagnostic
                result = _internal_error(job, exc)
            with self._cond:
                if self._stopped:
                    _release_gc()
                    return
            try:
                self._sig_done.emit(job, result)
            except RuntimeError:       # the QObject is gone (application quitting)
                _release_gc()
                return

    def _on_done(self, job: Job, result) -> None:
        try:
            with self._cond:
                self._taken -= 1
                idle = not self._queue and self._taken == 0
            if idle and self._busy:
                self._busy = False
                self.sig_busy.emit(False)
            if job.generation != self._generation.get(job.key, 0):
                return                                  # stale: newer text was requested
            self.sig_result.emit(job.key, result)
        finally:
            if job.gc_held:
                job.gc_held = False
                _release_gc()


def _internal_error(job: Job, exc: BaseException):
    from plcbuilder.lang.pipeline import procedure_name
    from plcbuilder.lang.source import SourceSet
    detail = "".join(traceback.format_exception_only(type(exc), exc)).strip()
    diag = error("internal", f"internal compiler error: {detail}", Span.point(job.path, 1, 1))
    return api.CompileResult(procedure_name(job.path), job.path, job.options.kind, None, [diag],
                             SourceSet(), None, job.options.limit)
