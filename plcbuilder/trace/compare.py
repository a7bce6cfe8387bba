"""Comparing two traces: the first tick where they differ, and in what.

The second trace can be lined up with the first before they are compared
(``align``): ``"none"`` (the same times: a replay against its session),
``"start"`` (the two starts together: two runs started at different
moments) or ``"trigger"`` (the two captures' triggers together: the before
and after captures of one session), then moved by ``offset_ms`` more. Every
time reported is the first trace's.

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
#: How the second trace can be lined up with the first.
ALIGNS = ("none", "start", "trigger")
#: The largest shift (ms) a comparison takes: 2^53, as trace files' times.
MAX_SHIFT = 1 << 53


class CompareError(ValueError):
    """Traces that cannot be lined up as asked (a trace with no trigger to
    align on); the message says why."""


def trigger_ms(trace: Trace) -> Optional[int]:
    """When a capture's trigger fired (None: not a capture)."""
    trig = trace.meta.get("trigger")
    t = trig.get("t_ms") if isinstance(trig, dict) else None
    return t if isinstance(t, int) and not isinstance(t, bool) else None


def shift_of(a: Trace, b: Trace, align: str = "none", offset_ms: int = 0) -> int:
    """The ms added to ``b``'s times to line it up with ``a`` (see the module
    docstring); raises CompareError."""
    if align not in ALIGNS:
        raise CompareError(f"align on {', '.join(ALIGNS)}, not {align!r}")
    if not -MAX_SHIFT <= offset_ms <= MAX_SHIFT:
        raise CompareError(f"an offset of {offset_ms} ms is more than {MAX_SHIFT} ms either way")
    if align == "start":
        return a.t_start - b.t_start + offset_ms
    if align == "trigger":
        ta, tb = trigger_ms(a), trigger_ms(b)
        missing = [n for n, t in (("first", ta), ("second", tb)) if t is None]
        if missing:
            which = "the first and the second traces have" if len(missing) > 1 else \
                f"the {missing[0]} trace has"
            raise CompareError(f"{which} no trigger (not a capture): align on the start, or "
                               f"none, with an offset")
        return ta - tb + offset_ms
    return offset_ms


def shifted(trace: Trace, dt: int) -> Trace:
    """``trace`` with every time moved by ``dt`` ms (its changes, its span, its
    events and its trigger)."""
    if not dt:
        return trace
    signals = {name: (kind, [(t + dt, v) for t, v in changes])
               for name, (kind, changes) in trace.signals.items()}
    events = [dict(e, t_ms=e["t_ms"] + dt) if isinstance(e.get("t_ms"), int) else dict(e)
              for e in trace.events]
    meta = dict(trace.meta)
    if trigger_ms(trace) is not None:
        meta["trigger"] = dict(meta["trigger"], t_ms=meta["trigger"]["t_ms"] + dt)
    return Trace(trace.t_start + dt, trace.t_end + dt, signals, list(trace.strings), events, meta)


@dataclass
class Difference:
    """Where two traces first differ: ``t_ms`` and, at that tick, each signal with
    its two values (as text), and whether the events differ there."""
    t_ms: Optional[int]                       # None: no difference over the common span
    signals: list[tuple[str, str, str]] = field(default_factory=list)
    events: bool = False
    only_in_a: list[str] = field(default_factory=list)
    only_in_b: list[str] = field(default_factory=list)
    #: the time each trace covers (the second's after its shift)
    spans: tuple[tuple[int, int], tuple[int, int]] = ((0, 0), (0, 0))
    #: how the second trace was lined up, and the ms added to its times
    align: str = "none"
    shift_ms: int = 0

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
                "overlap": self.overlap, "align": self.align, "shift_ms": self.shift_ms}

    def shift_text(self) -> str:
        """``the second trace moved by -4000 ms (triggers together)``, or ''."""
        if not self.shift_ms and self.align == "none":
            return ""
        how = {"none": "", "start": " (starts together)",
               "trigger": " (triggers together)"}[self.align]
        return f"the second trace moved by {self.shift_ms:+d} ms{how}"

    def text(self) -> str:
        lo, hi = self.span
        if not self.overlap:
            (a0, a1), (b0, b1) = self.spans
            head = (f"the traces have no tick in common (the first covers {a0}..{a1} ms, "
                    f"the second {b0}..{b1} ms): nothing to compare")
            if self.align == "none" and not self.shift_ms:
                head += ("; captures of different moments line up with --align trigger "
                         "(or start, or an --offset)")
        elif self.same:
            head = f"the traces are the same from {lo} to {hi} ms"
        else:
            what = ", ".join(f"{n} ({a} / {b})" for n, a, b in self.signals)
            if self.events:
                what = (what + ", " if what else "") + "the events"
            own = f" ({self.t_ms - self.shift_ms} ms in the second)" if self.shift_ms else ""
            head = f"first difference at {self.t_ms} ms{own}: {what}"
        extra = []
        if self.shift_text():
            extra.append(self.shift_text())
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


def compare(a: Trace, b: Trace, align: str = "none", offset_ms: int = 0) -> Difference:
    """The first difference of ``a`` and ``b`` over the span both cover, ``b``
    lined up with ``a`` first (``align``, ``offset_ms``: see the module
    docstring; raises CompareError)."""
    dt = shift_of(a, b, align, offset_ms)
    diff = _compare(a, shifted(b, dt))
    diff.align, diff.shift_ms = align, dt
    return diff


def _compare(a: Trace, b: Trace) -> Difference:
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
        if name.startswith("run "):                       # not started yet: not running
            ca = [(lo, "0")] + ca if not ca or ca[0][0] > lo else ca
            cb = [(lo, "0")] + cb if not cb or cb[0][0] > lo else cb
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
        if name.startswith("run "):
            va, vb = va or "0", vb or "0"
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
