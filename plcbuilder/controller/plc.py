"""The hardware PLC (1 ms ticks, one procedure at a time) and the software PLC
(100 ms ticks, every procedure side by side), scheduled together tick by tick.

One tick ``t`` (docs/controller.md, "Timing rules"):

1. starts due at ``t`` (hardware procedures asked for by a software procedure
   with ``gvarset(100040, N)`` in the previous tick) begin; starts, inputs and
   ADC values given from outside (:meth:`PLC.start_hardware`, the scenario) were
   applied before the tick;
2. when ``t`` is on the software grid (``t = grid + k·100``, ``grid`` being the
   tick of the controller's first load): pending software starts begin, then
   every running software procedure runs its tick, in name order — so
   ``__HANDLER_INIT``, started by the first load, runs before a hardware
   procedure started in that same tick;
3. the hardware procedure runs until it ends its tick or ends;
4. end of tick: each procedure that ran whose ``message`` is not 0 sends it
   (hardware first, then software by name) and its ``message`` becomes 0; the
   machine sees the message (stop messages stop motion); the state is sampled;
   the machine advances 1 ms.

Everything is deterministic: the same calls give the same events and samples.
"""

from __future__ import annotations

from collections import deque, namedtuple

from plcbuilder.bytecode import abi
from plcbuilder.bytecode.opcodes import WRITES_SLOT, decode
from plcbuilder.bytecode.program import Kind, Program
from plcbuilder.bytecode.semantics import wrap
from plcbuilder.controller import fastvm, vm
from plcbuilder.controller.events import (Ended, Fault, Message, Note, Print, Sample,
                                          Started)
from plcbuilder.controller.forces import ForcedSlots
from plcbuilder.controller.vm import HALT, Halted, Handoff, Host, Migrate, ProcExit, VMFault

TYPE_CHECKING = False               # (typing is not imported at run time: start-up)
if TYPE_CHECKING:
    from typing import Callable, Iterable, Optional

SOFTWARE_PERIOD_MS = 100
#: Exit code reported for a procedure that ended with a runtime fault (not in the seed's table).
FAULT_EXIT_CODE = -1
BACKENDS = ("fast", "reference")
EVENT_BUFFER = 200_000
SAMPLE_BUFFER = 120_000


#: One tick's sample as the PLC records it (:meth:`PLC.take_samples` makes
#: :class:`~plcbuilder.controller.events.Sample` of it): ``t``; ``running`` the
#: hardware procedure running, or None; ``proc``; ``message`` the first message
#: sent in the tick, or 0; ``fields`` the machine's sample_fields() (do not
#: modify). (collections' namedtuple: typing's would load typing at start-up.)
SampleRow = namedtuple("SampleRow", "t running proc message fields")


#: The machine's method a built-in call reaches where its name is not the Host's
#: (vm.CALLS; every other one is the machine's method of the same name).
_MACHINE_NAME = {"portclr": "portclear"}

#: "no sample recorded yet": differs from every real one
_NO_ROW = SampleRow(-1, object(), None, 0, None)
#: matches no fields
_NEVER = object()

class Process:
    """One run of a procedure."""

    __slots__ = ("name", "program", "kind", "slots", "eparam", "started_at", "resume",
                 "host", "ended_at", "exit_code", "syncing", "gen", "at", "fault", "watched")

    def __init__(self, program: Program, slots: list[int], eparam: int, started_at: int,
                 host: Host):
        self.name = program.name
        self.program = program
        self.kind = program.kind
        self.slots = slots
        self.eparam = eparam
        self.started_at = started_at
        self.host = host
        #: runs its next tick: ``resume(None)`` (its generator's send: cheaper than __next__)
        self.resume: Callable[[None], object] = _not_started
        self.ended_at: Optional[int] = None
        self.exit_code: Optional[int] = None
        #: the fast backend's generator when it keeps variables in locals between ticks
        self.syncing = None
        self.gen = None
        #: the offset of the instruction that ended its last tick (None: none yet)
        self.at: Optional[int] = None
        #: (pc, text, callers) of a fault it is halted at (it ends when the debugger goes on)
        self.fault = None
        #: runs code that asks the debugger (the reference interpreter, or watched fast code)
        self.watched = False

    @property
    def runner(self):
        """The generator that runs it (either backend; forces.py's name for ``gen``)."""
        return self.gen

    def set_gen(self, gen) -> None:
        self.gen = gen
        # (one halted at its fault ends there when it goes on, whatever runs it)
        self.resume = gen.send if self.fault is None else _at_fault

    def on_reference(self) -> bool:
        """Whether the reference interpreter runs it now."""
        gen = self.gen
        return gen is not None and gen.gi_code is vm.run_reference.__code__

    def sync(self) -> None:
        """Make ``slots`` hold every variable's value now (the fast backend keeps
        some in locals while it runs); call it before reading or writing them
        from outside. The procedure reads them again when its next tick begins."""
        gen = self.syncing
        if gen is not None and gen.gi_suspended:
            gen.send(fastvm.SYNC)

    def variables(self) -> dict[str, int]:
        """Every variable by name (predefined and the program's own)."""
        self.sync()
        s = self.slots
        return {name: s[slot] for slot, name in sorted(self.program.slot_names().items())
                if slot < len(s)}


def mcode_names(n: int) -> list[str]:
    """The procedure names M-code ``n`` may start, preferred first (3 -> M03, M3)."""
    return list(dict.fromkeys([f"M{n:02d}", f"M{n}"]))


class PLC:
    """The hardware and software PLC over one machine. Times are ticks (ms)."""

    def __init__(self, machine, *, backend: str = "fast", variables: Optional[Iterable[int]] = None,
                 gvarget_latency_ms: int = 0, record_samples: bool = True):
        if backend not in BACKENDS:
            raise ValueError(f"unknown backend {backend!r} (one of {', '.join(BACKENDS)})")
        self.machine = machine
        self.backend = backend
        vals = list(variables) if variables is not None else []
        if len(vals) > 16:
            raise ValueError(f"{len(vals)} initial variables, var00..var15 are 16")
        self.var_init = [wrap(int(v)) for v in vals] + [0] * (16 - len(vals))
        self.latency = max(0, int(gvarget_latency_ms))
        self.record_samples = record_samples
        #: record a sample only when it differs from the previous one (t aside):
        #: a sample then holds until the next (the link's telemetry sets this)
        self.sample_changes_only = False
        self._last_row: SampleRow = _NO_ROW
        #: a CodeCoverage recording the instructions that run (reference backend only)
        self.coverage = None
        #: the Debugger (controller/debugger.py) when there is one
        self.debugger = None
        #: the debugger may halt (a breakpoint is set, …): a hardware procedure on the
        #: reference interpreter then runs through _tick (which sees it yield HALT)
        self.halting = False
        #: a step or a run-to goes on: every tick runs through _tick
        self.watching = False
        #: the rest of a tick halted by the debugger: (t, procedures still to run, ran)
        self._rest = None
        #: procedure name -> {slot: value} of its forced variables (controller/forces.py):
        #: such a procedure runs on the reference interpreter over ForcedSlots
        self.var_forces: dict[str, dict[int, int]] = {}
        self.events: deque = deque(maxlen=EVENT_BUFFER)
        self.samples: deque = deque(maxlen=SAMPLE_BUFFER)
        self.programs: dict[str, Program] = {}
        self.t = 0
        #: the software grid: software ticks fall at grid + k·100 (the first load sets it)
        self.grid = 0
        self._proc = 0                     # the last hardware procedure's proc, kept after it ends
        self.hw: Optional[Process] = None
        self.sw: dict[str, Process] = {}
        self._sw_order: list[Process] = []
        self._pending_sw: list[tuple[str, int]] = []
        self._due_hw: list[tuple[int, str, int]] = []   # (tick, name, eparam)
        self.soft_eparam = 0               # gvarset(100041, e) from a software procedure
        self.last: dict[str, Process] = {}  # the latest run of each procedure
        #: (source, n) -> (procedure, eparam): an input pin ("in", pin), a virtual input
        #: or output ("vin"/"vout", 1..32) or a PLS's output ("pls", k) bound to a procedure
        self.bindings: dict[tuple[str, int], tuple[str, int]] = {}
        self._levels: dict[tuple[str, int], int] = {}    # last level seen of each bound source
        #: the G-code job (controller/job.py), or None
        self.job = None
        # advance() can be skipped while the machine is quiet and has no notes pending
        notes = getattr(machine, "pending_notes", None)
        quiet_machine = notes is not None and hasattr(machine, "quiet")
        if not quiet_machine:
            notes = (None,)                # another machine: always call advance()
        self._notes_pending = notes
        #: the machine's clock (t_ms) only moves 1 ms a tick while it is quiet
        #: with no notes pending: then the PLC moves it (_advance, _hardware_alone)
        self._quiet_machine = quiet_machine

    def prepare(self, programs: Iterable[Program]) -> None:
        """Translate programs for the fast backend now (as they will be run),
        so that the first start does not pay for it."""
        if self.backend != "fast":
            return
        m = self.machine
        pins = fastvm.io_shape(m if hasattr(m, "in_bits") else None)
        for p in programs:
            fastvm.factory(p, self.latency > 0 and p.kind is Kind.HARDWARE, pins)

    # ------------------------------------------------------------- hosts
    def _host(self, name: str, kind: Kind) -> Host:
        """The Host a procedure runs on (the one place a procedure's host is
        made; an expression's is :meth:`Host.for_expression`)."""
        m = self.machine
        events = self.events
        raw = m.gvarset
        lo, hi = abi.PRINT_FIRST, abi.PRINT_LAST

        def pr(addr: int, value: int) -> None:
            events.append(Print(self.t, addr, value, name))
            raw(addr, value)

        io = m if hasattr(m, "in_bits") else None
        if kind is Kind.HARDWARE:
            def gvarset(addr: int, value: int) -> None:
                if lo <= addr <= hi:
                    pr(addr, value)
                else:
                    raw(addr, value)

            own = dict(gvarset=gvarset, lat=self.latency)
        else:
            def starthw(n: int) -> None:
                self._request_hardware(n, name)

            def seteparam(v: int) -> None:
                self.soft_eparam = v

            softjog = m.soft_jog
            jog_lo, jog_hi = abi.SOFT_JOG_BASE, abi.SOFT_JOG_BASE + 7

            def sw_gvarset(addr: int, value: int) -> None:
                if addr == abi.SOFT_START_HW:
                    starthw(value)
                elif addr == abi.SOFT_START_EPARAM:
                    seteparam(value)
                elif jog_lo <= addr <= jog_hi:
                    softjog(addr - jog_lo, value)
                elif lo <= addr <= hi:
                    pr(addr, value)
                else:
                    raw(addr, value)

            own = dict(gvarset=sw_gvarset, lat=0, starthw=starthw, seteparam=seteparam,
                       softjog=softjog, software=True)
        calls = {name: getattr(m, _MACHINE_NAME.get(name, name)) for name in vm.CALLS}
        calls.update(own)
        store = getattr(m, "register_store", None)      # (gvarget is the machine's own)
        return Host(plain=m.is_plain_register, pr=pr, raw_gvarset=raw, io=io,
                    registers=store() if store is not None else None, **calls)

    def _spawn(self, program: Program, eparam: int) -> Process:
        eparam = wrap(int(eparam))
        slots = [0] * 256                  # every slot an instruction can name (a byte)
        slots[abi.SLOT_EPARAM] = eparam
        slots[abi.SLOT_VAR00:abi.SLOT_VAR00 + 16] = self.var_init
        if program.kind is Kind.SOFTWARE:
            slots[abi.SLOT_PARAM] = eparam
        host = self._host(program.name, program.kind)
        forced = self.var_forces.get(program.name) if self.var_forces else None
        if forced:
            slots = ForcedSlots(slots)
            for slot, value in forced.items():
                slots.hold(slot, value)
        p = Process(program, slots, eparam, self.t, host)
        dbg = self.debugger
        if dbg is not None:
            host.debug = dbg.watch(p)
        if forced:
            gen = vm.run_reference(program, slots, host, cover=self.coverage)
            p.watched = True
        elif self.backend == "fast":
            p.watched = dbg is not None and dbg.watched(program)
            gen = fastvm.make_runner(program, slots, host, watched=p.watched)
            if not p.watched and fastvm.answers_sync(program, host):
                p.syncing = gen
        else:
            gen = vm.run_reference(program, slots, host, cover=self.coverage)
            p.watched = True
        p.set_gen(gen)
        self.last[program.name] = p
        self.events.append(Started(self.t, program.name, program.kind.label, eparam))
        return p

    # ------------------------------------------------------------ endings
    def _end(self, p: Process, code: int) -> None:
        if p.ended_at is not None:
            return
        p.sync()                           # ended from outside: its variables as they are
        p.syncing = None
        p.ended_at = self.t
        p.exit_code = code
        p.resume = _finished
        p.fault = None
        if self.debugger is not None:
            self.debugger.ended(p)
        self.events.append(Ended(self.t, p.name, p.kind.label, code, abi.exit_name(code),
                                 p.slots[abi.SLOT_VEXIT]))
        job = self.job
        if job is not None and job.open_calls:      # a procedure the G-code job called
            job.report_ends(self.t)
        if p is self.hw:
            self.hw = None
            self._proc = p.slots[abi.SLOT_PROC]
        elif self.sw.get(p.name) is p:
            del self.sw[p.name]
            self._sw_order = [q for q in self._sw_order if q is not p]

    def _fault(self, p: Process, pc: Optional[int], text: str, callers=(),
               halt: bool = True) -> None:
        """End p with a fault event and a PLC_MESSAGE_ERR_VM message. The event
        names main's statement (the outermost call) and lists the whole chain;
        the text says where inside a called procedure it happened. When the
        debugger is on (``halt``), it halts there first: p ends when it goes on."""
        if halt and self.debugger is not None and self.debugger.faulted(p, pc, text, callers):
            p.fault = (pc, text, tuple(callers))
            p.resume = _at_fault               # going on ends it (_outcome)
            return
        prog = p.program
        chain = []
        for at in [*reversed(list(callers)), pc] if pc is not None else []:
            loc = prog.location(at)
            file, line = loc if loc else (None, None)
            chain.append((file, line, prog.proc_at(at)))
        file, line = chain[0][:2] if chain else (None, None)
        if len(chain) > 1 and chain[-1][1] is not None:
            f, ln, proc = chain[-1]
            inside = f"{proc}() at " if proc else ""
            text = f"{text} (in {inside}{f}:{ln})"
        self.events.append(Fault(self.t, p.name, file, line, text, calls=tuple(chain)))
        p.slots[abi.SLOT_MESSAGE] = abi.PLC_MESSAGE["PLC_MESSAGE_ERR_VM"]
        self._end(p, FAULT_EXIT_CODE)

    def _outcome(self, p: Process, exc: BaseException) -> None:
        """A procedure's tick raised: it ended, faulted, or hands over to the
        reference interpreter (which then finishes this tick)."""
        while True:
            if isinstance(exc, _AtFault):       # halted at its fault: now it ends
                if p.fault is not None:
                    pc, text, callers = p.fault
                    p.fault = None
                    self._fault(p, pc, text, callers, halt=False)
            elif isinstance(exc, ProcExit):
                self._end(p, wrap(exc.code))
            elif isinstance(exc, VMFault):
                self._fault(p, exc.pc, exc.text, exc.callers)
            elif isinstance(exc, StopIteration):
                self._end(p, 0)
            elif isinstance(exc, Halted):    # the debugger halted it: the reference goes on
                p.set_gen(vm.run_reference(p.program, p.slots, p.host, pc=exc.pc,
                                           stack=exc.stack, rets=exc.rets, count=exc.count,
                                           passed=exc.pc))
                p.syncing, p.watched = None, True
            elif isinstance(exc, Handoff):
                p.set_gen(vm.run_reference(p.program, p.slots, p.host, pc=exc.pc,
                                           stack=exc.stack, rets=exc.rets, count=exc.count))
                p.syncing, p.watched = None, True
                try:
                    at = p.resume(None)
                    if at is not HALT:
                        p.at = at
                    return
                except Exception as again:  # noqa: BLE001 - handled by the next round
                    exc = again
                    continue
            else:                           # a bug must not bring the controller down
                self._fault(p, None, f"internal error: {type(exc).__name__}: {exc}")
            return

    # ------------------------------------------------------------- starts
    def start_hardware(self, name: str, eparam: int = 0) -> None:
        """Start a hardware procedure now: it runs from the next tick (self.t) on;
        a running one ends with 100 (plc_exit_extern_break)."""
        program = self.programs[name]
        if self.hw is not None:
            self._end(self.hw, abi.EXIT_EXTERN_BREAK)
        self.hw = self._spawn(program, eparam)

    def start_software(self, name: str, eparam: int = 0) -> None:
        """Queue a software procedure: it starts at the next software tick
        (on the grid; at once if that is this tick)."""
        if name not in self.programs:
            raise KeyError(name)
        self._pending_sw.append((name, int(eparam)))
        if (self.t - self.grid) % SOFTWARE_PERIOD_MS == 0:
            self._begin_pending()          # this tick is a software tick: it begins now

    def _request_hardware(self, n: int, source: str) -> None:
        for name in mcode_names(n):
            p = self.programs.get(name)
            if p is not None and p.kind is Kind.HARDWARE:
                self._due_hw.append((self.t + 1, name, self.soft_eparam))
                return
        self.events.append(Note(self.t, f"{source}: gvarset({abi.SOFT_START_HW}, {n}) asks for "
                                        f"hardware procedure {mcode_names(n)[0]}, which is "
                                        f"not loaded", "warning"))

    def end_all(self, code: int = abi.EXIT_EXTERN_BREAK) -> None:
        if self.hw is not None:
            self._end(self.hw, code)
        for p in list(self._sw_order):
            self._end(p, code)
        self._pending_sw.clear()
        self._due_hw.clear()

    def end_hardware(self, code: int = abi.EXIT_EXTERN_BREAK) -> None:
        if self.hw is not None:
            self._end(self.hw, code)

    # -------------------------------------------------------------- state
    def idle(self) -> bool:
        """No procedure running and none due to start."""
        job = self.job
        return self.hw is None and not self.sw and not self._pending_sw and not self._due_hw \
            and not self._edge_due() and (job is None or not job.active)

    def _edge_due(self) -> bool:
        """A bound input went 0 -> 1 and the next tick will start its procedure."""
        if not self.bindings:
            return False
        level = self._level
        return any(level(key) and not self._levels.get(key) for key in self.bindings)

    @property
    def software_running(self) -> list[str]:
        return [p.name for p in self._sw_order]

    def next_due(self) -> Optional[int]:
        """The tick at which a pending start happens, or None."""
        due = [t for t, _n, _e in self._due_hw]
        if self._pending_sw:
            t = self.t
            due.append(t + (self.grid - t) % SOFTWARE_PERIOD_MS)
        return min(due) if due else None

    # ---------------------------------------------------------------- run
    def _begin_pending(self) -> None:
        """The pending software starts begin (a running one of the same name ends)."""
        for name, eparam in self._pending_sw:
            program = self.programs.get(name)
            if program is None:
                continue
            old = self.sw.get(name)
            if old is not None:
                self._end(old, abi.EXIT_EXTERN_BREAK)
            p = self._spawn(program, eparam)
            self.sw[name] = p
        if self._pending_sw:
            self._pending_sw.clear()
            self._sw_order = sorted(self.sw.values(), key=lambda q: q.name)

    def _software_tick(self) -> list[Process]:
        """The software procedures that run this tick, in order (pending ones begun)."""
        if self._pending_sw:
            self._begin_pending()
        return list(self._sw_order)

    def _send(self, p: Process, code: int) -> None:
        s = p.slots
        self.events.append(Message(self.t, code, abi.message_name(code),
                                   s[abi.SLOT_VAR00], s[abi.SLOT_VAR00 + 1], p.name))
        s[abi.SLOT_MESSAGE] = 0
        self.machine.on_message(code)
        job = self.job
        if job is not None:
            job.on_message(code, p.name)

    def _emit_notes(self, t: int, notes) -> None:
        """The machine's notes of tick t, as Note events."""
        events = self.events
        for level, text in notes:
            events.append(Note(t, text, level))

    def run(self, ms: int, until_idle: bool = False) -> int:
        """Run ``ms`` ticks; with ``until_idle``, stop after the first tick that
        leaves no procedure running and none due. Returns the ticks run.

        Every tick is :meth:`_tick`, except where no start is due and no input
        is bound, between software ticks: there the fast paths
        :meth:`_hardware_alone` (a hardware procedure alone, the common case;
        it also goes on through the software ticks, which are :meth:`_tick`'s)
        and :meth:`_machine_alone` (no procedure at all) do the same work, and
        end their ticks as :meth:`_after_tick` does. Samples are kept as raw
        rows (:class:`SampleRow`);
        :meth:`take_samples` turns them into :class:`Sample` objects."""
        dbg = self.debugger
        if dbg is not None and dbg.halt is not None:
            return 0                         # halted: time stands still
        t = start = self.t
        end = t + ms
        while t < end:
            next_sw = t + (self.grid - t) % SOFTWARE_PERIOD_MS
            hw = self.hw
            job = self.job
            if t == next_sw or self._due_hw or self.bindings or self.watching or \
                    (job is not None and job.active) or \
                    (self.halting and hw is not None and hw.on_reference()):
                if not self._tick(t, software=t == next_sw):
                    break                    # halted mid-tick: the rest waits
                t += 1
                if dbg is not None and dbg.halt is not None:
                    break
            elif hw is not None:
                t = self._hardware_alone(t, end)
                if dbg is not None and dbg.halt is not None:
                    break
            else:
                stop = t + 1 if until_idle and self.idle() else min(end, next_sw)
                t = self._machine_alone(t, stop)
            if until_idle and self.idle():
                break
        self.t = t
        return t - start

    def _tick(self, t: int, software: bool) -> bool:
        """Tick t in the order of the module's docstring: starts due, the
        software tick (when ``software``), the hardware procedure, the end of
        the tick. False when the debugger halted it: :meth:`resume_tick` runs the rest."""
        self.t = t
        if self._due_hw:
            self._apply_due(t)
        if self.bindings:
            self._input_edges()
        job = self.job
        if job is not None and job.active:
            job.tick(t)
        soft = self._software_tick() if software and (self.sw or self._pending_sw) else []
        hw = self.hw
        if hw is not None:
            return self._run_procedures(t, [*soft, hw], (hw, *soft))
        return self._run_procedures(t, soft, soft)

    def _run_procedures(self, t: int, todo: list, ran) -> bool:
        """Run the procedures of ``todo`` in order (tick t), then the end of the
        tick (``ran``: hardware first, then software). False when the debugger
        halted one: the rest of the tick waits in ``_rest``, the halted one first."""
        dbg = self.debugger
        for p in todo:
            # (one that ended raises StopIteration, which changes nothing; one
            # halted at its fault raises _AtFault: _outcome ends it)
            try:
                at = p.resume(None)
            except Exception as exc:  # noqa: BLE001 - ProcExit, VMFault, Handoff or a bug
                self._outcome(p, exc)
            else:
                if not p.watched:      # plain fast code: it cannot halt, nor yield HALT
                    p.at = at
                    continue
                if at is not HALT:
                    p.at = at
            if dbg is not None and dbg.halt is not None:
                self._rest = (t, todo[todo.index(p):], ran)
                return False
        self._rest = None
        self._after_tick(t, ran)
        if self.watching and dbg is not None:
            dbg.tick_ended()
        return True

    @property
    def mid_tick(self) -> bool:
        """The debugger halted a tick before its end."""
        return self._rest is not None

    def resume_tick(self) -> bool:
        """Run the rest of a halted tick; False when it halts again. Then the
        next tick is ``t + 1``."""
        rest = self._rest
        if rest is None:
            return True
        t, todo, ran = rest
        self._rest = None
        self.t = t
        if not self._run_procedures(t, list(todo), ran):
            return False
        self.t = t + 1
        return True

    def running(self) -> list[Process]:
        """The procedures running (a procedure halted at its fault too): the
        hardware one, then software by name."""
        out = [self.hw] if self.hw is not None else []
        return out + list(self._sw_order)

    def watch_process(self, p: Process) -> None:
        """Make p run code that asks the debugger: a procedure running plain
        fast code goes over to the reference interpreter, exactly where it is
        (suspended at a tick end, or not started yet)."""
        if p.watched or p.ended_at is not None or p.gen is None or p.fault is not None:
            return                      # (halted at its fault: it only ends from there)
        import inspect                  # (debugging only: not loaded at start)
        if self.backend == "fast" and inspect.getgeneratorstate(p.gen) == inspect.GEN_CREATED:
            p.set_gen(fastvm.make_runner(p.program, p.slots, p.host, watched=True))
            p.syncing, p.watched = None, True            # not started: watched code from the start
            return
        self.to_reference(p)

    def to_reference(self, p: Process) -> None:
        """Hand p (suspended at a tick end, or not started) to the reference
        interpreter, exactly where it is."""
        if p.ended_at is not None or p.gen is None or p.fault is not None:
            return
        if p.on_reference():
            p.watched = True
            return
        gen = p.gen
        import inspect                  # (debugging only: not loaded at start)
        if inspect.getgeneratorstate(gen) == inspect.GEN_CREATED:     # not started yet
            new = vm.run_reference(p.program, p.slots, p.host)
        else:
            try:
                gen.throw(Migrate)
            except Handoff as h:
                new = vm.run_reference(p.program, p.slots, p.host, pc=h.pc, stack=h.stack,
                                       rets=h.rets, count=h.count)
            except Exception as exc:  # noqa: BLE001 - a bug must not bring the controller down
                self._outcome(p, exc)
                return
            else:                            # pragma: no cover - every tick end answers
                return
        p.syncing = None
        p.watched = True
        p.set_gen(new)

    def _after_tick(self, t: int, ran) -> None:
        """The end of tick t: each procedure that ran (hardware first, then
        software by name) whose ``message`` is not 0 sends it; the sample is
        recorded (its message: the first one sent); the machine advances 1 ms."""
        msg = 0
        message_slot = abi.SLOT_MESSAGE
        for p in ran:
            if p.slots[message_slot]:
                code = p.slots[message_slot]
                self._send(p, code)
                if not msg:
                    msg = code
        if self.record_samples:
            hw = self.hw
            self._record(t, hw.name if hw is not None else None, self.proc, msg)
        self._advance(t)

    def _record(self, t: int, running: Optional[str], proc: int, message: int) -> None:
        """Tick t's sample; with ``sample_changes_only`` only when it differs
        from the last one recorded (t aside)."""
        fields = self.machine.sample_fields()
        if self.sample_changes_only and not message and self._same_row(running, proc, fields):
            return
        row = self._last_row = SampleRow(t, running, proc, message, fields)
        self.samples.append(row)

    def _same_row(self, running, proc, fields) -> bool:
        """Whether a sample of these values (no message) equals the last recorded one."""
        _t, last_running, last_proc, last_message, last_fields = self._last_row
        return not last_message and fields is last_fields and proc == last_proc \
            and running == last_running

    def _advance(self, t: int) -> None:
        """The machine advances 1 ms at the end of tick t (while it is quiet
        with no notes pending, advance() would only move its clock)."""
        machine = self.machine
        if self._notes_pending or not machine.quiet:
            notes = machine.advance()
            if notes:
                self._emit_notes(t, notes)
        else:
            machine.t_ms += 1

    def _hardware_alone(self, t: int, end: int) -> int:
        """Ticks from t (not a software tick) on, while the hardware procedure
        runs with no start due and no input bound: :meth:`_tick` for one
        procedure, its end of tick (:meth:`_after_tick`: the message, the
        sample, the machine) through the same helpers; the software ticks are
        :meth:`_tick`'s. Returns the next tick at ``end``, or after a tick that
        ended the procedure, handed it over to the reference interpreter or
        made a start due."""
        hw = self.hw
        resume, slots, name = hw.resume, hw.slots, hw.name
        message_slot, proc_slot = abi.SLOT_MESSAGE, abi.SLOT_PROC
        machine = self.machine
        notes_pending = self._notes_pending
        grid = self.grid
        send, record, advance = self._send, self._record, self._advance
        rec = self.record_samples
        only = self.sample_changes_only
        while True:
            stop = min(end, t + (grid - t) % SOFTWARE_PERIOD_MS)
            at = hw.at
            # the fields and proc of a tick whose sample _record would not
            # record again (machine._sample: the cached sample_fields() dict,
            # None once something changed), so that it is not asked
            seen, seen_proc = _NEVER, None
            # a quiet machine's clock reads t at the start of tick t (as it does
            # unless the machine ran before the PLC): it is set so from t (the
            # same int) instead of adding 1 ms (a new int) at each tick's end
            synced = self._quiet_machine and machine.t_ms == t
            if synced and not rec and not hw.watched and not slots[message_slot] \
                    and not _writes_message(hw.program):
                # the common case: no sample to record, no message to send (plain
                # fast code that never writes its message: none can be pending)
                for t in range(t, stop):
                    machine.t_ms = t
                    self.t = t
                    try:
                        at = resume(None)
                    except Exception as exc:  # noqa: BLE001 - as below
                        hw.at = at
                        return t + 1 if self._run_after(t, hw, exc) else t
                    if notes_pending or not machine.quiet:
                        advance(t)
            else:
                for t in range(t, stop):
                    if synced:
                        machine.t_ms = t
                    self.t = t
                    try:
                        at = resume(None)
                    except Exception as exc:  # noqa: BLE001 - ProcExit, VMFault, Handoff or a bug
                        hw.at = at
                        return t + 1 if self._run_after(t, hw, exc) else t
                    if slots[message_slot] or rec:
                        code = slots[message_slot]
                        if code:
                            send(hw, code)
                        if rec and (code or machine._sample is not seen
                                    or slots[proc_slot] != seen_proc):
                            seen_proc = slots[proc_slot]
                            record(t, name, seen_proc, code)
                            seen = machine._sample if only and not code else _NEVER
                    if notes_pending or not machine.quiet:
                        advance(t)
                    elif not synced:
                        machine.t_ms += 1          # advance() would do only this
            if synced:
                machine.t_ms = stop                # (the last tick's 1 ms)
            t = stop
            hw.at = at
            if t == end:
                return t
            if not self._tick(t, software=True):
                return t
            t += 1
            if self.hw is not hw or hw.resume is not resume or self._due_hw or self.bindings:
                return t

    def _run_after(self, t: int, hw: Process, exc: BaseException) -> bool:
        """The hardware procedure's tick t raised (the fast path): its outcome
        and the end of the tick; False when the debugger halted it there."""
        self._outcome(hw, exc)
        dbg = self.debugger
        if dbg is not None and dbg.halt is not None:
            self._rest = (t, [hw], (hw,))
            return False
        self._after_tick(t, (hw,))
        return True

    def _machine_alone(self, t: int, stop: int) -> int:
        """Ticks t..stop-1 with no procedure running and none due: only the
        machine moves (:meth:`_after_tick` with nothing that ran)."""
        proc = self._proc
        machine = self.machine
        rec = self.record_samples
        only = self.sample_changes_only
        while t < stop:
            if not self._notes_pending and machine.quiet and (not rec or only and self._same_row(
                    None, proc, machine.sample_fields())):
                machine.t_ms += stop - t           # nothing to record, nothing moves
                return stop
            if rec:
                self._record(t, None, proc, 0)
            self._advance(t)
            t += 1
        return t

    def record_next_sample(self) -> None:
        """With ``sample_changes_only``: record the next tick's sample even if
        nothing changed (a new subscriber's starting point)."""
        self._last_row = _NO_ROW

    def take_sample_rows(self) -> list[SampleRow]:
        """The samples recorded so far (fields: the machine's sample_fields
        dict; do not modify it), and forget them."""
        rows = list(self.samples)
        self.samples.clear()
        return rows

    def take_samples(self) -> list[Sample]:
        """The samples recorded so far, and forget them."""
        out = []
        for t, running, proc, msg, f in self.take_sample_rows():
            out.append(Sample(t, running, proc, msg, f["inputs"], f["outputs"], f["pwm"],
                              f["dac"], f["adc"], f["axes"], f["velocities"],
                              f.get("vio", ())))
        return out

    @property
    def proc(self) -> int:
        """The hardware PLC's ``proc``: the running procedure's, else the last one's."""
        hw = self.hw
        return hw.slots[abi.SLOT_PROC] if hw is not None else self._proc

    def bind_input(self, pin: int, name: str, eparam: int = 0, source: str = "in") -> None:
        """Start ``name`` whenever ``source`` ``pin`` goes from 0 to 1 (seen at the
        beginning of a tick, as a start given from outside would be): an input
        ("in"), a virtual input or output ("vin", "vout": 1..32) or the output of
        PLS ``pin`` ("pls": the seed's ``EventOn MyEvent MyPLS.PlsOutput = ON``)."""
        if name not in self.programs:
            raise KeyError(name)
        key = (source, pin)
        self.bindings[key] = (name, int(eparam))
        self._levels[key] = self._level(key)

    def unbind_input(self, pin: int, source: str = "in") -> None:
        self.bindings.pop((source, pin), None)
        self._levels.pop((source, pin), None)

    def _level(self, key: tuple[str, int]) -> int:
        """The level now of a bound source."""
        source, n = key
        m = self.machine
        if source == "in":
            return m.portget(n)
        if source == "vin":
            return m.vio.vin >> (n - 1) & 1
        if source == "vout":
            return m.vio.vout >> (n - 1) & 1
        p = m.pls.units.get(n)
        return p.state if p is not None and p.enabled else 0

    def _input_edges(self) -> None:
        get = self._level
        for key, (name, eparam) in list(self.bindings.items()):
            level = get(key)
            if level and not self._levels.get(key):
                program = self.programs.get(name)
                if program is not None and program.kind is Kind.HARDWARE:
                    self.start_hardware(name, eparam)
                elif program is not None:
                    self.start_software(name, eparam)
            self._levels[key] = level

    def _apply_due(self, t: int) -> None:
        due = [d for d in self._due_hw if d[0] <= t]
        self._due_hw = [d for d in self._due_hw if d[0] > t]
        for _t, name, eparam in due:
            if name in self.programs:
                self.start_hardware(name, eparam)


#: program code -> whether it may write its ``message`` (a STORE, INC or DEC of the slot)
_MESSAGE_WRITERS: dict[bytes, bool] = {}


def _writes_message(program: Program) -> bool:
    """Whether ``program``'s code may write its ``message`` slot."""
    code = program.code
    known = _MESSAGE_WRITERS.get(code)
    if known is None:
        if len(_MESSAGE_WRITERS) > 256:
            _MESSAGE_WRITERS.clear()
        try:
            known = any(i.op in WRITES_SLOT and i.arg == abi.SLOT_MESSAGE
                        for i in decode(code))
        except Exception:  # noqa: BLE001 - code that does not decode: assume it may
            known = True
        _MESSAGE_WRITERS[code] = known
    return known


def _not_started(_value=None) -> None:
    return None


def _finished(_value=None) -> None:
    raise StopIteration


class _AtFault(Exception):
    """What a procedure halted at its fault raises when it goes on (it ends then)."""


def _at_fault(_value=None) -> None:
    raise _AtFault
