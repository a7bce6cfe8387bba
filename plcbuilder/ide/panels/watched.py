"""Watched variables of the run model: each ``PROC.var``'s changes over time.

A variable the controller records for a trigger (or that a trace holds,
``--watch``) comes as changes: ``Watched(t_ms, name, value)`` events live, a
``PROC.var`` signal of a trace file. :class:`WatchedVariables` keeps them a
ring buffer a variable (time in seconds and value), outside any widget, and
says how the plots show each one:

- a **lane** (a digital signal in the Outputs plot) for the bit a trigger
  watches (``M80.var03 bit 2 rise``), and for a variable that has only ever
  been 0 or 1 (``M80.sens``);
- a **curve** (a step plot in the PWM / DAC / ADC dock) for every other one.

No Qt.
"""

from __future__ import annotations

from typing import Iterable, Mapping, Optional

import numpy as np

from plcbuilder.api import events as ev
from plcbuilder.ide.ringbuffer import RingBuffer

__all__ = ["WatchedVariables", "lane_label"]


class _Series:
    """One variable's changes: times (s) and values, oldest first."""

    __slots__ = ("t", "v", "binary")

    def __init__(self, capacity: int):
        self.t = RingBuffer(capacity, 1, np.float64)
        self.v = RingBuffer(capacity, 1, np.int64)
        self.binary = True               # every value so far 0 or 1

    def add(self, times, values) -> None:
        values = np.asarray(values, dtype=np.int64)
        self.t.extend(np.asarray(times, dtype=np.float64))
        self.v.extend(values)
        if self.binary and len(values) and bool(((values != 0) & (values != 1)).any()):
            self.binary = False


class WatchedVariables:
    """The watched variables' changes, and which lane or curve shows each.

    ``version`` goes up with every change (the plots redraw when it moved).
    ``bits``: a trigger's bit of a variable (``{"M80.var03": 2}``), shown as
    that variable's lane; kept over :meth:`clear`."""

    def __init__(self, capacity: int = 30000):
        self.capacity = max(1, int(capacity))
        self.series: dict[str, _Series] = {}
        self.bits: dict[str, int] = {}
        self.version = 0

    def __len__(self) -> int:
        return len(self.series)

    def names(self) -> list[str]:
        """The variables with a value, in the order they first came."""
        return list(self.series)

    def clear(self) -> None:
        """Forget every value (the trigger's bits stay)."""
        self.series.clear()
        self.version += 1

    def set_bits(self, bits: Mapping[str, int]) -> bool:
        """The bits a trigger watches; returns whether that changed."""
        bits = {str(k): int(v) for k, v in (bits or {}).items()}
        if bits == self.bits:
            return False
        self.bits = bits
        self.version += 1
        return True

    # ----------------------------------------------------------------- ingest
    def add_events(self, events: Iterable) -> bool:
        """Keep the values of ``Watched`` events (others are ignored); returns
        whether any came. A value older than the newest kept for its variable
        means the controller started over: that variable starts again."""
        batch: dict[str, tuple[list, list]] = {}
        for e in events:
            if isinstance(e, ev.Watched):
                times, values = batch.setdefault(e.name, ([], []))
                times.append(e.t_ms * 1e-3)
                values.append(int(e.value))
        for name, (times, values) in batch.items():
            s = self.series.get(name)
            if s is not None and len(s.t) and times[0] < float(s.t.latest()[0]):
                s = None
            if len(times) > 1 and any(b < a for a, b in zip(times, times[1:])):
                cut = max(i for i in range(1, len(times)) if times[i] < times[i - 1])
                times, values, s = times[cut:], values[cut:], None
            if s is None:
                s = self.series[name] = _Series(self.capacity)
            s.add(times, values)
        if batch:
            self.version += 1
        return bool(batch)

    def set_changes(self, changes: Mapping[str, list]) -> None:
        """Every value of a trace: ``{name: [(t_ms, value), …]}`` (replaces what was kept)."""
        self.series.clear()
        for name, ch in changes.items():
            if not ch:
                continue
            s = self.series[name] = _Series(max(self.capacity, len(ch)))
            s.add([t * 1e-3 for t, _v in ch], [v for _t, v in ch])
        self.version += 1

    # ------------------------------------------------------------------ query
    def lanes(self) -> list[tuple[str, int]]:
        """The digital lanes, ``(name, bit)``: a trigger's bit of a variable,
        and bit 0 of each variable that has only been 0 or 1."""
        out = []
        for name, s in self.series.items():
            if name in self.bits:
                out.append((name, self.bits[name]))
            elif s.binary:
                out.append((name, 0))
        return out

    def curves(self) -> list[str]:
        """The variables drawn as a number (every one that has been other than 0/1)."""
        return [name for name, s in self.series.items() if not s.binary]

    def is_binary(self, name: str) -> bool:
        s = self.series.get(name)
        return s is None or s.binary

    def window(self, name: str, t0: float, t1: float) -> tuple[np.ndarray, np.ndarray]:
        """The changes of ``name`` over [t0, t1] (seconds), with the one before
        t0 (the value held at t0) and the one after t1: times and values."""
        s = self.series.get(name)
        if s is None:
            return np.empty(0), np.empty(0, dtype=np.int64)
        t = s.t.view()
        a = max(0, int(np.searchsorted(t, t0, side="right")) - 1)
        b = min(len(t), int(np.searchsorted(t, t1, side="right")) + 1)
        return t[a:b], s.v.view()[a:b]

    def value_at(self, name: str, t: float) -> Optional[int]:
        """The value of ``name`` at time ``t`` (seconds); None before its first
        value (or when it has none)."""
        s = self.series.get(name)
        if s is None:
            return None
        i = int(np.searchsorted(s.t.view(), t + 1e-9, side="right")) - 1
        return None if i < 0 else int(s.v.view()[i])

    def t_end(self) -> float:
        """The newest change's time in seconds (0 without any)."""
        ends = [float(s.t.latest()[0]) for s in self.series.values() if len(s.t)]
        return max(ends, default=0.0)


def lane_label(name: str, bit: int, binary: bool) -> str:
    """``M80.sens`` for a 0/1 variable's bit 0, else ``M80.var03 bit 2``."""
    return name if bit == 0 and binary else f"{name} bit {bit}"
