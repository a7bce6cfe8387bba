"""Checks off the message loop: one worker thread compiles, the loop answers.

A document is checked when it is opened or saved (at once) and a moment after
the last change while typing (:data:`CHANGE_DELAY`). Each request takes a
snapshot of the open documents on the loop (:meth:`Analysis.plan`) and queues
it; the worker thread compiles the snapshot (:meth:`Analysis.compute`) and
hands the outcome back to the loop, which keeps it and publishes the
diagnostics (:meth:`Analysis.apply`). Meanwhile the loop goes on answering:
a hover, a completion or another document's change does not wait for a
compile.

A newer request supersedes an older one of the same document: each has a
generation number, a queued request is replaced by the newer one (only the
newest text is compiled), and the outcome of a compile that was overtaken
while it ran is dropped, so a client never gets diagnostics of text it no
longer has. A compile that has started runs to its end (Python cannot stop a
thread); the source size limit bounds how long that is.

The cyclic garbage collector is paused while a check compiles, and the young
generations are collected once its diagnostics are out. A compile leaves tens
of thousands of objects in reference cycles, and a collection of the whole
heap in the middle of one (~0.1 s with a 3,000-line file's caches) stopped
both threads: it was half the time of a keystroke that moved the lines below
it, and the pauses a hover on another file waited for while a large file was
checked. A full collection still comes now and then, between checks.
"""

from __future__ import annotations

import asyncio
import gc
import logging
import threading
from typing import Callable, Optional

from plcbuilder._support import gcpause
from plcbuilder.lsp.analysis import Analysis, Job, Outcome

log = logging.getLogger(__name__)

#: Seconds after the last change before a document is checked again.
CHANGE_DELAY = 0.15


class Checks:
    """Schedules the checks of one session (see the module docstring).
    ``publish(outcome_versions, {uri: diagnostics})`` is called on the loop."""

    def __init__(self, analysis: Analysis, publish: Callable[[dict, dict], None],
                 delay: float = CHANGE_DELAY):
        self.analysis = analysis
        self.publish = publish
        self.delay = delay
        self._generation: dict[str, int] = {}
        self._timers: dict[str, asyncio.TimerHandle] = {}
        self._queue: dict[str, Job] = {}
        self._cond = threading.Condition()
        self._thread: Optional[threading.Thread] = None
        self._loop: Optional[asyncio.AbstractEventLoop] = None
        self._stopped = False
        self.running: Optional[str] = None          # the uri being compiled

    # ------------------------------------------------------------ requests (loop)
    def now(self, uri: str) -> None:
        """Check ``uri`` as soon as the worker is free."""
        self._bump(uri)
        self._enqueue(uri)

    def later(self, uri: str, delay: Optional[float] = None) -> None:
        """Check ``uri`` once no change came for ``delay`` seconds."""
        self._bump(uri)
        loop = self._running_loop()
        if loop is None:
            self._enqueue(uri)
            return
        self._timers[uri] = loop.call_later(self.delay if delay is None else delay,
                                            self._fire, uri)

    def cancel(self, uri: str) -> None:
        """Forget ``uri``'s pending check (closed): any outcome on its way is dropped."""
        self._bump(uri)
        with self._cond:
            self._queue.pop(uri, None)

    def pending(self) -> bool:
        with self._cond:
            return bool(self._queue) or self.running is not None or bool(self._timers)

    def stop(self) -> None:
        for t in self._timers.values():
            t.cancel()
        self._timers.clear()
        with self._cond:
            self._stopped = True
            self._queue.clear()
            self._cond.notify_all()

    # ------------------------------------------------------------ private (loop)
    def _running_loop(self) -> Optional[asyncio.AbstractEventLoop]:
        try:
            self._loop = asyncio.get_running_loop()
        except RuntimeError:
            return None
        return self._loop

    def _bump(self, uri: str) -> None:
        self._generation[uri] = self._generation.get(uri, 0) + 1
        timer = self._timers.pop(uri, None)
        if timer is not None:
            timer.cancel()

    def _fire(self, uri: str) -> None:
        self._timers.pop(uri, None)
        self._enqueue(uri)

    def _enqueue(self, uri: str) -> None:
        job = self.analysis.plan(uri, self._generation.get(uri, 0))
        if self._running_loop() is None:
            # no loop (a caller outside the server): check here and now
            self._done(job, self.analysis.compute(job))
            return
        with self._cond:
            if self._stopped:
                return
            self._queue.pop(uri, None)
            self._queue[uri] = job                  # a newer request replaces a waiting one
            self._cond.notify()
            if self._thread is None:
                self._thread = threading.Thread(target=self._run, name="plcbuilder-lsp-checks",
                                                daemon=True)
                self._thread.start()

    def _done(self, job: Job, outcome: Optional[Outcome]) -> None:
        try:
            if outcome is None or self._stopped:
                return
            if job.generation != self._generation.get(job.uri, 0):
                return                              # overtaken: newer text was asked for
            self.publish(outcome.versions, self.analysis.apply(outcome))
        finally:
            gc.collect(1)                           # the compile's garbage (see the docstring)

    # ------------------------------------------------------------ the worker
    def _run(self) -> None:
        while True:
            with self._cond:
                while not self._queue and not self._stopped:
                    self._cond.wait()
                if self._stopped:
                    return
                uri = next(iter(self._queue))
                job = self._queue.pop(uri)
                self.running = uri
            outcome = None
            try:
                if job.generation == self._generation.get(uri, 0):   # else overtaken already
                    outcome = self._compute(job)
            except Exception:  # noqa: BLE001 - a checker bug must not end the session
                log.exception("checking %s failed", uri)
            with self._cond:
                self.running = None
                stopped = self._stopped
            if stopped:
                return
            loop = self._loop
            if loop is not None and not loop.is_closed():
                try:
                    loop.call_soon_threadsafe(self._done, job, outcome)
                except RuntimeError:                 # the loop closed meanwhile
                    return

    def _compute(self, job: Job) -> Outcome:
        """The compile, with the cyclic garbage collector paused (see the docstring)."""
        with gcpause.paused():   # every session's compiles share the one collector
            return self.analysis.compute(job)
