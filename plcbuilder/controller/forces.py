"""Write and force (SPEC §6): a debugger setting values in the running controller.

Targets are named as the command line names them::

    PROC.var    a procedure's variable (M03.speed, OFF.timer, __HANDLER_INIT.var00)
    in N        input N                 out N    output N
    adc N       ADC channel 0..7        pwm N    PWM channel 0..7
    dac N       DAC channel 0..7        gvar N   global register N (decimal or 0x…)

**Write** sets a value once. **Force** holds it: every read returns the forced
value and the program's writes are discarded until the force is released; the
engine still remembers the program's last write (its *would-be* value).
**Release** either keeps the current value (``keep``) or restores the value the
program would have now (``restore``): a variable or register takes the value
the program last stored, an output what the program last set, and an input or
ADC channel goes back to the machine's wiring (also when it was set by hand, not
forced: that is how a hand-set input is released).

Where the value is held:
- inputs, outputs, ADC, PWM, DAC and registers in the machine
  (:meth:`Machine.force_input` …), which the fast backend reads as it always does;
- a variable in its procedure's slots, a :class:`ForcedSlots` list, which only the
  reference interpreter runs over: forcing a variable of a running procedure
  hands it over there from the tick end where it is (``vm.HANDOVER``), and a
  procedure started while one of its variables is forced starts there. It
  stays on the reference interpreter until it ends.

Forces survive Build All (:meth:`Forces.on_load` applies them to the new
procedures; one whose procedure or variable is gone is released with a note).
Nothing here imports the controller: it raises :class:`ForceError`, which the
controller turns into its own ControllerError.
"""

from __future__ import annotations

import re

from plcbuilder._support.lazy import Pattern
from plcbuilder._support.records import dataclass
from plcbuilder._support.numbers import WORD32, to_int32
from plcbuilder.bytecode import abi
from plcbuilder.bytecode.program import Kind
from plcbuilder.controller.events import Forces as ForcesEvent
from plcbuilder.controller.events import Note
from plcbuilder.controller.vm import HANDOVER, Handoff, run_reference

TYPE_CHECKING = False               # (typing is not imported at run time: start-up)
if TYPE_CHECKING:
    from typing import Optional

__all__ = ["ForceError", "ForcedSlots", "Forces", "Target", "parse_target", "parse_value",
           "MODES"]

MODES = ("keep", "restore")
_CHANNELS = 8
_PIN = Pattern(r"^\s*(in|out|adc|pwm|dac|gvar)\s*(-?(?:0x[0-9a-f]+|\d+))\s*$", re.I)
_VAR = Pattern(r"^\s*([A-Za-z_][A-Za-z0-9_]*)\.([A-Za-z_][A-Za-z0-9_]*)\s*$")
_USAGE = "PROC.var, in N, out N, adc N, pwm N, dac N or gvar N"


class ForceError(ValueError):
    """A write, force or release that cannot be done; the message says why."""


class ForcedSlots(list):
    """A procedure's variable slots with some held: a store to a held slot only
    records the program's would-be value (``held[slot]``); the list keeps the
    forced value, so every read sees it."""

    __slots__ = ("held",)

    def __init__(self, values):
        super().__init__(values)
        self.held: dict[int, int] = {}

    def __setitem__(self, i, v):
        if i.__class__ is int and i in self.held:
            self.held[i] = v
        else:
            list.__setitem__(self, i, v)

    def hold(self, slot: int, value: int) -> None:
        """Force ``slot`` to ``value`` (the would-be value is what it holds now)."""
        if slot not in self.held:
            self.held[slot] = list.__getitem__(self, slot)
        list.__setitem__(self, slot, value)

    def release(self, slot: int, restore: bool) -> None:
        if slot in self.held:
            would = self.held.pop(slot)
            if restore:
                list.__setitem__(self, slot, would)


@dataclass(frozen=True)
class Target:
    """A parsed target: ``kind`` is var, in, out, adc, pwm, dac or reg."""
    kind: str
    n: int = 0                       # pin, channel or register address
    proc: str = ""
    var: str = ""

    @property
    def name(self) -> str:
        """The canonical name (``M03.speed``, ``in 4``, ``gvar 5000``)."""
        if self.kind == "var":
            return f"{self.proc}.{self.var}"
        return f"{'gvar' if self.kind == 'reg' else self.kind} {self.n}"


def parse_target(text) -> Target:
    """A target from its name; a register that is a pin or channel (0x400 + n,
    PWM, DAC, ADC) is named as that pin or channel."""
    if not isinstance(text, str):
        raise ForceError(f"a target is a name ({_USAGE}), not {text!r}")
    m = _PIN.match(text)
    if m:
        kind, n = m.group(1).lower(), int(m.group(2), 0)
        if kind != "gvar":
            return Target(kind, n)
        return _register(n)
    m = _VAR.match(text)
    if m:
        return Target("var", proc=m.group(1), var=m.group(2))
    raise ForceError(f"{text!r} is not a target: name {_USAGE}")


def _register(addr: int) -> Target:
    if abi.OUTPUT_STATE_BASE <= addr < abi.OUTPUT_STATE_BASE + 256:
        return Target("out", addr - abi.OUTPUT_STATE_BASE)
    for kind, base in (("pwm", abi.GVAR_HW_PWM0), ("dac", abi.GVAR_HW_DAC0),
                       ("adc", abi.GVAR_HW_ADC0)):
        if base <= addr < base + _CHANNELS:
            return Target(kind, addr - base)
    if addr in abi.GVAR_HW_INPUTS or addr in abi.GVAR_HW_OUTPUTS:
        word = "input" if addr in abi.GVAR_HW_INPUTS else "output"
        raise ForceError(f"gvar {addr} is an {word} word: write or force its pins "
                         f"({'in' if word == 'input' else 'out'} N)")
    return Target("reg", addr)


def parse_value(value, what: str = "value") -> int:
    """An integer value (int, or text in decimal or 0x hex), a 32-bit word held signed."""
    if isinstance(value, bool):
        value = int(value)
    elif not isinstance(value, int):
        try:
            value = int(str(value).strip(), 0)
        except ValueError:
            raise ForceError(f"{what} must be an integer, not {value!r}") from None
    lo, hi = WORD32
    if not lo <= value <= hi:
        raise ForceError(f"{what} {value} does not fit 32 bits")
    return to_int32(value)


class Forces:
    """The forces of one controller: over its PLC (``plc``) and machine."""

    def __init__(self, plc, machine):
        self.plc = plc
        self.machine = machine
        #: canonical target name -> [Target, value, since_ms, slot (variables)]
        self._held: dict[str, list] = {}
        #: variable forces not yet applied to their running procedure (it waits
        #: for a gvarget's latency): tried again before each step
        self.pending: set[str] = set()

    # --------------------------------------------------------------- list
    def __call__(self) -> list[dict]:
        """``controller.forces()``: the same as :meth:`list`."""
        return self.list()

    def list(self) -> list[dict]:
        """Everything forced: ``{target, value, since_ms}``, in the order forced."""
        return [{"target": name, "value": v, "since_ms": since}
                for name, (_t, v, since, _s) in self._held.items()]

    def check(self, target) -> str:
        """The canonical name of a target that exists; ForceError otherwise."""
        return self._resolve(target)[0].name

    def is_forced(self, target) -> bool:
        return self._resolve(target)[0].name in self._held

    # ------------------------------------------------------------ actions
    def write(self, target, value) -> str:
        """Set ``target`` to ``value`` once; on a forced target, the forced value
        changes. Returns the canonical target name."""
        t, slot = self._resolve(target)
        value = self._value(t, value)
        if t.name in self._held:
            return self.force(t.name, value)
        m = self.machine
        if t.kind == "var":
            p = self._running(t)
            if p is None:
                raise ForceError(f"{t.proc} is not running: a write sets a running "
                                 f"procedure's variable (a force also holds it from its start)")
            p.sync()
            p.slots[slot] = value
        elif t.kind == "in":
            m.set_input(t.n, value)
        elif t.kind == "out":
            (m.portset if value else m.portclear)(t.n)
        elif t.kind == "adc":
            m.set_adc(t.n, value)
        else:
            addr = self._address(t)
            if not m.writable_register(addr):
                what = abi.describe_register(addr) or f"register {addr}"
                raise ForceError(f"gvar {addr} ({what}) is read-only")
            m.gvarset(addr, value)
        return t.name

    def force(self, target, value) -> str:
        """Hold ``target`` at ``value`` until released. Returns the canonical name."""
        t, slot = self._resolve(target)
        value = self._value(t, value)
        m = self.machine
        if t.kind == "var":
            self.plc.var_forces.setdefault(t.proc, {})[slot] = value
            self._hold_running(t, slot, value)
        elif t.kind == "in":
            m.force_input(t.n, value)
        elif t.kind == "out":
            m.force_output(t.n, value)
        elif t.kind == "adc":
            m.force_adc(t.n, value)
        else:
            addr = self._address(t)
            if not m.forceable_register(addr):
                what = abi.describe_register(addr) or f"register {addr}"
                raise ForceError(f"gvar {addr} ({what}) is the machine's own: it cannot be "
                                 f"forced (a plain register, PWM or DAC can)")
            m.force_register(addr, value)
        old = self._held.get(t.name)
        since = old[2] if old is not None else self.plc.t
        self._held[t.name] = [t, value, since, slot]
        self._changed()
        return t.name

    def release(self, target, mode: str = "restore") -> str:
        """Release ``target``: ``keep`` its current value or ``restore`` the
        program's (for an input or ADC channel: the wiring, also when it was
        set by hand). Releasing what is not forced changes nothing else."""
        restore = self._mode(mode)
        t, slot = self._resolve(target)
        held = self._held.pop(t.name, None)
        m = self.machine
        if t.kind == "var":
            forced = self.plc.var_forces.get(t.proc, {})
            forced.pop(slot, None)
            if not forced:
                self.plc.var_forces.pop(t.proc, None)
            self.pending.discard(t.name)
            p = self._running(t)
            if p is not None and held is not None and isinstance(p.slots, ForcedSlots):
                p.slots.release(slot, restore)      # it stays on the reference interpreter
        elif t.kind == "in":
            m.release_input(t.n, restore)
        elif t.kind == "out":
            m.release_output(t.n, restore)
        elif t.kind == "adc":
            m.release_adc(t.n, restore)
        else:
            m.release_register(self._address(t), restore)
        if held is not None:
            self._changed()
        return t.name

    def release_all(self, mode: str = "restore") -> list[str]:
        """Release everything forced; returns the names released."""
        self._mode(mode)
        names = list(self._held)
        for name in names:
            self.release(name, mode)
        return names

    # ------------------------------------------------------------- events
    def on_load(self) -> None:
        """After Build All: the variable forces apply to the new procedures by
        name; one whose procedure or variable is gone is released, with a note."""
        plc = self.plc
        plc.var_forces = {}
        gone = []
        for name, entry in list(self._held.items()):
            t = entry[0]
            if t.kind != "var":
                continue
            try:
                _t, slot = self._resolve(name)
            except ForceError as exc:
                gone.append((name, str(exc)))
                del self._held[name]
                self.pending.discard(name)
                continue
            entry[3] = slot
            plc.var_forces.setdefault(t.proc, {})[slot] = entry[1]
        for name, why in gone:
            plc.events.append(Note(plc.t, f"force of {name} released after the build: {why}",
                                   "warning"))
        if gone:
            self._changed()

    def retry_pending(self) -> None:
        """Apply variable forces whose procedure could not change over before."""
        for name in list(self.pending):
            entry = self._held.get(name)
            if entry is None:
                self.pending.discard(name)
                continue
            self.pending.discard(name)
            self._hold_running(entry[0], entry[3], entry[1])

    # ------------------------------------------------------------ helpers
    def _hold_running(self, t: Target, slot: int, value: int) -> None:
        p = self._running(t)
        if p is not None and not self._hold_slot(p, slot, value):
            self.pending.add(t.name)

    def _hold_slot(self, p, slot: int, value: int) -> bool:
        """Force variable ``slot`` of the running process ``p`` to ``value``: p
        goes on, from where it is, on the reference interpreter over
        :class:`ForcedSlots`. False when p cannot change over now (it waits for
        a gvarget's latency): then it is tried again before the next step."""
        if not isinstance(p.slots, ForcedSlots) and not self._hand_over(p):
            return False
        p.slots.hold(slot, value)
        return True

    def _hand_over(self, p) -> bool:
        """Run ``p`` on the reference interpreter over ForcedSlots from where it is."""
        gen = p.runner
        if p.ended_at is not None or gen is None:
            return False
        kw = {}
        dbg = self.plc.debugger
        h = dbg.halt if dbg is not None else None
        if h is not None and h.process is p and h.pc is not None and self.plc.mid_tick:
            # halted before a statement: it is on the reference interpreter already
            # (started, or handed over by the fast backend and not started yet), and
            # goes on from that statement, not asked about it again
            here = gen.gi_frame.f_locals if gen.gi_frame is not None else {}
            kw = dict(pc=h.pc, stack=list(here.get("stack") or ()), rets=h.rets,
                      count=int(here.get("count") or 0), passed=h.pc)
        elif gen.gi_suspended:            # at a tick end
            try:
                p.sync()                   # (one that keeps locals takes HANDOVER after SYNC)
                gen.send(HANDOVER)
            except Handoff as h:
                kw = dict(pc=h.pc, stack=h.stack, rets=h.rets, count=h.count)
            else:
                return False               # waiting for a gvarget: no handover there
        elif gen.gi_frame is None or gen.gi_running:
            return False
        # (not started yet: the reference interpreter starts it from its entry)
        p.slots = ForcedSlots(p.slots)
        new = run_reference(p.program, p.slots, p.host, cover=self.plc.coverage, **kw)
        p.set_gen(new)                     # (the debugger's watch goes with it: p.host)
        p.syncing, p.watched = None, True
        return True

    def _changed(self) -> None:
        self.plc.events.append(ForcesEvent(self.plc.t, tuple(self.list())))

    def _running(self, t: Target):
        p = self.plc.last.get(t.proc)
        return p if p is not None and p.ended_at is None else None

    def _resolve(self, target) -> tuple[Target, Optional[int]]:
        """The target and, for a variable, its slot; ForceError when the
        procedure, variable, pin or channel does not exist."""
        t = target if isinstance(target, Target) else parse_target(target)
        m = self.machine
        if t.kind == "var":
            program = self.plc.programs.get(t.proc)
            if program is None:
                loaded = ", ".join(sorted(self.plc.programs)[:20]) or "nothing is loaded"
                raise ForceError(f"{t.name}: no procedure named {t.proc} (loaded: {loaded})")
            names = {n: s for s, n in program.slot_names().items()}
            names.setdefault("command", abi.SLOT_VAR00)
            names.setdefault("parameter", abi.SLOT_VAR00 + 1)
            if program.kind is not Kind.SOFTWARE:
                names.pop("Param", None)
            slot = names.get(t.var)
            if slot is None:
                own = ", ".join(program.var_names) or "none of its own"
                raise ForceError(f"{t.name}: {t.proc} has no variable {t.var!r} "
                                 f"(its variables: {own})")
            if t.var in ("command", "parameter"):
                t = Target("var", proc=t.proc, var=program.slot_names()[slot])
            return t, slot
        limits = {"in": (getattr(m, "input_count", 256), "input"),
                  "out": (getattr(m, "output_count", 256), "output"),
                  "adc": (_CHANNELS, "ADC channel"), "pwm": (_CHANNELS, "PWM channel"),
                  "dac": (_CHANNELS, "DAC channel")}
        if t.kind in limits:
            count, what = limits[t.kind]
            if not 0 <= t.n < count:
                raise ForceError(f"{t.name}: no {what} {t.n} (0..{count - 1})")
        elif not 0 <= t.n <= 0xFFFFFFFF:
            raise ForceError(f"{t.name}: no register {t.n}")
        return t, None

    @staticmethod
    def _value(t: Target, value) -> int:
        v = parse_value(value, f"the value for {t.name}")
        if t.kind in ("in", "out") and v not in (0, 1):
            raise ForceError(f"the value for {t.name} is 0 or 1, not {v}")
        return v

    @staticmethod
    def _address(t: Target) -> int:
        if t.kind == "pwm":
            return abi.GVAR_HW_PWM0 + t.n
        if t.kind == "dac":
            return abi.GVAR_HW_DAC0 + t.n
        return t.n

    @staticmethod
    def _mode(mode) -> bool:
        if mode not in MODES:
            raise ForceError(f"release mode is keep or restore, not {mode!r}")
        return mode == "restore"
