"""Triggers, as on a logic analyser (SPEC §7): a condition on one signal of a
:class:`~plcbuilder.controller.history.History`, and the captures it makes.

Trigger specs (the command line's ``--trigger``, the IDE's trigger bar)::

    in 3 rise          out 7 fall          in 0 edge         (a pin's edge)
    M80.var03 bit 2 rise                                      (a variable's bit)
    adc 0 up 1200      axis Z down -500    M80.timer up 10    (a level crossed)
    proc = 33          proc = plc_proc_probing                (proc becomes a value)
    message            message = 4         message = PLCCMD_LINE_STOP
    print              print = 20001                          (a print to a register)

A crossing *up* is a change from below the level to the level or above; *down*
from the level or above to below it. Numbers are decimal or 0x hex. In a
session that starts at t = 0, outputs, PWM and DAC power on at 0, so what the
first tick sets them to is an edge or a crossing; an input's first value comes
from the machine's wiring and is not.

:class:`Capturer` watches the history as it grows. In ``single`` mode it makes
one capture, in ``normal`` it re-arms after each, and in ``auto`` it also
captures without a trigger when none came for pre + post ms. A capture holds
every signal over [trigger − pre, trigger + post] and completes when the
history reaches trigger + post (or the session ends).
"""

from __future__ import annotations

import re

from plcbuilder._support.records import dataclass
from plcbuilder.bytecode import abi
from plcbuilder.controller.history import History, Trace

TYPE_CHECKING = False               # (typing is not imported at run time: start-up)
if TYPE_CHECKING:
    from typing import Optional

MODES = ("single", "normal", "auto")
EDGES = ("rise", "fall", "edge")
CROSSINGS = ("up", "down")
#: signals a controller powers on at 0: what the first tick sets them to is a change
#: (inputs are not: the machine's wiring gives them their value from the start)
POWER_ON_OFF = ("out ", "pwm ", "dac ")


class TriggerError(ValueError):
    """A trigger spec that cannot be read; the message says what and where."""


@dataclass(frozen=True)
class Trigger:
    """A parsed spec: ``what`` is one of rise/fall/edge/up/down/equals/message/print."""
    spec: str
    what: str
    signal: Optional[str] = None     # the history signal it watches
    bit: Optional[int] = None        # a variable's bit
    value: Optional[int] = None      # level, proc value, message code or print register


_NAMED = re.compile(r"^(in|out|pwm|dac|adc)\s*(\d+)$")
_VAR = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*\.[A-Za-z_][A-Za-z0-9_]*$")


def _number(text: str, spec: str, names: Optional[dict] = None) -> int:
    try:
        return int(text, 0)
    except ValueError:
        pass
    if names is not None and text in names:
        return names[text]
    raise TriggerError(f"trigger {spec!r}: {text!r} is not a number"
                       + (" or a known name" if names is not None else ""))


def _signal(words: list[str], spec: str) -> tuple[str, list[str]]:
    """The signal named at the start of ``words`` and the words after it."""
    if not words:
        raise TriggerError(f"trigger {spec!r}: no signal named")
    head = words[0]
    if head in ("in", "out", "pwm", "dac", "adc"):
        if len(words) < 2 or not words[1].isdigit():
            raise TriggerError(f"trigger {spec!r}: '{head}' needs a number (e.g. '{head} 3')")
        return f"{head} {int(words[1])}", words[2:]
    m = _NAMED.match(head)
    if m:
        return f"{m.group(1)} {int(m.group(2))}", words[1:]
    if head == "axis":
        if len(words) < 2 or words[1].upper() not in abi.AXES:
            raise TriggerError(f"trigger {spec!r}: 'axis' needs an axis letter "
                               f"({', '.join(abi.AXES)})")
        return f"axis {words[1].upper()}", words[2:]
    if _VAR.match(head):
        return head, words[1:]
    raise TriggerError(f"trigger {spec!r}: unknown signal {head!r} (in N, out N, adc N, pwm N, "
                       f"dac N, axis X, PROC.var, proc, message or print)")


def parse_trigger(spec: str) -> Trigger:
    """Read a trigger spec (see the module docstring); raises :class:`TriggerError`."""
    text = " ".join(str(spec).replace(":", " ").replace("=", " = ").split())
    words = text.split()
    if not words:
        raise TriggerError("trigger: empty (e.g. 'out 7 rise', 'adc 0 up 1200', 'proc = 33')")
    head = words[0]
    if head in ("proc", "message", "print"):
        rest = words[1:]
        if rest and rest[0] == "=":
            rest = rest[1:]
            if len(rest) != 1:
                raise TriggerError(f"trigger {spec!r}: '{head} =' needs one value")
        elif rest:
            raise TriggerError(f"trigger {spec!r}: expected '{head} = VALUE', not {' '.join(rest)!r}")
        if head == "proc":
            if not rest:
                raise TriggerError(f"trigger {spec!r}: 'proc' needs '= VALUE'")
            return Trigger(spec, "equals", "proc", value=_number(rest[0], spec, _PROC_NAMES))
        value = _number(rest[0], spec, _MESSAGE_NAMES if head == "message" else None) \
            if rest else None
        if head == "print" and value is not None and not 20000 <= value <= 20100:
            raise TriggerError(f"trigger {spec!r}: print registers are 20000..20100")
        return Trigger(spec, head, "message" if head == "message" else None, value=value)
    signal, rest = _signal(words, spec)
    bit = None
    if rest and rest[0] == "bit":
        if not _VAR.match(signal):
            raise TriggerError(f"trigger {spec!r}: 'bit' applies to a variable (PROC.var bit N)")
        if len(rest) < 2 or not rest[1].isdigit() or not 0 <= int(rest[1]) <= 31:
            raise TriggerError(f"trigger {spec!r}: 'bit' needs a bit number 0..31")
        bit, rest = int(rest[1]), rest[2:]
    if not rest:
        raise TriggerError(f"trigger {spec!r}: say what to wait for: rise, fall, edge, "
                           f"up LEVEL or down LEVEL")
    what = rest[0]
    if what in EDGES:
        if len(rest) > 1:
            raise TriggerError(f"trigger {spec!r}: unexpected {' '.join(rest[1:])!r}")
        digital = signal.startswith(("in ", "out ")) or bit is not None
        if not digital:
            raise TriggerError(f"trigger {spec!r}: edges are of inputs, outputs and variable "
                               f"bits; use 'up LEVEL' or 'down LEVEL' for {signal}")
        return Trigger(spec, what, signal, bit)
    if what in CROSSINGS:
        if len(rest) != 2:
            raise TriggerError(f"trigger {spec!r}: '{what}' needs one level")
        if bit is not None:
            raise TriggerError(f"trigger {spec!r}: a bit has edges, not levels")
        return Trigger(spec, what, signal, value=_number(rest[1], spec))
    raise TriggerError(f"trigger {spec!r}: unknown condition {what!r} (rise, fall, edge, "
                       f"up LEVEL, down LEVEL)")


_PROC_NAMES = {"plc_proc_idle": 0, **abi.PROC}
_MESSAGE_NAMES = {**abi.PLC_BROADCAST, **abi.PLC_MESSAGE, **abi.PLCCMD}


def is_variable(signal: str) -> bool:
    """Whether a history signal is a watched variable (``PROC.var``)."""
    return bool(_VAR.match(str(signal)))


def watched_variables(trigger: Trigger) -> list[str]:
    """The variables the history must record for this trigger."""
    return [trigger.signal] if trigger.signal and is_variable(trigger.signal) else []


class Capturer:
    """Captures of a history by one trigger (see the module docstring)."""

    def __init__(self, history: History, trigger: Trigger, pre_ms: int, post_ms: int,
                 mode: str = "single"):
        if mode not in MODES:
            raise TriggerError(f"trigger mode {mode!r}: one of {', '.join(MODES)}")
        if pre_ms < 0 or post_ms < 0:
            raise TriggerError("pre- and post-trigger times are 0 or more ms")
        self.history, self.trigger = history, trigger
        self.pre, self.post, self.mode = int(pre_ms), int(post_ms), mode
        self.captures: list[Trace] = []
        self.pending: Optional[int] = None     # trigger tick of a capture being completed
        self.armed = True
        self._from = None if history.t_start is None else history.t_end + 1
        self._event_pos = len(history.events)
        self._armed_at = 0 if self._from is None else self._from

    @property
    def done(self) -> bool:
        """A single capture has completed."""
        return self.mode == "single" and bool(self.captures)

    def trigger_now(self) -> None:
        """Trigger at the history's current end ("trigger now")."""
        if self.pending is None and not self.done:
            self.pending = max(self.history.t_end, 0)

    def update(self, final: bool = False) -> list[Trace]:
        """Look at what the history gained since the last call; returns the captures
        completed now. ``final``: the session ended, complete a pending capture."""
        h = self.history
        done: list[Trace] = []
        while True:
            if self.pending is None and self.armed and not self.done:
                t = self._find()
                if t is None and self.mode == "auto" and self._armed_at is not None \
                        and h.t_end - self._armed_at >= self.pre + self.post:
                    t = h.t_end - self.post if self.post <= h.t_end else h.t_end
                if t is None:
                    break
                self.pending = t
            if self.pending is None:
                break
            t = self.pending
            if h.t_end < t + self.post and not final:
                break
            cap = h.snapshot(t - self.pre, min(h.t_end, t + self.post),
                             meta={"trigger": {"spec": self.trigger.spec, "t_ms": t,
                                               "pre_ms": self.pre, "post_ms": self.post,
                                               "mode": self.mode}})
            self.captures.append(cap)
            done.append(cap)
            self.pending = None
            self._from = t + self.post + 1
            self._armed_at = self._from
            if self.mode == "single" or final:
                break
        return done

    def _find(self) -> Optional[int]:
        """The first tick from ``_from`` on where the trigger fires, or None."""
        tr, h = self.trigger, self.history
        start = self._from
        if tr.what == "print":
            events = h.events
            for i in range(self._event_pos, len(events)):
                e = events[i]
                t = int(e.get("t_ms", 0))
                if e.get("type") == "print" and (start is None or t >= start) and \
                        (tr.value is None or e.get("register") == tr.value):
                    self._event_pos = i + 1
                    return t
            self._event_pos = len(events)
            return None
        sig = h.signals.get(tr.signal)
        if sig is None:
            return None
        changes = sig.changes(start, None)
        if not changes:
            return None
        first = changes[0][0]
        prev = sig.value_at(first - 1)
        if prev is None and first == 0 == h.t_start and tr.signal.startswith(POWER_ON_OFF):
            prev = 0        # switched in the first tick: an edge from power-on's 0
        for t, v in changes:
            if self._fires(prev, v):
                return t
            prev = v
        self._from = changes[-1][0] + 1
        return None

    def _fires(self, prev: Optional[int], v: int) -> bool:
        tr = self.trigger
        w = tr.what
        if tr.bit is not None:
            prev = None if prev is None else (prev >> tr.bit) & 1
            v = (v >> tr.bit) & 1
            if prev == v:
                return False
        if w == "rise":
            return v == 1 and prev == 0
        if w == "fall":
            return v == 0 and prev == 1
        if w == "edge":
            return prev is not None and v != prev
        if w == "up":
            return prev is not None and prev < tr.value <= v
        if w == "down":
            return prev is not None and prev >= tr.value > v
        if w == "equals":
            return v == tr.value
        if w == "message":
            return v != 0 and (tr.value is None or v == tr.value)
        return False
