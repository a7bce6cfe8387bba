"""Telemetry changes -> the points a plot draws (:class:`StepSamples`).

Its own module, without numpy, so the IDE's link (which feeds it on its reader
thread) loads without the plotting stack. No Qt.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Iterable, Optional

from plcbuilder.api import events as ev

__all__ = ["StepSamples"]


class StepSamples:
    """Telemetry changes -> the samples to plot.

    :meth:`feed` takes one telemetry batch (its changes, oldest first, and its
    ``t_ms``, the tick the controller runs next) and returns the changes with
    a copy of the held sample on the tick before each change that follows a
    gap, and one on the newest tick. A change older than the last point (the
    controller started over) passes as it is; the model clears on it."""

    def __init__(self):
        self.reset()

    def reset(self) -> None:
        self._last: Optional[ev.Sample] = None
        self._t = -1                 # the time of the last point handed out

    def feed(self, changes: Iterable[ev.Sample], t_end: int) -> list[ev.Sample]:
        out: list[ev.Sample] = []
        last, t = self._last, self._t
        for s in changes:
            if last is not None and t < s.t_ms - 1:
                out.append(replace(last, t_ms=s.t_ms - 1, message=0))
            out.append(s)
            last, t = s, s.t_ms
        if last is not None and t < t_end - 1:
            out.append(replace(last, t_ms=t_end - 1, message=0))
            t = t_end - 1
        self._last, self._t = last, t
        return out
