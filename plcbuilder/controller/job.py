"""The G-code job runner (SPEC §10): a minimal motion controller that reads a
program block by block and starts the M-code procedures, as myCNC does (seed
000: "if within a running program the next code is a PLC M-code, then the
movement will be stopped and the controller will run the PLC program").

The job lives in the PLC (``plc.job``) and takes its steps at the beginning of
a tick, after the starts due and before the software tick, so what it starts
in tick t runs in tick t. Each block, in order:

1. settings: ``G90``/``G91``, ``F``, ``S`` (myCNC: the eparam of the next
   ``M03``/``M04``);
2. its functions in the order written: ``Mnn`` starts hardware procedure
   ``Mnn`` (``M03``, or ``M3``) with its eparam and waits until it exits, or
   until a procedure sends ``PLCCMD_MOTION_CONTINUE`` ("A message from within
   the PLC called PLCCMD_MOTION_CONTINUE is used to instruct the Motion
   controller to read and run the next code from the buffer"), after which the
   procedure and the job run side by side. On Huazhong M, S, B and T go to the
   handlers init() registered;
3. the dwell (``G4 P`` seconds) or the motion (``G0`` rapid, ``G1`` at F, ``G28``
   home), which starts when everything has stopped moving and is waited for;
   ``PLCCMD_MOTION_SKIP`` ("the motion controller will cancel current motion
   (it will stop moving) and will read the next code from the buffer") cuts it
   short, as a stop message (LINE_STOP …) does;
4. ``M2``/``M30``: the job ends (after procedure ``M02``/``M30`` when the project
   has it).

``__HANDLER_GCODE_START`` runs "just before the myCNC software run g-code
(after pressing PLAY button)": the job reads its first block once it has
ended. ``__HANDLER_GCODE_STOP`` starts "just after the myCNC software finished
g-code running (after pressing STOP/PAUSE button)": when the job ends, is
stopped, paused or fails. A procedure the job started that faults, or exits
with one of the seed's error codes (2..10, "PLC aborted ..."), stops the job
with an error naming the line.

Nothing here prints; the job reports through :class:`~plcbuilder.controller.
events.JobEvent` events and :meth:`Job.report`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Optional

from plcbuilder.bytecode import abi
from plcbuilder.bytecode.program import Kind
from plcbuilder.controller.events import JobEvent, Note
from plcbuilder.controller.gcode import Block, GcodeProgram

HANDLER_START = "__HANDLER_GCODE_START"
HANDLER_STOP = "__HANDLER_GCODE_STOP"
CONTINUE = abi.PLCCMD["PLCCMD_MOTION_CONTINUE"]
SKIP = abi.PLCCMD["PLCCMD_MOTION_SKIP"]
#: the seed's exit codes that say the PLC aborted (plc_exit_gas_fail .. broadcast_error)
ERROR_EXITS = frozenset(v for k, v in abi.EXIT.items() if 2 <= v <= 10)
FAULT_EXIT = -1
STATES = ("ready", "starting", "running", "paused", "ended", "stopped", "error")
ACTIVE = ("starting", "running")
#: M-code calls kept in the report at most (a long job's are counted)
MAX_CALLS = 10_000


@dataclass
class McodeCall:
    """One function the job issued: its line, the code and what handled it."""
    line: int
    code: str                          # "M03", "S1200" (Huazhong)
    procedure: Optional[str]
    eparam: int
    started_at_ms: int
    ended_at_ms: Optional[int] = None
    exit_code: Optional[int] = None
    continued_at_ms: Optional[int] = None
    process: object = field(default=None, repr=False)
    reported: bool = field(default=False, repr=False)     # its end is in a JobEvent

    def update(self) -> bool:
        """Take the end from the procedure once it has one; whether it has ended."""
        p = self.process
        if p is not None and self.ended_at_ms is None and p.ended_at is not None:
            self.ended_at_ms, self.exit_code = p.ended_at, p.exit_code
        return self.ended_at_ms is not None

    def to_dict(self) -> dict:
        return {"line": self.line, "code": self.code, "procedure": self.procedure,
                "eparam": self.eparam, "started_at_ms": self.started_at_ms,
                "ended_at_ms": self.ended_at_ms, "exit_code": self.exit_code,
                "exit_name": abi.exit_name(self.exit_code) if self.exit_code is not None
                else None, "continued_at_ms": self.continued_at_ms}


class Job:
    """One G-code program on one PLC (see the module docstring)."""

    def __init__(self, plc, program: GcodeProgram):
        self.plc = plc
        self.program = program
        self.state = "ready"
        self.error: Optional[str] = None
        self.size = 0                  # the program's bytes (the Server API's GetSVariable8109)
        self._rewind()

    def _rewind(self) -> None:
        self.index = 0                 # the next block
        self.step = 0                  # the next part of the current block (see _run_block)
        self.line = 0                  # the line reached (the last block read)
        self.absolute = True
        self.feed: Optional[float] = None
        self.speed = 0
        self.calls: list[McodeCall] = []
        self.call_count = 0
        self.open_calls: list[McodeCall] = []   # called, their end not reported yet
        self._tail: Optional[tuple] = None      # (index, ms): the estimate after a block
        self.started_at: Optional[int] = None
        self.ended_at: Optional[int] = None
        self.wait: Optional[tuple] = None
        self.target = None             # the motion of the current block (to resume it)

    # ------------------------------------------------------------ control
    @property
    def active(self) -> bool:
        return self.state in ACTIVE

    def play(self) -> None:
        """Start (from the first block), or go on after a pause."""
        t = self.plc.t
        if self.state == "paused":
            if self.wait and self.wait[0] == "paused-motion":
                self.wait = ("resume",)
            self._set("starting", "play: resumed")
        else:
            self._rewind()
            self.started_at = t
            self._set("starting", "play")
        if self._start_handler(HANDLER_START):
            self._before = self.wait
            self.wait = ("handler", HANDLER_START)
        else:
            self._before = None
            self.state = "running"

    def pause(self) -> None:
        if not self.active:
            return
        if self.wait and self.wait[0] == "motion":
            self.plc.machine.motion.stop()
            self.wait = ("paused-motion",)
        elif self.wait and self.wait[0] == "dwell":
            self.wait = ("paused-dwell", self.wait[1] - self.plc.t)
        self._set("paused", "pause")
        self._start_handler(HANDLER_STOP)

    def stop(self, why: str = "stop") -> None:
        if self.state not in ACTIVE and self.state != "paused":
            return
        if self.wait and self.wait[0] in ("motion", "resume"):
            self.plc.machine.motion.stop()
        self.wait = None
        self._finish("stopped", why)

    def reset(self) -> None:
        """Stop it if it runs, and go back to the first block (ready to play)."""
        self.stop("reset")
        self._rewind()
        self.state = "ready"
        self.error = None

    # -------------------------------------------------------------- ticks
    def tick(self, t: int) -> None:
        """The job's step at the beginning of tick t."""
        if not self.active:
            return
        if self.open_calls:
            self.report_ends(t)
        while self.active:
            if self.wait is not None and not self._waited(t):
                return
            if self.index >= len(self.program.blocks):
                self._finish("ended", "the end of the program")
                return
            self._run_block(self.program.blocks[self.index], t)

    def on_message(self, code: int, source: str) -> None:
        """A message sent at the end of a tick (PLC._send)."""
        if not self.active or self.wait is None:
            return
        if code in (CONTINUE, SKIP) and self.wait[0] == "proc":
            call = self.wait[1]
            call.continued_at_ms = self.plc.t
            self.wait = None           # the next block is read in the next tick
        # a stop message (SKIP, LINE_STOP, ...) stops the move itself (Machine.on_message);
        # the motion wait ends once it has stopped

    def _waited(self, t: int) -> bool:
        """Whether what the job waits for is over (clears the wait when it is)."""
        w = self.wait
        kind = w[0]
        plc = self.plc
        if kind == "handler":
            name = w[1]
            if any(n == name for n, _e in getattr(plc, "_pending_sw", ())) or \
                    name in getattr(plc, "sw", {}):
                return False
            self.wait = self._before
            self.state = "running"
            return self.wait is None or self._waited(t)
        if kind == "proc":
            call: McodeCall = w[1]
            p = call.process
            if p is not None and p.ended_at is None:
                return False
            self.wait = None
            return self._judge(call)
        if kind == "function":
            if not w[1].get("done"):
                return False
            self.wait = None
            return self._judge(w[2])
        if kind == "motion":
            if not plc.machine.motion.idle:
                return False
            self.wait = None
            return True
        if kind == "resume":
            if not plc.machine.motion.idle:
                return False
            self._move(*self.target)
            return False
        if kind == "dwell":
            if t < w[1]:
                return False
            self.wait = None
            return True
        if kind == "paused-dwell":
            self.wait = ("dwell", t + w[1])
            return False
        return True

    def _judge(self, call: McodeCall) -> bool:
        """A function's procedure ended: record it; an error stops the job."""
        call.update()
        self.report_ends(self.plc.t)
        code = call.exit_code
        if code == FAULT_EXIT or code in ERROR_EXITS:
            what = "faulted" if code == FAULT_EXIT else \
                f"ended with {code} ({abi.exit_name(code)})"
            self.error = f"{self.program.file}:{call.line}: {call.procedure} {what}: the job stops"
            self._finish("error", self.error)
            return False
        return True

    # ------------------------------------------------------------- blocks
    def _run_block(self, b: Block, t: int) -> None:
        """Run the parts of block b from ``self.step`` on, until one waits."""
        if self.step == 0:
            self.line = b.line
            self._event(t, "running", b.text)
            if b.absolute is not None:
                self.absolute = b.absolute
            if b.feed is not None:
                self.feed = b.feed
            if b.speed is not None:
                self.speed = b.speed
            self.step = 1
        while self.step - 1 < len(b.functions):
            letter, value = b.functions[self.step - 1]
            self.step += 1
            self._function(b, letter, value, t)
            if self.wait is not None or not self.active:
                return
        n = len(b.functions) + 1
        if self.step == n:
            self.step += 1
            if b.dwell_ms is not None:
                self.wait = ("dwell", t + b.dwell_ms)
                return
            if b.motion is not None:
                if not self.plc.machine.motion.idle:
                    self.step -= 1
                    self.wait = ("motion",)          # the earlier motion first
                    return
                self._motion(b)
                return
        if self.step == n + 1:
            self.step += 1
            if b.end is not None:
                self._function(b, "M", b.end, t, optional=True)
                if self.wait is not None:
                    return
        if b.end is not None:
            self.index = len(self.program.blocks)
            self._finish("ended", f"M{b.end}")
            return
        self.index += 1
        self.step = 0

    def _function(self, b: Block, letter: str, value: int, t: int,
                  optional: bool = False) -> None:
        plc = self.plc
        issue = getattr(plc, "issue_function", None)
        if issue is not None:                         # a target: its handlers
            if letter == "M" and optional:
                return
            code = f"M{value:02d}" if letter == "M" else f"{letter}{value}"
            call = self._record(b.line, code, None, value, t)
            box = {}

            def done(handler, code, box=box, call=call):
                box["done"] = True
                call.procedure, call.exit_code, call.ended_at_ms = handler, code, plc.t
                if handler is not None and code is None:
                    call.exit_code = FAULT_EXIT
            issue(letter, value, done)
            self.open_calls.append(call)
            self.wait = ("function", box, call)
            return
        if letter != "M":                             # pragma: no cover - the parser refuses
            return
        from plcbuilder.controller.plc import mcode_names
        name = next((n for n in mcode_names(value) if n in plc.programs
                     and plc.programs[n].kind is Kind.HARDWARE), None)
        code = f"M{value:02d}"
        if name is None:
            if not optional and hasattr(plc, "start_hardware") and getattr(plc, "target", "") == "":
                plc.events.append(Note(t, f"{self.program.file}:{b.line}: {code}: no procedure "
                                          f"{code} is loaded; the job goes on", "warning"))
                self._record(b.line, code, None, 0, t)
            elif not optional:
                plc.events.append(Note(t, f"{self.program.file}:{b.line}: {code}: the "
                                          f"{plc.target} target has no M-code procedures; the "
                                          f"job goes on", "warning"))
            return
        eparam = self.speed if value in (3, 4) else 0
        plc.start_hardware(name, eparam)
        call = self._record(b.line, code, name, eparam, t)
        call.process = plc.hw
        self.open_calls.append(call)
        self._event(t, "running", b.text, name)
        self.wait = ("proc", call)

    def _record(self, line: int, code: str, procedure, eparam: int, t: int) -> McodeCall:
        call = McodeCall(line, code, procedure, eparam, t)
        self.call_count += 1
        if len(self.calls) < MAX_CALLS:
            self.calls.append(call)
        return call

    def _motion(self, b: Block) -> None:
        m = self.plc.machine
        mo = m.motion
        if b.motion == 28:
            axes = list(b.axes) or [i for i in mo.present_idx if m.home_position(i) is not None]
            target = {i: m.home_position(i) for i in axes}
            feed = min(mo.jog_default[i] for i in axes) if axes else None
            self.target = (target, float(feed) if feed else None, 0, tuple(axes))
        else:
            target = {}
            for i, v in b.axes.items():
                units = round(v * 100)
                target[i] = (units + mo.offset[i]) if self.absolute else mo.ipos[i] + units
            self.target = (target, self.feed if b.motion == 1 else None, b.motion, ())
        self._move(*self.target)

    def _move(self, target, feed, code, homing) -> None:
        m = self.plc.machine
        m.quiet = False
        m.motion.line_to(target, feed, code, homing)
        self.wait = ("motion",)

    # ------------------------------------------------------------ helpers
    def _start_handler(self, name: str) -> bool:
        plc = self.plc
        p = plc.programs.get(name)
        if p is None or p.kind is not Kind.SOFTWARE or not hasattr(plc, "start_software"):
            return False
        try:
            plc.start_software(name)
        except KeyError:
            return False
        return True

    def report_ends(self, t: int) -> None:
        """A JobEvent for each called procedure that has ended since: the run
        log's "line 3: M03 exit 99" (a procedure the job went on from after its
        PLCCMD_MOTION_CONTINUE included, even after the job's end). The PLC calls
        it as a procedure ends; the job's tick for a Huazhong handler's end."""
        still = []
        for c in self.open_calls:
            if not c.update():
                still.append(c)
            elif not c.reported and (c.procedure is not None or c.process is not None):
                c.reported = True
                code = c.exit_code
                what = "faulted" if code == FAULT_EXIT else \
                    f"exit {code} {abi.exit_name(code) or ''}".rstrip()
                who = c.procedure if c.code == c.procedure else f"{c.code} ({c.procedure})"
                self.plc.events.append(JobEvent(t, self.program.file, c.line, self.state,
                                                f"{who} {what}", c.procedure, code))
        self.open_calls = still

    def _finish(self, state: str, why: str) -> None:
        self.report_ends(self.plc.t)
        self.state = state
        self.ended_at = self.plc.t
        self._event(self.plc.t, state, why)
        if state == "error":
            self.plc.events.append(Note(self.plc.t, why, "error"))
        self._start_handler(HANDLER_STOP)

    def _set(self, state: str, why: str) -> None:
        self.state = state
        self._event(self.plc.t, state, why)

    def _event(self, t: int, state: str, text: str, procedure: Optional[str] = None) -> None:
        self.plc.events.append(JobEvent(t, self.program.file, self.line, state, text,
                                        procedure))

    # ----------------------------------------------------------- time left
    def estimate_ms(self) -> float:
        """The job's time left, ms: its moves (at their feed or the rapid speeds,
        accelerating as the machine does) and dwells from where it is; the
        procedures' own time cannot be known before they run, and is not in it."""
        if self.state in ("ended", "stopped", "error"):
            return 0.0
        mo = self.plc.machine.motion
        blocks = self.program.blocks
        pos = {i: float(mo.pos[i]) for i in mo.present_idx}
        total, first = 0.0, self.index
        absolute, feed = self.absolute, self.feed
        if self.step > 0 and first < len(blocks):
            b = blocks[first]
            w = self.wait or ("",)
            if self.step > len(b.functions) + 1:          # its dwell or move has begun
                first += 1
                if w[0] == "dwell":
                    total += max(0, w[1] - self.plc.t)
                elif w[0] == "paused-dwell":
                    total += w[1]
                elif self.target is not None and w[0] in ("motion", "resume", "paused-motion"):
                    target, tfeed = self.target[0], self.target[1]
                    move = mo.move
                    if w[0] == "motion" and move is not None:
                        total += max(0.0, move.profile.t_end - move.t)
                    else:
                        total += mo.line_ms(pos, target, tfeed)
                    pos.update(target)
        key = (first, tuple(sorted(pos.items())), absolute, feed)
        if self._tail is None or self._tail[0] != key:
            self._tail = (key, self._rest_ms(first, pos, absolute, feed))
        return total + self._tail[1]

    def _rest_ms(self, first: int, pos: dict, absolute: bool, feed: Optional[float]) -> float:
        m = self.plc.machine
        mo = m.motion
        total = 0.0
        for b in self.program.blocks[first:]:
            if b.absolute is not None:
                absolute = b.absolute
            if b.feed is not None:
                feed = b.feed
            if b.dwell_ms is not None:
                total += b.dwell_ms
            elif b.motion == 28:
                axes = list(b.axes) or [i for i in mo.present_idx
                                        if m.home_position(i) is not None]
                target = {i: m.home_position(i) for i in axes}
                speeds = [mo.jog_default[i] for i in axes]
                total += mo.line_ms(pos, target, float(min(speeds)) if speeds else None)
                pos.update(target)
            elif b.motion is not None:
                target = {i: (round(v * 100) + mo.offset[i]) if absolute
                          else pos.get(i, 0.0) + round(v * 100) for i, v in b.axes.items()}
                total += mo.line_ms(pos, target, feed if b.motion == 1 else None)
                pos.update(target)
            if b.end is not None:
                break
        return total

    # ------------------------------------------------------------- report
    def report(self) -> dict:
        """The ``job`` entry of the run report (SPEC §10)."""
        for c in self.calls:
            c.update()
        return {"file": self.program.file, "state": self.state, "line": self.line,
                "lines": self.program.lines, "started_at_ms": self.started_at,
                "ended_at_ms": self.ended_at if self.state in ("ended", "stopped", "error")
                else None,
                "error": self.error, "mcodes": [c.to_dict() for c in self.calls],
                "mcode_count": self.call_count}


# -------------------------------------------------------- the Server API's runner
#: the job's states as the Server API's program commands name them
API_STATES = {"ready": "idle", "starting": "running", "running": "running",
              "paused": "paused", "ended": "done", "stopped": "stopped", "error": "stopped"}


@dataclass(frozen=True)
class RunnerStatus:
    """Where the job is, as the Server API's program commands read it
    (link/server_api.py's JobStatus has the same fields)."""
    state: str = "idle"                 # idle | running | paused | stopped | done
    name: Optional[str] = None
    path: Optional[str] = None
    line: int = 0
    paused_line: Optional[int] = None
    lines: int = 0
    size: int = 0
    estimate_s: Optional[float] = None


class JobRunner:
    """The controller's G-code job as the Server API drives it (ProgramFileOpen,
    ProgramPlay, ProgramPause, ProgramStop, ProgramReset, SetPendant): every
    call goes through the controller, which checks and records it."""

    def __init__(self, controller):
        self.c = controller
        self._job = None                # the job this runner opened, and its name and path
        self._name: Optional[str] = None
        self._path: Optional[str] = None

    def open(self, name: str, text: str, path: Optional[str] = None) -> None:
        self.c.job_open(text, path or name, play=False)
        self._job, self._name, self._path = self.c.job, name, path

    def play(self) -> None:
        self.c.job_control("play")

    def pause(self) -> None:
        self.c.job_control("pause")

    def stop(self) -> None:
        self.c.job_control("stop")

    def reset(self) -> None:
        self.c.job_control("reset")

    def move(self, axis: str, distance_mm: float) -> None:
        job = self.c.job
        if job is not None and job.active:
            from plcbuilder.controller.controller import ControllerError
            raise ControllerError("the handwheel moves an axis while no G-code job runs "
                                  "(ProgramPause or ProgramStop first)")
        self.c.handwheel(axis, distance_mm)

    def status(self) -> RunnerStatus:
        job = self.c.job
        if job is None:
            return RunnerStatus()
        if job is self._job:
            name, path = self._name, self._path
        else:                           # opened by a scenario, the IDE or plcbuilder run
            from pathlib import PurePath
            name, path = PurePath(job.program.file).name, job.program.file
        return RunnerStatus(API_STATES.get(job.state, "idle"), name, path, job.line,
                            job.line if job.state == "paused" else None, job.program.lines,
                            job.size, round(job.estimate_ms() / 1000, 3))
