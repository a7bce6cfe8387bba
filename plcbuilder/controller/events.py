"""What the simulated controller reports: events and per-tick telemetry samples.

These are plain data, shared by the controller, ``plcbuilder run`` (JSON and the
CSV trace), the TCP link (serialised with :func:`to_dict`) and the IDE panels.
"""

from __future__ import annotations

from plcbuilder._support.records import asdict, dataclass, field, fields_of

TYPE_CHECKING = False               # (typing is not imported at run time: start-up)
if TYPE_CHECKING:
    from typing import Optional


@dataclass(frozen=True)
class Started:
    t_ms: int
    name: str
    kind: str            # "hardware" | "software"
    eparam: int
    type: str = "started"


@dataclass(frozen=True)
class Ended:
    t_ms: int
    name: str
    kind: str
    exit_code: int
    exit_name: Optional[str]   # from abi.exit_name, None when not in the table
    vexit: int
    type: str = "ended"


@dataclass(frozen=True)
class Message:
    t_ms: int
    message: int
    name: Optional[str]        # abi.message_name
    command: int               # var00 at the end of the tick
    parameter: int             # var01
    source: str                # procedure name ("from" in JSON)
    type: str = "message"


@dataclass(frozen=True)
class Print:
    t_ms: int
    register: int              # 20000..20100
    value: int
    source: str
    type: str = "print"


@dataclass(frozen=True)
class Fault:
    """A runtime fault. ``file``/``line`` name the statement of ``main`` that was
    running (a call, when the fault happened inside a called procedure);
    ``calls`` is the whole chain, outermost first: (file, line, procedure) of
    each call and, last, of the instruction that faulted."""
    t_ms: int
    source: str                # procedure name
    file: Optional[str]
    line: Optional[int]
    text: str
    type: str = "fault"
    calls: tuple = ()


@dataclass(frozen=True)
class Note:
    """Anything else worth a line in the log (a limit hit, a jog watchdog stop, a refused start)."""
    t_ms: int
    text: str
    level: str = "info"        # "info" | "warning" | "error"
    type: str = "note"


@dataclass(frozen=True)
class Log:
    """A logpoint's message (controller/debugger.py): its ``{name}`` placeholders filled in."""
    t_ms: int
    source: str                # procedure name
    text: str
    type: str = "log"


@dataclass(frozen=True)
class Halted:
    """The debugger halted the controller; ``state`` is the halted state (docs/debugging.md)."""
    t_ms: int
    state: dict
    type: str = "halted"


@dataclass(frozen=True)
class Resumed:
    """The controller goes on after a halt."""
    t_ms: int
    type: str = "resumed"


@dataclass(frozen=True)
class Forces:
    """The set of forces changed (controller/forces.py): everything forced now,
    each ``{target, value, since_ms}``."""
    t_ms: int
    forces: tuple = ()
    type: str = "forces"


@dataclass(frozen=True)
class Watched:
    """A watched variable (``PROC.var``, controller/watch.py) is new or changed
    at the end of tick ``t_ms``."""
    t_ms: int
    name: str
    value: int
    type: str = "watch"


@dataclass(frozen=True)
class JobEvent:
    """The G-code job (controller/job.py) read a line, started a procedure or
    changed state: ``state`` is ready, starting, running, paused, ended, stopped
    or error; ``line`` the line reached; ``text`` the line's text or the reason;
    ``procedure`` the procedure it started (None otherwise); ``exit_code``, when
    set, says that procedure (or a Huazhong handler) ended with it."""
    t_ms: int
    file: str
    line: int
    state: str
    text: str
    procedure: Optional[str] = None
    exit_code: Optional[int] = None
    type: str = "job"


Event = (Started | Ended | Message | Print | Fault | Note | Log | Halted | Resumed | Forces
         | Watched | JobEvent)


@dataclass
class Sample:
    """The controller's state at the end of one tick (after the message is sent,
    before motion advances)."""
    t_ms: int
    running: Optional[str]          # hardware procedure running, or None
    proc: int                       # the hardware PLC's proc value (kept after a procedure ends)
    message: int                    # message sent this tick (0 if none)
    inputs: tuple[int, ...]         # 8 input words (32 pins each, pin n = word n//32 bit n%32)
    outputs: tuple[int, ...]        # 8 output words
    pwm: tuple[int, ...]            # 8 PWM values
    dac: tuple[int, ...]            # 8 DAC values
    adc: tuple[int, ...]            # 8 ADC values
    axes: tuple[int, ...]           # machine positions X..W in 0.01 mm (9 values)
    velocities: tuple[int, ...] = field(default=())   # 0.01 mm/s per axis (9 values)
    vio: tuple[int, ...] = field(default=())          # softMC VIN word, VOUT word (unsigned)


def to_dict(obj) -> dict:
    """A JSON-ready dict of an event or sample."""
    return asdict(obj)


def from_dict(d: dict):
    """The inverse of :func:`to_dict` for events (by their ``type``) and samples."""
    kinds = {"started": Started, "ended": Ended, "message": Message, "print": Print,
             "fault": Fault, "note": Note, "log": Log, "halted": Halted, "resumed": Resumed,
             "forces": Forces, "watch": Watched, "job": JobEvent}
    t = d.get("type")
    if t == "fault" and "calls" in d:
        d = dict(d, calls=tuple(tuple(c) for c in d["calls"]))
    if t == "forces":
        d = dict(d, forces=tuple(dict(f) for f in d.get("forces", ())))
    if t in kinds:
        return kinds[t](**d)
    s = dict(d)
    for k in ("inputs", "outputs", "pwm", "dac", "adc", "axes", "velocities", "vio"):
        if k in s:
            s[k] = tuple(s[k])
    return Sample(**s)


# ------------------------------------------------------------------ status
@dataclass(frozen=True)
class ControllerStatus:
    """The controller's state now, as ``plcbuilder state`` and the IDE see it.

    The controller fills the first part; a server adds the loaded image as it
    was uploaded (``image`` with sizes and CRCs, ``image_crc32``), its speed and
    its own counters. On the wire it is :meth:`to_dict`'s JSON object, read back
    with :meth:`from_dict` (keys it does not know are ignored, missing ones take
    their defaults, so either side may be newer)."""
    t_ms: int = 0
    running: Optional[str] = None          # the hardware procedure running
    software: tuple[str, ...] = ()         # the software procedures running, by name
    idle: bool = True                      # nothing running and nothing due
    proc: int = 0
    proc_name: Optional[str] = None
    inputs: tuple[int, ...] = ()           # input pins that read 1
    outputs: tuple[int, ...] = ()          # output pins that are on
    pwm: tuple[int, ...] = ()
    dac: tuple[int, ...] = ()
    adc: tuple[int, ...] = ()
    axes: dict = field(default_factory=dict)       # {"X": machine position in 0.01 mm, …}
    image: tuple[dict, ...] = ()           # {name, kind, size, crc32, …} per procedure
    image_crc32: Optional[str] = None      # the uploaded image's CRC-32 (hex), None if none
    speed: dict = field(default_factory=dict)      # {"mode", "factor", "dropped_ms", …}
    server: dict = field(default_factory=dict)     # {"clients", "uploads", "error", …}
    #: the G-code job: {file, state, line, lines, error} ({} without one)
    job: dict = field(default_factory=dict)

    def to_dict(self) -> dict:
        # Shallow: every field holds plain values already (asdict deep-copied each
        # image entry, 30 ms for 1,000 procedures on every ``state``).
        d = {k: getattr(self, k) for k in fields_of(self)}
        for k in ("axes", "speed", "server", "job"):
            d[k] = dict(d[k])
        for k in ("software", "inputs", "outputs", "pwm", "dac", "adc", "image"):
            d[k] = list(d[k])
        return d

    @classmethod
    def from_dict(cls, d: dict) -> "ControllerStatus":
        known = set(fields_of(cls))
        kw = {k: v for k, v in d.items() if k in known}
        for k in ("software", "inputs", "outputs", "pwm", "dac", "adc", "image"):
            if k in kw:
                kw[k] = tuple(kw[k] or ())
        for k in ("axes", "speed", "server", "job"):
            if k in kw and not isinstance(kw[k], dict):
                kw[k] = {}
        return cls(**kw)
