"""Python's cyclic garbage collector paused while compiles run.

A compile makes a few objects a token (tokens, spans, nodes) and keeps most
of them to its end: the collector went through them again and again, a third
to two fifths of a compile's time, for garbage a compile does not make (its
objects refer to their children, never back). The collector is one for the
process while compiles run in several threads (the IDE's diagnostics worker,
each language-server session's worker, Build All's): the first hold pauses
it, the last release puts it back as it was, so concurrent and nested holds
never undo each other. A hold may end on another thread than it began on
(the IDE keeps it until the window has taken the result)."""

from __future__ import annotations

import gc
from _thread import allocate_lock
from contextlib import contextmanager

_lock = allocate_lock()
_holds = 0                  # holds not yet released (every thread's)
_was_enabled = False        # the collector was on when the first hold began


def hold() -> None:
    """Pause the collector until the matching :func:`release`."""
    global _holds, _was_enabled
    with _lock:
        if _holds == 0:
            _was_enabled = gc.isenabled()
            gc.disable()
        _holds += 1


def release() -> bool:
    """End a hold: True when it was the last one and the collector is on
    again (the caller may then collect what its work left)."""
    global _holds
    with _lock:
        _holds -= 1
        if _holds or not _was_enabled:
            return False
        gc.enable()
        return True


@contextmanager
def paused():
    """The collector paused while the block runs (a hold and its release)."""
    hold()
    try:
        yield
    finally:
        release()
