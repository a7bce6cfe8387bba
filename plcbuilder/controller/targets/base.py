"""What the Huazhong and TG Motion schedulers share.

A target runs one program (the project's one source, compiled): the
controller's :class:`~plcbuilder.controller.plc.PLC` is replaced by a subclass
that calls the program's procedures by the target's rules instead of running
``main`` tick by tick. The program's variables live from its start to its end
(they are the C program's globals), so one set of slots serves every call.

The subclass keeps the PLC's events, samples and the end of each tick
(messages sent, a sample recorded, the machine advanced 1 ms), so the run
report, the trace and the scenario tests work unchanged. While the program
runs, ``hw`` is its :class:`~plcbuilder.controller.plc.Process`: the status
shows it as running, Stop ends it, a fault ends it with the fault's line.
"""

from __future__ import annotations

from collections import Counter
from typing import Optional

from plcbuilder.bytecode import abi
from plcbuilder.bytecode.program import Kind, Program
from plcbuilder.controller.events import Note, Started
from plcbuilder.controller.plc import PLC, Process
from plcbuilder.controller.targets import TargetConfig
from plcbuilder.controller.targets.calls import CallResult, Entries, call
from plcbuilder.controller.vm import Host

#: budget overruns listed in the report at most (each is counted all the same)
MAX_BUDGET_ENTRIES = 1000
#: run-log warnings per procedure for overruns (then they are only counted)
MAX_BUDGET_NOTES = 5


class TargetPLC(PLC):
    """A PLC that runs one program by a target's schedule (see the module docstring)."""

    target = ""

    def __init__(self, machine, config: TargetConfig, **kwargs):
        kwargs.pop("backend", None)
        super().__init__(machine, backend="reference", **kwargs)
        self.config = config
        self.calls: Counter = Counter()
        self.budget: list[dict] = []
        self.overruns: Counter = Counter()
        self.entries: Optional[Entries] = None
        self.program: Optional[Program] = None

    # ------------------------------------------------------------ the program
    def program_of(self, programs: dict[str, Program]) -> Program:
        """The one program a target runs; ValueError when there is not exactly one."""
        hw = [p for p in programs.values() if p.kind is Kind.HARDWARE]
        if len(programs) != 1 or len(hw) != 1:
            names = ", ".join(sorted(programs)) or "none"
            raise ValueError(f"the {self.target} target runs one program (one .plc file in "
                             f"hardware/), this image has: {names}")
        return hw[0]

    def begin(self) -> None:
        """(Re)start the program from its first procedure: new variables, the
        target's own start (Huazhong's init(), TG Motion's Program_Ini)."""
        if self.hw is not None:
            self._end(self.hw, abi.EXIT_EXTERN_BREAK)
        program = self.program_of(self.programs)
        self.program = program
        self.entries = Entries(program)
        slots = [0] * 256
        slots[abi.SLOT_VAR00:abi.SLOT_VAR00 + 16] = self.var_init
        host = self._target_host(self._host(program.name, Kind.HARDWARE))
        p = Process(program, slots, 0, self.t, host)
        self.hw = p
        self.last[program.name] = p
        self.events.append(Started(self.t, program.name, program.kind.label, 0))
        self.on_begin(p)

    def on_begin(self, p: Process) -> None:
        """The target's start (overridden)."""

    def _target_host(self, base: Host) -> Host:
        """The host the program's calls see (overridden: registers)."""
        return base

    def var_slot(self, name: str) -> Optional[int]:
        """The slot of the program's variable ``name``, or None."""
        names = self.program.var_names if self.program is not None else []
        return abi.FIRST_USER_SLOT + names.index(name) if name in names else None

    # ---------------------------------------------------------------- calls
    def call(self, name: str) -> Optional[CallResult]:
        """Call procedure ``name`` of the running program to its end. A fault
        ends the program (fault event, PLC_MESSAGE_ERR_VM) and gives None."""
        p = self.hw
        if p is None or name not in self.entries:
            return None
        self.calls[name] += 1
        r = call(self.entries.get(name), p.slots, p.host, cover=self.coverage)
        if r.fault is not None:
            self._fault(p, r.fault.pc, r.fault.text, r.fault.callers)
            return None
        return r

    def over_budget(self, procedure: str, cycle: int, used_us: float, budget_us: float) -> None:
        """Report a call that took longer than its budget: a warning in the run
        log (the first few of each procedure) and an entry of the report."""
        self.overruns[procedure] += 1
        n = self.overruns[procedure]
        if len(self.budget) < MAX_BUDGET_ENTRIES:
            self.budget.append({"procedure": procedure, "cycle": cycle,
                                "used_us": round(used_us, 3), "budget_us": round(budget_us, 3)})
        if n <= MAX_BUDGET_NOTES:
            more = (" (further overruns of it are counted, not logged)"
                    if n == MAX_BUDGET_NOTES else "")
            self.events.append(Note(self.t, f"{procedure} took {used_us:.3f} µs in cycle {cycle}, "
                                            f"over its budget of {budget_us:.3f} µs{more}",
                                    "warning"))

    # ------------------------------------------------------ PLC's interface
    def start_hardware(self, name: str, eparam: int = 0) -> None:
        """Starting the program (by its name) restarts it."""
        self.begin()

    def start_software(self, name: str, eparam: int = 0) -> None:
        raise KeyError(f"the {self.target} target has no software PLC")

    def idle(self) -> bool:
        job = self.job
        return self.hw is None and (job is None or not job.active)

    def next_due(self) -> Optional[int]:
        return None

    def run(self, ms: int, until_idle: bool = False) -> int:
        """Run ``ms`` ticks of 1 ms (with ``until_idle``: stop once the program ended)."""
        t = start = self.t
        end = t + ms
        while t < end:
            self.t = t
            job = self.job
            if job is not None and job.active:
                job.tick(t)
            p = self.hw
            if p is not None:
                self.tick(t, p)
                self._after_tick(t, (p,) if self.hw is p or p.ended_at == t else ())
            else:
                self._after_tick(t, ())
            t += 1
            if until_idle and self.idle():
                break
        self.t = t
        return t - start

    def tick(self, t: int, p: Process) -> None:
        """One 1 ms tick of the target (overridden)."""

    # ---------------------------------------------------------------- report
    def registers(self) -> dict[str, dict[str, int]]:
        """The target's registers that are not 0: {bank: {index: value}} (overridden)."""
        return {}

    def report(self) -> dict:
        """What ``plcbuilder run`` adds to its JSON for this target."""
        return {"target_profile": self.target, "registers": self.registers(),
                "calls": dict(sorted(self.calls.items())), "budget": list(self.budget),
                "budget_overruns": dict(sorted(self.overruns.items()))}
