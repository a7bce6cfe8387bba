"""TG Motion's virtual PLC (seed 002, SPEC §9 "tgmotion").

``Program_Ini`` runs once when the PLC starts, to its end however long (the
seed: "The execution length of this function is not limited"): it is not cut
at the instruction limit of the cyclic programs. Its modelled time passes as
it runs, one tick's worth of instructions (1 ms / ``instruction_ns``) a tick,
and the first cycle begins in the tick where it ends. A status of 0
(``exit(0)``, or its end without ``exit(1)``) aborts the start with an error. Then each cycle
of ``cycle_time_us`` (250, 500 or 1000) is split into equal slots, 5 (250 and
500 µs) or 10 (1000 µs). In each slot, in this order:

1. ``Program_05`` (every slot; budget 10 µs);
2. in the fourth slot only, ``Program_04`` (budget 10 % of the cycle), then
   the oscilloscope's sample;
3. in the time the slot has left, ``Program_01`` … ``Program_03``, each
   released at its own period (``cycle_time_program_0N_us``) and run when it
   is the highest released one: ``Program_03`` first, then ``02``, then
   ``01``. A call's effects happen when it starts (it runs to its end, as every
   call here does); its modelled time then uses up the free time of this slot
   and the next ones, so a lower one is interrupted by the slots' higher
   programs and by a higher one released meanwhile (budget 20 % of the period).
   A program released again before its last call finished is not released
   twice: the release is counted as missed (a warning).

Time is modelled: a call takes (instructions it ran) × ``instruction_ns``.
A call over its budget is a warning in the run log and an entry of
:attr:`budget`. The 1 ms tick of the machine holds 1000 / cycle_time_us
cycles; the machine advances after the tick's cycles.

TGM_Data, the shared memory of 512 KiB, is 131072 32-bit words at
``TGM_DATA_BASE + i``. The other shared memories PLC_DATA points to are mapped
onto the machine as far as the seed documents them: TGM_System's HEADER
(``Mem_Size_Data``, ``Compatibility_Id``), TGM_Servo (each axis's position and
status read, its desired position written: the axis follows it), TGM_Dio (the
input and output words, ADC and DAC), TGM_Oscilloscope (the samples). Other
addresses are the machine's registers. The diagnostic prints
``RtWprintf_String``/``_Long``/``_Ex`` (compiled to writes of ``TGM_RTW_*``)
are lines of the run log that name the line they came from.

The oscilloscope samples the signals the project picks (controller/targets/
scope.py) after each Program_04.
"""

from __future__ import annotations

import sys
from collections import deque
from typing import Optional

from plcbuilder.bytecode import abi
from plcbuilder.bytecode import targets as T
from plcbuilder.bytecode.semantics import wrap
from plcbuilder.controller.events import Log, Note
from plcbuilder.controller.plc import Process
from plcbuilder.controller.targets.base import TargetPLC
from plcbuilder.controller.targets import TargetConfigError
from plcbuilder.controller.targets.calls import _RUN_CODE, Call
from plcbuilder.controller.targets.scope import DEFAULT_SIGNALS, ScopeError, parse_signal, readers
from plcbuilder.controller.vm import Host

LOW = ("Program_03", "Program_02", "Program_01")      # highest of the three first
#: oscilloscope samples kept (the newest)
SCOPE_SAMPLES = 10_000


class TgMotionPLC(TargetPLC):
    target = T.TGMOTION

    def __init__(self, machine, config, **kwargs):
        super().__init__(machine, config, **kwargs)
        self.cycle_us = config.cycle_time_us
        self.nslots = T.TGM_SLOTS[self.cycle_us]
        self.slot_us = self.cycle_us / self.nslots
        self.ns = config.instruction_ns
        self.periods = dict(zip(("Program_01", "Program_02", "Program_03"),
                                config.program_periods_us))
        self.data: dict[int, int] = {}            # TGM_Data: word index -> value (0 if absent)
        #: oscilloscope: (t_us, cycle, value of each signal), after each Program_04
        self.scope: deque = deque(maxlen=SCOPE_SAMPLES)
        self.signals = [parse_signal(t) for t in (config.scope or DEFAULT_SIGNALS)]
        self._readers: list = []
        self.scope_count = 0
        self._scope_fields = None                 # the machine's fields at the tick's last sample
        self.missed: dict[str, int] = {}
        self._ini_due = False
        self._ini_call: Optional[Call] = None     # Program_Ini while it runs (over ticks)
        self._severity = 0                        # RtWprintf_Ex's severity, written first
        self._warned_ro: set = set()
        self._reset_schedule()

    def _reset_schedule(self) -> None:
        self.cycle = 0
        self._next_release = {n: 0 for n in LOW}
        self._released = {n: False for n in LOW}    # waiting to start
        self._remaining = {n: 0.0 for n in LOW}     # µs still to run of a started call
        self._started_cycle = {n: 0 for n in LOW}
        self._used = {n: 0.0 for n in LOW}

    # ---------------------------------------------------------------- start
    def on_begin(self, p: Process) -> None:
        def slot_of(var: str) -> int:
            slot = self.var_slot(var)
            if slot is None:
                raise ScopeError(f"oscilloscope signal {var!r}: {self.program.name} has no "
                                 f"variable {var} (its variables: "
                                 f"{', '.join(self.program.var_names) or 'none'})")
            return slot
        try:
            self._readers = readers(self.signals, self.machine, p.host.gvarget, slot_of, p.slots)
        except ScopeError as exc:
            raise TargetConfigError(str(exc)) from None
        self._reset_schedule()
        self._ini_due = True
        if self._ini_call is not None:
            self._ini_call.close()
        self._ini_call = None

    def _ini(self, p: Process) -> bool:
        """Run Program_Ini on for this tick's worth of modelled time; True once
        it has ended well (the cycles may begin), False while it runs on or
        when it failed (the program then ended)."""
        if self._ini_due:
            self._ini_due = False
            self.calls["Program_Ini"] += 1
            self._ini_call = Call(self.entries.get("Program_Ini"), p.slots, p.host,
                                  cover=self.coverage)
        r = self._ini_call.run(max(1, 1_000_000 // self.ns))
        if r is None:
            return False                            # it goes on in the next tick
        self._ini_call = None
        if r.fault is not None:
            self._fault(p, r.fault.pc, r.fault.text, r.fault.callers)
            return False
        if r.code == 0:
            file, line = self.entries.line_of("Program_Ini")
            self._fault(p, self.entries.get("Program_Ini").entry,
                        "Program_Ini returned 0 (exit(1) says it succeeded): the PLC's start "
                        "is aborted")
            self.events.append(Note(self.t, f"TG Motion: the PLC did not start: Program_Ini "
                                            f"returned 0 ({file}:{line})", "error"))
            return False
        return self.hw is p

    # ----------------------------------------------------------------- tick
    def tick(self, t: int, p: Process) -> None:
        if (self._ini_due or self._ini_call is not None) and not self._ini(p):
            return
        for _ in range(1000 // self.cycle_us):
            if not self._cycle(p):
                return

    def _cycle(self, p: Process) -> bool:
        """One cycle; False once a fault ended the program."""
        k = self.cycle
        base = k * self.cycle_us
        for s in range(self.nslots):
            start = base + s * self.slot_us
            used = self._timed("Program_05", k, T.TGM_P05_BUDGET_US)
            if used is None:
                return False
            if s == T.TGM_P04_SLOT:
                u4 = self._timed("Program_04", k, T.TGM_P04_SHARE * self.cycle_us)
                if u4 is None:
                    return False
                used += u4
                self._sample(start + used, k)
            if not self._low(k, start, self.slot_us - used):
                return False
        self.cycle = k + 1
        return True

    def _timed(self, name: str, cycle: int, budget_us: float) -> Optional[float]:
        r = self.call(name)
        if r is None:
            return None
        used = r.instructions * self.ns / 1000.0
        if used > budget_us:
            self.over_budget(name, cycle, used, budget_us)
        return used

    def _low(self, cycle: int, start: float, free: float) -> bool:
        """Programs 01..03 in a slot's free time; False once a fault ended the program."""
        for name in LOW:
            if self._next_release[name] <= start:
                self._next_release[name] += self.periods[name]
                if self._released[name] or self._remaining[name] > 0:
                    self.missed[name] = self.missed.get(name, 0) + 1
                    if self.missed[name] <= 5:
                        self.events.append(Note(self.t, f"{name} was due again in cycle {cycle} "
                                                        f"before its last call finished: this "
                                                        f"release is skipped", "warning"))
                else:
                    self._released[name] = True
        while free > 0:
            name = next((n for n in LOW if self._remaining[n] > 0 or self._released[n]), None)
            if name is None:
                break
            if self._released[name]:
                self._released[name] = False
                r = self.call(name)
                if r is None:
                    return False
                used = r.instructions * self.ns / 1000.0
                self._used[name] = used
                self._started_cycle[name] = cycle
                self._remaining[name] = used
                if used == 0:
                    self._done(name)
                    continue
            step = min(free, self._remaining[name])
            free -= step
            self._remaining[name] -= step
            if self._remaining[name] <= 1e-9:
                self._remaining[name] = 0.0
                self._done(name)
        return True

    def _done(self, name: str) -> None:
        budget = T.TGM_LOW_SHARE * self.periods[name]
        if self._used[name] > budget:
            self.over_budget(name, self._started_cycle[name], self._used[name], budget)

    def _sample(self, t_us: float, cycle: int) -> None:
        """The oscilloscope's sample of the signals picked, right after Program_04."""
        self.scope_count += 1
        self._scope_fields = self.machine.sample_fields()
        self.scope.append((round(t_us, 3), cycle, *(r() for r in self._readers)))

    def _after_tick(self, t: int, ran) -> None:
        """The end of the tick as on myCNC, but the tick's sample (the trace) is
        the oscilloscope's: the machine as it was right after the tick's last
        Program_04, not at the end of the tick."""
        samples = self.samples
        before = samples[-1] if samples else None
        fields, self._scope_fields = self._scope_fields, None
        super()._after_tick(t, ran)
        if fields is not None and samples and samples[-1] is not before:
            row = samples[-1][:4] + (fields,)
            samples[-1] = row
            self._last_row = row

    # ----------------------------------------------------------------- host
    def _target_host(self, base: Host) -> Host:
        data = self.data
        lo, hi = T.TGM_DATA_BASE, T.TGM_DATA_BASE + T.TGM_DATA_WORDS
        mem_lo, mem_hi = T.TGM_SYSTEM_BASE, T.TGM_RTW_EX + 1
        get, put = base.gvarget, base.gvarset

        def gvarget(addr: int) -> int:
            if lo <= addr < hi:
                return data.get(addr - lo, 0)
            if mem_lo <= addr < mem_hi:
                v = self._memory_get(addr)
                if v is not None:
                    return v
            return get(addr)

        def gvarset(addr: int, value: int) -> None:
            if lo <= addr < hi:
                if value:
                    data[addr - lo] = wrap(value)
                else:
                    data.pop(addr - lo, None)
                return
            if mem_lo <= addr < mem_hi and self._memory_set(addr, value):
                return
            put(addr, value)

        return base.replace(gvarget=gvarget, gvarset=gvarset, raw_gvarset=gvarset, lat=0,
                            io=None, software=False, starthw=None, seteparam=None,
                            softjog=None)

    # ------------------------------------------------------ shared memories
    def _memory_get(self, addr: int) -> Optional[int]:
        """A register of TGM_System, TGM_Servo, TGM_Dio or TGM_Oscilloscope; None
        for an address none of them has (a plain register then)."""
        m = self.machine
        off = addr - T.TGM_SYSTEM_BASE
        if off == T.TGM_SYSTEM_FIELDS["Mem_Size_Data"]:
            return T.TGM_DATA_WORDS * 4
        if off == T.TGM_SYSTEM_FIELDS["Compatibility_Id"]:
            return T.TGM_COMPATIBILITY_ID
        servo = self._servo(addr)
        if servo is not None:
            i, field = servo
            mo = m.motion
            if field == T.TGM_SERVO_FIELDS["Act_Position"]:
                return mo.ipos[i]
            if field == T.TGM_SERVO_FIELDS["Status"]:
                st = T.TGM_SERVO_STATUS
                w = st["SERVO_ST_PRESENT"] if mo.present[i] else 0
                if mo.vel[i]:
                    w |= st["SERVO_ST_MOVING"]
                elif i not in mo.follow and (mo.move is None or i not in mo.move.axes):
                    w |= st["SERVO_ST_IN_POSITION"]
                return w
            if field == T.TGM_SERVO_FIELDS["Desired_Position"]:
                t = mo.follow.get(i)
                return round(t) if t is not None else mo.ipos[i]
            return None
        off = addr - T.TGM_DIO_BASE
        if 0 <= off < 32:
            group, k = divmod(off, 8)
            reg = (abi.GVAR_HW_INPUTS, abi.GVAR_HW_OUTPUTS)[group][k] if group < 2 else \
                (abi.GVAR_HW_ADC0, abi.GVAR_HW_DAC0)[group - 2] + k
            return m.gvarget(reg)
        off = addr - T.TGM_OSC_BASE
        if off == 0:
            return self.scope_count
        if 1 <= off <= len(self.signals):
            last = self.scope[-1] if self.scope else None
            return last[1 + off] if last is not None else 0
        return None

    def _memory_set(self, addr: int, value: int) -> bool:
        """A write to a shared memory register; False when the address is not one."""
        m = self.machine
        if addr in (T.TGM_RTW_STRING, T.TGM_RTW_LONG, T.TGM_RTW_EX_SEVERITY, T.TGM_RTW_EX):
            self._print(addr, value)
            return True
        if T.TGM_SYSTEM_BASE <= addr < T.TGM_SYSTEM_BASE + len(T.TGM_SYSTEM_FIELDS) or \
                T.TGM_OSC_BASE <= addr <= T.TGM_OSC_BASE + len(self.signals):
            self._read_only(addr, value)
            return True
        servo = self._servo(addr)
        if servo is not None:
            i, field = servo
            if field == T.TGM_SERVO_FIELDS["Desired_Position"]:
                m.quiet = False
                m.motion.servo_target(i, value)
                return True
            self._read_only(addr, value)
            return True
        off = addr - T.TGM_DIO_BASE
        if 0 <= off < 32:
            group, k = divmod(off, 8)
            if group == 1:
                m.gvarset(abi.GVAR_HW_OUTPUTS[k], value)
            elif group == 3:
                m.gvarset(abi.GVAR_HW_DAC0 + k, value)
            else:
                self._read_only(addr, value)                  # DI and AI
            return True
        return False

    def _read_only(self, addr: int, value: int) -> None:
        if addr not in self._warned_ro:
            self._warned_ro.add(addr)
            self.events.append(Note(self.t, f"gvarset({addr}, {value}) ignored: that register "
                                            f"of TG Motion's shared memory is read-only",
                                    "warning"))

    def _servo(self, addr: int) -> Optional[tuple[int, int]]:
        off = addr - T.TGM_SERVO_BASE
        if 0 <= off < T.TGM_SERVO_STRIDE * len(abi.AXES):
            i, field = divmod(off, T.TGM_SERVO_STRIDE)
            if self.machine.motion.present[i] and field in T.TGM_SERVO_FIELDS.values():
                return i, field
        return None

    def _print(self, addr: int, value: int) -> None:
        """RtWprintf_*: a line of the run log naming where it came from."""
        if addr == T.TGM_RTW_EX_SEVERITY:
            self._severity = value
            return
        where = ""
        frame = sys._getframe(2)               # the interpreter that ran the gvarset
        while frame is not None and frame.f_code is not _RUN_CODE:
            frame = frame.f_back
        if frame is not None and self.program is not None:
            loc = self.program.location(frame.f_locals.get("pc", -1))
            if loc:
                where = f" ({loc[0]}:{loc[1]})"
        name = {T.TGM_RTW_STRING: "RtWprintf_String", T.TGM_RTW_LONG: "RtWprintf_Long",
                T.TGM_RTW_EX: "RtWprintf_Ex"}[addr]
        sev = f"severity {self._severity}, " if addr == T.TGM_RTW_EX else ""
        proc = self.program.proc_at(frame.f_locals.get("pc", -1)) if frame is not None else None
        self.events.append(Log(self.t, proc or (self.program.name if self.program else ""),
                               f"{name}({sev}{value}){where}"))

    # --------------------------------------------------------------- report
    def registers(self) -> dict[str, dict[str, int]]:
        return {"TGM_Data": {str(i): v for i, v in sorted(self.data.items())}}

    def report(self) -> dict:
        out = super().report()
        out["cycles"] = self.cycle
        out["missed_releases"] = dict(sorted(self.missed.items()))
        out["oscilloscope"] = {"signals": [s.text for s in self.signals],
                               "samples": self.scope_count,
                               "last": [list(s) for s in list(self.scope)[-10:]]}
        return out
