"""``plcbuilder run``: compile a procedure or a project, simulate it, report.

    run(target, RunOptions(...)) -> RunResult

1. compile the target: one ``.plc`` file (a hardware procedure, or a software
   one with ``software=True``) or a project folder (every procedure of
   ``hardware/`` and ``software/``, with its include folder, size limits,
   ``plc-variables.xml`` and machine file);
2. build a :class:`~plcbuilder.controller.controller.Controller` and load them;
3. run the scenario (``--start``/``--input``/``--adc`` and a scenario file)
   until the time limit, or until no procedure runs and none is due to start;
4. report what happened as the dict of SPEC §5 (``RunResult.report``),
   streaming one CSV row per tick to the trace file while it runs.

Bad usage (a missing target, a bad machine or scenario file, an unknown
``--start`` name) raises :class:`UsageError`; compile errors are returned as
diagnostics with ``report`` None. Nothing here prints.
"""

from __future__ import annotations

import gzip
import io
from dataclasses import dataclass, field
from pathlib import Path
from typing import Optional, Sequence

from plcbuilder import api
from plcbuilder.bytecode import abi
from plcbuilder.bytecode.program import Program
from plcbuilder.controller.events import Ended, Fault, Message, Note, Print, Started

DEFAULT_MS = 60_000
MAX_MS = 7 * 24 * 3600 * 1000          # a week of simulated time
CHUNK_MS = 1000


class UsageError(Exception):
    """The run cannot start as asked; the message says why (exit status 2)."""


@dataclass
class RunOptions:
    ms: Optional[int] = None             # the time limit (None: DEFAULT_MS)
    eparam: int = 0                      # for a single-file target
    starts: Sequence[str] = ()           # "NAME[:EPARAM]@MS"
    inputs: Sequence[str] = ()           # "PIN=0|1@MS"
    adcs: Sequence[str] = ()             # "CH=VALUE@MS"
    scenario: Optional[Path] = None
    machine: Optional[Path] = None
    software: bool = False
    strict: bool = False
    include_dirs: tuple = ()
    trace: Optional[Path] = None         # CSV, one row per tick (gzip when it ends in .gz)
    backend: str = "fast"
    gvarget_latency_ms: int = 0


@dataclass
class RunResult:
    compiled: list = field(default_factory=list)     # api.CompileResult per procedure
    report: Optional[dict] = None                    # None when a procedure has errors

    @property
    def ok(self) -> bool:
        return self.report is not None


# ------------------------------------------------------------------ compile

@dataclass
class _Target:
    programs: list[Program]
    compiled: list
    machine_path: Optional[Path]
    variables: Optional[list[int]]
    single: Optional[Program]            # the procedure of a single-file target


def _compile_target(target: Path, opts: RunOptions) -> _Target:
    if target.is_dir():
        return _compile_project(target, opts)
    if not target.exists():
        raise UsageError(f"{target}: no such file or folder")
    kind = api.kind_for_path(target, opts.software)
    options = api.CompileOptions(kind=kind, strict=opts.strict,
                                 include_dirs=tuple(opts.include_dirs))
    r = api.compile_file(target, options)
    program = r.program if r.ok else None
    return _Target([program] if program else [], [r], None, None, program)


def _compile_project(root: Path, opts: RunOptions) -> _Target:
    from plcbuilder.controller import machine_config, variables_xml
    from plcbuilder.project.model import DEFAULT_MACHINE, Project, ProjectError
    try:
        project = Project.open(root)
        procs = project.procedures()
    except ProjectError as exc:
        raise UsageError(str(exc)) from None
    if not procs:
        raise UsageError(f"{root}: no procedures (a project has hardware/*.plc and "
                         f"software/*.plc)")
    strict = opts.strict or project.settings.strict
    includes = tuple(opts.include_dirs) + tuple(project.include_dirs())
    compiled, programs = [], []
    for proc in procs:
        options = api.CompileOptions(kind=proc.kind, strict=strict, include_dirs=includes,
                                     code_limit=project.limits.proc_limit(proc.kind))
        r = api.compile_file(proc.path, options)
        compiled.append(r)
        if r.ok and r.program is not None:
            programs.append(r.program)
    names: dict[str, Path] = {}
    for proc in procs:
        if proc.name in names:
            raise UsageError(f"two procedures named {proc.name}: {names[proc.name]} and "
                             f"{proc.path}")
        names[proc.name] = proc.path
    variables = None
    if project.variables_path.is_file():
        try:
            variables = variables_xml.load_variables(project.variables_path)
        except machine_config.ConfigError as exc:
            raise UsageError(str(exc)) from None
    machine = project.machine_path if project.machine_path.is_file() else None
    if machine is None and project.settings.machine != DEFAULT_MACHINE:
        raise UsageError(f"{project.settings_path}: machine: no such file "
                         f"{project.machine_path}")
    return _Target(programs, compiled, machine, variables, None)


# ------------------------------------------------------------------- trace

class TraceWriter:
    """One CSV row per tick: ``t_ms, proc, message, running``, the input and
    output words the machine has (``in0``…, ``out0``…; pin n is bit n%32 of
    word n//32), ``pwm0..7``, ``dac0..7`` and the machine position of each
    configured axis in 0.01 mm. A path ending in ``.gz`` is gzip-compressed."""

    def __init__(self, path: Path, machine):
        self.path = Path(path)
        self.n_in = max(1, (getattr(machine, "input_count", 256) + 31) // 32)
        self.n_out = max(1, (getattr(machine, "output_count", 256) + 31) // 32)
        axes = list(machine.axis_positions())
        self.axis_idx = [abi.AXES.index(a) for a in axes]
        try:
            if self.path.suffix == ".gz":
                raw = gzip.open(self.path, "wb", compresslevel=3)
                self.f = io.TextIOWrapper(raw, encoding="ascii", newline="")
            else:
                self.f = open(self.path, "w", encoding="ascii", newline="",
                              buffering=1 << 20)
        except OSError as exc:
            raise UsageError(f"{self.path}: cannot write the trace: {exc.strerror or exc}") \
                from None
        head = (["t_ms", "proc", "message", "running"]
                + [f"in{i}" for i in range(self.n_in)] + [f"out{i}" for i in range(self.n_out)]
                + [f"pwm{i}" for i in range(8)] + [f"dac{i}" for i in range(8)] + axes)
        self.f.write(",".join(head) + "\n")
        self._key = None
        self._tail = ""
        self.rows = 0

    def write(self, rows) -> None:
        """Write sample rows ``(t_ms, running, proc, message, fields)`` as given
        by Controller.drain_sample_rows()."""
        n_in, n_out, idx = self.n_in, self.n_out, self.axis_idx
        key, tail = self._key, self._tail
        out = []
        for t, running, proc, msg, f in rows:
            if f is not key:                # the machine's dict is shared while unchanged
                key = f
                ax = f["axes"]
                tail = ",".join(map(str, (*f["inputs"][:n_in], *f["outputs"][:n_out], *f["pwm"],
                                          *f["dac"], *(ax[i] for i in idx))))
            out.append(f"{t},{proc},{msg},{running or ''},{tail}\n")
        self._key, self._tail = key, tail
        self.rows += len(out)
        self.f.write("".join(out))

    def close(self) -> None:
        self.f.close()


# --------------------------------------------------------------------- run

def _scenario(opts: RunOptions):
    from plcbuilder.controller.scenario import (Scenario, ScenarioError, parse_adc, parse_input,
                                                parse_start)
    sc = Scenario()
    try:
        if opts.scenario is not None:
            sc.extend(Scenario.load(opts.scenario).actions)
        sc.extend(parse_start(s) for s in opts.starts)
        sc.extend(parse_input(s) for s in opts.inputs)
        sc.extend(parse_adc(s) for s in opts.adcs)
    except ScenarioError as exc:
        raise UsageError(str(exc)) from None
    return sc


def _check_scenario(sc, controller, machine) -> None:
    programs = controller.programs
    n_in = getattr(machine, "input_count", 256)
    for a in sc.actions:
        if a.kind in ("start", "bind") and a.name not in programs:
            loaded = ", ".join(sorted(programs)) or "none"
            raise UsageError(f"--start {a.name}: no procedure named {a.name} (loaded: {loaded})")
        if a.kind in ("input", "bind") and not 0 <= a.a < n_in:
            raise UsageError(f"--input {a.a}: no such input (the machine has inputs "
                             f"0..{n_in - 1})")
        if a.kind == "adc" and not 0 <= a.a < 8:
            raise UsageError(f"--adc {a.a}: no such ADC channel (0..7)")


def run(target, options: Optional[RunOptions] = None) -> RunResult:
    """Compile ``target`` and simulate it (see the module docstring)."""
    from plcbuilder.controller import machine_config, variables_xml
    from plcbuilder.controller.controller import Controller, ControllerError
    from plcbuilder.controller.scenario import Action, drive

    opts = options or RunOptions()
    limit = DEFAULT_MS if opts.ms is None else opts.ms
    if not 0 <= limit <= MAX_MS:
        raise UsageError(f"--ms must be from 0 to {MAX_MS}, not {limit}")
    target = Path(target)
    sc = _scenario(opts)
    tg = _compile_target(target, opts)
    if any(not r.ok for r in tg.compiled):
        return RunResult(tg.compiled, None)
    machine_path = opts.machine if opts.machine is not None else tg.machine_path
    try:
        mconf = machine_config.load_machine(machine_path) if machine_path is not None \
            else machine_config.default_machine()
    except machine_config.ConfigError as exc:
        raise UsageError(str(exc)) from None
    try:
        c = Controller(mconf, backend=opts.backend, variables=tg.variables,
                      gvarget_latency_ms=opts.gvarget_latency_ms,
                      record_samples=opts.trace is not None)
        c.load(tg.programs, autostart=tg.single is None)
    except ControllerError as exc:
        raise UsageError(str(exc)) from None
    if tg.single is not None:
        sc.actions.insert(0, Action(0, "start", tg.single.name, opts.eparam))
    _check_scenario(sc, c, c.machine)

    collector = _Collector(c)
    trace = TraceWriter(opts.trace, c.machine) if opts.trace is not None else None

    def drain() -> None:
        collector.take(c.drain_events())
        if trace is not None:
            trace.write(c.drain_sample_rows())

    try:
        ended = drive(c, sc, limit, until_idle=True, chunk_ms=CHUNK_MS, on_chunk=drain)
        drain()
    except ControllerError as exc:
        raise UsageError(str(exc)) from None
    finally:
        if trace is not None:
            trace.close()
    return RunResult(tg.compiled, collector.report(ended, target))


class _Collector:
    """Turns the controller's events into the lists of the report."""

    def __init__(self, controller):
        self.c = controller
        self.procedures: list[dict] = []
        self.open: dict[str, dict] = {}
        self.messages: list[dict] = []
        self.prints: list[dict] = []
        self.faults: list[dict] = []
        self.notes: list[dict] = []

    def take(self, events) -> None:
        for e in events:
            if isinstance(e, Print):
                self.prints.append({"t_ms": e.t_ms, "register": e.register, "value": e.value,
                                    "from": e.source})
            elif isinstance(e, Message):
                self.messages.append({"t_ms": e.t_ms, "message": e.message, "name": e.name,
                                      "command": e.command, "parameter": e.parameter,
                                      "from": e.source})
            elif isinstance(e, Started):
                entry = {"name": e.name, "kind": e.kind, "started_at_ms": e.t_ms,
                         "ended_at_ms": None, "exit_code": None, "exit_name": None,
                         "vexit": None, "eparam": e.eparam}
                self.procedures.append(entry)
                self.open[e.name] = entry
            elif isinstance(e, Ended):
                entry = self.open.pop(e.name, None)
                if entry is not None:
                    entry.update(ended_at_ms=e.t_ms, exit_code=e.exit_code,
                                 exit_name=e.exit_name, vexit=e.vexit)
            elif isinstance(e, Fault):
                self.faults.append({"t_ms": e.t_ms, "from": e.source, "file": e.file,
                                    "line": e.line, "text": e.text,
                                    "calls": [{"file": f, "line": ln, "procedure": pr}
                                              for f, ln, pr in e.calls]})
            elif isinstance(e, Note):
                self.notes.append({"t_ms": e.t_ms, "level": e.level, "text": e.text})

    def report(self, ended: int, target: Path) -> dict:
        c = self.c
        m = c.machine
        fields = m.sample_fields()
        variables = c.variables()
        for name, entry in self.open.items():          # still running: its vexit so far
            entry["vexit"] = variables.get(name, {}).get("vexit")
        st = c.state()
        return {
            "target": str(target),
            "ended_at_ms": ended,
            "procedures": self.procedures,
            "vars": variables,
            "outputs": m.outputs_on(),
            "pwm": list(fields["pwm"]),
            "dac": list(fields["dac"]),
            "messages": self.messages,
            "prints": self.prints,
            "faults": self.faults,
            "notes": self.notes,
            "axes": m.axis_positions(),
            "proc": st.proc,
            "proc_name": st.proc_name,
            "running": st.running,
            "software": list(st.software),
        }
