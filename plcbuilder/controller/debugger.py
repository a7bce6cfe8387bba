"""The debugger: line breakpoints (conditions, hit counts, logpoints), halting
mid-tick, stepping and the halted state (SPEC §6, docs/debugging.md).

How it reaches the running code: each program has a list of *marks*, one per
code offset, true where something is watched (a breakpoint's offset, a "run
to" target, every statement start of a program being stepped). The reference
interpreter asks before each marked instruction (its per-instruction hook,
controller/vm.py ``_hooks``); the fast
backend, for a program that has breakpoints when a procedure starts, runs a
translation that tests the mark at every statement start (a plain translation
otherwise; a procedure running plain code when its program gets a mark is
handed over to the reference interpreter at its tick end). At a marked
offset both call :meth:`Watch.brk`, which decides: a condition, a hit count,
a logpoint (a log event and no halt), a step that is done, or a halt. A halt
in the fast backend hands the procedure to the reference interpreter, which
goes on from there when it resumes; so both backends halt at the same
instruction with the same stack and variables.

Halting stops the whole controller: the PLC keeps the rest of the tick
(the procedures not yet run, then the end of the tick) and runs it on
:meth:`Debugger.resume` (continue, a step). While halted, time does not move.
"""

from __future__ import annotations

from plcbuilder._support.lazy import Pattern
from plcbuilder._support.records import dataclass, field
from plcbuilder.bytecode import abi
from plcbuilder.bytecode.opcodes import HAS_SLOT, Op, size_of, validate
from plcbuilder.bytecode.program import LoadError, Program
from plcbuilder.controller import vm
from plcbuilder.controller.events import Halted, Log, Resumed

TYPE_CHECKING = False               # (typing is not imported at run time: start-up)
if TYPE_CHECKING:
    from typing import Optional

REASONS = ("breakpoint", "step", "pause", "fault")
HIT_MODES = ("eq", "ge", "every")
STEP_KINDS = ("tick", "into", "over", "out")
_CALL_SIZE = size_of(Op.CALL)
_PLACEHOLDER = Pattern(r"\{([A-Za-z_][A-Za-z0-9_]*)\}")
#: The longest condition or log text a breakpoint takes (the compiler's limit for a
#: condition, plcbuilder.project.conditions.MAX_CONDITION_CHARS, and the link's).
MAX_TEXT = 1000
#: The largest compiled condition or expression (a condition of MAX_TEXT characters
#: compiles to far less).
MAX_CODE = 64 * 1024


class DebugError(Exception):
    """A debugger request refused; the message says why. Nothing was changed."""


@dataclass
class Breakpoint:
    id: int
    file: str
    line: int                          # the line asked for (kept across rebuilds)
    enabled: bool = True
    condition: Optional[str] = None
    code: Optional[bytes] = None       # the compiled condition (a Program binary)
    hit: Optional[tuple[str, int]] = None
    log: Optional[str] = None
    #: where it resolved: program name -> (line, offsets); and the bound conditions
    where: dict = field(default_factory=dict)
    bound: dict = field(default_factory=dict)
    hits: int = 0
    reason: Optional[str] = None

    @property
    def at_line(self) -> int:
        """The line it moved to (the first line with code at or after ``line``)."""
        lines = sorted(ln for ln, _ in self.where.values())
        return lines[0] if lines else self.line

    def answer(self) -> dict:
        return {"id": self.id, "file": self.file, "line": self.at_line,
                "verified": bool(self.where) and self.reason is None, "reason": self.reason}

    def spec(self) -> dict:
        return {"id": self.id, "file": self.file, "line": self.line, "enabled": self.enabled,
                "condition": self.condition,
                "hit": {"mode": self.hit[0], "n": self.hit[1]} if self.hit else None,
                "log": self.log, "hits": self.hits, **{k: v for k, v in self.answer().items()
                                                     if k in ("verified", "reason")},
                "at_line": self.at_line}


@dataclass
class Halt:
    reason: str
    process: object = None             # plc.Process, or None (pause, step tick)
    pc: Optional[int] = None
    rets: tuple = ()
    breakpoint: Optional[Breakpoint] = None
    fault: Optional[str] = None


class Watch:
    """What one running procedure's interpreter asks (``Host.debug``)."""

    __slots__ = ("marks", "brk", "_debugger", "_program")

    def __init__(self, debugger: "Debugger", process):
        self._debugger = debugger
        self._program = process.program
        self.marks = debugger._marks_of(process.program)

        at = debugger._at_of(process.program.name)      # kept up to date in place

        def brk(pc: int, rets, _d=debugger, _p=process, _at=at) -> bool:
            # asked at every watched statement start: the common case (no
            # step going on, no breakpoint at pc) answered here at once
            if _d._busy:                    # a step or a run-to goes on
                return _d._reached(_p, pc, rets)
            bps = _at.get(pc)
            return bps is not None and _d._breakpoints_at(_p, pc, rets, bps)

        self.brk = brk

    def table(self, program: Program, base: list) -> list:
        return self._debugger._table_of(program, base)


def resolve(program: Program, file: str, line: int) -> Optional[tuple[int, list[int]]]:
    """(the line, its offsets): the first line at or after ``line`` of ``file``
    that has code in ``program``, and the offsets where that line is entered
    (an entry of the line table whose previous entry is another line)."""
    want = [i for i, f in enumerate(program.files) if _same_file(f, file)]
    if not want:
        return None
    starts: dict[int, list[int]] = {}
    prev = None
    for e in sorted(program.lines, key=lambda e: e.pc):
        key = (e.file, e.line)
        if e.file in want and e.line >= line and key != prev:
            starts.setdefault(e.line, []).append(e.pc)
        prev = key
    if not starts:
        return None
    first = min(starts)
    return first, starts[first]


def _same_file(stored: str, asked: str) -> bool:
    if stored == asked:
        return True
    a = asked.replace("\\", "/").rsplit("/", 1)[-1]
    return stored.replace("\\", "/").rsplit("/", 1)[-1] == a


def bind(condition: Program, target: Program) -> Program:
    """The condition with its variables renumbered to ``target``'s slots, by
    name (predefined variables have the same slots everywhere)."""
    slots = {n: abi.FIRST_USER_SLOT + i for i, n in enumerate(target.var_names)}
    own = {abi.FIRST_USER_SLOT + i: n for i, n in enumerate(condition.var_names)}
    code = bytearray(condition.code)
    for ins in validate(condition.code, condition.entry):
        if ins.op in HAS_SLOT and ins.arg in own:
            name = own[ins.arg]
            if name not in slots:
                raise DebugError(f"the condition reads {name!r}, which is not a variable "
                                 f"of {target.name}")
            code[ins.offset + 1] = slots[name]
    return Program(condition.name, target.kind, bytes(code), condition.entry,
                   list(target.var_names), list(condition.files), list(condition.lines),
                   list(condition.procs))


class Debugger:
    """Breakpoints, stepping and the halted state of one PLC (``controller.debugger``)."""

    def __init__(self, plc):
        self.plc = plc
        self._next_id = 1
        self._bps: dict[str, list[Breakpoint]] = {}      # by file as given
        self._marks: dict[str, list] = {}                 # program name -> per-offset marks
        self._tables: dict[str, tuple[list, list]] = {}   # program name -> (base, table)
        #: program name -> offset -> the enabled breakpoints there
        self._at: dict[str, dict[int, list[Breakpoint]]] = {}
        self._busy = False                                # a step or a run-to goes on
        self._run_to: dict[str, set[int]] = {}
        self._stepping: Optional[tuple] = None            # (process, kind, depth)
        self._step_end_tick = False                       # halt at this tick's end
        self.halt: Optional[Halt] = None
        self._told: Optional[Halt] = None                 # the halt last announced
        self._halt_on_fault = False
        #: counts the statements one procedure reaches (stepping back, controller/rewind.py):
        #: an object with ``name`` and ``reach(t, pc, rets) -> bool`` (True: halt there)
        self.counter = None

    # ----------------------------------------------------------- queries
    @property
    def halt_on_fault(self) -> bool:
        """Halt at a runtime fault even with no breakpoint set (the IDE's debug session)."""
        return self._halt_on_fault

    @halt_on_fault.setter
    def halt_on_fault(self, on: bool) -> None:
        self._halt_on_fault = bool(on)
        self._remark()

    @property
    def on(self) -> bool:
        """Whether faults halt: a breakpoint is set, a step runs, or asked for."""
        return self.halt_on_fault or any(self._at.values()) or any(self._bps.values()) \
            or self._stepping is not None or bool(self._run_to) or self.counter is not None

    @property
    def halted(self) -> bool:
        return self.halt is not None

    def breakpoints(self) -> list[dict]:
        return [bp.spec() for file in sorted(self._bps) for bp in self._bps[file]]

    def watched(self, program: Program) -> bool:
        """Whether a procedure of ``program`` starting now runs watched code."""
        marks = self._marks.get(program.name)
        return marks is not None and any(marks) or any(
            program.name in bp.where for bps in self._bps.values() for bp in bps)

    def watch(self, process) -> Watch:
        return Watch(self, process)

    # ------------------------------------------------------- breakpoints
    def set_breakpoints(self, file: str, specs: list) -> list[dict]:
        """Replace the breakpoints of ``file`` with ``specs`` (dicts: line,
        enabled, condition ({text, code} or None), hit ({mode, n} or None),
        log). Refuses the whole request (DebugError) when one is bad."""
        if not isinstance(file, str) or not file.strip():
            raise DebugError("a breakpoint needs a file name")
        if not isinstance(specs, (list, tuple)):
            raise DebugError("breakpoints must be a list")
        programs = self._programs_with(file)
        if specs and not programs:
            loaded = sorted({_base(f) for p in self.plc.programs.values() for f in p.files})
            raise DebugError(f"no loaded procedure is built from {file!r}"
                             + (f" (files: {', '.join(loaded[:20])})" if loaded else
                                " (nothing is loaded)"))
        made = []
        for k, spec in enumerate(specs):
            made.append(self._make(file, spec, programs, f"breakpoint {k + 1}"))
        old = {(bp.line, bp.condition, bp.hit, bp.log): bp for bp in self._bps.get(file, [])}
        for bp in made:                     # a breakpoint set again keeps its id and hits
            same = old.get((bp.line, bp.condition, bp.hit, bp.log))
            if same is not None:
                bp.id, bp.hits = same.id, same.hits
            else:
                bp.id, self._next_id = self._next_id, self._next_id + 1
        if made:
            self._bps[file] = made
        else:
            self._bps.pop(file, None)
        self._remark()
        return [bp.answer() for bp in made]

    def _make(self, file: str, spec, programs: list[Program], what: str) -> Breakpoint:
        if not isinstance(spec, dict):
            raise DebugError(f"{what}: not an object")
        line = spec.get("line")
        if isinstance(line, bool) or not isinstance(line, int) or line < 1:
            raise DebugError(f"{what}: line must be a whole number from 1, not {line!r}")
        bp = Breakpoint(0, file, line, enabled=bool(spec.get("enabled", True)))
        hit = spec.get("hit")
        if hit is not None:
            if not isinstance(hit, dict) or hit.get("mode") not in HIT_MODES:
                raise DebugError(f"{what}: hit must be {{mode: eq|ge|every, n}}, not {hit!r}")
            n = hit.get("n")
            if isinstance(n, bool) or not isinstance(n, int) or n < 1:
                raise DebugError(f"{what}: hit count n must be 1 or more, not {n!r}")
            bp.hit = (hit["mode"], n)
        log = spec.get("log")
        if log is not None and (not isinstance(log, str) or len(log) > MAX_TEXT):
            raise DebugError(f"{what}: log must be text of at most {MAX_TEXT} characters")
        bp.log = log
        cond = spec.get("condition")
        if cond is not None:
            if isinstance(cond, Program):
                cond = {"text": cond.name, "code": cond.to_bytes()}
            if not isinstance(cond, dict) or not isinstance(cond.get("code"), (bytes, bytearray)):
                raise DebugError(f"{what}: a condition must arrive compiled ({{text, code}})")
            if len(str(cond.get("text") or "")) > MAX_TEXT or len(cond["code"]) > MAX_CODE:
                raise DebugError(f"{what}: a condition is at most {MAX_TEXT} characters "
                                 f"({MAX_CODE // 1024} KiB compiled)")
            try:
                Program.from_bytes(bytes(cond["code"]))
            except LoadError as exc:
                raise DebugError(f"{what}: the compiled condition is damaged: {exc}") from None
            bp.condition = str(cond.get("text") or "")
            bp.code = bytes(cond["code"])
        self._resolve(bp, programs)
        if bp.reason is not None and programs:
            raise DebugError(f"{what}: {bp.reason}")
        if programs and not bp.where:
            last = max((e.line for p in programs for e in p.lines
                        if _same_file(p.files[e.file] if e.file < len(p.files) else "", file)),
                       default=0)
            raise DebugError(f"{what}: {file} has no code on line {line} or after it "
                             f"(its last line with code is {last})")
        return bp

    def _programs_with(self, file: str) -> list[Program]:
        return [p for _n, p in sorted(self.plc.programs.items())
                if any(_same_file(f, file) for f in p.files)]

    def _resolve(self, bp: Breakpoint, programs: list[Program]) -> None:
        """Where bp is in these programs (its offsets), and its condition bound to each."""
        bp.where, bp.bound, bp.reason = {}, {}, None
        for p in programs:
            r = resolve(p, bp.file, bp.line)
            if r is None:
                continue
            if bp.code is not None:
                try:
                    bp.bound[p.name] = bind(Program.from_bytes(bp.code), p)
                except DebugError as exc:
                    bp.reason = str(exc)
                    continue
            bp.where[p.name] = r
        if not programs:
            bp.reason = f"no loaded procedure is built from {bp.file}"

    def rebind(self) -> None:
        """After a rebuild: every breakpoint again on its line in the new programs."""
        self._stepping = None
        self._run_to.clear()
        self._marks.clear()
        self._tables.clear()
        for file, bps in self._bps.items():
            programs = self._programs_with(file)
            for bp in bps:
                self._resolve(bp, programs)
        self._remark()

    def copy_breakpoints(self, other: "Debugger") -> None:
        """The breakpoints of ``other`` (hits from 0) and its halt-on-fault, for a
        controller that runs the same session again (stepping back)."""
        self._bps = {file: [Breakpoint(bp.id, bp.file, bp.line, bp.enabled, bp.condition,
                                       bp.code, bp.hit, bp.log) for bp in bps]
                     for file, bps in other._bps.items()}
        self._next_id = other._next_id
        self._halt_on_fault = other._halt_on_fault
        self.rebind()

    def clear(self) -> None:
        """No breakpoint, no step, not halted (the rest of a halted tick is the PLC's)."""
        self._bps.clear()
        self._run_to.clear()
        self._stepping = None
        self.halt = None
        self._remark()

    def _remark(self) -> None:
        """Marks from the breakpoints, the run-to targets and the step, set in
        place (running interpreters see them); procedures running plain fast
        code whose program gains marks go over to the reference interpreter."""
        at: dict[str, dict[int, list[Breakpoint]]] = {}
        for bps in self._bps.values():
            for bp in bps:
                if not bp.enabled:
                    continue
                for name, (_line, pcs) in bp.where.items():
                    for pc in pcs:
                        at.setdefault(name, {}).setdefault(pc, []).append(bp)
        for name in set(self._at) | set(at):
            mine = self._at_of(name)
            mine.clear()
            mine.update(at.get(name, {}))
        counter = self.counter
        self._busy = self._stepping is not None or bool(self._run_to) or counter is not None
        want: dict[str, set[int]] = {name: set(pcs) for name, pcs in at.items() if pcs}
        for name, pcs in self._run_to.items():
            want.setdefault(name, set()).update(pcs)
        step = self._stepping
        if step is not None:
            prog = step[0].program
            want.setdefault(prog.name, set()).update(e.pc for e in prog.lines)
        if counter is not None and counter.name in self.plc.programs:
            prog = self.plc.programs[counter.name]
            want.setdefault(prog.name, set()).update(e.pc for e in prog.lines)
        for name, program in self.plc.programs.items():
            pcs = want.get(name, ())
            if not pcs and name not in self._marks:
                continue
            marks = self._marks_of(program)
            table = self._tables.get(name)
            for pc in range(len(marks)):
                on = pc in pcs
                if marks[pc] != on:
                    marks[pc] = on
                    if table is not None:
                        table[1][pc] = on or table[0][pc]
            if pcs:
                for p in self.plc.running():
                    if p.program is program:
                        self.plc.watch_process(p)
        self.plc.halting = self.on
        self.plc.watching = self._stepping is not None or bool(self._run_to) \
            or counter is not None

    def _at_of(self, name: str) -> dict:
        """The breakpoints of a program by offset (one dict, changed in place)."""
        at = self._at.get(name)
        if at is None:
            at = self._at[name] = {}
        return at

    def _marks_of(self, program: Program) -> list:
        marks = self._marks.get(program.name)
        if marks is None or len(marks) != len(program.code) + 1:
            marks = self._marks[program.name] = [False] * (len(program.code) + 1)
        return marks

    def _table_of(self, program: Program, base: list) -> list:
        """A list true where ``program`` is marked or ``base`` (coverage's list of
        the offsets not yet seen) is; kept so as the marks change (:meth:`_remark`)
        and by the interpreter as ``base`` changes (controller/vm.py ``_hooks``)."""
        entry = self._tables.get(program.name)
        if entry is None or entry[0] is not base:
            marks = self._marks_of(program)
            table = [marks[pc] or bool(b) for pc, b in enumerate(base)]
            entry = self._tables[program.name] = (base, table)
        return entry[1]

    # ------------------------------------------------------------ reaching
    def _reached(self, p, pc: int, rets) -> bool:
        """An interpreter reached a marked offset: True to halt before it."""
        counter = self.counter
        if counter is not None and p.name == counter.name and \
                counter.reach(self.plc.t, pc, rets):
            return self._halt_at("step", p, pc, rets)
        step = self._stepping
        if step is not None and step[0] is p:
            depth = len(rets)
            kind, depth0 = step[1], step[2]
            if kind == "into" or (kind == "over" and depth <= depth0) or \
                    (kind == "out" and depth < depth0):
                return self._halt_at("step", p, pc, rets)
        if pc in self._run_to.get(p.program.name, ()):
            return self._halt_at("step", p, pc, rets)
        bps = self._at.get(p.program.name, {}).get(pc)
        return bps is not None and self._breakpoints_at(p, pc, rets, bps)

    def _breakpoints_at(self, p, pc: int, rets, bps: list) -> bool:
        """The breakpoints at pc decide: a condition, a hit count, a logpoint, a halt."""
        for bp in bps:
            if bp.code is not None and not self._holds(bp, p):
                continue
            bp.hits += 1
            if bp.hit is not None:
                mode, n = bp.hit
                if mode == "eq" and bp.hits != n or mode == "ge" and bp.hits < n \
                        or mode == "every" and bp.hits % n:
                    continue
            if bp.log is not None:
                self._log(p, bp.log)
                continue
            return self._halt_at("breakpoint", p, pc, rets, bp)
        return False

    def _holds(self, bp: Breakpoint, p) -> bool:
        cond = bp.bound.get(p.program.name)
        if cond is None:
            return False
        try:
            next(vm.run_reference(cond, p.slots, p.host.for_expression()))
        except vm.ProcExit as done:
            return done.code != 0
        except vm.VMFault as exc:
            self._log(p, f"breakpoint condition {bp.condition!r}: {exc.text}")
            return False
        return False

    def _log(self, p, text: str) -> None:
        values = p.variables()
        out = _PLACEHOLDER.sub(lambda m: str(values[m.group(1)]) if m.group(1) in values
                               else m.group(0), text)
        self.plc.events.append(Log(self.plc.t, p.name, out))

    def _halt_at(self, reason: str, p, pc: int, rets, bp=None) -> bool:
        self.halt = Halt(reason, p, pc, tuple(rets), bp)
        self._finish_command()
        return True

    def faulted(self, p, pc: Optional[int], text: str, callers) -> bool:
        """A runtime fault in p: True when it halts there (the PLC ends p on resume)."""
        if not self.on or pc is None:
            return False
        rets = tuple(c + _CALL_SIZE for c in reversed(list(callers)))
        self.halt = Halt("fault", p, pc, rets, fault=text)
        self._finish_command()
        return True

    def ended(self, p) -> None:
        """p ended: a step in it halts at the end of this tick."""
        if self._stepping is not None and self._stepping[0] is p:
            self._stepping = None
            self._step_end_tick = True

    def tick_ended(self) -> None:
        """The end of a tick (the PLC calls this while watching)."""
        if self._step_end_tick and self.halt is None:
            self._step_end_tick = False
            self.halt = Halt("step")
            self._finish_command()

    def _finish_command(self) -> None:
        """A halt ends the step or run-to that was going on."""
        self._step_end_tick = False
        if self._stepping is not None or self._run_to:
            self._stepping = None
            self._run_to.clear()
            self._remark()

    def settle(self) -> None:
        """Announce what changed since the last call: a ``resumed`` event when
        the halt announced is over, a ``halted`` event (with the state) for a
        new one. The controller calls it after running ticks and after each command."""
        h = self.halt
        if h is self._told:
            return
        events = self.plc.events
        if self._told is not None:
            events.append(Resumed(self.plc.t))
        if h is not None:
            events.append(Halted(self.plc.t, self.halted_state()))
        self._told = h

    def unannounce(self) -> None:
        """Take back the announcement of the last halt (while its event is
        not taken yet) and forget it: the halt was a replay's own, to do an
        action where it was done live (controller/scenario.py, ``Action.at``);
        nobody halted there."""
        if self._told is not None:
            events = self.plc.events
            for k in range(len(events) - 1, -1, -1):
                if isinstance(events[k], Halted):
                    del events[k]
                    break
        self._told = None

    # ------------------------------------------------------------ commands
    def pause(self) -> None:
        """Halt at the end of the current tick (now, between ticks)."""
        if self.halt is None:
            self.halt = Halt("pause")
            self._finish_command()
        self.settle()

    def resume(self) -> None:
        """Continue: the rest of a halted tick runs (it may halt again)."""
        if self.halt is None:
            return
        self.halt = None
        self.plc.resume_tick()
        self.settle()

    def step(self, kind: str, procedure: Optional[str] = None) -> None:
        """Step ``kind`` (tick, into, over, out) in ``procedure`` (default: the one halted)."""
        if kind not in STEP_KINDS:
            raise DebugError(f"unknown step {kind!r} (one of {', '.join(STEP_KINDS)})")
        if self.halt is None:
            raise DebugError("not halted: pause first")
        if kind == "tick":                  # the rest of this tick, or one whole tick
            self.halt = None
            mid_tick = self.plc.mid_tick
            if self.plc.resume_tick() and not mid_tick:
                self.plc.run(1)
            if self.halt is None:
                self.halt = Halt("step")
            self.settle()
            return
        p = self._procedure(procedure)
        depth = len(self._position(p)[1])
        self.plc.watch_process(p)
        self._stepping = (p, kind, depth)
        self._remark()
        self.halt = None
        self.plc.resume_tick()
        self.settle()

    def run_to(self, file: str, line: int) -> dict:
        """Run until any procedure reaches ``file:line`` (a one-time breakpoint)."""
        if self.halt is None:
            raise DebugError("not halted: pause first")
        programs = self._programs_with(file)
        if not programs:
            raise DebugError(f"no loaded procedure is built from {file!r}")
        if isinstance(line, bool) or not isinstance(line, int) or line < 1:
            raise DebugError(f"line must be a whole number from 1, not {line!r}")
        found = {p.name: r for p in programs if (r := resolve(p, file, line)) is not None}
        if not found:
            raise DebugError(f"{file} has no code on line {line} or after it")
        self._run_to = {name: set(pcs) for name, (_ln, pcs) in found.items()}
        self._remark()
        self.halt = None
        self.plc.resume_tick()
        self.settle()
        return {"file": file, "line": min(ln for ln, _ in found.values())}

    def _procedure(self, name: Optional[str]):
        running = self.plc.running()
        if name is None:
            h = self.halt
            if h.process is not None and h.process in running and h.reason != "fault":
                return h.process
            if self.plc.hw is not None:
                return self.plc.hw
            if running:
                return running[0]
            raise DebugError("no procedure is running")
        for p in running:
            if p.name == name:
                return p
        raise DebugError(f"{name!r} is not running (running: "
                         f"{', '.join(p.name for p in running) or 'none'})")

    # ------------------------------------------------------- evaluate
    def evaluate(self, code: bytes, procedure: Optional[str] = None) -> int:
        """The value of an expression compiled as a condition is
        (``compile_condition``), over the variables of ``procedure`` (None: the
        halted one, else the hardware one, else the first running); built-in
        functions read the machine as the procedure would. It writes nothing."""
        if len(code) > MAX_CODE:
            raise DebugError(f"a compiled expression is at most {MAX_CODE // 1024} KiB")
        try:
            cond = Program.from_bytes(bytes(code))
        except LoadError as exc:
            raise DebugError(f"the compiled expression is damaged: {exc}") from None
        if procedure is None and self.halt is None:
            running = self.plc.running()
            if not running:
                raise DebugError("no procedure is running")
            p = self.plc.hw if self.plc.hw is not None else running[0]
        else:
            p = self._procedure(procedure)
        p.sync()
        bound = bind(cond, p.program)

        def refused(*_a):
            raise DebugError("an expression to evaluate may not write")
        host = p.host.for_expression(write=refused)
        try:
            next(vm.run_reference(bound, list(p.slots), host))
        except vm.ProcExit as done:
            return done.code
        except vm.VMFault as exc:
            raise DebugError(f"{exc.text}") from None
        raise DebugError("the expression did not end")       # pragma: no cover

    # ------------------------------------------------------- halted state
    # (controller/halted_state.py is loaded when first asked: a run that never
    # steps or halts does not need it)
    def _position(self, p) -> tuple[Optional[int], tuple, bool]:
        from plcbuilder.controller.halted_state import position
        return position(self, p)

    def halted_state(self) -> Optional[dict]:
        """The halted state (docs/debugging.md), or None while running."""
        from plcbuilder.controller.halted_state import state_of
        return state_of(self)


def _base(f: str) -> str:
    return f.replace("\\", "/").rsplit("/", 1)[-1]
