"""The simulated controller: the one object the TCP server, the IDE and
``plcbuilder run`` drive.

It owns a machine (:mod:`plcbuilder.controller.machine`) and the hardware and
software PLC (:mod:`plcbuilder.controller.plc`). Simulated time only moves in
:meth:`Controller.step`; everything else (start, stop, inputs) acts "now",
that is at the beginning of the next tick, ``t_ms``.

Typical use::

    c = Controller()
    c.load(programs)            # Build All: software procedures (re)start
    c.start("M03", eparam=12000)
    c.step(500)
    for event in c.drain_events(): ...
"""

from __future__ import annotations

from plcbuilder._support.numbers import INT32, WORD32, to_int32
from plcbuilder.bytecode import abi, softmc
from plcbuilder.bytecode.opcodes import DecodeError, validate
from plcbuilder.bytecode.program import Kind, Program
from plcbuilder.controller.debugger import Debugger
from plcbuilder.controller.events import ControllerStatus, Event, Note, Sample
from plcbuilder.controller.forces import MODES as _MODES, ForceError, Forces
from plcbuilder.controller.plc import BACKENDS, PLC, mcode_names
from plcbuilder.controller.recorder import Recorder, image_id
from plcbuilder.controller.scenario import Action
from plcbuilder.controller.targets import TargetConfig, TargetConfigError, make_plc
from plcbuilder.controller.watch import VariableWatch, check_name

TYPE_CHECKING = False               # (typing is not imported at run time: start-up)
if TYPE_CHECKING:
    from typing import Iterable, Optional

HANDLER_INIT = "__HANDLER_INIT"
HANDLER_EXIT = "__HANDLER_EXIT"
SHUTDOWN_LIMIT_MS = 10_000
#: Controller.job_runner before it is first asked for (made then)
_NO_RUNNER_YET = object()


def _as_int(value) -> int:
    """A written or forced value as the recording writes it (it was accepted)."""
    return to_int32(int(value, 0) if isinstance(value, str) else int(value))


def bind_source_error(machine, source: str, n: int) -> Optional[str]:
    """Why ``bind SOURCE N`` cannot be bound on this machine, or None."""
    if source == "in":
        count = getattr(machine, "input_count", None)
        if n < 0 or (count is not None and n >= count):
            return f"no input {n}" + (f" (the machine has inputs 0..{count - 1})" if count else "")
    elif source in ("vin", "vout"):
        if not 1 <= n <= softmc.VIRTUAL_BITS:
            return f"no {source} {n} (virtual inputs and outputs are 1..{softmc.VIRTUAL_BITS})"
    elif source == "pls":
        if not 1 <= n <= softmc.PLS_NUMBER_MAX:
            return f"no PLS {n} (PLSs are numbered from 1)"
    else:
        return f"cannot bind {source!r} (in, vin, vout or pls)"
    return None


class ControllerError(Exception):
    """A request the controller refuses; the message says why."""


class Controller:
    """A simulated myCNC controller: hardware PLC, software PLC and machine."""

    def __init__(self, machine_config=None, *, backend: str = "fast",
                 variables: Optional[Iterable[int]] = None, gvarget_latency_ms: int = 0,
                 record_samples: bool = True, machine=None, coverage=None,
                 target: Optional[TargetConfig] = None):
        if backend not in BACKENDS:
            raise ControllerError(f"unknown backend {backend!r} (use {' or '.join(BACKENDS)})")
        if coverage is not None and backend != "reference":
            raise ControllerError("coverage is recorded by the reference backend only")
        if machine is None:
            from plcbuilder.controller.machine import Machine
            machine = Machine(machine_config)
        self.machine = machine
        #: the target profile (docs/targets.md); None: myCNC's hardware and software PLC
        self.target = target if target is not None and target.name != "mycnc" else None
        try:
            if self.target is not None:
                self._plc = make_plc(self.target, machine, variables=variables,
                                     gvarget_latency_ms=gvarget_latency_ms,
                                     record_samples=record_samples)
            else:
                self._plc = PLC(machine, backend=backend, variables=variables,
                                gvarget_latency_ms=gvarget_latency_ms,
                                record_samples=record_samples)
        except (TypeError, ValueError, TargetConfigError) as exc:
            raise ControllerError(str(exc)) from None
        self._plc.coverage = coverage            # a CodeCoverage (controller/coverage.py)
        #: breakpoints, stepping, the halted state (controller/debugger.py)
        self.debugger = Debugger(self._plc)
        self._plc.debugger = self.debugger
        self._loaded_once = False
        self._stop_presses = 0
        self._crc: dict[str, int] = {}
        #: write, force and release (controller/forces.py); forces() lists them
        self.forces = Forces(self._plc, machine)
        #: everything done to this controller from outside (controller/recorder.py)
        self.recorder = Recorder()
        self.recorder.where = self._halt_point
        #: what a replayed ``upload`` line loads (None: the procedures loaded now)
        self.replay_image: Optional[list[Program]] = None
        #: every image loaded, by its identity (what stepping back loads again)
        self.images: dict[str, list[Program]] = {}
        #: the variables recorded each tick (controller/watch.py, watch_variables)
        self.watch = VariableWatch()

    def _halt_point(self) -> Optional[tuple]:
        """Where the debugger holds the tick (procedure, code offset, return
        offsets), when it is halted before a statement of a procedure mid-tick."""
        h = self.debugger.halt
        if h is None or h.process is None or h.pc is None or not self._plc.mid_tick:
            return None
        return (h.process.name, h.pc, tuple(h.rets))

    # ------------------------------------------------------------ basics
    @property
    def t_ms(self) -> int:
        """Ticks run so far: the tick that runs next."""
        return self._plc.t

    @property
    def backend(self) -> str:
        return self._plc.backend

    @property
    def record_samples(self) -> bool:
        return self._plc.record_samples

    @record_samples.setter
    def record_samples(self, on: bool) -> None:
        self._plc.record_samples = bool(on)
        if not on:
            self._plc.samples.clear()

    @property
    def sample_changes_only(self) -> bool:
        """Record a sample only on a tick where it differs from the previous one
        (each then holds until the next); the link's telemetry turns it on."""
        return self._plc.sample_changes_only

    @sample_changes_only.setter
    def sample_changes_only(self, on: bool) -> None:
        self._plc.sample_changes_only = bool(on)
        self._plc.record_next_sample()

    def record_next_sample(self) -> None:
        """Record the next tick's sample even when nothing changed."""
        self._plc.record_next_sample()

    @property
    def programs(self) -> dict[str, Program]:
        return dict(self._plc.programs)

    @property
    def plc(self) -> PLC:
        return self._plc

    # -------------------------------------------------------------- load
    def load(self, programs: Iterable[Program], *, autostart: bool = True) -> None:
        """Replace the loaded procedures with ``programs`` (the whole set), as
        Build All does: every running procedure ends (100, extern break), the
        software procedures whose names do not start with ``__`` start at the
        next software tick, and on the first load ``__HANDLER_INIT`` too
        (``autostart=False``: nothing starts)."""
        progs = list(programs)
        by_name: dict[str, Program] = {}
        for p in progs:
            if not isinstance(p, Program):
                raise ControllerError(f"not a compiled procedure: {p!r}")
            if not p.name:
                raise ControllerError("a procedure without a name")
            if p.name in by_name:
                raise ControllerError(f"two procedures named {p.name}")
            try:
                validate(p.code, p.entry)
            except DecodeError as exc:
                raise ControllerError(f"{p.name}: invalid code: {exc}") from None
            if p.code and not 0 <= p.entry < len(p.code):
                raise ControllerError(f"{p.name}: entry point {p.entry} is outside the code")
            by_name[p.name] = p
        plc = self._plc
        self._drop_halt()
        if plc.job is not None:
            plc.job.stop("the image was loaded again")
        plc.end_all()
        plc.programs = by_name
        self.debugger.rebind()                   # breakpoints stay on their lines
        for (source, pin), (name, _e) in list(plc.bindings.items()):
            if name not in by_name:
                plc.unbind_input(pin, source)
        self._crc = {name: p.crc32 for name, p in by_name.items()}
        plc.prepare(progs)                           # translate now, not on first start
        first, self._loaded_once = not self._loaded_once, True
        if first:
            plc.grid = plc.t               # the software grid starts at the first load
        self.forces.on_load()              # forces survive the build
        iid = image_id(progs)
        self.images[iid] = progs
        self.recorder.add(Action(plc.t, "upload", iid))
        if self.target is not None:        # a target's one program: it starts now
            try:
                plc.program_of(by_name)
                if autostart:
                    plc.begin()
            except ValueError as exc:
                raise ControllerError(str(exc)) from None
            return
        if not autostart:
            return
        for name in sorted(by_name):
            if by_name[name].kind is Kind.SOFTWARE and not name.startswith("__"):
                plc.start_software(name)
        init = by_name.get(HANDLER_INIT)
        if first and init is not None and init.kind is Kind.SOFTWARE:
            plc.start_software(HANDLER_INIT)

    def reload(self) -> None:
        """Load the replay image (a recorded session's ``upload`` line), or the
        procedures loaded now again."""
        image = self.replay_image if self.replay_image is not None else \
            list(self._plc.programs.values())
        self.load(image)

    # ------------------------------------------------------------- starts
    def start(self, name: str, eparam: int = 0) -> None:
        """Start a procedure by name. A hardware procedure begins in tick
        ``t_ms`` and ends the running one (exit code 100); a software procedure
        begins at the next software tick (and restarts if it runs)."""
        program = self._plc.programs.get(name)
        if program is None:
            raise ControllerError(self._unknown(name))
        eparam = self._eparam(eparam)
        self._stop_presses = 0
        self.recorder.add(Action(self._plc.t, "start", name, eparam))
        if program.kind is Kind.HARDWARE:
            self._plc.start_hardware(name, eparam)
        else:
            self._plc.start_software(name, eparam)

    def start_mcode(self, n: int, eparam: int = 0) -> str:
        """Start the hardware procedure of M-code ``n`` (3 starts M03); returns its name."""
        n = self._int(n, "M-code")
        for name in mcode_names(n):
            p = self._plc.programs.get(name)
            if p is not None and p.kind is Kind.HARDWARE:
                self.start(name, eparam)
                return name
        raise ControllerError(f"M{n:02d}: no hardware procedure {mcode_names(n)[0]} is loaded")

    def stop(self) -> Optional[str]:
        """Press Stop: the first press starts ``M02``, the second ``OFF`` (then
        M02 again, …). Where the project lacks that procedure the running
        hardware procedure just ends (100). Outputs stay as they are. Returns
        the name started, or None."""
        self._stop_presses += 1
        name = "M02" if self._stop_presses % 2 == 1 else "OFF"
        plc = self._plc
        self.recorder.add(Action(plc.t, "stop"))
        if plc.job is not None and (plc.job.active or plc.job.state == "paused"):
            plc.job.stop("Stop pressed")
        p = plc.programs.get(name)
        if p is not None and p.kind is Kind.HARDWARE:
            plc.start_hardware(name, 0)
            plc.events.append(Note(plc.t, f"Stop: started {name}"))
            return name
        if plc.hw is not None:
            plc.events.append(Note(plc.t, f"Stop: {plc.hw.name} ended (no {name} loaded)"))
            plc.end_hardware()
        return None

    def bind_input(self, pin: int, name: str, eparam: int = 0, source: str = "in") -> None:
        """Bind an input to a procedure: a 0 -> 1 edge of input ``pin`` starts
        ``name`` (with ``eparam``) at the beginning of the next tick, as an
        input pin bound to a procedure does on the controller. ``source`` "vin"
        or "vout" binds virtual input or output ``pin`` (1..32), "pls" the output
        of PLS ``pin`` (the softMC seed: "You can use software I/O to start
        events just as with standard I/O"; ``EventOn MyEvent MyPLS.PlsOutput = ON``)."""
        pin = self._int(pin, "input pin")
        if name not in self._plc.programs:
            raise ControllerError(self._unknown(name))
        why = bind_source_error(self.machine, source, pin)
        if why:
            raise ControllerError(why)
        eparam = self._eparam(eparam)
        self._plc.bind_input(pin, name, eparam, source)
        self.recorder.add(Action(self._plc.t, "bind", name, pin, eparam, source=source))

    @property
    def bindings(self) -> dict[tuple[str, int], tuple[str, int]]:
        """(source, n) -> (procedure, eparam) of what is bound to procedures
        (source "in", "vin", "vout" or "pls")."""
        return dict(self._plc.bindings)

    def unbind_input(self, pin: int, source: str = "in") -> None:
        self._plc.unbind_input(self._int(pin, "input pin"), source)

    def event(self, handler_name: str) -> bool:
        """A host event: starts the system procedure that handles it
        (``"GCODE_START"`` or ``"__HANDLER_GCODE_START"``, likewise STOP, INIT,
        EXIT). Returns whether one was loaded and started."""
        key = str(handler_name).strip().upper().lstrip("_")
        if not key.startswith("HANDLER_"):
            key = "HANDLER_" + key
        name = "__" + key
        p = self._plc.programs.get(name)
        if p is None or p.kind is not Kind.SOFTWARE:
            return False
        self._plc.start_software(name)
        self.recorder.add(Action(self._plc.t, "event", key.removeprefix("HANDLER_")))
        return True

    # ------------------------------------------------------ G-code jobs
    def job_open(self, text: str, file: str = "job.nc", play: bool = False) -> None:
        """Load a G-code program (SPEC §10; controller/job.py), checked whole:
        a line it cannot run is refused naming the file and the line, and the
        job loaded before stays. With ``play`` it starts at once."""
        from plcbuilder.controller.gcode import GcodeError, parse
        from plcbuilder.controller.job import Job
        plc = self._plc
        target = self.target.name if self.target is not None else "mycnc"
        present = tuple(abi.AXES[i] for i in self.machine.motion.present_idx) \
            if hasattr(self.machine, "motion") else abi.AXES
        try:
            program = parse(str(text), str(file), axes=present,
                            functions="MSTB" if target == "huazhong" else "M")
            self._check_homes(program)
        except GcodeError as exc:
            raise ControllerError(str(exc)) from None
        old = plc.job
        if old is not None and (old.active or old.state == "paused"):
            old.stop("another program was opened")
        plc.job = Job(plc, program)
        plc.job.size = len(str(text).encode("utf-8"))
        self.recorder.add(Action(plc.t, "gcode", str(file), int(play), text=str(text)))
        if play:
            plc.job.play()

    def _check_homes(self, program) -> None:
        from plcbuilder.controller.gcode import GcodeError
        home = getattr(self.machine, "home_position", None)
        for b in program.blocks:
            if b.motion != 28 or home is None:
                continue
            for i in b.axes:
                if home(i) is None:
                    raise GcodeError(f"G28: axis {abi.AXES[i]} has no home switch (an input "
                                     f"with home = true in the machine file)", program.file,
                                     b.line)
            if not b.axes and all(home(i) is None for i in self.machine.motion.present_idx):
                raise GcodeError("G28: no axis of the machine has a home switch (an input "
                                 "with home = true in the machine file)", program.file, b.line)

    def job_control(self, verb: str) -> None:
        """``play``, ``pause``, ``stop`` or ``reset`` the job loaded (the Server
        API's ProgramPlay/Pause/Stop/Reset, the IDE's Start menu)."""
        job = self._plc.job
        if verb not in ("play", "pause", "stop", "reset"):
            raise ControllerError(f"unknown job command {verb!r} (play, pause, stop or reset)")
        if job is None:
            raise ControllerError("no G-code program is open (open one first)")
        self.recorder.add(Action(self._plc.t, "job", verb))
        getattr(job, verb)()

    @property
    def job(self):
        """The G-code job (controller/job.py), or None."""
        return self._plc.job

    @property
    def job_runner(self):
        """The job as the Server API's program commands drive it (controller/job.py;
        link/server_api.py's JobRunner). Settable: a test puts another in its
        place, or None for a controller without one."""
        runner = getattr(self, "_job_runner", _NO_RUNNER_YET)
        if runner is _NO_RUNNER_YET:
            from plcbuilder.controller.job import JobRunner
            runner = self._job_runner = JobRunner(self)
        return runner

    @job_runner.setter
    def job_runner(self, runner) -> None:
        self._job_runner = runner

    def handwheel(self, axis: str, distance_mm: float) -> None:
        """One incremental rapid move of ``axis`` by ``distance_mm`` (a handwheel
        click: the Server API's SetPendant), recorded (scenario ``move X=0.1``)."""
        axis = str(axis).upper()
        if axis not in abi.AXES:
            raise ControllerError(f"no axis {axis!r} (one of {' '.join(abi.AXES)})")
        units = round(float(distance_mm) * 100)
        self.machine.g0move(0, 1 << abi.AXES.index(axis), units)
        self.recorder.add(Action(self._plc.t, "move", axis, units))

    def job_report(self) -> Optional[dict]:
        """The run report's ``job`` (SPEC §10), or None without one."""
        job = self._plc.job
        return job.report() if job is not None else None

    def issue_code(self, letter: str, value: int) -> Optional[str]:
        """The simulated CNC issues code ``letter`` ``value`` (a scenario's ``code
        M3``): on myCNC an M code starts procedure M<value>; on Huazhong an M,
        S, B or T code goes to the handler init() registered. Returns the
        procedure started (myCNC), else None."""
        letter = str(letter).upper()
        value = self._int(value, "code")
        plc = self._plc
        issue = getattr(plc, "issue_function", None)
        if issue is not None:
            try:
                issue(letter, value)
            except ValueError as exc:
                raise ControllerError(str(exc)) from None
            self.recorder.add(Action(plc.t, "code", letter, value))
            return None
        if letter != "M":
            raise ControllerError(f"{letter}{value}: on this target the CNC issues M codes only "
                                  f"(S is the eparam of M03/M04 in a G-code job)")
        name = self.start_mcode(value)
        return name

    def shutdown(self, limit_ms: int = SHUTDOWN_LIMIT_MS) -> None:
        """Run ``__HANDLER_EXIT`` to its end (at most ``limit_ms`` of simulated
        time), then end every procedure (100)."""
        plc = self._plc
        self._drop_halt()
        self.debugger.clear()
        if self.event("EXIT"):
            end = plc.t + max(0, int(limit_ms))
            while plc.t < end:
                plc.run(1)
                pending = any(n == HANDLER_EXIT for n, _e in plc._pending_sw)
                if not pending and HANDLER_EXIT not in plc.sw:
                    break
        plc.end_all()

    # ------------------------------------------------------------- inputs
    def set_input(self, pin: int, value: int) -> None:
        """Set input ``pin`` by hand from now on (overrides the machine's wiring)."""
        pin = self._int(pin, "input pin")
        value = 1 if self._int(value, "input value") else 0
        try:
            self.machine.set_input(pin, value)
        except ValueError as exc:
            raise ControllerError(str(exc)) from None
        self.recorder.add(Action(self._plc.t, "input", "", pin, value))

    def set_adc(self, ch: int, value: int) -> None:
        ch = self._int(ch, "ADC channel")
        value = self._ranged(value, "ADC value", *INT32)
        try:
            self.machine.set_adc(ch, value)
        except ValueError as exc:
            raise ControllerError(str(exc)) from None
        self.recorder.add(Action(self._plc.t, "adc", "", ch, value))

    # ------------------------------------------------------ write and force
    def write(self, target: str, value) -> str:
        """Set a target (``M03.x``, ``in 4``, ``out 0``, ``adc 1``, ``pwm 0``,
        ``dac 1``, ``gvar 5000``) to ``value`` once. Returns its canonical name."""
        name = self._forcing(self.forces.write, target, value)
        self.recorder.add(Action(self._plc.t, "write", name, _as_int(value)))
        return name

    def force(self, target: str, value) -> str:
        """Hold a target at ``value`` until released (SPEC §6)."""
        name = self._forcing(self.forces.force, target, value)
        self.recorder.add(Action(self._plc.t, "force", name, _as_int(value)))
        return name

    def release(self, target: str, mode: str = "restore") -> str:
        """Release a target: ``keep`` its value or ``restore`` the program's."""
        name = self._forcing(self.forces.release, target, mode)
        self.recorder.add(Action(self._plc.t, "release", name, 0, _MODES.index(mode)))
        return name

    def release_all(self, mode: str = "restore") -> list[str]:
        """Release everything forced; returns the names released."""
        names = self._forcing(self.forces.release_all, mode)
        self.recorder.add(Action(self._plc.t, "release", "all", 0, _MODES.index(mode)))
        return names

    @staticmethod
    def _forcing(fn, *args):
        try:
            return fn(*args)
        except ForceError as exc:
            raise ControllerError(str(exc)) from None

    # --------------------------------------------------------------- time
    def step(self, ms: int = 1) -> None:
        """Run ``ms`` ticks of 1 ms."""
        ms = self._int(ms, "ms")
        if ms < 0:
            raise ControllerError(f"cannot step {ms} ms")
        if self.forces.pending:
            self.forces.retry_pending()
        if self.watch:
            self._run_watched(ms)
        else:
            self._plc.run(ms)
        self.debugger.settle()

    def run_until_idle(self, ms: int) -> int:
        """Run at most ``ms`` ticks, stopping after the first tick that leaves
        no procedure running and none due to start. Returns the ticks run."""
        ms = self._int(ms, "ms")
        if ms < 0:
            raise ControllerError(f"cannot step {ms} ms")
        if self.forces.pending:
            self.forces.retry_pending()
        ran = self._run_watched(ms, True) if self.watch else self._plc.run(ms, until_idle=True)
        self.debugger.settle()
        return ran

    def watch_variables(self, names: Iterable[str], check: bool = True) -> list[str]:
        """Record these variables (``PROC.var``) at the end of every tick, as
        ``Watched`` events (controller/watch.py); an empty list stops. With
        ``check``, each must name a variable of a loaded procedure (else
        ControllerError, and nothing changes). While watching, time runs one
        tick at a time."""
        names = [str(n) for n in names]
        if check:
            for name in names:
                try:
                    check_name(self._plc.programs, name)
                except ValueError as exc:
                    raise ControllerError(str(exc)) from None
        self.watch.set(names)
        return list(self.watch.names)

    def _run_watched(self, ms: int, until_idle: bool = False) -> int:
        """Run up to ``ms`` ticks one at a time, reading the watched variables
        after each (and first a tick a halt held, if it ended since)."""
        plc, dbg, watch = self._plc, self.debugger, self.watch
        events = plc.events
        events.extend(watch.read(plc))
        ran = 0
        while ran < ms:
            n = plc.run(1, until_idle=until_idle)
            ran += n
            events.extend(watch.read(plc))
            if not n or dbg.halt is not None or until_idle and plc.idle():
                break
        return ran

    def idle(self) -> bool:
        """No procedure runs and none is due to start."""
        return self._plc.idle()

    def next_due(self) -> Optional[int]:
        """The tick of the next start already scheduled inside the controller."""
        return self._plc.next_due()

    def drain_events(self) -> list[Event]:
        ev = self._plc.events
        out = list(ev)
        ev.clear()
        return out

    def drain_samples(self) -> list[Sample]:
        """The per-tick samples since the last drain (when record_samples is on)."""
        return self._plc.take_samples()

    def drain_sample_rows(self) -> list[tuple]:
        """The same as raw rows ``(t_ms, running, proc, message, fields)``, where
        fields is the machine's sample_fields() dict (shared while nothing
        changes; do not modify it): cheaper for high-volume consumers."""
        return self._plc.take_sample_rows()

    # -------------------------------------------------------------- state
    def state(self) -> ControllerStatus:
        plc = self._plc
        m = self.machine
        f = m.sample_fields()
        inputs = [w * 32 + b for w, word in enumerate(f["inputs"]) for b in range(32)
                  if (word >> b) & 1]
        return ControllerStatus(
            t_ms=plc.t,
            running=plc.hw.name if plc.hw is not None else None,
            software=tuple(plc.software_running),
            idle=plc.idle(),
            proc=plc.proc,
            proc_name=abi.proc_name(plc.proc),
            inputs=tuple(inputs),
            outputs=tuple(m.outputs_on()),
            pwm=tuple(f["pwm"]),
            dac=tuple(f["dac"]),
            adc=tuple(f["adc"]),
            axes=m.axis_positions(),
            image=tuple({"name": p.name, "kind": p.kind.label, "size": p.code_size,
                         "crc32": self._crc.get(p.name, 0)}
                        for p in sorted(plc.programs.values(), key=lambda q: q.name)),
            job=self._job_state(),
        )

    def _job_state(self) -> dict:
        job = self._plc.job
        if job is None:
            return {}
        last = job.calls[-1] if job.calls else None
        if last is not None:
            last.update()
            last = {"line": last.line, "code": last.code, "procedure": last.procedure,
                    "exit_code": last.exit_code}
        return {"file": job.program.file, "state": job.state, "line": job.line,
                "lines": job.program.lines, "error": job.error, "last_call": last,
                "mcode_count": job.call_count}

    def target_report(self) -> dict:
        """What a target adds to the run report (registers, calls, budget
        overruns: docs/targets.md); {} on myCNC."""
        return self._plc.report() if self.target is not None else {}

    def retained(self) -> Optional[list[int]]:
        """The Huazhong target's B registers (kept across a restart), else None."""
        kept = getattr(self._plc, "retained", None)
        return list(kept) if kept is not None else None

    def variables(self) -> dict[str, dict[str, int]]:
        """Each procedure that has run: its variables' latest values, by name."""
        return {name: p.variables() for name, p in sorted(self._plc.last.items())}

    def _drop_halt(self) -> None:
        """Not halted any more; the rest of a halted tick runs (its procedures
        already ended or ending do nothing more)."""
        dbg = self.debugger
        if dbg.halt is not None:
            dbg.halt = None
            self._plc.end_all()
            self._plc.resume_tick()

    # ------------------------------------------------------------ helpers
    def _unknown(self, name: str) -> str:
        names = sorted(self._plc.programs)
        if not names:
            return f"no procedure named {name!r}: nothing is loaded"
        shown = ", ".join(names[:20]) + (" …" if len(names) > 20 else "")
        return f"no procedure named {name!r} is loaded (loaded: {shown})"

    @classmethod
    def _ranged(cls, v, what: str, lo: int, hi: int) -> int:
        v = cls._int(v, what)
        if not lo <= v <= hi:
            raise ControllerError(f"{what} must be from {lo} to {hi}, not {v}")
        return v

    @classmethod
    def _eparam(cls, v) -> int:
        """An eparam: a 32-bit word (signed or unsigned), held signed; refused
        outside, never wrapped."""
        return to_int32(cls._ranged(v, "eparam", *WORD32))

    @staticmethod
    def _int(v, what: str) -> int:
        if isinstance(v, bool):
            return int(v)
        if not isinstance(v, int):
            try:
                v = int(str(v), 0)
            except ValueError:
                raise ControllerError(f"{what} must be an integer, not {v!r}") from None
        return v
