"""myCNC's Server API on the simulated controller (docs/editors.md, "The
Server API").

A real myCNC controller answers a telnet-style text protocol that pendant
drivers and scripts use: one command a line, one reply a line. This offers
the same command set on an extra port of ``plcbuilder controller``
(``--server-api PORT``). Like myCNC's, it has no token: it listens on
loopback unless the user names another address.

Replies are ``OK`` followed by the values, or ``ERROR`` followed by the
reason; the connection stays open either way. Numbers may be decimal or
``0x`` hex; command names are not case sensitive.

The commands are those of myCNC's published list (its Server API page), one
``cmd_<name>`` method each in :class:`Commands`; the ones with no meaning on
the simulated controller answer why (:data:`NOT_HERE`), and the program
commands drive the controller's G-code job runner through :class:`JobRunner`
(``Controller.job_runner``, controller/job.py). What a command changes goes through ``Controller.write``,
which records it, so replays and stepping back do it too.

The connections are served by the controller server's own selector loop
(:meth:`plcbuilder.link.server.Server.attach`): non-blocking sockets, lines of
at most :attr:`ServerApi.max_line` bytes (a longer one is answered with an
error and skipped), at most :attr:`ServerApi.lines_per_turn` commands of one
client per pass of the loop, and a client that does not read its replies is
not read either (then closed past :attr:`ServerApi.max_outbuf`), so a flood
never stalls the controller or the other clients. Idle connections are closed
after :attr:`ServerApi.idle_timeout`, and a new client takes the place of the
oldest silent one when every place is taken (issue 24.6).
"""

from __future__ import annotations

import re
import selectors
import socket
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Optional, Protocol

from plcbuilder._support.files import read_bounded
from plcbuilder.controller import abi
from plcbuilder.controller.controller import Controller, ControllerError
from plcbuilder.controller.events import Message
from plcbuilder.link.pacing import SimulationDown
from plcbuilder.link.protocol import accept_all, listening_socket, refuse, send_pending

__all__ = ["COMMANDS", "DEFAULT_PORT", "JobRunner", "JobStatus", "NOT_HERE", "ServerApi",
           "job_runner"]

#: myCNC's own Server API port.
DEFAULT_PORT = 4266


class ApiError(Exception):
    """A command that cannot be carried out; the reason goes back as ``ERROR reason``."""


def _int(text: str, what: str) -> int:
    try:
        return int(text, 0)
    except ValueError:
        raise ApiError(f"{what} must be a whole number (decimal or 0x hex), not {text!r}") from None


def _args(args: list[str], n: int, usage: str) -> list[str]:
    if len(args) != n:
        raise ApiError(f"usage: {usage}")
    return args


# ===================================================================== G-code jobs

#: Why the program commands cannot answer on a controller whose ``job_runner``
#: is None (the simulated one has SPEC §10's: :func:`job_runner` finds it).
NO_JOB_RUNNER = "no G-code job runner in this controller yet"

#: Largest G-code program ProgramFileOpen reads, or ProgramBegin/ProgramAppend collect.
MAX_PROGRAM = 16 << 20


@dataclass(frozen=True)
class JobStatus:
    """What the program commands read of a job (:meth:`JobRunner.status`)."""
    state: str = "idle"                 # idle | running | paused | stopped | done
    name: Optional[str] = None          # the program's file name (or "(server api)")
    path: Optional[str] = None          # its full path, when it came from a file
    line: int = 0                       # the line reached (1-based; 0: not started)
    paused_line: Optional[int] = None   # where it paused (ProgramPause), else None
    lines: int = 0                      # lines in the program
    size: int = 0                       # bytes
    estimate_s: Optional[float] = None  # time left, seconds (None: not known)


class JobRunner(Protocol):
    """The G-code job runner the program commands drive (SPEC §10). Each method
    runs on the simulation thread; a refusal raises ControllerError or
    ValueError with the reason."""

    def open(self, name: str, text: str, path: Optional[str] = None) -> None:
        """Load a program (not started)."""

    def play(self) -> None:
        """Start or continue the loaded program."""

    def pause(self) -> None:
        """Pause it at the end of the block it is in."""

    def stop(self) -> None:
        """Stop it."""

    def reset(self) -> None:
        """Back to its first line."""

    def move(self, axis: str, distance_mm: float) -> None:
        """One incremental rapid move of ``axis`` (``G91 G0 X…``), recorded as
        the runner records its blocks: what a handwheel click does (SetPendant)."""

    def status(self) -> JobStatus:
        """Where the job is."""


def job_runner(controller) -> Optional[JobRunner]:
    """The controller's G-code job runner, or None while it has none."""
    return getattr(controller, "job_runner", None)


# ===================================================================== the commands

def _axes_text(positions: dict[str, int]) -> str:
    return " ".join(f"{axis} {value / 100:.2f}" for axis, value in positions.items())


def _words(bits: int, count: int) -> str:
    words = max(1, -(-count // 32))
    return " ".join(f"0x{(bits >> (32 * k)) & 0xFFFFFFFF:08x}" for k in range(words))


class Session:
    """What one Server API connection keeps: echo, the program being collected
    (ProgramBegin … ProgramEnd) and the emulated handwheel (SetPendant)."""

    def __init__(self):
        self.echo = False
        self.program: Optional[list[str]] = None
        self.program_size = 0
        self.wheel: Optional[int] = None     # the handwheel's last position (0..99)
        self.wheel_axis = 0                  # its axis selector (0: off)


#: SetPendant's step selector (the high byte of its second parameter): mm a click
PENDANT_STEPS = (0.001, 0.01, 0.1, 1.0)
#: ... and its axis selector (the low byte): 0 is off
PENDANT_AXES = ("OFF", "X", "Y", "Z", "A", "B", "C")

#: Commands of myCNC's published list that mean nothing on the simulated
#: controller, and why (each answers ``ERROR NAME: why``, never "unknown").
NOT_HERE = {
    "PendantWidgetShow": "no pendant widget: the simulated controller has no screen",
    "PendantWidgetHide": "no pendant widget: the simulated controller has no screen",
    "PendantWidgetHidden": "no pendant widget: the simulated controller has no screen",
    "SaveConfig": "nothing to save: the simulated controller's configuration is its machine "
                  "description file (--machine)",
    "ShutDown": "refused: the simulated controller is stopped by whoever started it "
                "(Ctrl+C, SIGTERM or the IDE), not over the Server API",
    "GetScanData": "no scanning (digitizing) on the simulated controller",
    "GetMCPtr": "no motion control buffer on the simulated controller (moves are simulated, "
                "not queued)",
    "SetG92": "the simulated controller's work offsets come from the machine description; "
              "they cannot be set at run time",
    "SetCNCVariable": "CNC (G-code macro) variables are not simulated; PLC global registers: "
                      "SetGVariable",
    "SetScale": "the simulated G-code job runner does not scale programs",
    "SetRotationAngle": "the simulated G-code job runner does not rotate programs",
    "ProgramPlayBack": "the simulated G-code job runner does not run programs backwards",
    "ProgramPlayStepBack": "the simulated G-code job runner does not run programs backwards",
    "ProgramPlayStep": "the simulated G-code job runner does not run a program block by block",
    "SinglePlay": "the simulated G-code job runner does not run a program block by block",
    "LineAppend": "not available on the simulated controller: send a program with "
                  "ProgramBegin, ProgramAppend and ProgramEnd",
}
#: myCNC's own spellings that name another command (its list spells ProgramEnd "ProgrmaEnd").
ALIASES = {"ProgrmaEnd": "ProgramEnd", "SetHWOutputBit": "SetHWBinaryOutput",
           "GetGVariable": "GetIVariable", "GetPWMs": "GetHWPWM",
           "SetScale++": "SetScale", "SetRotationAngle++": "SetRotationAngle"}
#: myCNC's string variables that name the job (GetSVariable8020 …)
S_VARIABLES = {8020: "the job's full path", 8107: "the job's name without its folder",
               8108: "the job's folder", 8109: "the job's size in MB"}


class Commands:
    """The commands, one ``cmd_<name>`` each, run on the simulation thread
    with the controller; each returns the text after ``OK``."""

    #: name as shown by ``?`` -> (usage, what it does)
    HELP = {
        "RunPLC": ("RunPLC NAME [EPARAM]", "start a hardware procedure (M03, or an M-code number)"),
        "SetHWOutputBit": ("SetHWOutputBit PORT 0|1", "set an output"),
        "SetHWBinaryOutput": ("SetHWBinaryOutput PORT 0|1", "set an output (its older name)"),
        "SetHWPWM": ("SetHWPWM CHANNEL VALUE", "set a PWM channel (0..7)"),
        "SetHWDAC": ("SetHWDAC CHANNEL VALUE", "set a DAC channel (0..7)"),
        "GetHW": ("GetHW", "inputs, outputs, PWM, DAC and ADC in one line"),
        "GetHWInputs": ("GetHWInputs", "the input pins, 32 a word, hex, pin 0 = bit 0 of the first"),
        "GetHWInputBit": ("GetHWInputBit PIN", "one input: 0 or 1"),
        "GetHWOutputs": ("GetHWOutputs", "the output pins, as GetHWInputs"),
        "GetHWOutputBit": ("GetHWOutputBit PORT", "one output: 0 or 1"),
        "GetHWPWM": ("GetHWPWM [CHANNEL]", "PWM channels 0..7 (or one)"),
        "GetPWMs": ("GetPWMs", "PWM channels 0..7"),
        "GetHWDAC": ("GetHWDAC [CHANNEL]", "DAC channels 0..7 (or one)"),
        "GetHWADC": ("GetHWADC [CHANNEL]", "ADC channels 0..7 (or one)"),
        "GetSensors": ("GetSensors", "the inputs the machine wires (switches, probe): NAME=LEVEL"),
        "GetIVariable": ("GetIVariable ADDRESS", "a global register, as gvarget reads it"),
        "GetGVariable": ("GetGVariable ADDRESS", "the same as GetIVariable"),
        "GetFVariable": ("GetFVariable ADDRESS", "a global register as a real number"),
        "SetGVariable": ("SetGVariable ADDRESS VALUE", "write a global register, as gvarset"),
        "GetMachinePosition": ("GetMachinePosition", "machine position of each axis, mm"),
        "GetWorkPosition": ("GetWorkPosition", "program (work) position of each axis, mm"),
        "GetMCC": ("GetMCC", "the motion control code (register 6060): 0 moving, 77 idle"),
        "GetProcess": ("GetProcess", "the proc value and its name"),
        "GetRunning": ("GetRunning", "the hardware procedure running (or -) and the time"),
        "GetWorkState": ("GetWorkState", "idle, plc NAME, moving, halted, job running|paused"),
        "GetReady": ("GetReady", "1 when nothing runs or moves, else 0"),
        "GetLastMessage": ("GetLastMessage", "the last PLC message: CODE NAME COMMAND PARAMETER"),
        "GetMyCNCVersion": ("GetMyCNCVersion", "the simulated controller's version"),
        "SetJog": ("SetJog x+|x-|xstop|…|stop", "jog an axis (refresh within 1 s, as a pendant does)"),
        "SetPendant": ("SetPendant WHEEL;SELECT", "handwheel: WHEEL 0..99, SELECT = step<<8 | axis"),
        "EchoMode": ("EchoMode [0|1]", "echo each command line before its reply"),
        "ProgramFileOpen": ("ProgramFileOpen FILE", "load a G-code program"),
        "ProgramBegin": ("ProgramBegin", "start sending a G-code program a line at a time"),
        "ProgramAppend": ("ProgramAppend LINE", "one line of it"),
        "ProgramEnd": ("ProgramEnd", "the end of it: load it (myCNC's list spells it ProgrmaEnd)"),
        "ProgramPlay": ("ProgramPlay", "run the loaded program"),
        "ProgramPause": ("ProgramPause", "pause it"),
        "ProgramStop": ("ProgramStop", "stop it"),
        "ProgramReset": ("ProgramReset", "back to its first line"),
        "GetPausedLine": ("GetPausedLine", "the line it paused at (0: not paused)"),
        "GetJobName": ("GetJobName", "the job's full path (GetSVariable8020 too)"),
        "GetSVariable": ("GetSVariable8020|8107|8108|8109", "the job's path, name, folder, size"),
        "GetEstimateTime": ("GetEstimateTime", "the job's time left, seconds"),
        "?": ("?", "list the commands"),
    }
    _LOWER = {name.lower(): name for name in HELP}
    _LOWER.update({name.lower(): name for name in NOT_HERE})
    _LOWER.update({name.lower(): name for name in ALIASES})

    def __init__(self, controller: Controller, session: Optional[Session] = None,
                 last_message=None):
        self.c = controller
        self.session = session if session is not None else Session()
        self.last_message = last_message
        self.called = ""

    @property
    def m(self):
        return self.c.machine

    def run(self, name: str, args: list[str]) -> str:
        if name == "?":
            return " ".join(COMMANDS)
        key = name.lower()
        if key.startswith("getsvariable") and key != "getsvariable":
            return self.cmd_getsvariable([name[len("getsvariable"):], *args])
        known = self._LOWER.get(key)
        if known is None:
            raise ApiError(f"unknown command {name[:40]!r} (? lists the commands)")
        if known in NOT_HERE:
            raise ApiError(f"{known}: {NOT_HERE[known]}")
        self.called = known                        # as typed (an alias's usage names it)
        known = ALIASES.get(known, known)
        if known in NOT_HERE:
            raise ApiError(f"{name}: {NOT_HERE[known]}")
        return getattr(self, "cmd_" + known.lower())(args)

    # ------------------------------------------------------------ procedures
    def cmd_runplc(self, args: list[str]) -> str:
        if len(args) not in (1, 2):
            raise ApiError("usage: RunPLC NAME [EPARAM]")
        eparam = _int(args[1], "EPARAM") if len(args) == 2 else 0
        name = args[0]
        if name.isdigit():
            started = self.c.start_mcode(int(name), eparam)
        else:
            self.c.start(name, eparam)
            started = name
        return f"{started} {eparam}"

    # ------------------------------------------------------------ outputs
    # Every change goes through Controller.write, which records it, so that
    # replaying the session (and stepping back) does what the client did.
    def _write(self, target: str, value: int) -> None:
        self.c.write(target, value)

    def cmd_sethwbinaryoutput(self, args: list[str]) -> str:
        port, value = _args(args, 2, f"{self.called} PORT 0|1")
        port = self._pin(_int(port, "PORT"), self.m.output_count, "output")
        v = _int(value, "value")
        if v not in (0, 1):
            raise ApiError(f"an output is 0 or 1, not {v}")
        self._write(f"out {port}", v)
        return f"{port} {v}"

    def cmd_sethwpwm(self, args: list[str]) -> str:
        return self._set_channel(args, "SetHWPWM", "pwm")

    def cmd_sethwdac(self, args: list[str]) -> str:
        return self._set_channel(args, "SetHWDAC", "dac")

    def _set_channel(self, args, name: str, kind: str) -> str:
        ch, value = _args(args, 2, f"{name} CHANNEL VALUE")
        ch = self._pin(_int(ch, "CHANNEL"), 8, "channel")
        v = self._word(_int(value, "VALUE"))
        self._write(f"{kind} {ch}", v)
        return f"{ch} {v}"

    # ------------------------------------------------------------ reading
    def cmd_gethw(self, args: list[str]) -> str:
        _args(args, 0, "GetHW")
        f = self.m.sample_fields()
        return (f"IN {_words(self.m.in_bits, self.m.input_count)} "
                f"OUT {_words(self.m.out_bits, self.m.output_count)} "
                + " ".join(f"{k.upper()} {' '.join(map(str, f[k]))}" for k in ("pwm", "dac", "adc")))

    def cmd_gethwinputs(self, args: list[str]) -> str:
        _args(args, 0, "GetHWInputs")
        return _words(self.m.in_bits, self.m.input_count)

    def cmd_gethwoutputs(self, args: list[str]) -> str:
        _args(args, 0, "GetHWOutputs")
        return _words(self.m.out_bits, self.m.output_count)

    def cmd_gethwinputbit(self, args: list[str]) -> str:
        (pin,) = _args(args, 1, "GetHWInputBit PIN")
        pin = self._pin(_int(pin, "PIN"), self.m.input_count, "input")
        return str(self.m.portget(pin))

    def cmd_gethwoutputbit(self, args: list[str]) -> str:
        (pin,) = _args(args, 1, "GetHWOutputBit PORT")
        pin = self._pin(_int(pin, "PORT"), self.m.output_count, "output")
        return str((self.m.out_bits >> pin) & 1)

    def cmd_gethwpwm(self, args: list[str]) -> str:
        return self._channels(args, "GetHWPWM", "pwm")

    def cmd_gethwdac(self, args: list[str]) -> str:
        return self._channels(args, "GetHWDAC", "dac")

    def cmd_gethwadc(self, args: list[str]) -> str:
        return self._channels(args, "GetHWADC", "adc")

    def _channels(self, args, name: str, field: str) -> str:
        values = self.m.sample_fields()[field]
        if not args:
            return " ".join(str(v) for v in values)
        (ch,) = _args(args, 1, f"{name} [CHANNEL]")
        return str(values[self._pin(_int(ch, "CHANNEL"), len(values), "channel")])

    def cmd_getsensors(self, args: list[str]) -> str:
        _args(args, 0, "GetSensors")
        wired = sorted(self.m.config.inputs, key=lambda i: i.pin)
        return " ".join(f"{i.name or f'in{i.pin}'}={self.m.portget(i.pin)}" for i in wired)

    def cmd_getivariable(self, args: list[str]) -> str:
        (addr,) = _args(args, 1, "GetIVariable ADDRESS")
        return str(self.m.gvarget(self._word(_int(addr, "ADDRESS"))))

    def cmd_getfvariable(self, args: list[str]) -> str:
        (addr,) = _args(args, 1, "GetFVariable ADDRESS")
        return f"{float(self.m.gvarget(self._word(_int(addr, 'ADDRESS')))):.6f}"

    def cmd_setgvariable(self, args: list[str]) -> str:
        addr, value = _args(args, 2, "SetGVariable ADDRESS VALUE")
        a, v = self._word(_int(addr, "ADDRESS")), self._word(_int(value, "VALUE"))
        self._write(f"gvar {a}", v)
        return f"{a} {self.m.gvarget(a)}"

    def cmd_getmachineposition(self, args: list[str]) -> str:
        _args(args, 0, "GetMachinePosition")
        return _axes_text(self.m.axis_positions())

    def cmd_getworkposition(self, args: list[str]) -> str:
        _args(args, 0, "GetWorkPosition")
        return _axes_text(self.m.program_positions())

    def cmd_getmcc(self, args: list[str]) -> str:
        _args(args, 0, "GetMCC")
        return str(self.m.motion_code)

    def cmd_getprocess(self, args: list[str]) -> str:
        _args(args, 0, "GetProcess")
        st = self.c.state()
        return f"{st.proc} {st.proc_name or '-'}"

    def cmd_getrunning(self, args: list[str]) -> str:
        _args(args, 0, "GetRunning")
        st = self.c.state()
        return f"{st.running or '-'} {st.t_ms}"

    def _work_state(self) -> str:
        if self.c.debugger.halt is not None:
            return "halted"
        job = job_runner(self.c)
        if job is not None:
            st = job.status().state
            if st in ("running", "paused"):
                return f"job {st}"
        hw = self.c.plc.hw
        if hw is not None:
            return f"plc {hw.name}"
        if self.m.motion_code != abi.MOTION_CODE_IDLE:
            return "moving"
        return "idle"

    def cmd_getworkstate(self, args: list[str]) -> str:
        _args(args, 0, "GetWorkState")
        return self._work_state()

    def cmd_getready(self, args: list[str]) -> str:
        _args(args, 0, "GetReady")
        return "1" if self._work_state() == "idle" else "0"

    def cmd_getlastmessage(self, args: list[str]) -> str:
        _args(args, 0, "GetLastMessage")
        m = self.last_message() if self.last_message is not None else None
        if m is None:
            return "-"
        return f"{m.message} {m.name or '-'} {m.command} {m.parameter}"

    def cmd_getmycncversion(self, args: list[str]) -> str:
        _args(args, 0, "GetMyCNCVersion")
        from plcbuilder import __version__
        return f"PLC Builder {__version__} (simulated myCNC controller)"

    # ------------------------------------------------------------ jog
    def cmd_setjog(self, args: list[str]) -> str:
        """``x+`` / ``x-`` jog X (bits 0..7 move +, 8..15 move -, as register
        8635), ``xstop`` stops X, ``stop`` stops every axis; ``x+y-`` and
        ``xystop`` (myCNC's two-axis forms) too."""
        if not args:
            raise ApiError("usage: SetJog x+|x-|xstop|…|stop (several may follow)")
        bits = self.m.gvarget(abi.JOG) & 0xFFFF
        axes = "".join(a.lower() for a in abi.AXES[:8])
        for word in args:
            w = word.lower()
            if w == "stop":
                bits = 0
                continue
            parts = re.fullmatch(rf"(?:[{axes}][+-])+", w) and re.findall(r"(.)([+-])", w)
            if not parts:
                stop = re.fullmatch(rf"([{axes}]+)stop", w)
                if stop is None:
                    raise ApiError(f"SetJog: {word!r} is not AXIS+, AXIS- or AXISstop "
                                   f"(axes {' '.join(axes)}; x+y- and xystop too)")
                parts = [(a, "stop") for a in stop.group(1)]
            for axis, how in parts:
                i = abi.AXES.index(axis.upper())
                bits &= ~((1 << i) | (1 << (8 + i)))
                if how == "+":
                    bits |= 1 << i
                elif how == "-":
                    bits |= 1 << (8 + i)
        self._write(f"gvar {abi.JOG}", bits)
        return f"0x{bits:04x}"

    def cmd_setpendant(self, args: list[str]) -> str:
        """``SetPendant WHEEL;SELECT`` (myCNC's pendant emulation): WHEEL is the
        handwheel's position (0..99, it wraps), SELECT's high byte the step
        (0: 0.001, 1: 0.01, 2: 0.1, 3: 1 unit a click), its low byte the axis
        (0 off, 1..6 X Y Z A B C). Turning the wheel with an axis selected
        moves that axis by clicks x step; selecting another axis (or off)
        moves nothing. Answers the axis and the distance moved, in mm."""
        text = " ".join(args).replace(" ", "")
        parts = text.split(";")
        if len(parts) != 2 or not parts[0] or not parts[1]:
            raise ApiError("usage: SetPendant WHEEL;SELECT (WHEEL 0..99; SELECT: step << 8 | "
                           "axis, e.g. SetPendant 55;0x0301)")
        wheel, select = _int(parts[0], "WHEEL"), _int(parts[1], "SELECT")
        if not 0 <= wheel <= 99:
            raise ApiError(f"the handwheel's position is 0..99, not {wheel}")
        step, axis = select >> 8, select & 0xFF
        if not 0 <= select <= 0xFFFF or step >= len(PENDANT_STEPS) or axis >= len(PENDANT_AXES):
            raise ApiError(f"SELECT {select:#06x}: the high byte is the step (0..3), the low "
                           f"byte the axis (0 off, 1..6 X Y Z A B C)")
        s = self.session
        last, last_axis = s.wheel, s.wheel_axis
        clicks = 0
        if last is not None and axis == last_axis and axis != 0:
            clicks = (wheel - last + 50) % 100 - 50          # the short way round
        name = PENDANT_AXES[axis]
        if clicks:
            if name not in abi.AXES or abi.AXES.index(name) not in self.m.motion.present_idx:
                raise ApiError(f"SetPendant: the machine has no {name} axis")
            job = job_runner(self.c)
            if job is None:
                raise ApiError(f"SetPendant: the handwheel moves an axis through the G-code job "
                               f"runner, and there is {NO_JOB_RUNNER}")
            job.move(name, round(clicks * PENDANT_STEPS[step], 3))
        s.wheel, s.wheel_axis = wheel, axis
        return f"{name} {clicks * PENDANT_STEPS[step]:.3f}"

    # ------------------------------------------------------------ the connection
    def cmd_echomode(self, args: list[str]) -> str:
        if args:
            (v,) = _args(args, 1, "EchoMode [0|1]")
            on = _int(v, "EchoMode")
            if on not in (0, 1):
                raise ApiError(f"EchoMode is 0 or 1, not {on}")
            self.session.echo = bool(on)
        return "1" if self.session.echo else "0"

    # ------------------------------------------------------------ G-code jobs
    def _job(self, what: str) -> JobRunner:
        job = job_runner(self.c)
        if job is None:
            raise ApiError(f"{what}: {NO_JOB_RUNNER}")
        return job

    def cmd_programfileopen(self, args: list[str]) -> str:
        if not args:
            raise ApiError("usage: ProgramFileOpen FILE")
        job = self._job("ProgramFileOpen")
        path = Path(" ".join(args)).expanduser()
        try:
            text = read_bounded(path, MAX_PROGRAM, "G-code program").decode("utf-8", "replace")
        except OSError as exc:
            raise ApiError(f"ProgramFileOpen: cannot read {path}: {exc.strerror or exc}") from None
        job.open(path.name, text, str(path.resolve()))
        return str(path)

    def cmd_programbegin(self, args: list[str]) -> str:
        _args(args, 0, "ProgramBegin")
        self._job("ProgramBegin")
        self.session.program, self.session.program_size = [], 0
        return ""

    def cmd_programappend(self, args: list[str]) -> str:
        s = self.session
        if s.program is None:
            raise ApiError("ProgramAppend: no program begun (ProgramBegin first)")
        line = " ".join(args)
        s.program_size += len(line) + 1
        if s.program_size > MAX_PROGRAM:
            s.program = None
            raise ApiError(f"ProgramAppend: the program is over {MAX_PROGRAM} bytes; dropped")
        s.program.append(line)
        return str(len(s.program))

    def cmd_programend(self, args: list[str]) -> str:
        _args(args, 0, "ProgramEnd")
        s = self.session
        if s.program is None:
            raise ApiError("ProgramEnd: no program begun (ProgramBegin first)")
        lines, s.program = s.program, None
        self._job("ProgramEnd").open("(server api)", "\n".join(lines) + "\n")
        return str(len(lines))

    def cmd_programplay(self, args: list[str]) -> str:
        _args(args, 0, "ProgramPlay")
        self._job("ProgramPlay").play()
        return ""

    def cmd_programpause(self, args: list[str]) -> str:
        _args(args, 0, "ProgramPause")
        self._job("ProgramPause").pause()
        return ""

    def cmd_programstop(self, args: list[str]) -> str:
        _args(args, 0, "ProgramStop")
        self._job("ProgramStop").stop()
        return ""

    def cmd_programreset(self, args: list[str]) -> str:
        _args(args, 0, "ProgramReset")
        self._job("ProgramReset").reset()
        return ""

    def cmd_getpausedline(self, args: list[str]) -> str:
        _args(args, 0, "GetPausedLine")
        return str(self._job("GetPausedLine").status().paused_line or 0)

    def cmd_getjobname(self, args: list[str]) -> str:
        _args(args, 0, "GetJobName")
        st = self._job("GetJobName").status()
        return st.path or st.name or "-"

    def cmd_getsvariable(self, args: list[str]) -> str:
        if len(args) != 1 or not args[0].isdigit() or int(args[0]) not in S_VARIABLES:
            raise ApiError("GetSVariable: the simulated controller knows "
                           + ", ".join(f"GetSVariable{n} ({what})" for n, what in
                                       S_VARIABLES.items()))
        n = int(args[0])
        st = self._job(f"GetSVariable{n}").status()
        path = st.path or st.name or ""
        if n == 8020:
            return path or "-"
        if n == 8107:
            return Path(path).name if path else "-"
        if n == 8108:
            return str(Path(path).parent) if st.path else "-"
        return f"{st.size / (1 << 20):.3f}"

    def cmd_getestimatetime(self, args: list[str]) -> str:
        _args(args, 0, "GetEstimateTime")
        st = self._job("GetEstimateTime").status()
        return "-" if st.estimate_s is None else f"{st.estimate_s:.3f}"

    # ------------------------------------------------------------ checks
    @staticmethod
    def _pin(n: int, count: int, what: str) -> int:
        if not 0 <= n < count:
            raise ApiError(f"no {what} {n} (0..{count - 1})")
        return n

    @staticmethod
    def _word(v: int) -> int:
        if not -(1 << 31) <= v < (1 << 32):
            raise ApiError(f"{v} is not a 32-bit value")
        return v - (1 << 32) if v >= 1 << 31 else v


#: Every command answered, as ``?`` lists them: the published ones myCNC's
#: list names, with what they do here or why they do nothing (NOT_HERE).
COMMANDS = tuple([n for n in Commands.HELP if n not in ("?", "GetSVariable")]
                 + ["GetSVariable8020", "GetSVariable8107", "GetSVariable8108",
                    "GetSVariable8109", "ProgrmaEnd"] + sorted(NOT_HERE) + ["?"])


# ===================================================================== the network

class _Client:
    __slots__ = ("sock", "peer", "inbuf", "out", "skipping", "mask", "closing", "session",
                 "opened", "active", "commands")

    def __init__(self, sock: socket.socket, peer: str, now: float):
        self.sock = sock
        self.peer = peer
        self.inbuf = bytearray()
        self.out = bytearray()
        self.skipping = False       # inside a line that was too long: drop to its end
        self.mask = 0
        self.closing = False
        self.session = Session()
        self.opened = now
        self.active = now           # when it last sent a command (or connected)
        self.commands = 0


class ServerApi:
    """The Server API's listener and connections, served by the loop of a
    :class:`~plcbuilder.link.server.Server` (``server.attach(api)``).

    Places: at most :attr:`max_clients` connections. A connection that sends
    no command for :attr:`idle_timeout` seconds is closed (with a line saying
    why). When every place is taken, a new connection makes room: the oldest
    one that never sent a command goes first, else the one idle longest if it
    has been idle :attr:`evict_idle` seconds; only when all are busy is the
    new one refused. So idle sockets, however many, never keep a client from
    an answer, and a pendant that polls is never pushed out by them.
    """

    max_line = 1024
    lines_per_turn = 16
    max_clients = 16
    #: Seconds without a command after which a connection is closed.
    idle_timeout = 60.0
    #: Seconds a client that has sent commands must have been idle to make room.
    evict_idle = 2.0
    #: Reply bytes waiting for a client above which it is not read, and closed above max_outbuf.
    read_pause = 64 << 10
    max_outbuf = 1 << 20

    def __init__(self, sim, host: str = "127.0.0.1", port: int = DEFAULT_PORT):
        self.sim = sim
        lsock = self._lsock = listening_socket(host, port, 16)
        self.address: tuple[str, int] = lsock.getsockname()[:2]
        self._clients: dict[int, _Client] = {}
        self._ready: list[_Client] = []          # whole lines waiting for the next pass
        self._loop = None
        self._next_check = 0.0
        self._last_message = None                # the last PLC message event (GetLastMessage)
        self.stats = {"accepted": 0, "commands": 0, "errors": 0, "long_lines": 0, "closed": 0,
                      "idle_closed": 0, "evicted": 0, "refused": 0}
        listen = getattr(sim, "listen", None)
        if listen is not None:
            listen(self._on_events)

    def _on_events(self, events: list) -> None:
        """On the simulation thread, after each batch: remember the last PLC message."""
        for e in reversed(events):
            if isinstance(e, Message):
                self._last_message = e
                return

    # ------------------------------------------------------------ the loop's side
    def attach_to(self, loop) -> None:
        """Called by Server.attach: register the listener with its selector."""
        self._loop = loop
        loop.watch(self._lsock, selectors.EVENT_READ, self._on_accept)

    @property
    def pending(self) -> bool:
        """Work left for the next pass (the loop does not sleep meanwhile)."""
        return bool(self._ready)

    def on_pass(self) -> None:
        ready, self._ready = self._ready, []
        for client in ready:
            self._serve(client)
        now = time.monotonic()
        if now >= self._next_check:
            self._next_check = now + 1.0
            for client in list(self._clients.values()):
                idle = now - client.active
                if idle > self.idle_timeout and not client.out:
                    self.stats["idle_closed"] += 1
                    self._goodbye(client, f"ERROR closed: no command for {idle:.0f} s (the "
                                          f"Server API closes a connection idle for "
                                          f"{self.idle_timeout:g} s)")

    def close(self) -> None:
        for client in list(self._clients.values()):
            self._drop(client)
        try:
            self._loop.unwatch(self._lsock)
        except Exception:  # noqa: BLE001 - the selector may be closed already
            pass
        try:
            self._lsock.close()
        except OSError:
            pass

    # ------------------------------------------------------------ connections
    def _on_accept(self, _sock, _mask) -> None:
        for sock, peer in accept_all(self._lsock):
            self.stats["accepted"] += 1
            now = time.monotonic()
            if len(self._clients) >= self.max_clients:
                victim = self._make_room(now)
                if victim is None:
                    self.stats["refused"] += 1
                    refuse(sock, f"ERROR too many Server API clients ({self.max_clients}), "
                                 f"all of them busy\r\n".encode())
                    continue
                self.stats["evicted"] += 1
                idle = now - victim.active
                self._goodbye(victim, f"ERROR closed to make room for a new client: "
                                      f"{'no command' if not victim.commands else 'idle'} for "
                                      f"{idle:.0f} s, and the Server API's {self.max_clients} "
                                      f"places are taken")
            client = _Client(sock, peer, now)
            self._clients[sock.fileno()] = client
            self._update(client)

    def _make_room(self, now: float) -> Optional[_Client]:
        """The connection that goes so a new one can come in, or None: the oldest
        that never sent a command, else the one idle longest (if idle enough)."""
        clients = [c for c in self._clients.values()
                   if not c.out and not c.inbuf and c not in self._ready]
        silent = [c for c in clients if not c.commands]
        if silent:
            return min(silent, key=lambda c: c.opened)
        if clients:
            idlest = min(clients, key=lambda c: c.active)
            if now - idlest.active >= self.evict_idle:
                return idlest
        return None

    def _goodbye(self, client: _Client, text: str) -> None:
        """Tell the client why in one last line (when its socket has room), and close."""
        client.out += text.encode("utf-8") + b"\r\n"
        send_pending(client.sock, client.out, 65536)
        self._drop(client)

    def _on_ready(self, client: _Client, mask: int) -> None:
        if mask & selectors.EVENT_WRITE:
            self._write(client)
        if mask & selectors.EVENT_READ and not client.closing:
            self._read(client)
        if client.sock.fileno() in self._clients:
            self._update(client)

    def _read(self, client: _Client) -> None:
        try:
            data = client.sock.recv(16384)
        except (BlockingIOError, InterruptedError):
            return
        except OSError:
            self._drop(client)
            return
        if not data:
            client.closing = True
            if client.inbuf.strip() and not client.skipping and b"\n" not in client.inbuf:
                client.inbuf += b"\n"            # the last line without its newline
            self._serve(client)
            return
        client.inbuf += data
        self._serve(client)

    def _serve(self, client: _Client) -> None:
        """Answer the whole lines buffered, a turn's worth at most."""
        if client.sock.fileno() not in self._clients:
            return
        n = 0
        while n < self.lines_per_turn and len(client.out) < self.read_pause:
            nl = client.inbuf.find(b"\n")
            if nl < 0:
                if len(client.inbuf) > self.max_line:
                    if not client.skipping:
                        self._long_line(client)
                    client.skipping = True
                    del client.inbuf[:]
                break
            line = bytes(client.inbuf[:nl])
            del client.inbuf[:nl + 1]
            if client.skipping:
                client.skipping = False          # the end of the long line
                continue
            if len(line) > self.max_line:
                self._long_line(client)
                continue
            n += 1
            client.commands += 1
            client.active = time.monotonic()
            if client.session.echo:
                self._reply(client, line.decode("utf-8", "replace").rstrip("\r"))
            self._reply(client, self.answer(line, client.session))
        if client.inbuf.find(b"\n") >= 0 and client not in self._ready:
            self._ready.append(client)           # the rest: next pass
        elif client.closing and client.inbuf.strip() and not client.skipping:
            client.inbuf += b"\n"               # the last line, once the rest is answered
            self._ready.append(client)
        self._write(client)
        if client.sock.fileno() in self._clients:
            self._update(client)

    def _long_line(self, client: _Client) -> None:
        self.stats["long_lines"] += 1
        self._reply(client, f"ERROR line longer than {self.max_line} bytes; ignored")

    def answer(self, raw: bytes, session: Optional[Session] = None) -> str:
        """One command line -> its reply line (without the line end)."""
        text = raw.decode("utf-8", "replace").strip().strip("\x00")
        if not text:
            return "ERROR empty command (? lists the commands)"
        words = text.split()
        self.stats["commands"] += 1
        session = session if session is not None else Session()
        last = lambda: self._last_message  # noqa: E731

        def run():
            return Commands(self.sim.controller, session, last).run(words[0], words[1:])
        try:
            result = self.sim.call(run, timeout=5.0)
        except ApiError as exc:
            self.stats["errors"] += 1
            return f"ERROR {exc}"
        except (ControllerError, ValueError) as exc:
            self.stats["errors"] += 1
            return f"ERROR {exc}"
        except (SimulationDown, TimeoutError) as exc:
            self.stats["errors"] += 1
            return f"ERROR the controller is not running ({exc})"
        return f"OK {result}" if result else "OK"

    def _reply(self, client: _Client, text: str) -> None:
        client.out += text.replace("\r", " ").replace("\n", " ").encode("utf-8") + b"\r\n"
        if len(client.out) > self.max_outbuf:
            self._drop(client)

    def _write(self, client: _Client) -> None:
        if not send_pending(client.sock, client.out, 65536):
            self._drop(client)
            return
        if not client.out and client.closing and client not in self._ready:
            self._drop(client)                   # it said all it had to say, and has it all

    def _update(self, client: _Client) -> None:
        mask = 0
        if not client.closing and len(client.out) < self.read_pause and client not in self._ready:
            mask |= selectors.EVENT_READ
        if client.out:
            mask |= selectors.EVENT_WRITE
        if mask == client.mask:
            return
        cb: Callable = lambda _s, m, c=client: self._on_ready(c, m)  # noqa: E731
        if client.mask and mask:
            self._loop.rewatch(client.sock, mask, cb)
        elif mask:
            self._loop.watch(client.sock, mask, cb)
        else:
            self._loop.unwatch(client.sock)
        client.mask = mask

    def _drop(self, client: _Client) -> None:
        if self._clients.pop(client.sock.fileno(), None) is None:
            return
        self.stats["closed"] += 1
        if client.mask:
            try:
                self._loop.unwatch(client.sock)
            except Exception:  # noqa: BLE001
                pass
        client.mask = 0
        if client in self._ready:
            self._ready.remove(client)
        try:
            client.sock.close()
        except OSError:
            pass
