"""A run of the simulated controller from start to end, headless: what
``plcbuilder run`` and the scenario tests drive once the procedures are compiled.

    run_session(controller, scenario, limit_ms, trace=PATH) -> report dict

The controller (already loaded) runs the scenario until ``limit_ms``, or until
no procedure runs and none is due to start; the events become the report of
docs/controller.md ("The JSON object"), and, with a trace, one CSV row per tick
is streamed to the file while it runs. A run that cannot go as asked (a scenario
that names a procedure that is not loaded, a trace that cannot be written)
raises :class:`UsageError`. Nothing here prints.
"""

from __future__ import annotations

import io
from pathlib import Path

from plcbuilder._support.records import replace
from plcbuilder.bytecode import abi
from plcbuilder.controller.controller import Controller, ControllerError
from plcbuilder.controller.events import Ended, Fault, Log, Message, Note, Print, Started
from plcbuilder.controller.watch import check_name
from plcbuilder.controller.scenario import (Scenario, ScenarioError, drive, parse_adc,
                                            parse_force, parse_input, parse_start, parse_write)

TYPE_CHECKING = False               # (typing is not imported at run time: start-up)
if TYPE_CHECKING:
    from typing import Optional, Sequence

if TYPE_CHECKING:                   # (a run without --trigger or --history does not load them)
    from plcbuilder.controller.history import History
    from plcbuilder.controller.trigger import Capturer

__all__ = ["CHUNK_MS", "ReportCollector", "TraceWriter", "UsageError", "build_scenario",
           "check_scenario", "run_session"]

CHUNK_MS = 1000


class UsageError(Exception):
    """The run cannot go as asked; the message says why (exit status 2)."""


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
                import gzip
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

def build_scenario(scenario: Optional[Path] = None, starts: Sequence[str] = (),
                   inputs: Sequence[str] = (), adcs: Sequence[str] = (),
                   writes: Sequence[str] = (), forces: Sequence[str] = ()) -> Scenario:
    """A scenario file's actions, then ``--start``/``--input``/``--adc``/
    ``--write``/``--force`` options."""
    sc = Scenario()
    try:
        if scenario is not None:
            sc.extend(Scenario.load(scenario).actions)
        for option, parse, texts in (("--start", parse_start, starts),
                                     ("--input", parse_input, inputs),
                                     ("--adc", parse_adc, adcs),
                                     ("--write", parse_write, writes),
                                     ("--force", parse_force, forces)):
            sc.extend(replace(parse(s), src=f"{option} {s}") for s in texts)
    except ScenarioError as exc:
        raise UsageError(str(exc)) from None
    return sc


def check_scenario(sc: Scenario, controller) -> None:
    """Refuse a scenario that names a procedure that is not loaded, or a pin or
    channel the machine does not have."""
    machine = controller.machine
    programs = controller.programs
    if getattr(controller, "replay_image", None) is not None:   # loaded by an upload line
        programs = {**{p.name: p for p in controller.replay_image}, **programs}
    n_in = getattr(machine, "input_count", 256)
    for a in sc.actions:
        if a.kind in ("start", "bind") and a.name not in programs:
            loaded = ", ".join(sorted(programs)) or "none"
            raise UsageError(f"{a.src or '--start ' + a.name}: no procedure named {a.name} "
                             f"(loaded: {loaded})")
        if (a.kind == "input" or a.kind == "bind" and a.source == "in") and not 0 <= a.a < n_in:
            raise UsageError(f"{a.src or '--input ' + str(a.a)}: no such input (the machine "
                             f"has inputs 0..{n_in - 1})")
        if a.kind == "adc" and not 0 <= a.a < 8:
            raise UsageError(f"{a.src or '--adc ' + str(a.a)}: no such ADC channel (0..7)")
        if a.kind in ("write", "force", "release") and a.name != "all":
            proc = a.name.partition(".")[0] if "." in a.name else None
            if proc is not None and proc not in controller.programs and proc in programs:
                _check_variable(a, programs[proc])      # of the image an upload line loads
                continue
            try:
                controller.forces.check(a.name)
            except ValueError as exc:
                raise UsageError(f"{a.src or '--' + a.kind}: {exc}") from None


def _check_variable(a, program) -> None:
    """A write, force or release of ``PROC.var`` where PROC is in the image a
    recording's upload line loads (not loaded yet when the run starts)."""
    var = a.name.partition(".")[2]
    if var not in program.slot_names().values() and var not in ("command", "parameter"):
        own = ", ".join(program.var_names) or "none of its own"
        raise UsageError(f"--{a.kind}: {a.name}: {program.name} has no variable {var!r} "
                         f"(its variables: {own})")


def run_session(c: Controller, sc: Scenario, limit_ms: int, *, trace: Optional[Path] = None,
                target="", chunk_ms: int = CHUNK_MS, history: Optional[History] = None,
                capturer: Optional[Capturer] = None, watch: Sequence[str] = ()) -> dict:
    """Run the loaded controller through the scenario (see the module docstring).
    With a ``history``, every change goes into it (and ``capturer`` looks at it
    as it grows); ``watch`` names variables (``PROC.var``) it records each tick,
    which runs the session one tick at a time."""
    check_scenario(sc, c)
    collector = ReportCollector(c)
    writer = TraceWriter(trace, c.machine) if trace is not None else None
    for w in watch:
        _watched(c, w)
    if history is not None:
        c.record_samples = True
        if writer is None:
            c.sample_changes_only = True
        c.watch_variables(watch, check=False)        # Watched events, read each tick

    def drain() -> None:
        events = c.drain_events()
        collector.take(events)
        rows = c.drain_sample_rows() if (writer is not None or history is not None) else ()
        if writer is not None:
            writer.write(rows)
        if history is not None:
            history.feed(rows, events)
            t = c.t_ms - 1
            if t >= 0:
                history.advance_to(t)
            if capturer is not None:
                capturer.update()

    try:
        ended = drive(c, sc, limit_ms, until_idle=True, chunk_ms=chunk_ms, on_chunk=drain)
        drain()
        if capturer is not None:
            capturer.update(final=True)
    except ControllerError as exc:
        raise UsageError(str(exc)) from None
    finally:
        if writer is not None:
            writer.close()
    return collector.report(ended, target)


def _watched(c: Controller, name: str) -> tuple[str, str]:
    """(procedure, variable) of a watched ``PROC.var``; UsageError naming what is wrong."""
    programs = c.programs
    if getattr(c, "replay_image", None) is not None:   # loaded later, by an upload line
        programs = {**{p.name: p for p in c.replay_image}, **programs}
    try:
        return check_name(programs, name)
    except ValueError as exc:
        raise UsageError(f"--watch {exc}") from None


class ReportCollector:
    """Turns the controller's events into the lists of the report."""

    def __init__(self, controller):
        self.c = controller
        self.procedures: list[dict] = []
        self.open: dict[str, dict] = {}
        self.messages: list[dict] = []
        self.prints: list[dict] = []
        self.faults: list[dict] = []
        self.notes: list[dict] = []
        self.logs: list[dict] = []

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
            elif isinstance(e, Log):
                self.logs.append({"t_ms": e.t_ms, "from": e.source, "text": e.text})

    def report(self, ended: int, target) -> dict:
        c = self.c
        m = c.machine
        fields = m.sample_fields()
        variables = c.variables()
        for name, entry in self.open.items():          # still running: its vexit so far
            entry["vexit"] = variables.get(name, {}).get("vexit")
        st = c.state()
        extra = c.target_report() if hasattr(c, "target_report") else {}
        return {**extra,
            "target": str(target),
            "ended_at_ms": ended,
            "procedures": self.procedures,
            "vars": variables,
            "outputs": m.outputs_on(),
            "vins": m.vio.vins_on() if hasattr(m, "vio") else [],
            "vouts": m.vio.vouts_on() if hasattr(m, "vio") else [],
            "pls": m.pls.report() if hasattr(m, "pls") else [],
            "pwm": list(fields["pwm"]),
            "dac": list(fields["dac"]),
            "messages": self.messages,
            "prints": self.prints,
            "faults": self.faults,
            "notes": self.notes,
            "logs": self.logs,
            "axes": m.axis_positions(),
            "proc": st.proc,
            "proc_name": st.proc_name,
            "running": st.running,
            "software": list(st.software),
            "job": c.job_report() if hasattr(c, "job_report") else None,
            "forces": c.forces(),
        }
