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
``TGM_DATA_BASE + i``; other addresses are the machine's registers.
"""

from __future__ import annotations

from collections import deque
from typing import Optional

from plcbuilder.bytecode import targets as T
from plcbuilder.bytecode.semantics import wrap
from plcbuilder.controller.events import Note
from plcbuilder.controller.plc import Process
from plcbuilder.controller.targets.base import TargetPLC
from plcbuilder.controller.targets.calls import Call
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
        #: oscilloscope: (t_us, cycle, input word 0, output word 0), after each Program_04
        self.scope: deque = deque(maxlen=SCOPE_SAMPLES)
        self.scope_count = 0
        self._scope_fields = None                 # the machine's fields at the tick's last sample
        self.missed: dict[str, int] = {}
        self._ini_due = False
        self._ini_call: Optional[Call] = None     # Program_Ini while it runs (over ticks)
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
        """The oscilloscope's sample, right after Program_04."""
        m = self.machine
        self.scope_count += 1
        self._scope_fields = m.sample_fields()
        self.scope.append((round(t_us, 3), cycle, m.in_bits & 0xFFFFFFFF,
                           m.out_bits & 0xFFFFFFFF))

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
        get, put = base.gvarget, base.gvarset

        def gvarget(addr: int) -> int:
            if lo <= addr < hi:
                return data.get(addr - lo, 0)
            return get(addr)

        def gvarset(addr: int, value: int) -> None:
            if lo <= addr < hi:
                if value:
                    data[addr - lo] = wrap(value)
                else:
                    data.pop(addr - lo, None)
                return
            put(addr, value)

        return Host(portset=base.portset, portclr=base.portclr, portget=base.portget,
                    gvarget=gvarget, gvarset=gvarset, g0move=base.g0move, plain=base.plain,
                    lat=0, pr=base.pr, raw_gvarset=gvarset, io=None)

    # --------------------------------------------------------------- report
    def registers(self) -> dict[str, dict[str, int]]:
        return {"TGM_Data": {str(i): v for i, v in sorted(self.data.items())}}

    def report(self) -> dict:
        out = super().report()
        out["cycles"] = self.cycle
        out["missed_releases"] = dict(sorted(self.missed.items()))
        out["oscilloscope"] = {"samples": self.scope_count,
                               "last": [list(s) for s in list(self.scope)[-10:]]}
        return out
