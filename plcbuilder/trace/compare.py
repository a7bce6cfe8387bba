"""Comparing two traces: the first tick where they differ, and in what.

Signals are compared by name over the time both traces cover (two traces
with no tick in common are not "the same": nothing could be compared); a
signal that only one trace has is listed apart (``only_in_a``/``only_in_b``)
and does not make them differ. The procedures' events (starts and ends, messages, prints,
faults) are compared too: the first tick where they differ counts. Notes,
logpoint lines and the forces list are the tools' remarks, not what the
procedures did, and are left out.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from typing import Optional

from plcbuilder.controller.history import Trace


#: The events compare() compares: what the procedures did.
COMPARED_EVENTS = frozenset({"started", "ended", "message", "print", "fault"})


@dataclass
class Difference:
    """Where two traces first differ: ``t_ms`` and, at that tick, each signal with
    its two values (as text), and whether the events differ there."""
    t_ms: Optional[int]                       # None: no difference over the common span
    signals: list[tuple[str, str, str]] = field(default_factory=list)
    events: bool = False
    only_in_a: list[str] = field(default_factory=list)
    only_in_b: list[str] = field(default_factory=list)
    #: the time each trace covers
    spans: tuple[tuple[int, int], tuple[int, int]] = ((0, 0), (0, 0))

    @property
    def span(self) -> tuple[int, int]:
        """The time both cover (empty, start after end, when they have no tick in common)."""
        (a0, a1), (b0, b1) = self.spans
        return max(a0, b0), min(a1, b1)

    @property
    def overlap(self) -> bool:
        """Whether the traces have a tick in common (else nothing was compared)."""
        return self.span[0] <= self.span[1]

    @property
    def same(self) -> bool:
        """No difference over a common span; traces with no tick in common are not."""
        return self.t_ms is None and self.overlap

    def to_dict(self) -> dict:
        return {"same": self.same, "t_ms": self.t_ms,
                "signals": [{"name": n, "a": a, "b": b} for n, a, b in self.signals],
                "events": self.events, "only_in_a": self.only_in_a,
                "only_in_b": self.only_in_b, "span": list(self.span),
                "overlap": self.overlap}

    def text(self) -> str:
        lo, hi = self.span
        if not self.overlap:
            (a0, a1), (b0, b1) = self.spans
            head = (f"the traces have no tick in common (the first covers {a0}..{a1} ms, "
                    f"the second {b0}..{b1} ms): nothing to compare")
        elif self.same:
            head = f"the traces are the same from {lo} to {hi} ms"
        else:
            what = ", ".join(f"{n} ({a} / {b})" for n, a, b in self.signals)
            if self.events:
                what = (what + ", " if what else "") + "the events"
            head = f"first difference at {self.t_ms} ms: {what}"
        extra = []
        if self.only_in_a:
            extra.append("only in the first: " + ", ".join(self.only_in_a))
        if self.only_in_b:
            extra.append("only in the second: " + ", ".join(self.only_in_b))
        return "\n".join([head, *extra])


def _first_change_difference(a: list, b: list, lo: int, hi: int) -> Optional[int]:
    """The first tick in [lo, hi] where two change lists give different values."""
    ia = ib = 0
    va = vb = None
    times = sorted({t for t, _ in a if t <= hi} | {t for t, _ in b if t <= hi})
    for t in times:
        while ia < len(a) and a[ia][0] <= t:
            va = a[ia][1]
            ia += 1
        while ib < len(b) and b[ib][0] <= t:
            vb = b[ib][1]
            ib += 1
        if t >= lo and va != vb:
            return t
        if t < lo:
            continue
    if va != vb and not times:
        return lo
    return None


def compare(a: Trace, b: Trace) -> Difference:
    """The first difference of ``a`` and ``b`` over the span both cover."""
    names_a, names_b = set(a.signals), set(b.signals)
    diff = Difference(None, only_in_a=sorted(names_a - names_b),
                      only_in_b=sorted(names_b - names_a),
                      spans=((a.t_start, a.t_end), (b.t_start, b.t_end)))
    lo, hi = diff.span
    if hi < lo:
        return diff
    first: Optional[int] = None
    for name in (n for n in a.signals if n in names_b):
        ka, ca = a.signals[name]
        kb, cb = b.signals[name]
        ca = [(t, a.display(name, v)) for t, v in ca]      # text signals by their text
        cb = [(t, b.display(name, v)) for t, v in cb]
        t = _first_change_difference(ca, cb, lo, hi)
        if t is not None and (first is None or t < first):
            first = t
    ea = _events_by_tick(a, lo, hi)
    eb = _events_by_tick(b, lo, hi)
    t_events = next((t for t in sorted(set(ea) | set(eb)) if ea.get(t) != eb.get(t)), None)
    if t_events is not None and (first is None or t_events < first):
        first = t_events
    if first is None:
        return diff
    diff.t_ms = first
    for name in (n for n in a.signals if n in names_b):
        va, vb = a.display(name, a.value_at(name, first)), b.display(name, b.value_at(name, first))
        if va != vb:
            diff.signals.append((name, va, vb))
    diff.events = t_events == first
    return diff


def _events_by_tick(trace: Trace, lo: int, hi: int) -> dict[int, list[str]]:
    out: dict[int, list[str]] = {}
    for e in trace.events:
        t = int(e.get("t_ms", 0))
        if lo <= t <= hi and e.get("type") in COMPARED_EVENTS:
            out.setdefault(t, []).append(json.dumps(e, sort_keys=True))
    return out
