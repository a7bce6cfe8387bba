"""A session's whole history, kept as changes (SPEC §7), and its snapshots.

    h = History(machine)            # the signals this machine has
    h.feed(rows, events)            # Controller.drain_sample_rows() / drain_events()
    h.watch(t, "M80.var03", 5)      # a watched variable's value at the end of tick t
                                    # (a ``watch`` event fed does the same)
    trace = h.snapshot(t0, t1)      # a Trace: every signal over [t0, t1]

A signal is a list of changes ``(t_ms, value)``: the value holds from its tick
until the next change. Signals are named as the command line names things:
``in N`` and ``out N`` (bits), ``pwm N``, ``dac N``, ``adc N``, ``proc``,
``message`` (the code sent at the end of a tick, 0 in the other ticks),
``running`` (the hardware procedure, a text signal), ``axis X`` (machine
position, 0.01 mm), ``run NAME`` (1 while a procedure runs) and ``PROC.var``
(a watched variable).

Memory: changes go into chunks of :data:`CHUNK` entries; a full chunk is delta
encoded and compressed, so a signal that toggles every tick for an hour costs a
few hundred kilobytes, not the 16 bytes a change of a plain list would.
"""

from __future__ import annotations

import bisect
import zlib
from array import array

from plcbuilder._support.records import dataclass, field
from plcbuilder.bytecode import abi
from plcbuilder.controller.events import to_dict

TYPE_CHECKING = False               # (typing is not imported at run time: start-up)
if TYPE_CHECKING:
    from typing import Iterable, Iterator, Optional

#: changes per chunk before it is compressed
CHUNK = 1024
#: signal kinds
BIT, INT, TEXT = "bit", "int", "text"
#: the axes a history may hold, in their order (X..W)
AXES = abi.AXES


class Signal:
    """One signal's changes, oldest first, with at most one change a tick."""

    __slots__ = ("name", "kind", "_t", "_v", "_chunks", "_firsts", "_count", "_cache")

    def __init__(self, name: str, kind: str = INT):
        self.name = name
        self.kind = kind
        self._t = array("q")             # the open chunk
        self._v = array("q")
        self._chunks: list[tuple[int, int, bytes]] = []   # (first t, count, packed)
        self._firsts: list[int] = []
        self._count = 0
        self._cache: Optional[tuple[int, array, array]] = None

    def __len__(self) -> int:
        return self._count

    @property
    def last(self) -> Optional[int]:
        """The value now (None before the first change)."""
        if self._v:
            return self._v[-1]
        if self._chunks:
            return self._unpack(len(self._chunks) - 1)[1][-1]
        return None

    @property
    def last_t(self) -> Optional[int]:
        if self._t:
            return self._t[-1]
        if self._chunks:
            return self._unpack(len(self._chunks) - 1)[0][-1]
        return None

    def append(self, t: int, value: int) -> bool:
        """Record ``value`` from tick ``t`` on; False when it is no change. A second
        change in the same tick replaces the first (what held at the tick's end)."""
        ts, vs = self._t, self._v
        if ts:
            if vs[-1] == value:
                return False
            if ts[-1] == t:
                vs[-1] = value
                if len(vs) > 1 and vs[-2] == value:    # back to what it was: no change
                    ts.pop()
                    vs.pop()
                    self._count -= 1
                return True
        elif self._chunks and self.last == value:
            return False
        ts.append(t)
        vs.append(value)
        self._count += 1
        if len(ts) >= CHUNK:
            self._seal()
        return True

    def _seal(self) -> None:
        ts, vs = self._t, self._v
        dt = array("q", [ts[0]]) + array("q", (ts[i] - ts[i - 1] for i in range(1, len(ts))))
        dv = array("q", [vs[0]]) + array("q", (vs[i] - vs[i - 1] for i in range(1, len(vs))))
        self._chunks.append((ts[0], len(ts), zlib.compress(dt.tobytes() + dv.tobytes(), 1)))
        self._firsts.append(ts[0])
        self._t, self._v = array("q"), array("q")

    def _unpack(self, i: int) -> tuple[array, array]:
        c = self._cache
        if c is not None and c[0] == i:
            return c[1], c[2]
        _first, n, blob = self._chunks[i]
        raw = array("q")
        raw.frombytes(zlib.decompress(blob))
        ts, vs = array("q"), array("q")
        acc = 0
        for d in raw[:n]:
            acc += d
            ts.append(acc)
        acc = 0
        for d in raw[n:]:
            acc += d
            vs.append(acc)
        self._cache = (i, ts, vs)
        return ts, vs

    def _parts(self) -> Iterator[tuple[array, array]]:
        for i in range(len(self._chunks)):
            yield self._unpack(i)
        if self._t:
            yield self._t, self._v

    def changes(self, t0: Optional[int] = None, t1: Optional[int] = None) -> list[tuple[int, int]]:
        """The changes with t0 <= t <= t1 (either bound None: open)."""
        out: list[tuple[int, int]] = []
        start = 0
        if t0 is not None and self._chunks:
            start = max(0, bisect.bisect_right(self._firsts, t0) - 1)
        parts = [self._unpack(i) for i in range(start, len(self._chunks))]
        if self._t:
            parts.append((self._t, self._v))
        for ts, vs in parts:
            if t1 is not None and ts and ts[0] > t1:
                break
            lo = 0 if t0 is None else bisect.bisect_left(ts, t0)
            hi = len(ts) if t1 is None else bisect.bisect_right(ts, t1)
            out.extend(zip(ts[lo:hi], vs[lo:hi]))
        return out

    def value_at(self, t: int) -> Optional[int]:
        """The value that holds at the end of tick t (None before the first change)."""
        if self._t and self._t[0] <= t:
            ts, vs = self._t, self._v
        else:
            i = bisect.bisect_right(self._firsts, t) - 1
            if i < 0:
                return None
            ts, vs = self._unpack(i)
        j = bisect.bisect_right(ts, t) - 1
        return vs[j] if j >= 0 else None

    def nbytes(self) -> int:
        """Memory the changes take (approximately)."""
        return (sum(len(b) + 64 for _f, _n, b in self._chunks)
                + (self._t.itemsize * (len(self._t) + len(self._v))) + 200)


@dataclass
class Trace:
    """Every signal over [t_start, t_end] (inclusive), and the events of that time;
    what a capture, a saved session or a reopened trace file holds. ``signals``
    keep their changes (each signal's first change is its value at ``t_start``
    when it had one); ``strings`` names the values of text signals."""
    t_start: int
    t_end: int
    signals: dict[str, tuple[str, list[tuple[int, int]]]] = field(default_factory=dict)
    strings: list[str] = field(default_factory=list)
    events: list[dict] = field(default_factory=list)
    meta: dict = field(default_factory=dict)

    def value_at(self, name: str, t: int) -> Optional[int]:
        """The value of a signal at the end of tick t (None before its first change)."""
        kind, changes = self.signals[name]
        i = bisect.bisect_right(changes, (t, float("inf"))) - 1
        return changes[i][1] if i >= 0 else None

    def display(self, name: str, value: Optional[int]) -> str:
        """A value as text (a text signal's name; '' for None)."""
        if value is None:
            return ""
        if self.signals[name][0] == TEXT:
            return self.strings[value] if 0 <= value < len(self.strings) else "?"
        return str(value)


class History:
    """The session's signals (see the module docstring), fed from the controller."""

    def __init__(self, machine=None, *, input_count: Optional[int] = None,
                 output_count: Optional[int] = None, axes: Iterable[str] = ()):
        n_in = input_count if input_count is not None else getattr(machine, "input_count", 64)
        n_out = output_count if output_count is not None else getattr(machine, "output_count", 64)
        if machine is not None and not axes:
            axes = list(machine.axis_positions())
        self.input_count, self.output_count = int(n_in), int(n_out)
        self.axes = [a for a in axes if a in abi.AXES]
        self._axis_idx = [abi.AXES.index(a) for a in self.axes]
        self.signals: dict[str, Signal] = {}
        self.strings: list[str] = [""]
        self._string_ids: dict[str, int] = {"": 0}
        self.events: list[dict] = []
        self.t_start: Optional[int] = None
        self.t_end: int = -1
        self._last_fields = None
        self._message_reset: Optional[int] = None
        for n in range(self.input_count):
            self._add(f"in {n}", BIT)
        for n in range(self.output_count):
            self._add(f"out {n}", BIT)
        for bank in ("pwm", "dac", "adc"):
            for n in range(8):
                self._add(f"{bank} {n}", INT)
        for a in self.axes:
            self._add(f"axis {a}", INT)
        self._add("proc", INT)
        self._add("message", INT)
        self._add("running", TEXT)

    def _add(self, name: str, kind: str) -> Signal:
        s = self.signals.get(name)
        if s is None:
            s = self.signals[name] = Signal(name, kind)
        return s

    def _string(self, text: Optional[str]) -> int:
        text = text or ""
        i = self._string_ids.get(text)
        if i is None:
            i = self._string_ids[text] = len(self.strings)
            self.strings.append(text)
        return i

    # ------------------------------------------------------------- feeding

    def feed(self, rows: Iterable[tuple] = (), events: Iterable = ()) -> None:
        """Sample rows ``(t, running, proc, message, fields)`` as the controller
        records them (changes only is enough), and events (objects or dicts)."""
        sig = self.signals
        for t, running, proc, msg, f in rows:
            self._seen(t)
            if self._message_reset is not None and self._message_reset <= t:
                sig["message"].append(self._message_reset, 0)
                self._message_reset = None
            if msg:
                sig["message"].append(t, msg)
                self._message_reset = t + 1
            elif not len(sig["message"]):
                sig["message"].append(t, 0)
            sig["proc"].append(t, proc)
            sig["running"].append(t, self._string(running))
            if f is not self._last_fields:
                self._fields(t, f, self._last_fields)
                self._last_fields = f
        for e in events:
            d = e if isinstance(e, dict) else to_dict(e)
            t = int(d.get("t_ms", 0))
            self._seen(t)
            kind = d.get("type")
            if kind == "watch":                 # a watched variable: a signal, not an event
                self.watch(t, str(d.get("name")), int(d.get("value", 0)))
                continue
            self.events.append(d)
            if kind == "started":
                self._add(f"run {d['name']}", BIT).append(t, 1)
            elif kind == "ended":
                self._add(f"run {d['name']}", BIT).append(t, 0)

    def feed_samples(self, samples: Iterable, events: Iterable = ()) -> None:
        """The same from :class:`~plcbuilder.controller.events.Sample` objects
        (what a client of the controller's server receives)."""
        rows = []
        last = None
        for s in samples:
            f = {"inputs": tuple(s.inputs), "outputs": tuple(s.outputs), "pwm": tuple(s.pwm),
                 "dac": tuple(s.dac), "adc": tuple(s.adc), "axes": tuple(s.axes)}
            if last is not None and f == last:
                f = last
            rows.append((s.t_ms, s.running, s.proc, s.message, f))
            last = f
        if rows and self._last_fields is not None and rows[0][4] == self._last_fields:
            rows[0] = rows[0][:4] + (self._last_fields,)
        self.feed(rows, events)

    def _fields(self, t: int, f: dict, old: Optional[dict]) -> None:
        sig = self.signals
        for bank, count in (("in", self.input_count), ("out", self.output_count)):
            words = f["inputs" if bank == "in" else "outputs"]
            before = old["inputs" if bank == "in" else "outputs"] if old else None
            for w, word in enumerate(words):
                if before is not None and w >= len(before):
                    before = None               # a sample with more words: all of them new
                base = w * 32
                if base >= count:
                    break
                diff = word ^ before[w] if before is not None else 0xFFFFFFFF
                while diff:
                    low = diff & -diff
                    b = low.bit_length() - 1
                    diff ^= low
                    if base + b < count:
                        sig[f"{bank} {base + b}"].append(t, (word >> b) & 1)
        for bank in ("pwm", "dac", "adc"):
            vals = f[bank]
            before = old[bank] if old else None
            if before is None or vals != before:
                for n, v in enumerate(vals[:8]):
                    sig[f"{bank} {n}"].append(t, v)
        axes = f["axes"]
        if old is None or axes != old["axes"]:
            for a, i in zip(self.axes, self._axis_idx):
                if i < len(axes):               # a sample may carry fewer axes
                    sig[f"axis {a}"].append(t, axes[i])

    def watch(self, t: int, name: str, value: int) -> None:
        """A watched value (a variable ``PROC.var``) at the end of tick t."""
        self._seen(t)
        self._add(name, INT).append(t, value)

    def _seen(self, t: int) -> None:
        if self.t_start is None or t < self.t_start:
            self.t_start = t
        if t > self.t_end:
            self.t_end = t

    def advance_to(self, t: int) -> None:
        """The session has run to the end of tick t (nothing changed since)."""
        if self._message_reset is not None and self._message_reset <= t:
            self.signals["message"].append(self._message_reset, 0)
            self._message_reset = None
        self._seen(t)

    # ------------------------------------------------------------- reading

    def nbytes(self) -> int:
        """Memory the history takes (approximately)."""
        return sum(s.nbytes() for s in self.signals.values()) + 300 * len(self.events)

    def snapshot(self, t0: Optional[int] = None, t1: Optional[int] = None,
                 meta: Optional[dict] = None) -> Trace:
        """Every signal and event over [t0, t1] (default: the whole session)."""
        start = self.t_start if self.t_start is not None else 0
        t0 = start if t0 is None else max(t0, start)
        t1 = self.t_end if t1 is None else t1
        signals = {}
        for name, s in self.signals.items():
            ch = s.changes(t0, t1)
            v0 = s.value_at(t0)
            if v0 is not None and (not ch or ch[0][0] != t0):
                ch.insert(0, (t0, v0))
            signals[name] = (s.kind, ch)
        events = [e for e in self.events if t0 <= int(e.get("t_ms", 0)) <= t1]
        return Trace(t0, max(t0, t1), signals, list(self.strings), events, dict(meta or {}))
