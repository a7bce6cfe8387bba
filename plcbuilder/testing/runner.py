"""Running scenario tests: build the project once, run each test on the
in-process controller, judge its expectations tick by tick.

    prepare(project_dir, select=None) -> Suite     build, read tests/*.toml, check names
    run_suite(suite, coverage=False, jobs=None) -> SuiteRun
    run_test(test, env) -> TestResult              one test (what a worker runs)

How a test runs: a controller on the test's machine (the project's by default)
with the project's plc-variables.xml loads every procedure (software ones start
as after a Build All), then the scenario's actions happen at their ticks. The
run stops at ``ms``, or once no procedure runs, none is due to start and no
expectation waits for a later tick.

What is recorded is only what the expectations look at: per-tick samples only
inside a timed expectation's window (``at_ms``: that tick; ``by_ms``: from 0
until it first holds; ``during_ms``: its range, until its first bad tick), the
procedures' variables only on the ticks of an expectation that names them
(those ticks run one at a time), and the events (messages, prints, starts,
ends, faults) as they come. ``at_end`` is judged on the state when the run
stops, as ``plcbuilder run`` reports it.

Many tests run in a process pool; each test is a pure function of the built
procedures and its own file, so the results are the same, in the same order,
as a serial run.
"""

from __future__ import annotations

import os
import time
from collections import deque
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field
from importlib import resources
from multiprocessing import get_context
from pathlib import Path
from typing import Callable, Optional

from plcbuilder.controller import names as abi
from plcbuilder.controller.controller import Controller, ControllerError
from plcbuilder.controller.coverage import CodeCoverage
from plcbuilder.controller.events import Ended, Fault, Message, Print, Started
from plcbuilder.controller.machine import Machine
from plcbuilder.controller.io_dat import io_dat_of, load_io_dat, with_io_dat
from plcbuilder.controller.machine_config import ConfigError, default_machine, load_machine
from plcbuilder.controller.scenario import STARTING, apply, drive
from plcbuilder.controller.session import TraceWriter, UsageError, check_scenario
from plcbuilder.controller.targets import TargetConfig
from plcbuilder.controller.variables_xml import load_variables
from plcbuilder.project.build import ProcedureBuild, compile_all
from plcbuilder.project.model import DEFAULT_MACHINE, Project, ProjectError
from plcbuilder.testing.spec import (TESTS_DIR, Condition, Expectation, Names, TestCase,
                                     TestFileError, load_dir, pin_names, resolve)
from plcbuilder.testing.coverage import ProcedureCoverage, summarize

__all__ = ["Failure", "RecordedRun", "Suite", "SuiteRun", "TestResult", "prepare", "record_run",
           "run_suite", "run_test"]

CHUNK_MS = 1000
#: Below this much simulated time in all, a pool costs more than it saves:
#: starting the workers takes about a second, and a test simulates 10 s in
#: 10-20 ms (scripts/bench.py tests: 100 tests of 10 s run in 1.8 s serially,
#: 3 s in two processes).
PARALLEL_MIN_MS = 2_000_000
PARALLEL_MIN_TESTS = 4


class SuiteError(Exception):
    """The project cannot be tested (no such folder, bad settings, bad machine)."""


# ----------------------------------------------------------------- results

@dataclass
class Failure:
    """One condition that did not hold: at ``tick``, ``expected`` but ``actual``."""
    when: str                     # the expectation's selector: at_ms = 5
    condition: str                # outputs_on = [0]
    expected: str
    actual: str
    tick: Optional[int]
    file: str
    line: Optional[int]           # the condition's line
    note: str = ""                # by_ms: "never held by then"

    def to_dict(self) -> dict:
        return {"when": self.when, "condition": self.condition, "expected": self.expected,
                "actual": self.actual, "tick": self.tick, "file": self.file,
                "line": self.line, "note": self.note}

    def text(self) -> str:
        where = f"{self.file}:{self.line}: " if self.line else ""
        note = f" ({self.note})" if self.note else ""
        return (f"{where}{self.when}: {self.condition}: expected {self.expected}, actual "
                f"{self.actual} at tick {self.tick}{note}")


@dataclass
class TestResult:
    __test__ = False

    name: str
    file: str
    line: Optional[int]
    failures: list[Failure] = field(default_factory=list)
    error: Optional[str] = None   # the run could not go (a refused start…)
    ended_at_ms: Optional[int] = None
    expectations: list[dict] = field(default_factory=list)   # {when, line, passed, tick}
    trace: Optional[str] = None   # the CSV trace of a failing run, when asked for
    seconds: float = 0.0          # wall time (not part of equality: see same_as)

    @property
    def passed(self) -> bool:
        return not self.failures and self.error is None

    def outcome(self) -> tuple:
        """Everything but the wall time: equal for a serial and a parallel run."""
        return (self.name, self.file, self.line, [f.to_dict() for f in self.failures],
                self.error, self.ended_at_ms, self.expectations)

    def to_dict(self) -> dict:
        return {"name": self.name, "file": self.file, "line": self.line,
                "passed": self.passed, "failures": [f.to_dict() for f in self.failures],
                "error": self.error, "ended_at_ms": self.ended_at_ms,
                "expectations": self.expectations, "trace": self.trace, "seconds": round(self.seconds, 6)}


@dataclass
class Env:
    """What a run needs, picklable for the workers: the built procedures, the
    variables, the machines by file (None: the built-in default machine)."""
    programs: list                       # Program, as the build loaded them
    variables: Optional[list[int]]
    machine: Optional[str]
    backend: str = "fast"
    coverage: bool = False
    stop_early: bool = True
    target: Optional[TargetConfig] = None  # the project's target profile (None: mycnc)
    io_dat: Optional[str] = None         # the project's IO.DAT (softMC input presets)


_MACHINES: dict[tuple[Optional[str], Optional[str]], object] = {}


def _machine(path: Optional[str], io_dat: Optional[str] = None):
    m = _MACHINES.get((path, io_dat))
    if m is None:
        m = load_machine(path) if path is not None else default_machine()
        if io_dat is not None:
            m = with_io_dat(m, load_io_dat(io_dat))
        _MACHINES[(path, io_dat)] = m
    return m


@dataclass
class Suite:
    """A built project and its tests, ready to run."""
    project: Project
    compiled: list[ProcedureBuild]
    tests: list[TestCase] = field(default_factory=list)
    errors: list[TestFileError] = field(default_factory=list)
    env: Optional[Env] = None
    machines: dict[str, Optional[str]] = field(default_factory=dict)   # test name -> machine

    @property
    def built(self) -> bool:
        return all(pb.ok for pb in self.compiled)

    @property
    def programs(self) -> list:
        return [p for p in (pb.program() for pb in self.compiled) if p is not None]


@dataclass
class SuiteRun:
    results: list[TestResult]
    coverage: Optional[list[ProcedureCoverage]] = None
    seconds: float = 0.0
    jobs: int = 1
    backend: str = "fast"

    @property
    def passed(self) -> int:
        return sum(1 for r in self.results if r.passed)

    @property
    def failed(self) -> int:
        return len(self.results) - self.passed


# ----------------------------------------------------------------- prepare

def prepare(root, select: Optional[str] = None, *, tests_dir: Optional[Path] = None,
            strict: Optional[bool] = None) -> Suite:
    """Open and build the project (compile every procedure, write nothing), read
    its tests and check the names they use. Raises :class:`SuiteError` when the
    project cannot be opened; compile errors are in ``compiled``; mistakes in
    test files are ``errors`` (those tests are left out). ``select``: only the
    tests whose name (or file name) contains it, ignoring case."""
    try:
        project = Project.open(root)
        compiled = compile_all(project, strict=strict)
    except (ProjectError, OSError) as exc:
        raise SuiteError(str(exc)) from None
    folder = tests_dir if tests_dir is not None else project.root / TESTS_DIR
    tests, errors = load_dir(folder)
    suite = Suite(project, compiled, [], list(errors))
    if select:
        s = select.lower()
        tests = [t for t in tests if s in t.name.lower() or s in Path(t.file).stem.lower()]
    if not suite.built:
        suite.tests = tests
        return suite
    variables = None
    if project.variables_path.is_file():
        try:
            variables = load_variables(project.variables_path)
        except ConfigError as exc:
            raise SuiteError(str(exc)) from None
    default = str(project.machine_path) if project.machine_path.is_file() else None
    if default is None and project.settings.machine != DEFAULT_MACHINE:
        raise SuiteError(f"{project.settings_path}: machine: no such file "
                         f"{project.machine_path}")
    io_dat = io_dat_of(project.root)
    if io_dat is not None:
        try:
            load_io_dat(io_dat)
        except ConfigError as exc:
            raise SuiteError(str(exc)) from None
    programs = suite.programs
    names = Names({p.name: set(p.slot_names().values()) for p in programs},
                  _pins(project))
    machine_names: dict[Optional[str], Names] = {}
    for t in tests:
        path = default if t.machine is None else str(project.root / t.machine)
        try:
            if path not in machine_names:
                m = Machine(_machine(path))
                machine_names[path] = Names(names.variables, names.pins,
                                            set(m.axis_positions()), m.input_count,
                                            m.output_count)
            resolve(t, names, machine_names[path])
        except ConfigError as exc:
            suite.errors.append(TestFileError(f"machine: {exc}", t.file, t.machine_line))
            continue
        except TestFileError as exc:
            suite.errors.append(exc)
            continue
        suite.machines[t.name] = path
        suite.tests.append(t)
    target = None
    if project.target != "mycnc":
        try:
            target = TargetConfig(**project.target_settings())
        except ProjectError as exc:
            raise SuiteError(str(exc)) from None
    suite.env = Env(programs, variables, default, target=target,
                    io_dat=None if io_dat is None else str(io_dat))
    return suite


def _pins(project: Project) -> dict[str, int]:
    """pins.h's names: the project's (its include folders), else the built-in one."""
    for d in project.include_dirs():
        p = d / "pins.h"
        if p.is_file():
            try:
                return pin_names(p.read_text(encoding="utf-8", errors="replace"))
            except OSError:
                break
    ref = resources.files("plcbuilder") / "resources" / "include" / "pins.h"
    return pin_names(ref.read_text(encoding="utf-8"))


# --------------------------------------------------------------------- run

def run_suite(suite: Suite, *, coverage: bool = False, jobs: Optional[int] = None,
              tests: Optional[list[TestCase]] = None,
              progress: Optional[Callable[[TestResult], None]] = None,
              trace_dir: Optional[Path] = None) -> SuiteRun:
    """Run the suite's tests (or ``tests``), in order. ``jobs``: processes (None:
    as many as there are cores when the tests are many and long enough to pay
    for a pool; 1: in this process). ``coverage`` runs on the reference
    interpreter, which records the lines that ran. ``progress`` is called with
    each result as it comes (serial runs) or in order at the end (parallel).
    ``trace_dir``: each failing test's run is run again and written there as a
    CSV trace (one row a tick, as ``plcbuilder run --trace``), to its failing tick."""
    t0 = time.perf_counter()
    todo = list(suite.tests if tests is None else tests)
    env = suite.env
    if env is None:
        raise SuiteError("the project did not build; nothing to run")
    env = Env(env.programs, env.variables, env.machine, "reference" if coverage else "fast",
              coverage, stop_early=not coverage, target=env.target,
              io_dat=env.io_dat)
    work = [(t, suite.machines.get(t.name, env.machine)) for t in todo]
    n = _jobs(jobs, todo)
    cov = CodeCoverage() if coverage else None
    results: list[TestResult] = []
    if n <= 1:
        for t, machine in work:
            r = run_test(t, env, machine, cov)
            results.append(r)
            if progress:
                progress(r)
    else:
        ctx = get_context("spawn")       # never fork a process that may hold Qt
        chunk = max(1, len(work) // (n * 4))
        with ProcessPoolExecutor(n, mp_context=ctx, initializer=_init_worker,
                                 initargs=(env,)) as pool:
            for r, h, b in pool.map(_run_in_worker, work, chunksize=chunk):
                results.append(r)
                if cov is not None:
                    cov.merge(h, b)
                if progress:
                    progress(r)
    if trace_dir is not None:
        for (t, machine), r in zip(work, results):
            if r.failures:
                r.trace = str(write_trace(t, env, machine, Path(trace_dir), r))
    report = None
    if cov is not None:
        report = summarize(env.programs, cov.hits, suite.project, cov.branches)
    return SuiteRun(results, report, time.perf_counter() - t0, max(1, n), env.backend)


def _jobs(jobs: Optional[int], tests: list[TestCase]) -> int:
    if jobs is not None:
        return max(1, min(jobs, len(tests)))
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    if (cores or 1) < 2 or len(tests) < PARALLEL_MIN_TESTS \
            or sum(t.ms for t in tests) < PARALLEL_MIN_MS:
        return 1
    return min(cores or 1, len(tests))


_WORKER: dict = {}


def _init_worker(env: Env) -> None:
    _WORKER["env"] = env


def _run_in_worker(item) -> tuple[TestResult, dict[str, set[int]], dict[str, dict[int, int]]]:
    t, machine = item
    env = _WORKER["env"]
    cov = CodeCoverage() if env.coverage else None
    r = run_test(t, env, machine, cov)
    return r, (cov.hits if cov is not None else {}), (cov.branches if cov is not None else {})


# ------------------------------------------------------------- one test

class _Seen:
    """What the events said so far (cumulative: "sent by then")."""

    __slots__ = ("messages", "sent", "prints", "exits", "faults")

    def __init__(self):
        self.messages: set[int] = set()        # codes sent, and the commands of replies
        self.sent: list[str] = []              # for messages: NAME@t
        self.prints: dict[int, list[int]] = {}  # register -> values printed
        self.exits: dict[str, Optional[tuple[int, int]]] = {}   # None: running
        self.faults: list[Fault] = []

    def take(self, e) -> None:
        if isinstance(e, Message):
            self.messages.add(e.message)
            if e.message == abi.REPLY_TO_MYCNC:
                self.messages.add(e.command)   # a reply carries its message in command
            if len(self.sent) < 20:
                self.sent.append(f"{e.name or e.message} at {e.t_ms}")
        elif isinstance(e, Print):
            vals = self.prints.setdefault(e.register, [])
            if len(vals) < 20:
                vals.append(e.value)
            elif e.value not in vals:
                vals.append(e.value)
        elif isinstance(e, Started):
            self.exits[e.name] = None
        elif isinstance(e, Ended):
            self.exits[e.name] = (e.exit_code, e.t_ms)
        elif isinstance(e, Fault):
            self.faults.append(e)


def _named(value: int, name: Optional[str]) -> str:
    return f"{name} ({value})" if name else str(value)


def _pins_text(word: str, pins, state: str) -> str:
    return f"{word}{'s' if len(pins) > 1 else ''} {', '.join(map(str, pins))} {state}"


def _fault_text(f: Fault) -> str:
    where = f" ({f.file}:{f.line})" if f.file else ""
    return f"fault in {f.source} at {f.t_ms}: {f.text}{where}"


def _checker(c: Condition) -> Callable:
    """check(row, seen, variables) -> None when the condition holds, else
    (expected, actual). ``row`` is a sample row (t, running, proc, message, fields)."""
    k, v = c.key, c.value
    if k in ("outputs_on", "outputs_off", "inputs_on", "inputs_off"):
        fld = "outputs" if k.startswith("outputs") else "inputs"
        noun = fld[:-1]
        want = 1 if k.endswith("_on") else 0
        state, other = ("on", "off") if want else ("off", "on")
        pins = list(v)

        def check(row, seen, variables):
            words = row[4][fld]
            bad = [p for p in pins if ((words[p >> 5] >> (p & 31)) & 1) != want]
            if not bad:
                return None
            return _pins_text(noun, pins, state), _pins_text(noun, bad, other)
        return check
    if k in ("pwm", "dac", "adc"):
        want_ch = dict(v)

        def check(row, seen, variables):
            vals = row[4][k]
            bad = [ch for ch, x in want_ch.items() if vals[ch] != x]
            if not bad:
                return None
            return (", ".join(f"{k} {ch} = {want_ch[ch]}" for ch in bad),
                    ", ".join(f"{k} {ch} = {vals[ch]}" for ch in bad))
        return check
    if k == "proc":
        def check(row, seen, variables):
            if row[2] == v:
                return None
            return (f"proc {_named(v, abi.proc_name(v))}",
                    f"proc {_named(row[2], abi.proc_name(row[2]))}")
        return check
    if k == "message":
        codes = list(v)

        def check(row, seen, variables):
            missing = [m for m in codes if m not in seen.messages]
            if not missing:
                return None
            sent = ", ".join(seen.sent) if seen.sent else "no message"
            return ("sent: " + ", ".join(_named(m, abi.message_name(m)) for m in missing),
                    f"sent: {sent}")
        return check
    if k == "print":
        want_p = dict(v)

        def check(row, seen, variables):
            bad = [r for r, x in want_p.items() if x not in seen.prints.get(r, ())]
            if not bad:
                return None
            return (", ".join(f"print [{r}] = {want_p[r]}" for r in bad),
                    ", ".join(f"[{r}] printed " + (", ".join(map(str, seen.prints[r]))
                                                   if seen.prints.get(r) else "nothing")
                              for r in bad))
        return check
    if k == "exit":
        want_e = dict(v)

        def check(row, seen, variables):
            bad = []
            for proc, code in want_e.items():
                got = seen.exits.get(proc, "none")
                if got == "none":
                    bad.append((proc, code, "not started"))
                elif got is None:
                    bad.append((proc, code, "still running"))
                elif got[0] != code:
                    bad.append((proc, code, f"exit {_named(got[0], abi.exit_name(got[0]))} "
                                            f"(ended at {got[1]} ms)"))
            if not bad:
                return None
            return (", ".join(f"{p} exit {_named(c_, abi.exit_name(c_))}" for p, c_, _ in bad),
                    ", ".join(f"{p} {a}" for p, _, a in bad))
        return check
    if k == "vars":
        want_v = dict(v)

        def check(row, seen, variables):
            bad = []
            for (proc, var), x in want_v.items():
                vals = (variables or {}).get(proc)
                if vals is None:
                    bad.append((proc, var, x, f"{proc} has not run"))
                elif vals.get(var) != x:
                    bad.append((proc, var, x, f"{proc}.{var} = {vals.get(var)}"))
            if not bad:
                return None
            return (", ".join(f"{p}.{n} = {x}" for p, n, x, _ in bad),
                    ", ".join(a for *_, a in bad))
        return check
    if k == "axes":
        want_a = {abi.AXES.index(a): (a, lo, hi) for a, (lo, hi) in v.items()}

        def check(row, seen, variables):
            pos = row[4]["axes"]
            bad = [(a, lo, hi, pos[i]) for i, (a, lo, hi) in want_a.items()
                   if not lo <= pos[i] <= hi]
            if not bad:
                return None
            return (", ".join(f"{a} in [{lo}, {hi}]" for a, lo, hi, _ in bad),
                    ", ".join(f"{a} = {p}" for a, _, _, p in bad))
        return check
    if k == "no_faults":
        def check(row, seen, variables):
            if not seen.faults:
                return None
            return "no fault", "; ".join(_fault_text(f) for f in seen.faults[:3])
        return check
    if k == "faults":
        def check(row, seen, variables):
            if len(seen.faults) == v:
                return None
            got = len(seen.faults)
            detail = (": " + "; ".join(_fault_text(f) for f in seen.faults[:3])) if got else ""
            return f"{v} fault{'s' if v != 1 else ''}", f"{got}{detail}"
        return check
    raise ValueError(f"unknown condition {k!r}")  # pragma: no cover


class _Watch:
    """One expectation being judged."""

    __slots__ = ("ex", "checks", "done", "failures", "file", "tick")

    def __init__(self, ex: Expectation, file: str):
        self.ex = ex
        self.file = file
        self.checks = [(c, _checker(c)) for c in ex.conditions]
        self.done = False
        self.failures: list[Failure] = []
        self.tick: Optional[int] = None         # where it was judged (by_ms: the first tick)

    def judged(self) -> dict:
        return {"when": self.ex.when, "line": self.ex.line, "passed": not self.failures,
                "tick": self.tick}

    def feed(self, row, seen, variables) -> None:
        t = row[0]
        bad = []
        for c, check in self.checks:
            r = check(row, seen, variables)
            if r is not None:
                bad.append((c, r))
        sel, ex = self.ex.selector, self.ex
        self.tick = t
        if sel == "by_ms":
            if not bad:
                self.done = True
            elif t >= ex.hi:
                self._fail(bad, t, f"never held by tick {ex.hi}")
        elif sel == "during_ms":
            if bad:
                self._fail(bad, t, f"the first tick of [{ex.lo}, {ex.hi}] where it fails")
            elif t >= ex.hi:
                self.done = True
        else:                                   # at_ms, at_end: this one tick
            if bad:
                self._fail(bad, t)
            self.done = True

    def _fail(self, bad, t: int, note: str = "") -> None:
        self.done = True
        self.failures = [Failure(self.ex.when, c.text, exp, act, t, self.file, c.line, note)
                         for c, (exp, act) in bad]


def run_test(tc: TestCase, env: Env, machine: Optional[str] = None,
             coverage: Optional[CodeCoverage] = None) -> TestResult:
    """Run one test (see the module docstring) and judge it."""
    t0 = time.perf_counter()
    result = TestResult(tc.name, tc.file, tc.line)
    try:
        c = Controller(_machine(machine if machine is not None else env.machine, env.io_dat),
                       backend=env.backend, variables=env.variables, record_samples=False,
                       coverage=coverage, target=env.target)
        c.load(env.programs)
        check_scenario(tc.scenario, c)
        result.ended_at_ms, seen, watches = _drive(c, tc, env.stop_early)
    except (ControllerError, UsageError, ConfigError) as exc:
        result.error = str(exc)
        result.seconds = time.perf_counter() - t0
        return result
    for w in watches:
        if not w.done:                          # cannot happen: every window is inside ms
            result.failures.append(Failure(w.ex.when, "(not judged)", "judged", "the run "
                                           "ended first", result.ended_at_ms, tc.file,
                                           w.ex.line))
        result.failures.extend(w.failures)
        result.expectations.append(w.judged())
    result.seconds = time.perf_counter() - t0
    return result


def trace_name(name: str) -> str:
    """A file name for a test's trace: its name, letters, digits, ``-`` and ``_`` kept."""
    safe = "".join(ch if ch.isalnum() or ch in "-_" else "_" for ch in name).strip("_")
    return (safe or "test")[:80] + ".csv"


def _last_failing_tick(result: TestResult) -> int:
    ticks = [f.tick for f in result.failures if f.tick is not None]
    return max(ticks) if ticks else (result.ended_at_ms or 0)


def _recording(env: Env, machine: Optional[str]) -> Controller:
    """A fresh controller for a rerun: the fast backend, a sample every tick."""
    c = Controller(_machine(machine if machine is not None else env.machine, env.io_dat),
                   backend="fast", variables=env.variables, record_samples=True,
                   target=env.target)
    c.load(env.programs)
    return c


def _replay(c: Controller, tc: TestCase, ticks: int, take: Callable[[Controller], None]) -> None:
    """Run ``tc`` again on ``c`` (from :func:`_recording`) for ``ticks`` ticks (at
    most ``tc.ms``); ``take(c)`` drains the samples and events after every
    chunk and once at the end. The same test gives the same run."""
    drive(c, tc.scenario, min(ticks, tc.ms), until_idle=False, on_chunk=lambda: take(c))
    take(c)


def write_trace(tc: TestCase, env: Env, machine: Optional[str], folder: Path,
                result: TestResult) -> Path:
    """Run ``tc`` again with a CSV trace to ``folder``: from tick 0 through the
    last failing tick (or the end of its run). Raises UsageError when the file
    cannot be written."""
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise UsageError(f"{folder}: cannot make the trace folder: {exc.strerror or exc}") \
            from None
    path = folder / trace_name(tc.name)
    c = _recording(env, machine)
    writer = TraceWriter(path, c.machine)
    try:
        _replay(c, tc, _last_failing_tick(result) + 1,
                lambda c: (writer.write(c.drain_sample_rows()), c.drain_events()))
    finally:
        writer.close()
    return path


#: How far past the (last) failing tick :func:`record_run` records, in ms.
RECORD_AFTER_MS = 100


@dataclass
class RecordedRun:
    """A test's run, recorded again for inspection (the IDE's "Open Failing Run")."""
    name: str
    samples: list                 # Sample, one a tick from 0 (the last ``keep`` of them)
    events: list                  # Started, Ended, Message, Print, Fault, as they came
    failing_tick: Optional[int]   # the first failing condition's tick (None: it passed)
    end_ms: int                   # the ticks recorded: 0 … end_ms - 1
    result: Optional[TestResult] = None


def record_run(suite: Suite, name: str, *, after_ms: int = RECORD_AFTER_MS,
               keep: Optional[int] = None, result: Optional[TestResult] = None) -> RecordedRun:
    """Run the test ``name`` of ``suite`` (to judge it, unless ``result`` is
    given) and then again recording every tick, as ``--trace-failed`` does:
    from tick 0 through ``after_ms`` past its last failing tick (or the end of
    its run), at most to its ``ms``. ``keep``: only the newest that many
    samples (a long run; None: all). Raises SuiteError when the project did
    not build or has no test ``name``."""
    if suite.env is None:
        raise SuiteError("the project did not build; nothing to run")
    tc = next((t for t in suite.tests if t.name == name), None)
    if tc is None:
        raise SuiteError(f"no test named {name!r}")
    env = suite.env
    machine = suite.machines.get(tc.name, env.machine)
    if result is None:
        result = run_test(tc, env, machine)
    failing = next((f.tick for f in result.failures if f.tick is not None), None)
    end = min(_last_failing_tick(result) + 1 + max(0, after_ms), tc.ms)
    samples: list = deque(maxlen=keep) if keep else []
    events: list = []

    def take(c: Controller) -> None:
        samples.extend(c.drain_samples())
        events.extend(c.drain_events())
    _replay(_recording(env, machine), tc, end, take)
    return RecordedRun(tc.name, list(samples), events, failing, end, result)


def _drive(c: Controller, tc: TestCase, stop_early: bool):
    actions = tc.scenario.ordered()
    n, i = len(actions), 0
    seen = _Seen()
    watches = [_Watch(ex, tc.file) for ex in tc.expectations]
    timed = [w for w in watches if w.ex.selector != "at_end"]
    at_end = [w for w in watches if w.ex.selector == "at_end"]
    limit = tc.ms
    ended = limit
    while True:
        t = c.t_ms
        while i < n and actions[i].t_ms <= t:
            apply(c, actions[i])
            i += 1
        if t >= limit:
            break
        open_ = [w for w in timed if not w.done]
        if stop_early and not open_ and not at_end:
            ended = max(t - 1, 0)               # nothing left to judge
            break
        active = [w for w in open_ if w.ex.lo <= t]
        nxt = min(limit, t + CHUNK_MS)
        if i < n:
            nxt = min(nxt, actions[i].t_ms)
        for w in open_:
            nxt = min(nxt, w.ex.lo if w.ex.lo > t else w.ex.hi + 1)
        count = max(1, nxt - t)
        if active:
            needs_vars = any(w.ex.needs_vars for w in active)
            if needs_vars:
                count = 1
            c.record_samples = True
            c.step(count)
            rows = c.drain_sample_rows()
            evs = c.drain_events()
            variables = c.variables() if needs_vars else None
            j = 0
            for row in rows:
                rt = row[0]
                while j < len(evs) and evs[j].t_ms <= rt:
                    seen.take(evs[j])
                    j += 1
                for w in active:
                    if not w.done:
                        w.feed(row, seen, variables)
            for e in evs[j:]:
                seen.take(e)
            continue
        c.record_samples = False
        bound = bool(c.bindings)
        more_starts = any(a.kind in STARTING or (bound and a.kind == "input")
                          for a in actions[i:])
        can_stop = not open_ and not more_starts
        if can_stop and c.idle():
            ended = max(t - 1, 0) if t else 0
            break
        ran = c.run_until_idle(count) if can_stop else (c.step(count) or count)
        for e in c.drain_events():
            seen.take(e)
        if can_stop and ran < count:
            ended = c.t_ms - 1
            break
    for e in c.drain_events():
        seen.take(e)
    if at_end:
        plc = c.plc
        row = (ended, plc.hw.name if plc.hw is not None else None, plc.proc, 0,
               c.machine.sample_fields())
        variables = c.variables() if any(w.ex.needs_vars for w in at_end) else None
        for w in at_end:
            w.feed(row, seen, variables)
    return ended, seen, watches
