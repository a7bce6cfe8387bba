"""Scenarios: what happens to the controller from outside, and when.

A scenario is a list of actions, each at a tick: start a procedure, set an
input or an ADC channel, press Stop, raise a host event. ``plcbuilder run``
builds one from its ``--start``/``--input``/``--adc`` options and a scenario
file (``--scenario FILE``), whose lines are the same::

    # a comment; blank lines are ignored
    start M03:12000 @ 0        # NAME[:EPARAM] @ MS
    input 4=0 @ 150            # PIN=0|1 @ MS
    adc 0=2048 @ 200           # CH=VALUE @ MS
    stop @ 5000                # press Stop (M02, then OFF)
    event GCODE_START @ 100    # __HANDLER_GCODE_START
    bind 9=M88:0 @ 0           # from then on, input 9 going 0 -> 1 starts M88
    bind vin 1=M20 @ 0         # ... virtual input 1 (vin/vout 1..32), PLS 2's output (pls 2)
    write M03.speed=500 @ 10   # TARGET=VALUE @ MS: set once (SPEC §6 names)
    force in 2=1 @ 20          # TARGET=VALUE @ MS: hold until released
    release in 2 keep @ 30     # TARGET [keep|restore] @ MS (default restore)
    release all @ 40           # everything forced [keep|restore]
    upload 1c2d3e4f @ 0        # load the image here (a recorded session's upload)
    gcode job.nc @ 100         # run a G-code program (relative to this file's folder)
    gcode job.nc open @ 0      # only load it (the Server API's ProgramFileOpen)
    job pause @ 900            # the job: play, pause, stop or reset
    code M3 @ 50               # the CNC issues a code (Huazhong: M, S, B, T handlers)
    move X=0.1 @ 60            # a handwheel click: X 0.1 mm at rapid (Server API SetPendant)
    write M03.x=5 @ 12 at M03:24        # done mid-tick: before the statement at
    force in 2=1 @ 12 at M03:40 returns 27   # code offset 24 of M03 (inside the
                                        # calls that return to 27) in tick 12

A target is ``PROC.var``, ``in N``, ``out N``, ``adc N``, ``pwm N``, ``dac N`` or
``gvar N`` (controller/forces.py).

Numbers are decimal or hex (``0x…``); ``@ MS`` may be left out (0), and the
command may also be written as its option (``--start M03@0``).

An action at tick t is applied before tick t runs, in the order given, so a
procedure started at t runs in tick t and sees an input set at t. An action
with ``at PROC:OFFSET [returns RET,…]`` was done while the debugger held tick t
halted before a statement (``Action.at``): a replay does it there, when PROC
reaches that code offset (the disassembler's) with that call stack in tick t.
"""

from __future__ import annotations

import re
from pathlib import Path

from plcbuilder._support.lazy import Pattern
from plcbuilder._support.records import dataclass, field, replace
from plcbuilder._support.files import read_bounded
from plcbuilder._support.numbers import INT32, WORD32, parse_int_in, to_int32
from plcbuilder.bytecode import softmc
from plcbuilder.controller.forces import MODES, ForceError, parse_target

TYPE_CHECKING = False               # (typing is not imported at run time: start-up)
if TYPE_CHECKING:
    from typing import Callable, Iterable, Optional

MAX_SCENARIO_BYTES = 4 << 20
KINDS = ("start", "input", "adc", "stop", "event", "bind", "write", "force", "release",
         "upload", "gcode", "job", "code", "move")


class ScenarioError(ValueError):
    """A scenario line or option that cannot be understood; says where and why."""

    def __init__(self, message: str, file: Optional[str] = None, line: Optional[int] = None):
        self.message, self.file, self.line = message, file, line
        where = f"{file}:{line}: " if file and line else f"{file}: " if file else ""
        super().__init__(where + message)


@dataclass(frozen=True)
class Action:
    t_ms: int
    kind: str                  # one of KINDS
    name: str = ""             # start, bind: procedure; event: handler; write, force,
                               # release: target ("all": release everything)
    a: int = 0                 # start: eparam; input, bind: pin; adc: channel; write/force: value
    b: int = 0                 # input/adc: value; bind: eparam; release: 1 restore, 0 keep
    #: done while the debugger held the tick halted before a statement: (procedure,
    #: code offset, return offsets) there; a replay does it at that statement of
    #: tick ``t_ms`` (controller/rewind.py). None: before the tick runs.
    at: Optional[tuple] = None
    source: str = "in"         # bind: what is bound ("in", "vin", "vout", "pls")
    text: str = ""             # gcode: the program's text (name: its file; a: 1 to play it)
    #: where it was written: ``FILE:LINE`` of a scenario file ("" for an option or a
    #: recording); an error about the action names it
    src: str = field(default="", compare=False, repr=False)

    def describe(self) -> str:
        """The scenario line of this action (what :meth:`Scenario.parse` reads back)."""
        line = self._describe()
        if self.at is not None:
            name, pc, rets = self.at
            line += f" at {name}:{pc}"
            if rets:
                line += " returns " + ",".join(str(r) for r in rets)
        return line

    def _describe(self) -> str:
        if self.kind == "start":
            return f"start {self.name}:{self.a} @ {self.t_ms}"
        if self.kind in ("input", "adc"):
            return f"{self.kind} {self.a}={self.b} @ {self.t_ms}"
        if self.kind == "event":
            return f"event {self.name} @ {self.t_ms}"
        if self.kind == "bind":
            src = "" if self.source == "in" else f"{self.source} "
            return f"bind {src}{self.a}={self.name}:{self.b} @ {self.t_ms}"
        if self.kind in ("write", "force"):
            return f"{self.kind} {self.name}={self.a} @ {self.t_ms}"
        if self.kind == "release":
            return f"release {self.name} {MODES[self.b]} @ {self.t_ms}"
        if self.kind == "gcode":
            return f"gcode {self.name}{'' if self.a else ' open'} @ {self.t_ms}"
        if self.kind == "job":
            return f"job {self.name} @ {self.t_ms}"
        if self.kind == "code":
            return f"code {self.name}{self.a} @ {self.t_ms}"
        if self.kind == "move":
            return f"move {self.name}={self.a / 100:g} @ {self.t_ms}"
        if self.kind == "upload":
            return f"upload {self.name} @ {self.t_ms}" if self.name else f"upload @ {self.t_ms}"
        return f"stop @ {self.t_ms}"


#: The ranges numbers are refused outside of (never wrapped): an eparam is a
#: 32-bit word (written signed or unsigned, held signed), an ADC value a signed
#: 32-bit register, a time at most a week of simulated time.
EPARAM_RANGE = WORD32
ADC_RANGE = INT32
PIN_RANGE = (0, 255)              # the most inputs a machine has (8 words of 32)
CHANNEL_RANGE = (0, 7)
MAX_TIME_MS = 7 * 24 * 3600 * 1000


def parse_int(text: str, what: str, lo: int = -(1 << 63), hi: int = (1 << 63) - 1) -> int:
    """A decimal or 0x-hex whole number in lo..hi (ScenarioError naming ``what``
    and the range otherwise)."""
    try:
        return parse_int_in(text, lo, hi, what)
    except ValueError as exc:
        raise ScenarioError(str(exc)) from None


def parse_eparam(text: str, what: str) -> int:
    """An eparam: a 32-bit word, held as the signed value the procedure reads."""
    return to_int32(parse_int(text, what, *EPARAM_RANGE))


def _split_time(text: str, what: str) -> tuple[str, int]:
    if "@" not in text:
        return text.strip(), 0
    body, _, ms = text.rpartition("@")
    t = parse_int(ms, f"the time of {what}")
    if t < 0:
        raise ScenarioError(f"the time of {what} must not be negative ({t})")
    if t > MAX_TIME_MS:
        raise ScenarioError(f"the time of {what} must be from 0 to {MAX_TIME_MS} ms "
                            f"(a week), not {t}")
    return body.strip(), t


def parse_start(text: str) -> Action:
    """``NAME[:EPARAM][@MS]``."""
    body, t = _split_time(text, "--start")
    name, sep, ep = body.partition(":")
    name = name.strip()
    if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", name):
        raise ScenarioError(f"--start needs NAME[:EPARAM]@MS, and {name!r} is not a "
                            "procedure name")
    eparam = parse_eparam(ep, "the eparam of --start") if sep else 0
    return Action(t, "start", name, eparam)


def _pin_value(text: str, kind: str, lo: Optional[int] = None, hi: Optional[int] = None) -> Action:
    body, t = _split_time(text, f"--{kind}")
    left, sep, right = body.partition("=")
    if not sep:
        shape = "PIN=0|1@MS" if kind == "input" else "CH=VALUE@MS"
        raise ScenarioError(f"--{kind} needs {shape}, not {text!r}")
    what = "pin" if kind == "input" else "channel"
    a = parse_int(left, f"the {what} of --{kind}",
                  *(PIN_RANGE if kind == "input" else CHANNEL_RANGE))
    if lo is not None:
        b = parse_int(right, f"the value of --{kind}")
        if not lo <= b <= hi:
            raise ScenarioError(f"an input is 0 or 1, not {b}")
    else:
        b = parse_int(right, f"the value of --{kind}", *ADC_RANGE)
    return Action(t, kind, "", a, b)


def parse_input(text: str) -> Action:
    """``PIN=0|1[@MS]``."""
    return _pin_value(text, "input", 0, 1)


def parse_adc(text: str) -> Action:
    """``CH=VALUE[@MS]``."""
    return _pin_value(text, "adc")


def parse_stop(text: str) -> Action:
    body, t = _split_time(text, "stop")
    if body:
        raise ScenarioError(f"stop takes only a time (stop @ MS), not {body!r}")
    return Action(t, "stop")


def parse_event(text: str) -> Action:
    body, t = _split_time(text, "event")
    if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", body):
        raise ScenarioError(f"event needs a handler name (GCODE_START, GCODE_STOP, …), "
                            f"not {body!r}")
    return Action(t, "event", body)


BIND_SOURCES = ("in", "vin", "vout", "pls")


def parse_bind(text: str) -> Action:
    """``[in|vin|vout|pls] N=NAME[:EPARAM][@MS]`` (a bare N is an input pin)."""
    body, t = _split_time(text, "bind")
    left, sep, right = body.partition("=")
    if not sep:
        raise ScenarioError(f"bind needs [in|vin|vout|pls] N=NAME[:EPARAM]@MS, not {text!r}")
    words = left.split()
    source = "in"
    if len(words) == 2 and words[0].lower() in BIND_SOURCES:
        source = words[0].lower()
        left = words[1]
    elif len(words) != 1:
        raise ScenarioError(f"bind: {left.strip()!r} is not a pin or one of "
                            f"in N, vin N, vout N, pls K")
    if source == "in":
        pin = parse_int(left, "the pin of bind", *PIN_RANGE)
    elif source == "pls":
        pin = parse_int(left, "the PLS of bind", 1, softmc.PLS_NUMBER_MAX)
    else:
        pin = parse_int(left, f"the {source} of bind", 1, softmc.VIRTUAL_BITS)
    start = parse_start(right)
    return Action(t, "bind", start.name, pin, start.a, source=source)


def _target(text: str, what: str) -> str:
    try:
        return parse_target(text).name
    except ForceError as exc:
        raise ScenarioError(f"{what}: {exc}") from None


def _set(text: str, kind: str) -> Action:
    body, t = _split_time(text, f"--{kind}")
    left, sep, right = body.partition("=")
    if not sep:
        raise ScenarioError(f"--{kind} needs NAME=VALUE@MS (NAME: PROC.var, in N, out N, "
                            f"adc N, pwm N, dac N or gvar N), not {text!r}")
    name = _target(left, f"--{kind}")
    value = to_int32(parse_int(right, f"the value of --{kind} {name}", *WORD32))
    return Action(t, kind, name, value)


def parse_write(text: str) -> Action:
    """``NAME=VALUE[@MS]``: set once."""
    return _set(text, "write")


def parse_force(text: str) -> Action:
    """``NAME=VALUE[@MS]``: hold until released."""
    return _set(text, "force")


def parse_release(text: str) -> Action:
    """``NAME [keep|restore][@MS]`` or ``all [keep|restore][@MS]``."""
    body, t = _split_time(text, "release")
    words = body.split()
    mode = "restore"
    if words and words[-1].lower() in MODES:
        mode = words.pop().lower()
    rest = " ".join(words)
    if not rest:
        raise ScenarioError("release needs NAME [keep|restore] @ MS, or all")
    name = "all" if rest.lower() == "all" else _target(rest, "release")
    return Action(t, "release", name, 0, MODES.index(mode))


def parse_upload(text: str) -> Action:
    """``[IMAGE][@MS]``: load the image there (a recorded session's upload;
    IMAGE, 8 hex digits, names the image recorded)."""
    body, t = _split_time(text, "upload")
    ident = body.strip().lower()
    if ident and (len(ident) != 8 or any(c not in "0123456789abcdef" for c in ident)):
        raise ScenarioError(f"upload: the image is named by 8 hex digits (as recorded), "
                            f"not {body.strip()!r}")
    return Action(t, "upload", ident)


def parse_gcode(text: str, base: Optional[Path] = None) -> Action:
    """``FILE [open] [@MS]``: the program's text is read now (FILE relative to
    ``base``, the scenario file's folder)."""
    body, t = _split_time(text, "gcode")
    words = body.split()
    play = 1
    if len(words) >= 2 and words[-1].lower() == "open":
        play = 0
        words = words[:-1]
    if len(words) != 1:
        raise ScenarioError(f"gcode needs FILE [open] @ MS, not {text!r}")
    path = Path(words[0])
    if not path.is_absolute() and base is not None:
        path = base / path
    return Action(t, "gcode", str(path), play, text=read_gcode(path))


def read_gcode(path) -> str:
    """The text of a G-code file (ScenarioError saying why it cannot be read)."""
    try:
        data = read_bounded(Path(path), MAX_SCENARIO_BYTES, "G-code file")
        return data.decode("utf-8")
    except OSError as exc:
        raise ScenarioError(f"gcode: cannot read {path}: {exc.strerror or exc}") from None
    except UnicodeDecodeError:
        raise ScenarioError(f"gcode: {path} is not UTF-8 text") from None


JOB_VERBS = ("play", "pause", "stop", "reset")


def parse_job(text: str) -> Action:
    """``play|pause|stop|reset [@MS]``."""
    body, t = _split_time(text, "job")
    verb = body.strip().lower()
    if verb not in JOB_VERBS:
        raise ScenarioError(f"job needs play, pause, stop or reset, not {body.strip()!r}")
    return Action(t, "job", verb)


def parse_code(text: str) -> Action:
    """``M3``, ``S1200``, ``T5``, ``B2`` ``[@MS]``: the CNC issues that code."""
    body, t = _split_time(text, "code")
    m = re.fullmatch(r"\s*([MmSsTtBb])\s*([0-9]+)\s*", body)
    if not m:
        raise ScenarioError(f"code needs a letter M, S, T or B and a number (code M3 @ 100), "
                            f"not {body.strip()!r}")
    return Action(t, "code", m.group(1).upper(), parse_int(m.group(2), "the code", 0, 1 << 31))


def parse_move(text: str) -> Action:
    """``AXIS=MM [@MS]``: a handwheel click (an incremental rapid move)."""
    body, t = _split_time(text, "move")
    m = re.fullmatch(r"\s*([XYZABCUVWxyzabcuvw])\s*=\s*([+-]?(?:\d+\.?\d*|\.\d+))\s*", body)
    if not m:
        raise ScenarioError(f"move needs AXIS=MM (move X=0.1 @ 100), not {body.strip()!r}")
    return Action(t, "move", m.group(1).upper(), round(float(m.group(2)) * 100))


_AT = Pattern(r"\s+at\s+(\S+?)\s*:\s*(\S+)(?:\s+returns\s+(\S+(?:\s*,\s*\S+)*))?\s*$",
              re.IGNORECASE)
_NAME = Pattern(r"[A-Za-z_][A-Za-z0-9_]*")
#: the most code offsets a position names (a procedure's code is at most 64 KiB;
#: calls nest at most 16 deep)
MAX_OFFSET = 0xFFFF
MAX_RETURNS = 16


def split_at(text: str) -> tuple[str, Optional[tuple]]:
    """``… @ MS at PROC:OFFSET [returns RET,…]``: the text before ``at`` and
    the position ``(PROC, OFFSET, (RET, …))`` (None without ``at``)."""
    head, sep, tail = text.rpartition("@")
    if not sep:
        return text, None
    m = _AT.search(tail)
    if m is None:
        if re.search(r"\bat\b", tail, re.IGNORECASE):
            raise ScenarioError(f"a position within the tick is 'at PROC:OFFSET' or "
                                f"'at PROC:OFFSET returns RET,…', not {tail.strip()!r}")
        return text, None
    name = m.group(1)
    if not _NAME.fullmatch(name):
        raise ScenarioError(f"at {name}:…: {name!r} is not a procedure name")
    pc = parse_int(m.group(2), f"the code offset of at {name}", 0, MAX_OFFSET)
    rets: tuple = ()
    if m.group(3):
        parts = [r.strip() for r in m.group(3).split(",")]
        if len(parts) > MAX_RETURNS:
            raise ScenarioError(f"at {name}:{pc}: calls nest at most {MAX_RETURNS} deep, "
                                f"not {len(parts)}")
        rets = tuple(parse_int(r, f"a return offset of at {name}:{pc}", 0, MAX_OFFSET)
                     for r in parts)
    return head + sep + tail[:m.start()], (name, pc, rets)


_PARSERS: dict[str, Callable[[str], Action]] = {
    "start": parse_start, "input": parse_input, "adc": parse_adc,
    "stop": parse_stop, "event": parse_event, "bind": parse_bind,
    "write": parse_write, "force": parse_force, "release": parse_release,
    "upload": parse_upload, "job": parse_job, "code": parse_code, "move": parse_move,
}


class Scenario:
    """Actions in the order they were given; applied by time, then that order."""

    def __init__(self, actions: Iterable[Action] = ()):
        self.actions: list[Action] = list(actions)

    def add(self, action: Action) -> None:
        self.actions.append(action)

    def extend(self, actions: Iterable[Action]) -> None:
        self.actions.extend(actions)

    def ordered(self) -> list[Action]:
        return sorted(self.actions, key=lambda a: a.t_ms)   # stable: given order within a tick

    @classmethod
    def parse(cls, text: str, file: str = "<scenario>", first_line: int = 1) -> "Scenario":
        """The actions of a scenario text; ``first_line`` is the file's line of its
        first line (a scenario inside a test file), for the places actions keep."""
        out = cls()
        for n, raw in enumerate(text.splitlines(), 1):
            line = raw.split("#", 1)[0].strip()
            if not line:
                continue
            word, _, rest = line.partition(" ")
            if "=" in word and word.startswith("--"):      # --input=3=1@5
                word, _, rest0 = word.partition("=")
                rest = rest0 + " " + rest
            kind = word.lower().lstrip("-")
            if kind not in _PARSERS and "@" in word and word.split("@")[0].lower() == "stop":
                kind, rest = "stop", "@" + word.split("@", 1)[1] + rest
            parser = _PARSERS.get(kind)
            if kind == "gcode":
                base = Path(file).parent if file and not file.startswith("<") else None
                parser = (lambda rest, base=base: parse_gcode(rest, base))
            if parser is None:
                raise ScenarioError(f"unknown action {word!r} (one of {', '.join(KINDS)})",
                                    file, n)
            try:
                rest, at = split_at(rest)
                action = replace(parser(rest), src=f"{file}:{first_line + n - 1}")
                out.add(action if at is None else replace(action, at=at))
            except ScenarioError as exc:      # said as the line is written
                raise ScenarioError(exc.message.replace(f"--{kind}", kind), file, n) from None
        return out

    @classmethod
    def load(cls, path) -> "Scenario":
        p = Path(path)
        try:
            data = read_bounded(p, MAX_SCENARIO_BYTES, "scenario file")
        except OSError as exc:
            raise ScenarioError(f"cannot read the scenario: {exc.strerror or exc}", str(p)) from None
        try:
            text = data.decode("utf-8")
        except UnicodeDecodeError as exc:
            raise ScenarioError("not UTF-8 text", str(p), data[:exc.start].count(b"\n") + 1) \
                from None
        return cls.parse(text, str(p))


def apply(controller, action: Action) -> None:
    """Do one action on a :class:`~plcbuilder.controller.controller.Controller` now."""
    if action.kind == "start":
        controller.start(action.name, action.a)
    elif action.kind == "input":
        controller.set_input(action.a, action.b)
    elif action.kind == "adc":
        controller.set_adc(action.a, action.b)
    elif action.kind == "stop":
        controller.stop()
    elif action.kind == "event":
        controller.event(action.name)
    elif action.kind == "bind":
        controller.bind_input(action.a, action.name, action.b, action.source)
    elif action.kind == "write":
        controller.write(action.name, action.a)
    elif action.kind == "force":
        controller.force(action.name, action.a)
    elif action.kind == "release":
        if action.name == "all":
            controller.release_all(MODES[action.b])
        else:
            controller.release(action.name, MODES[action.b])
    elif action.kind == "upload":
        controller.reload()
    elif action.kind == "gcode":
        controller.job_open(action.text, action.name, play=bool(action.a))
    elif action.kind == "job":
        controller.job_control(action.name)
    elif action.kind == "code":
        controller.issue_code(action.name, action.a)
    elif action.kind == "move":
        controller.handwheel(action.name, action.a / 100)
    else:  # pragma: no cover
        raise ScenarioError(f"unknown action {action.kind!r}")


#: Actions that can start a procedure (the run is not over while one is due).
STARTING = frozenset({"start", "stop", "event", "bind", "upload", "gcode", "job", "code"})
#: Actions that can change an input (which may be bound to a procedure).
_PIN_CHANGES = frozenset({"input", "write", "force", "release"})


def aim(dbg, actions: list, i: int, t: int) -> None:
    """Halt tick ``t`` where the next action was done mid-tick (a one-time
    "run to" at its statement, ``Action.at``), or nowhere."""
    a = actions[i] if i < len(actions) else None
    want = {a.at[0]: {a.at[1]}} if a is not None and a.at is not None and a.t_ms == t else {}
    if dbg._run_to != want:
        dbg._run_to = want
        dbg._remark()


def due_before(action: Action, t: int) -> bool:
    """Whether ``action`` is done before tick ``t`` runs: it is due by then and
    not placed within tick ``t`` itself (one placed in a tick already over,
    which a replay of the same image cannot meet, is done now rather than never)."""
    return action.t_ms <= t and not (action.at is not None and action.t_ms == t)


def at_halt(controller, actions: list, i: int, do: Callable = None,
            counted: bool = False) -> int:
    """``controller`` halted: when it is where the next actions were done
    mid-tick, do them (``do(controller, action)``, by default :func:`apply`)
    after the breakpoints there, which the "run to" halt came before (their hits
    count as they did live; ``counted``: the halt was a counter's, which
    already looked); returns the index of the next action."""
    dbg = controller.debugger
    h = dbg.halt
    if i >= len(actions) or h.process is None or not controller.plc.mid_tick:
        return i
    point = (h.process.name, h.pc, tuple(h.rets))
    t = controller.t_ms
    a = actions[i]
    if a.at != point or a.t_ms != t:
        return i
    if h.reason == "step" and h.breakpoint is None and not counted:
        bps = dbg._at.get(h.process.program.name, {}).get(h.pc)
        if bps:
            dbg._breakpoints_at(h.process, h.pc, h.rets, bps)
            dbg.halt = dbg.halt or h
    do = do or apply
    while i < len(actions) and actions[i].at == point and actions[i].t_ms == t:
        do(controller, actions[i])
        i += 1
    return i


def drive(controller, scenario: Scenario, limit_ms: int, *, until_idle: bool = True,
          chunk_ms: int = 1000, on_chunk: Optional[Callable[[], None]] = None) -> int:
    """Run ``controller`` with ``scenario`` until ``limit_ms`` ticks have run or,
    with ``until_idle``, until no procedure runs and none is due to start
    (scenario actions included). ``on_chunk`` is called after every step of at
    most ``chunk_ms`` ticks (to drain events and samples). Returns the time the
    run ended: ``limit_ms``, or the tick in which it became idle.

    An action placed within its tick (``Action.at``, done live while the
    debugger held the tick halted there) is done when the tick reaches that
    statement: the debugger halts the tick there for it and goes on. The run
    ends at a halt of its own only (a breakpoint, or a fault while the debugger
    was on before: ``--break``)."""
    actions = scenario.ordered()
    i = 0
    n = len(actions)
    c = controller
    dbg = getattr(c, "debugger", None)
    placed = dbg is not None and any(a.at is not None for a in actions)
    halts = dbg is not None and dbg.on         # breakpoints set: their halts end the run
    while True:
        t = c.t_ms
        while i < n and due_before(actions[i], t):
            try:
                apply(c, actions[i])
            except Exception as exc:         # the controller's refusal, said where
                if actions[i].src:
                    exc.args = (f"{actions[i].src}: {exc}",)
                raise
            i += 1
        if placed:
            aim(dbg, actions, i, t)
        if t >= limit_ms:
            return limit_ms
        bound = bool(c.bindings)           # then an input can start a procedure too
        more_starts = any(a.kind in STARTING or (bound and a.kind in _PIN_CHANGES)
                          for a in actions[i:])
        if until_idle and not more_starts and c.idle():
            return max(t - 1, 0) if t else 0
        stop = limit_ms if i >= n else min(limit_ms, max(actions[i].t_ms, t + 1))
        count = min(stop - t, chunk_ms)
        ran = c.run_until_idle(count) if (until_idle and not more_starts) else None
        if ran is None:
            c.step(count)
        went_on = False
        while placed and dbg.halt is not None:
            i = at_halt(c, actions, i)
            h = dbg.halt
            if h.reason == "breakpoint" or (h.reason == "fault" and halts):
                if h is not dbg._told:     # a breakpoint where the action was done
                    dbg.unannounce()
                    dbg.settle()
                break
            dbg.unannounce()               # the replay's own halt: nobody halted
            dbg.halt = None
            aim(dbg, actions, i, c.t_ms)
            c.plc.resume_tick()            # the rest of the tick (it may halt again)
            dbg.settle()
            went_on = True
        if on_chunk is not None:
            on_chunk()
        if dbg is not None and dbg.halted:  # the debugger halted it: the run ends there
            return c.t_ms
        if ran is not None and ran < count and not went_on:
            return c.t_ms - 1
