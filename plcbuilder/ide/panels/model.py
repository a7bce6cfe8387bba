"""The run model: telemetry and events of one controller, outside any widget.

Samples (:class:`plcbuilder.controller.events.Sample`) are parsed here, in
batches, into preallocated numpy ring buffers; the plots only read views of
them when the redraw timer fires. Message events are kept in a bounded list, the
watched variables' values (``Watched`` events) in :mod:`.watched`. No Qt.

The controller sends only the ticks where something changed (each sample holds
until the next); :class:`StepSamples` turns those changes into the points a
plot draws (the held value just before each change, and up to the newest tick),
so the model and the plots see the same steps as they would with a sample every
tick.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Iterable, Optional

import numpy as np

from plcbuilder.api import abi
from plcbuilder.api import events as ev
from plcbuilder.ide.panels.steps import StepSamples  # noqa: F401 - part of this module's API
from plcbuilder.ide.panels.watched import WatchedVariables
from plcbuilder.ide.ringbuffer import RingBuffer

__all__ = ["RunModel", "StepSamples", "MessageRow", "decode_message", "ANALOG_NAMES", "AXES", "WORDS", "PINS"]

WORDS = 8                  # input / output words in a sample
PINS = WORDS * 32          # pins a sample can describe
AXES = abi.AXES            # X..W
ANALOG_NAMES = ([f"PWM{i}" for i in range(8)] + [f"DAC{i}" for i in range(8)]
                + [f"ADC{i}" for i in range(8)])
PWM_COLS = range(0, 8)
DAC_COLS = range(8, 16)
ADC_COLS = range(16, 24)
_MASK32 = 0xFFFFFFFF


def decode_message(code: int, command: int, parameter: int) -> str:
    """What a message says beyond its name: ``PLCCMD_REPLY_TO_MYCNC`` carries a
    ``PLC_MESSAGE_*`` code in ``command`` (var00) and its value in ``parameter``
    (var01), as in the manual's spindle-speed example."""
    if code == abi.PLCCMD["PLCCMD_REPLY_TO_MYCNC"]:
        name = abi.message_name(command)
        what = f"{name} ({command})" if name else f"message {command}"
        return f"to myCNC: {what}, parameter {parameter}"
    return ""


@dataclass(frozen=True)
class MessageRow:
    """One message event, decoded for the message log and the proc plot."""
    t_ms: int
    code: int
    name: Optional[str]
    command: int
    parameter: int
    source: str

    @property
    def label(self) -> str:
        return self.name or str(self.code)

    @property
    def meaning(self) -> str:
        return decode_message(self.code, self.command, self.parameter)

    @property
    def short(self) -> str:
        """A marker label: the name, or for a reply to myCNC what it replies."""
        if self.code == abi.PLCCMD["PLCCMD_REPLY_TO_MYCNC"]:
            return f"reply {abi.message_name(self.command) or self.command}"
        return self.label


def _bits_set(mask_words: np.ndarray) -> set[int]:
    out = set()
    for w, word in enumerate(mask_words.tolist()):
        word = int(word)
        while word:
            low = word & -word
            out.add(w * 32 + low.bit_length() - 1)
            word ^= low
    return out


# columns of the per-sample table built by _table
_IN = slice(2, 2 + WORDS)
_OUT = slice(2 + WORDS, 2 + 2 * WORDS)
_ANALOG = slice(2 + 2 * WORDS, 2 + 2 * WORDS + 24)
_MOTION = slice(2 + 2 * WORDS + 24, 2 + 2 * WORDS + 24 + 2 * len(AXES))
_NO_VELOCITIES = (0,) * len(AXES)


def _table(samples: list) -> np.ndarray:
    """The numbers of a batch of samples as one int64 array, a row each:
    proc, message, 8 input words, 8 output words, PWM0-7, DAC0-7, ADC0-7,
    9 positions, 9 velocities. One tuple per sample (the fast path), or
    padded field by field when a sample has short fields."""
    rows = [(s.proc, s.message, *s.inputs, *s.outputs, *s.pwm, *s.dac, *s.adc, *s.axes,
             *(s.velocities or _NO_VELOCITIES)) for s in samples]
    width = _MOTION.stop
    if all(len(r) == width for r in rows):
        return np.array(rows, dtype=np.int64)
    na = len(AXES)
    rows = [(s.proc, s.message, *_fixed([s.inputs], WORDS)[0], *_fixed([s.outputs], WORDS)[0],
             *_fixed([s.pwm], 8)[0], *_fixed([s.dac], 8)[0], *_fixed([s.adc], 8)[0],
             *_fixed([s.axes], na)[0], *_fixed([s.velocities or _NO_VELOCITIES], na)[0])
            for s in samples]
    return np.array(rows, dtype=np.int64)


def _fixed(rows: list, width: int) -> list:
    """Rows of exactly ``width`` values, as tuples (short ones padded with 0)."""
    return [tuple(r) if len(r) == width else (tuple(r) + (0,) * width)[:width] for r in rows]


class RunModel:
    """Live data of a run: ring buffers of every sampled signal.

    ``version`` goes up with every change, so views can redraw only when
    something new arrived. Time is kept in seconds (float), positions in mm,
    velocities in mm/s.
    """

    def __init__(self, capacity: int = 30000, messages: int = 5000):
        self.capacity = int(capacity)
        self.time = RingBuffer(self.capacity, 1, np.float64)
        self.scalars = RingBuffer(self.capacity, 2, np.float64)     # proc, message
        self.inputs = RingBuffer(self.capacity, WORDS, np.uint32)
        self.outputs = RingBuffer(self.capacity, WORDS, np.uint32)
        self.vouts = RingBuffer(self.capacity, 1, np.uint32)        # softMC VOUT.1..32
        self.analog = RingBuffer(self.capacity, 24, np.float64)     # PWM0-7, DAC0-7, ADC0-7
        self.axes = RingBuffer(self.capacity, 2 * len(AXES), np.float64)  # pos mm, vel mm/s
        self.message_limit = int(messages)
        self.messages: list[MessageRow] = []       # oldest first, at most message_limit
        self.message_times: list[float] = []       # their times in seconds (for bisect)
        self.message_version = 0
        #: the watched variables' changes (``Watched`` events, a trace's PROC.var)
        self.watched = WatchedVariables(self.capacity)
        self.version = 0
        self.last_sample: Optional[ev.Sample] = None
        self.running: Optional[str] = None
        self.samples_seen = 0
        self.clear()

    # ------------------------------------------------------------------ state
    def clear(self) -> None:
        """Forget everything (a controller reset or restart)."""
        for rb in (self.time, self.scalars, self.inputs, self.outputs, self.vouts, self.analog,
                   self.axes):
            rb.clear()
        self._out_ever = np.zeros(WORDS, dtype=np.uint32)
        self._vout_ever = 0
        self.active_vouts: set[int] = set()        # bit n-1 for VOUT.n
        self._in_ever_set = np.zeros(WORDS, dtype=np.uint32)
        self._in_ever_clear = np.zeros(WORDS, dtype=np.uint32)
        self._analog_ever = np.zeros(24, dtype=bool)
        self._axes_ever = np.zeros(len(AXES), dtype=bool)
        self._axes_first: Optional[np.ndarray] = None
        self.active_outputs: set[int] = set()
        self.active_inputs: set[int] = set()
        self.proc_values: set[int] = {0}
        self.messages.clear()
        self.message_times.clear()
        self.message_version += 1
        self.watched.clear()
        self.last_sample = None
        self.running = None
        self.epoch = getattr(self, "epoch", -1) + 1
        self.version += 1

    def __len__(self) -> int:
        return len(self.time)

    def resize(self, capacity: int) -> None:
        """Keep up to ``capacity`` samples from now on (a long recorded trace
        shown whole); forgets what it has. The live capacity comes back with
        ``resize(live_capacity)``."""
        capacity = max(1, int(capacity))
        if capacity == self.capacity:
            self.clear()
            return
        self.capacity = capacity
        self.time = RingBuffer(capacity, 1, np.float64)
        self.scalars = RingBuffer(capacity, 2, np.float64)
        self.inputs = RingBuffer(capacity, WORDS, np.uint32)
        self.outputs = RingBuffer(capacity, WORDS, np.uint32)
        self.vouts = RingBuffer(capacity, 1, np.uint32)
        self.analog = RingBuffer(capacity, 24, np.float64)
        self.axes = RingBuffer(capacity, 2 * len(AXES), np.float64)
        self.watched.capacity = capacity
        self.clear()

    def sample_at(self, t: float) -> Optional[dict]:
        """Every value the model holds at time ``t`` (seconds): the newest kept
        sample at or before it, as {"t", "proc", "message", "inputs", "outputs",
        "analog", "positions", "watched"} ("watched": each watched variable's
        value then, None before its first); None before the first sample."""
        times = self.time.view()
        i = int(np.searchsorted(times, t + 1e-9, side="right")) - 1
        if i < 0:
            return None
        na = len(AXES)
        return {"t": float(times[i]),
                "proc": int(self.scalars.view(0)[i]), "message": int(self.scalars.view(1)[i]),
                "inputs": [int(self.inputs.view(w)[i]) for w in range(WORDS)],
                "outputs": [int(self.outputs.view(w)[i]) for w in range(WORDS)],
                "analog": [float(self.analog.view(c)[i]) for c in range(24)],
                "positions": [float(self.axes.view(c)[i]) for c in range(na)],
                "watched": {name: self.watched.value_at(name, t) for name in self.watched.names()}}

    @property
    def t_end(self) -> float:
        """The newest sample's time in seconds (0 when empty)."""
        last = self.time.latest()
        return float(last[0]) if last is not None else 0.0

    def set_watched(self, changes: dict, bits: Optional[dict] = None) -> None:
        """A trace's watched variables (``{name: [(t_ms, value), …]}``) and the
        bit its trigger watched (``{name: bit}``), instead of what was kept."""
        self.watched.set_bits(bits or {})
        self.watched.set_changes(changes)
        self.version += 1

    def set_watch_bits(self, bits: dict) -> None:
        """The bit a trigger watches of a variable (``{name: bit}``): its lane."""
        if self.watched.set_bits(bits):
            self.version += 1

    # ----------------------------------------------------------------- ingest
    def add_samples(self, samples: Iterable[ev.Sample]) -> None:
        """Append a batch of samples (oldest first). A sample older than the
        newest one kept means the controller started over: the model clears."""
        samples = [s for s in samples if isinstance(s, ev.Sample)]
        if not samples:
            return
        n = len(samples)
        t_ms = np.fromiter((s.t_ms for s in samples), dtype=np.float64, count=n)
        if len(self.time) and t_ms[0] * 1e-3 < self.t_end:
            self.clear()
        if n > 1 and np.any(np.diff(t_ms) < 0):     # a restart inside the batch
            cut = int(np.nonzero(np.diff(t_ms) < 0)[0][-1]) + 1
            self.clear()
            samples, t_ms, n = samples[cut:], t_ms[cut:], n - cut
        if self._holds(samples):
            # only time advanced (the held value again, as the telemetry's steps
            # are while nothing changes): the newest row again, nothing new to find
            self.time.extend(t_ms * 1e-3)
            for rb in self._value_buffers():
                rb.repeat_last(n)
            self.last_sample = samples[-1]
            self.samples_seen += n
            self.version += 1
            return
        self.time.extend(t_ms * 1e-3)
        table = _table(samples)                      # one int64 row per sample
        self.scalars.extend(table[:, 0:2])
        ins = (table[:, _IN] & _MASK32).astype(np.uint32)
        outs = (table[:, _OUT] & _MASK32).astype(np.uint32)
        self.inputs.extend(ins)
        self.outputs.extend(outs)
        vouts = np.fromiter((s.vio[1] if len(s.vio) > 1 else 0 for s in samples),
                            dtype=np.int64, count=n)
        self.vouts.extend((vouts & _MASK32).astype(np.uint32).reshape(n, 1))
        vout_or = int(np.bitwise_or.reduce(vouts)) & _MASK32
        if vout_or & ~self._vout_ever:
            self._vout_ever |= vout_or
            self.active_vouts = _bits_set(np.array([self._vout_ever], dtype=np.uint32))
        analog = table[:, _ANALOG].astype(np.float64)
        self.analog.extend(analog)
        motion = table[:, _MOTION] * 0.01            # 0.01 mm -> mm, 0.01 mm/s -> mm/s
        self.axes.extend(motion)
        na = len(AXES)
        pos, vel = motion[:, :na], motion[:, na:]

        # what is worth showing: outputs ever on, inputs that changed, analog
        # channels ever non-zero, axes that moved (or sit off zero)
        out_or = np.bitwise_or.reduce(outs, axis=0)
        if np.any(out_or & ~self._out_ever):
            self._out_ever |= out_or
            self.active_outputs = _bits_set(self._out_ever)
        in_set = np.bitwise_or.reduce(ins, axis=0)
        in_clear = np.bitwise_or.reduce(~ins, axis=0)
        if np.any(in_set & ~self._in_ever_set) or np.any(in_clear & ~self._in_ever_clear):
            self._in_ever_set |= in_set
            self._in_ever_clear |= in_clear
            self.active_inputs = _bits_set(self._in_ever_set & self._in_ever_clear)
        self._analog_ever |= np.any(analog != 0, axis=0)
        if self._axes_first is None:
            self._axes_first = pos[0].copy()
        self._axes_ever |= (np.any(pos != self._axes_first, axis=0) | np.any(pos != 0, axis=0)
                            | np.any(vel != 0, axis=0))
        # (not np.unique: it loads numpy.ma, 18 ms on the way to the first redraw)
        self.proc_values.update(int(p) for p in set(self.scalars.views(last=n)[0].tolist()))

        self.last_sample = samples[-1]
        self.running = samples[-1].running
        self.samples_seen += n
        self.version += 1

    def _holds(self, samples: list) -> bool:
        """Whether every sample of a batch holds the newest one kept: the same
        values (no message), only a later time."""
        last = self.last_sample
        if last is None or not len(self.time) or last.message:
            return False
        key = (last.running, last.proc, last.inputs, last.outputs, last.pwm, last.dac,
               last.adc, last.axes, last.velocities, last.vio)
        return all(not s.message and (s.running, s.proc, s.inputs, s.outputs, s.pwm, s.dac,
                                      s.adc, s.axes, s.velocities, s.vio) == key
                   for s in samples)

    def _value_buffers(self) -> tuple:
        return (self.scalars, self.inputs, self.outputs, self.vouts, self.analog, self.axes)

    def add_events(self, events: Iterable) -> list[MessageRow]:
        """Keep the message events and the watched variables' values (the log
        panel keeps the rest); returns the new message rows."""
        events = list(events)
        if self.watched.add_events(events):
            self.version += 1
        new: list[MessageRow] = []
        for e in events:
            if isinstance(e, ev.Message):
                name = e.name if e.name is not None else abi.message_name(e.message)
                row = MessageRow(e.t_ms, e.message, name, e.command, e.parameter, e.source)
                self.messages.append(row)
                self.message_times.append(e.t_ms * 1e-3)
                new.append(row)
        over = len(self.messages) - self.message_limit
        if over > 0:
            over = max(over, self.message_limit // 10)
            del self.messages[:over]
            del self.message_times[:over]
        if new:
            self.message_version += 1
            self.version += 1
        return new

    # ------------------------------------------------------------------ query
    def active_analog(self) -> list[int]:
        return [int(i) for i in np.nonzero(self._analog_ever)[0]]

    def active_axes(self) -> list[int]:
        return [int(i) for i in np.nonzero(self._axes_ever)[0]]

    def window(self, t0: float, t1: float, pad: int = 1) -> tuple[int, int]:
        """The index range ``[a, b)`` of the kept samples with time in
        ``[t0, t1]``, widened by ``pad`` samples each side."""
        t = self.time.view()
        a = int(np.searchsorted(t, t0, side="left")) - pad
        b = int(np.searchsorted(t, t1, side="right")) + pad
        n = len(t)
        return max(0, min(a, n)), max(0, min(b, n))

    def words(self, which: str) -> RingBuffer:
        """The ring buffer of ``which``: "outputs", "inputs" or "vouts" (VOUT.n is
        bit n-1 of its one word)."""
        return {"outputs": self.outputs, "inputs": self.inputs, "vouts": self.vouts}[which]

    def bit_series(self, which: str, pin: int, a: int = 0, b: Optional[int] = None) -> np.ndarray:
        """Pin ``pin`` of the inputs, outputs or virtual outputs (``which``; bit
        n-1 for VOUT.n) over samples [a, b), 0/1 as uint8."""
        rb = self.words(which)
        words = rb.view(pin // 32)[a:b]
        return ((words >> np.uint32(pin % 32)) & np.uint32(1)).astype(np.uint8)

    def pin_state(self, which: str, pin: int) -> Optional[int]:
        """The newest sample's state of a pin, or None without samples."""
        s = self.last_sample
        if s is None:
            return None
        words = {"outputs": s.outputs, "inputs": s.inputs, "vouts": s.vio[1:]}[which]
        if pin // 32 >= len(words):
            return 0
        return (int(words[pin // 32]) >> (pin % 32)) & 1
