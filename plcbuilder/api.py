"""The facade: what the command line and the IDE call, composing the stages.

    check / compile     compile_source, compile_file, compile_bytes -> CompileResult
    binaries            load_program, disassemble (text), instructions (records)
    projects            Project, create_project, build_project, compile_all
    run                 run(target, RunOptions) -> RunResult: compile, load, simulate
    debugging           compile_condition (a breakpoint's condition, compiled)
    test                test(project, TestOptions) -> TestRun: scenario tests (tests/*.toml)
    rendering           render_text, summary (diagnostics as text)

and the names a caller needs with them (``Kind``, ``Diagnostic``, the ABI tables
as ``abi``, the controller's events as ``events``). Options are passed in;
nothing here keeps global state or prints.
"""

from __future__ import annotations

import importlib
from pathlib import Path

from plcbuilder._support.records import dataclass, field, replace
from plcbuilder._support.files import atomic_write, read_bounded
from plcbuilder.bytecode import abi
from plcbuilder.bytecode.abi import proc_name
from plcbuilder.bytecode.kind import Kind
from plcbuilder.diagnostics import (Diagnostic, Related, Severity, Span, error, render_text,
                                    summary, summary_counts)
from plcbuilder.lang.options import CompileOptions

TYPE_CHECKING = False               # (typing is not imported at run time: start-up)
if TYPE_CHECKING:
    from typing import Callable, Optional, Sequence

if TYPE_CHECKING:                    # loaded on first use (_LAZY): for the type checkers
    from plcbuilder.bytecode.program import MAGIC, LoadError, Program
    from plcbuilder.controller import events
    from plcbuilder.controller.events import ControllerStatus
    from plcbuilder.bytecode import disasm
    from plcbuilder.controller.controller import Controller, ControllerError
    from plcbuilder.controller.debugger import DebugError
    from plcbuilder.controller.history import History, Trace
    from plcbuilder.controller.io_dat import io_dat_of, io_dat_path, load_io_dat, with_io_dat
    from plcbuilder.controller.machine_config import ConfigError, default_machine, load_machine
    from plcbuilder.controller.recorder import image_id
    from plcbuilder.controller.scenario import Action
    from plcbuilder.controller.session import UsageError, build_scenario, run_session
    from plcbuilder.controller.targets import TargetConfig
    from plcbuilder.controller.trigger import (Capturer, TriggerError, parse_trigger,
                                              watched_variables)
    from plcbuilder.lang.preprocess import BUILTIN_PREFIX, builtin_header, builtin_header_names
    from plcbuilder.controller.variables_xml import load_variables
    from plcbuilder.image.manifest import ImageError, read_image, write_image
    from plcbuilder.lang.highlight import PlcLexer
    from plcbuilder.lang.pipeline import CompileResult, compile_bytes, compile_file, compile_source
    from plcbuilder.project import (BuildResult, ProcedureBuild, Project, ProjectError,
                                    build_project, create_project)
    from plcbuilder.project.build import compile_all
    from plcbuilder.project.conditions import compile_condition
    from plcbuilder.project.model import DEFAULT_MACHINE, kind_of
    from plcbuilder.testing.cobertura import cobertura_xml, coverage_totals, write_cobertura
    from plcbuilder.testing.junit import junit_xml, write_junit
    from plcbuilder.testing.runner import Suite, SuiteError, SuiteRun, prepare, run_suite
    from plcbuilder.testing.spec import TestFileError
    from plcbuilder.trace import compare as trace_compare, export as trace_export, file as trace_file
    from plcbuilder.trace.compare import CompareError
    from plcbuilder.trace.export import ExportError
    from plcbuilder.trace.file import TraceFileError

#: The heavy stages (the compiler and lark, the controller, projects, tests,
#: traces), loaded the first time one of their names is used, through this
#: module's ``__getattr__`` (``from plcbuilder.api import X`` and ``api.X`` work
#: as before) or :func:`_load` (this module's own functions): importing the
#: facade costs little, so the IDE paints its window before they load.
_LAZY: dict[str, tuple[str, str | None]] = {}
for _module, _names in (
        ("plcbuilder.bytecode.program", "MAGIC LoadError Program"),
        ("plcbuilder.controller.controller", "Controller ControllerError"),
        ("plcbuilder.controller.debugger", "DebugError"),
        ("plcbuilder.controller.events", "ControllerStatus"),
        ("plcbuilder.controller.history", "History Trace"),
        ("plcbuilder.controller.io_dat", "io_dat_of io_dat_path load_io_dat with_io_dat"),
        ("plcbuilder.controller.machine_config", "ConfigError default_machine load_machine"),
        ("plcbuilder.controller.recorder", "image_id"),
        ("plcbuilder.controller.scenario", "Action"),
        ("plcbuilder.controller.session", "UsageError build_scenario run_session"),
        ("plcbuilder.controller.targets", "TargetConfig"),
        ("plcbuilder.controller.trigger", "Capturer TriggerError parse_trigger watched_variables"),
        ("plcbuilder.controller.variables_xml", "load_variables"),
        ("plcbuilder.image.manifest", "ImageError read_image write_image"),
        ("plcbuilder.lang.highlight", "PlcLexer"),
        ("plcbuilder.lang.preprocess", "BUILTIN_PREFIX builtin_header builtin_header_names"),
        ("plcbuilder.lang.pipeline",
         "CompileResult compile_bytes compile_file compile_source"),
        ("plcbuilder.project",
         "BuildResult ProcedureBuild Project ProjectError build_project create_project"),
        ("plcbuilder.project.build", "compile_all"),
        ("plcbuilder.project.conditions", "compile_condition"),
        ("plcbuilder.project.model", "DEFAULT_MACHINE kind_of"),
        ("plcbuilder.testing.cobertura", "cobertura_xml coverage_totals write_cobertura"),
        ("plcbuilder.testing.junit", "junit_xml write_junit"),
        ("plcbuilder.testing.runner", "Suite SuiteError SuiteRun prepare run_suite"),
        ("plcbuilder.testing.spec", "TestFileError"),
        ("plcbuilder.trace.file", "TraceFileError")):
    for _name in _names.split():
        _LAZY[_name] = (_module, _name)
_LAZY["ExportError"] = ("plcbuilder.trace.export", "ExportError")
_LAZY["CompareError"] = ("plcbuilder.trace.compare", "CompareError")
for _name, _module in (("disasm", "plcbuilder.bytecode.disasm"),
                       ("events", "plcbuilder.controller.events"),
                       ("trace_compare", "plcbuilder.trace.compare"),
                       ("trace_export", "plcbuilder.trace.export"),
                       ("trace_file", "plcbuilder.trace.file")):
    _LAZY[_name] = (_module, None)
del _module, _names, _name


def __getattr__(name: str):
    """A heavy stage's name, loaded now (PEP 562), and kept in this module."""
    where = _LAZY.get(name)
    if where is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    module = importlib.import_module(where[0])
    value = module if where[1] is None else getattr(module, where[1])
    globals()[name] = value
    return value


_LOADED = False


def _load(*names: str) -> None:
    """Lazy names into this module (its functions use them as globals): those
    named, or (no names) every one. A function loads only what it uses, so a
    command pays for its own stages only (``check`` does not load the controller)."""
    global _LOADED
    if names:
        g = globals()
        for name in names:
            if name not in g:
                __getattr__(name)
        return
    if not _LOADED:
        for name in _LAZY:
            if name not in globals():
                __getattr__(name)
        _LOADED = True


__all__ = [
    "Action", "BUILTIN_PREFIX", "BuildResult", "CompileOptions", "CompileResult", "ConfigError",
    "Controller", "ControllerError", "ControllerStatus", "DEFAULT_MS", "Diagnostic", "ImageError",
    "Kind", "LoadError", "MAGIC", "MAX_MS", "PlcLexer", "ProcedureBuild", "Program", "Project",
    "ProjectError", "Related", "RunOptions", "RunResult", "Severity", "Span", "UsageError", "abi",
    "atomic_write", "build_project", "builtin_header", "builtin_header_names", "compile_all",
    "compile_bytes", "compile_condition", "compile_file", "compile_source", "create_project",
    "default_machine",
    "disassemble", "error", "events", "image_of", "instructions", "kind_of", "load_machine", "load_program",
    "load_variables", "options_for", "proc_name", "read_image", "render_text", "run", "summary",
    "summary_counts",
    "write_image", "TestFileError", "TestOptions", "TestRun", "junit_xml", "test", "write_junit",
    "cobertura_xml", "coverage_totals", "write_cobertura",
    "Capturer", "History", "Trace", "TriggerError", "parse_trigger", "watched_variables", "load_trace", "save_trace",
    "export_trace", "trace_exporters", "compare_traces",
    "TraceFileError", "ExportError", "CompareError",
]

DEFAULT_MS = 60_000
MAX_MS = 7 * 24 * 3600 * 1000          # a week of simulated time


# --------------------------------------------------------------- binaries

def load_program(path) -> Program:
    """Read a compiled procedure (.bin); raises LoadError saying why it is refused."""
    from plcbuilder.bytecode.program import MAX_FILE_SIZE, LoadError, Program
    try:
        data = read_bounded(path, MAX_FILE_SIZE, "compiled procedure")
    except OSError as exc:
        raise LoadError(f"cannot read {path}: {exc.strerror or exc}") from None
    return Program.from_bytes(data)


def image_of(sources: dict[str, str]) -> bytes:
    """An eeprom.rom of hardware procedures ``{name: source}`` with the built-in
    headers only (raises ValueError naming the first that does not compile)."""
    _load("compile_source", "write_image")
    items = []
    for name, text in sources.items():
        r = compile_source(text, f"{name}.plc")
        if not r.ok:
            raise ValueError(f"{name}: " + "; ".join(str(d) for d in r.diagnostics))
        items.append((name, r.kind, r.program.to_bytes()))
    return write_image(items)


def disassemble(program: Program, source_line: Optional[Callable[[str, int], Optional[str]]] = None) -> str:
    _load("disasm")
    return disasm.render_text(program, source_line)


def instructions(program: Program) -> list:
    """The disassembly as records (one per instruction, with its source line)."""
    _load("disasm")
    return disasm.instructions(program)


# ---------------------------------------------------------------- sources

def options_for(path, *, software: bool = False, strict: Optional[bool] = None,
                extra_includes: Sequence = (), project: Optional[Project] = None,
                ) -> CompileOptions:
    """How a source file is compiled: as Build All does when it belongs to a
    project (``project``, or the one it sits in), else with the options given.
    ``strict`` None: as its project says (not strict outside a project).
    Raises ProjectError when its project's settings cannot be read."""
    _load("Project", "kind_of")
    if project is None:
        project = Project.find_for(path)
    if project is not None:
        return project.compile_options(path, software=software, strict=strict,
                                       extra_includes=tuple(extra_includes))
    return CompileOptions(kind=kind_of(path, software), strict=bool(strict),
                          include_dirs=tuple(extra_includes))


# -------------------------------------------------------------------- run

@dataclass
class RunOptions:
    ms: Optional[int] = None             # the time limit (None: DEFAULT_MS)
    eparam: int = 0                      # for a single-file target
    starts: Sequence[str] = ()           # "NAME[:EPARAM]@MS"
    inputs: Sequence[str] = ()           # "PIN=0|1@MS"
    adcs: Sequence[str] = ()             # "CH=VALUE@MS"
    writes: Sequence[str] = ()           # "NAME=VALUE@MS" (SPEC §6 names)
    forces: Sequence[str] = ()           # "NAME=VALUE@MS"
    scenario: Optional[Path] = None
    machine: Optional[Path] = None
    software: bool = False
    strict: bool = False
    include_dirs: tuple = ()
    trace: Optional[Path] = None         # CSV, one row per tick (gzip when it ends in .gz)
    backend: str = "fast"
    gvarget_latency_ms: int = 0
    #: the controller's kept state (Huazhong's B registers): read before, written after
    state: Optional[Path] = None
    trigger: Optional[str] = None        # SPEC §7 trigger spec (controller/trigger.py)
    pre_ms: int = 0
    post_ms: int = 0
    trigger_mode: str = "single"
    capture: Optional[Path] = None       # where the capture goes (.plctrace, or an export's suffix)
    history: Optional[Path] = None       # the whole session as a trace file
    watch: Sequence[str] = ()            # PROC.var recorded each tick into the history
    breaks: Sequence[str] = ()           # "FILE:LINE[:CONDITION]": the run ends where one halts
    scope: Sequence[str] = ()            # TG Motion: the oscilloscope's signals (the project's if ())
    gcode: Optional[Path] = None         # a G-code program the job runs from 0 ms (SPEC §10)


@dataclass
class RunResult:
    compiled: list = field(default_factory=list)     # per procedure: diagnostics, ok, name
    report: Optional[dict] = None                    # None when a procedure has errors

    @property
    def ok(self) -> bool:
        return self.report is not None


@dataclass
class _Target:
    programs: list[Program]
    compiled: list
    machine_path: Optional[Path]
    variables: Optional[list[int]]
    single: Optional[Program]            # the procedure of a single-file target
    target: Optional[TargetConfig] = None   # the project's target profile (docs/targets.md)
    io_dat: Optional[Path] = None        # the project's IO.DAT (softMC input presets)


def run(target, options: Optional[RunOptions] = None) -> RunResult:
    """``plcbuilder run``: compile a procedure or a project, simulate it, report.

    1. compile the target: one ``.plc`` file (a hardware procedure, or a software
       one with ``software=True``) or a project folder (as Build All compiles it);
    2. build a controller on the machine (the option's, the project's, or the
       default one) with the project's plc-variables.xml, and load the procedures;
    3. run the scenario (``--start``/``--input``/``--adc`` and a scenario file)
       until the time limit, or until no procedure runs and none is due to start;
    4. report what happened as the dict of docs/controller.md.

    Bad usage raises :class:`UsageError`; compile errors come back as the
    procedures' diagnostics with ``report`` None."""
    _load("UsageError", "build_scenario", "Controller", "ControllerError", "Action",
          "run_session", "load_machine", "default_machine", "ConfigError")
    opts = options or RunOptions()
    limit = DEFAULT_MS if opts.ms is None else opts.ms
    if not 0 <= limit <= MAX_MS:
        raise UsageError(f"--ms must be from 0 to {MAX_MS}, not {limit}")
    target = Path(target)
    sc = build_scenario(opts.scenario, opts.starts, opts.inputs, opts.adcs, opts.writes,
                        opts.forces)
    if opts.gcode is not None:
        sc.actions.insert(0, _gcode_action(Path(opts.gcode)))
    tg = _compile_target(target, opts)
    if any(not r.ok for r in tg.compiled):
        return RunResult(tg.compiled, None)
    machine_path = opts.machine if opts.machine is not None else tg.machine_path
    io_note = None
    try:
        mconf = load_machine(machine_path) if machine_path is not None else default_machine()
        if tg.io_dat is not None:
            _load("with_io_dat", "load_io_dat")
            io = load_io_dat(tg.io_dat)
            io_note = io.note
            mconf = with_io_dat(mconf, io)
    except ConfigError as exc:
        raise UsageError(str(exc)) from None
    config = tg.target
    if config is not None and opts.scope:
        config = replace(config, scope=tuple(opts.scope))
    if config is not None and opts.state is not None:
        config = replace(config, retained=_read_state(opts.state, config.name))
    try:
        c = Controller(mconf, backend=opts.backend, variables=tg.variables,
                       gvarget_latency_ms=opts.gvarget_latency_ms,
                       record_samples=opts.trace is not None, target=config)
        replay = _replay_image(c, tg.programs, sc)
        if replay is None:
            c.load(tg.programs, autostart=tg.single is None or config is not None)
    except ControllerError as exc:
        raise UsageError(str(exc)) from None
    if tg.single is not None and config is None:
        sc.actions.insert(0, Action(0, "start", tg.single.name, opts.eparam))
    history = capturer = None
    watch = list(opts.watch)
    if opts.trigger is not None or opts.history is not None or watch:
        _load("History", "Capturer", "TriggerError", "parse_trigger", "watched_variables")
        history = History(c.machine)
    if opts.trigger is not None:
        if opts.capture is None:
            raise UsageError("--trigger needs --capture FILE (where the capture is written)")
        try:
            trig = parse_trigger(opts.trigger)
            capturer = Capturer(history, trig, opts.pre_ms, opts.post_ms, opts.trigger_mode)
        except TriggerError as exc:
            raise UsageError(str(exc)) from None
        watch += [w for w in watched_variables(trig) if w not in watch]
    elif opts.capture is not None:
        raise UsageError("--capture needs --trigger SPEC (what starts the capture)")
    _set_breaks(c, opts.breaks, target)
    report = run_session(c, sc, limit, trace=opts.trace, target=str(target), history=history,
                         capturer=capturer, watch=watch)
    if io_note:
        report["notes"].insert(0, {"t_ms": 0, "level": "info", "text": io_note})
    if replay:
        report["notes"].insert(0, {"t_ms": 0, "level": "warning", "text": replay})
    forces = report.pop("forces", None)          # (the forces stay last)
    report["halted"] = _halted_report(c.debugger.halted_state()) if opts.breaks else None
    if history is not None:
        if capturer is not None:         # (no trigger asked for: no capture to speak of)
            report["capture"] = _save_capture(capturer, opts)
        if opts.history is not None:
            _save_trace(history.snapshot(meta={"target": str(target)}), opts.history, "--history")
            report["history"] = {"file": str(opts.history), "bytes": history.nbytes()}
    if opts.state is not None and c.retained() is not None:
        _write_state(opts.state, config.name, c.retained())
    if forces is not None:
        report["forces"] = forces
    return RunResult(tg.compiled, report)


def _gcode_action(path: Path) -> Action:
    """``--gcode FILE``: open and play it at 0 ms."""
    from plcbuilder.controller.scenario import ScenarioError, read_gcode
    try:
        return Action(0, "gcode", str(path), 1, text=read_gcode(path))
    except ScenarioError as exc:
        raise UsageError(f"--gcode: {exc.message}") from None


def _read_state(path: Path, target: str) -> Optional[tuple[int, ...]]:
    """The B registers kept in a state file (None when it does not exist yet)."""
    import json
    if not Path(path).exists():
        return None
    try:
        doc = json.loads(read_bounded(path, 1 << 20, "state file").decode("utf-8"))
        kept = doc[target]["B"]
        if not isinstance(kept, list) or not all(type(v) is int for v in kept):
            raise ValueError("B must be a list of whole numbers")
        return tuple(kept)
    except (OSError, ValueError, KeyError, TypeError, UnicodeDecodeError) as exc:
        raise UsageError(f"{path}: not a controller state file: {exc}") from None


def _write_state(path: Path, target: str, kept: list[int]) -> None:
    import json
    try:
        atomic_write(path, json.dumps({target: {"B": kept}}) + "\n")
    except OSError as exc:
        raise UsageError(f"{path}: cannot write the state: {exc.strerror or exc}") from None


def _save_trace(trace, path: Path, option: str) -> None:
    _load("trace_export", "trace_file")
    try:
        if trace_export.can_export(path):
            trace_export.export(trace, path)
        else:
            trace_file.save(trace, path)
    except (trace_export.ExportError, trace_file.TraceFileError) as exc:
        raise UsageError(f"{option}: {exc}") from None


def _save_capture(capturer, opts: RunOptions) -> Optional[dict]:
    """Write the first capture to ``--capture`` (later ones, in normal or auto
    mode, beside it as NAME-2.EXT, …); the report's ``capture`` entry."""
    caps = capturer.captures
    if not caps:
        return None
    files = []
    for i, cap in enumerate(caps):
        path = opts.capture if i == 0 else \
            opts.capture.with_name(f"{opts.capture.stem}-{i + 1}{opts.capture.suffix}")
        _save_trace(cap, path, "--capture")
        files.append(str(path))
    first = caps[0].meta["trigger"]
    return {"trigger": opts.trigger, "t_ms": first["t_ms"], "from_ms": caps[0].t_start,
            "to_ms": caps[0].t_end, "file": files[0], "count": len(caps), "files": files}


# -------------------------------------------------------------- debugging

# compile_condition lives in plcbuilder.project.conditions (the debug adapter uses it
# too, and may not import api); it is part of this facade as it was.


def _set_breaks(c: Controller, breaks: Sequence[str], target: Path) -> None:
    """``--break FILE:LINE[:CONDITION]`` options, set on the loaded controller
    (a bad one raises UsageError naming it)."""
    if breaks:
        _load("compile_condition", "DebugError")
    by_file: dict[str, list[dict]] = {}
    for text in breaks:
        parts = str(text).split(":", 2)
        if len(parts) < 2 or not parts[0] or not parts[1].strip().isdigit():
            raise UsageError(f"--break {text}: give FILE:LINE[:CONDITION], e.g. M80.plc:31")
        file, line = parts[0], int(parts[1])
        spec: dict = {"line": line}
        if len(parts) == 3 and parts[2].strip():
            code = compile_condition(parts[2], _source_of(target, file))
            if not isinstance(code, bytes):
                raise UsageError(f"--break {text}: the condition does not compile: "
                                 + "; ".join(f"col {d.span.col}: {d.message}" if d.span
                                             else d.message for d in code))
            spec["condition"] = {"text": parts[2], "code": code}
        by_file.setdefault(file, []).append(spec)
    try:
        for file, specs in by_file.items():
            c.debugger.set_breakpoints(file, specs)
    except DebugError as exc:
        raise UsageError(f"--break: {exc}") from None


def _source_of(target: Path, file: str) -> Optional[Path]:
    """The source file named ``file`` of a run's target (a file, or a project's)."""
    if target.is_file():
        near = target.with_name(Path(file).name)
        return near if near.is_file() else target
    for sub in ("hardware", "software", "include", ""):
        p = target / sub / file
        if p.is_file():
            return p
    return None


def _halted_report(state: Optional[dict]) -> Optional[dict]:
    """SPEC §6's ``halted`` object of ``plcbuilder run --json``: the halt, its
    procedure's call stack (innermost first) and variables; the whole halted
    state's other procedures and machine too."""
    if state is None:
        return None
    mine = next((p for p in state["procedures"] if p["name"] == state["procedure"]), None)
    return {"reason": state["reason"], "t_ms": state["t_ms"], "procedure": state["procedure"],
            "file": state["file"], "line": state["line"],
            "stack": [{"procedure": f["procedure"], "line": f["line"], "file": f["file"]}
                      for f in mine["stack"]] if mine else [],
            "vars": mine["vars"] if mine else {},
            "fault": state["fault"], "breakpoint": state["breakpoint"],
            "procedures": state["procedures"], "machine": state["machine"]}


def _replay_image(c: Controller, programs: list, sc) -> Optional[str]:
    """A scenario with ``upload`` lines (a recorded session) loads the image
    there, not at 0: None when it has none (load now), else '' or a warning
    that the image recorded is not the one this target builds."""
    uploads = [a for a in sc.actions if a.kind == "upload"]
    if not uploads:
        return None
    _load("image_id")
    c.replay_image = list(programs)
    have = image_id(programs)
    other = sorted({a.name for a in uploads if a.name and a.name != have})
    if not other:
        return ""
    return (f"the recording loaded image {', '.join(other)}; this project builds image {have}: "
            f"the replay runs the project's image and may differ from the session")


def _compile_target(target: Path, opts: RunOptions) -> _Target:
    _load("compile_file", "Project", "ProjectError", "kind_of")
    if target.is_dir():
        return _compile_project(target, opts)
    if not target.exists():
        raise UsageError(f"{target}: no such file or folder")
    try:                             # a file of a project: as Build All compiles it
        options = options_for(target, software=opts.software, strict=opts.strict or None,
                              extra_includes=opts.include_dirs)
    except (ProjectError, OSError):  # a project that cannot be read: the options alone
        options = CompileOptions(kind=kind_of(target, opts.software), strict=opts.strict,
                                 include_dirs=tuple(opts.include_dirs))
    r = compile_file(target, options)
    program = r.program if r.ok else None
    config = None
    if options.target != "mycnc":
        project = Project.find_for(target)
        _load("TargetConfig")
        config = _target_config(project) if project is not None else TargetConfig(options.target)
    return _Target([program] if program else [], [r], None, None, program, config)


def _compile_project(root: Path, opts: RunOptions) -> _Target:
    _load("compile_all", "load_variables", "DEFAULT_MACHINE", "io_dat_of", "io_dat_path",
          "TargetConfig")
    try:
        project = Project.open(root)
        procs = project.procedures()
    except ProjectError as exc:
        raise UsageError(str(exc)) from None
    if not procs:
        raise UsageError(f"{root}: no procedures (a project has hardware/*.plc and "
                         f"software/*.plc)")
    names: dict[str, Path] = {}
    for proc in procs:
        if proc.name in names:
            raise UsageError(f"two procedures named {proc.name}: {names[proc.name]} and "
                             f"{proc.path}")
        names[proc.name] = proc.path
    compiled = compile_all(project, strict=opts.strict or None, extra_includes=tuple(opts.include_dirs))
    programs = [p for p in (pb.program() for pb in compiled) if p is not None]
    variables = None
    if project.variables_path.is_file():
        try:
            variables = load_variables(project.variables_path)
        except ConfigError as exc:
            raise UsageError(str(exc)) from None
    machine = project.machine_path if project.machine_path.is_file() else None
    if machine is None and project.settings.machine != DEFAULT_MACHINE:
        raise UsageError(f"{project.settings_path}: machine: no such file "
                         f"{project.machine_path}")
    return _Target(programs, compiled, machine, variables, None,
                   _target_config(project) if project.target != "mycnc" else None,
                   io_dat_path(project.root))


def _target_config(project: Project) -> TargetConfig:
    """The controller's configuration of the project's target (reads its files)."""
    try:
        return TargetConfig(**project.target_settings())
    except ProjectError as exc:
        raise UsageError(str(exc)) from None


# ----------------------------------------------------------------- traces

def load_trace(path) -> Trace:
    """Reopen a trace file (``.plctrace``); raises TraceFileError saying why not."""
    _load("trace_file")
    return trace_file.load(path)


def save_trace(trace: Trace, path) -> None:
    """Save a trace as a ``.plctrace`` file, atomically; raises TraceFileError."""
    _load("trace_file")
    trace_file.save(trace, path)


def export_trace(trace: Trace, path, fmt: Optional[str] = None, **chosen: bool) -> str:
    """Export in one of the ways of ``plcbuilder.trace.export.EXPORTERS`` (``fmt``,
    or the one the suffix of ``path`` names), ``chosen`` its options switched on.
    Returns the format; raises ExportError."""
    _load("trace_export")
    return trace_export.export(trace, path, fmt, **chosen)


def trace_exporters():
    """The ways to export a trace, in the order the IDE offers them (each with
    ``fmt``, ``option``, ``flag``, ``label``, ``help``): the command line's
    export options and the IDE's file-dialog filters are made from them."""
    from plcbuilder.trace.export import EXPORTERS
    return EXPORTERS


def compare_traces(a: Trace, b: Trace, align: str = "none",
                   offset_ms: int = 0) -> "trace_compare.Difference":
    """The first tick where two traces differ, and in which signals; ``b``
    lined up with ``a`` first (``align``: none, start or trigger, then
    ``offset_ms`` more). Raises CompareError when they cannot be lined up so."""
    _load("trace_compare")
    return trace_compare.compare(a, b, align, offset_ms)


# ------------------------------------------------------------------- test

@dataclass
class TestOptions:
    __test__ = False
    select: Optional[str] = None         # -k TEXT: tests whose name or file contains it
    coverage: bool = False               # record the lines that ran (reference interpreter)
    jobs: Optional[int] = None           # processes (None: as many cores as pay off)
    strict: Optional[bool] = None
    trace_dir: Optional[Path] = None     # write each failing run's CSV trace there


@dataclass
class TestRun:
    """What ``plcbuilder test`` reports. ``run`` is None when the project did
    not build (``compiled`` has the diagnostics): then nothing ran. A test file
    with a mistake is in ``errors`` and its tests are left out; the others run."""
    __test__ = False
    suite: Suite
    run: Optional[SuiteRun] = None

    @property
    def compiled(self) -> list:
        return self.suite.compiled

    @property
    def built(self) -> bool:
        return self.suite.built

    @property
    def errors(self) -> list:
        return self.suite.errors

    @property
    def results(self) -> list:
        return self.run.results if self.run is not None else []

    @property
    def exit_status(self) -> int:
        """SPEC §8: 0 when all pass, 1 when any fails (or the project does not
        build), 2 when a test file cannot be read."""
        if self.errors:
            return 2
        if not self.built or any(not r.passed for r in self.results):
            return 1
        return 0

    def to_dict(self) -> dict:
        run = self.run
        return {
            "project": str(self.suite.project.root),
            "passed": run.passed if run else 0,
            "failed": run.failed if run else 0,
            "tests": [r.to_dict() for r in self.results],
            "errors": [e.to_dict() for e in self.errors],
            "compile_errors": [f"{pb.name}: {d}" for pb in self.compiled for d in pb.diagnostics
                               if d.is_error],
            "coverage": ([c.to_dict() for c in run.coverage]
                         if run is not None and run.coverage is not None else None),
            "backend": run.backend if run else None,
            "jobs": run.jobs if run else 0,
            "seconds": round(run.seconds, 6) if run else 0.0,
        }


def test(project, options: Optional[TestOptions] = None, progress=None) -> TestRun:
    """``plcbuilder test``: build the project once (writing nothing), read
    ``tests/*.toml``, run every test (or those ``select`` picks), judge them.
    The tests of a file with a mistake are left out (the file is in
    ``errors``); the others run. A project that cannot be opened raises
    :class:`UsageError`."""
    _load("prepare", "SuiteError", "run_suite", "UsageError")
    opts = options or TestOptions()
    try:
        suite = prepare(project, opts.select, strict=opts.strict)
    except SuiteError as exc:
        raise UsageError(str(exc)) from None
    if not suite.built:
        return TestRun(suite)
    return TestRun(suite, run_suite(suite, coverage=opts.coverage, jobs=opts.jobs,
                                    progress=progress, trace_dir=opts.trace_dir))


test.__test__ = False
