"""A trace as the controller's per-tick samples and events, its watched
variables and the bit its trigger watched, for the run panels (which show a
reopened trace, or a capture, as they show a live controller)."""

from __future__ import annotations

from typing import Optional

from plcbuilder.controller.events import Sample, from_dict
from plcbuilder.controller.history import AXES, TEXT, Trace
from plcbuilder.controller.trigger import TriggerError, is_variable, parse_trigger

WORDS = 8


def to_samples(trace: Trace) -> list[Sample]:
    """One sample at every tick where something changed (each holds until the
    next), and one at the trace's last tick."""
    times = sorted({t for _kind, ch in trace.signals.values() for t, _v in ch} | {trace.t_end})
    cursors = {name: [kind, ch, 0, None] for name, (kind, ch) in trace.signals.items()}

    def advance(t: int) -> None:
        for cur in cursors.values():
            kind, ch, i, v = cur
            while i < len(ch) and ch[i][0] <= t:
                v = ch[i][1]
                i += 1
            cur[2], cur[3] = i, v

    def value(name: str, default: int = 0) -> int:
        cur = cursors.get(name)
        return default if cur is None or cur[3] is None else cur[3]

    def text(name: str) -> Optional[str]:
        cur = cursors.get(name)
        if cur is None or cur[3] is None or cur[0] != TEXT:
            return None
        s = trace.strings[cur[3]] if 0 <= cur[3] < len(trace.strings) else ""
        return s or None

    pins_in = [(int(n[3:]), n) for n in cursors if n.startswith("in ") and n[3:].isdigit()]
    pins_out = [(int(n[4:]), n) for n in cursors if n.startswith("out ") and n[4:].isdigit()]
    out: list[Sample] = []
    for t in times:
        if t < trace.t_start or t > trace.t_end:
            continue
        advance(t)
        ins = [0] * WORDS
        outs = [0] * WORDS
        for pin, name in pins_in:
            if pin < WORDS * 32 and value(name):
                ins[pin // 32] |= 1 << (pin % 32)
        for pin, name in pins_out:
            if pin < WORDS * 32 and value(name):
                outs[pin // 32] |= 1 << (pin % 32)
        out.append(Sample(
            t, text("running"), value("proc"), value("message"), tuple(ins), tuple(outs),
            tuple(value(f"pwm {n}") for n in range(8)), tuple(value(f"dac {n}") for n in range(8)),
            tuple(value(f"adc {n}") for n in range(8)),
            tuple(value(f"axis {a}") for a in AXES), (0,) * len(AXES)))
    return out


def variables_of(trace: Trace) -> dict[str, list[tuple[int, int]]]:
    """The trace's watched variables (its ``PROC.var`` signals): name -> changes,
    over the trace's span."""
    return {name: [(t, v) for t, v in ch if trace.t_start <= t <= trace.t_end]
            for name, (kind, ch) in trace.signals.items()
            if kind != TEXT and is_variable(name)}


def trigger_bits(trace: Trace) -> dict[str, int]:
    """The variable bit a capture's trigger watched (``M80.var03 bit 2 rise``
    gives ``{"M80.var03": 2}``); empty for any other trace."""
    spec = (trace.meta.get("trigger") or {}).get("spec")
    if not spec:
        return {}
    try:
        trig = parse_trigger(spec)
    except TriggerError:
        return {}
    return {trig.signal: trig.bit} if trig.bit is not None and trig.signal else {}


def events_of(trace: Trace) -> list:
    """The trace's events as the controller's event objects (unknown ones left out)."""
    out = []
    for d in trace.events:
        try:
            out.append(from_dict(dict(d)))
        except (TypeError, ValueError):
            continue
    return out
