"""The machine description: a TOML file.

A machine description says what the simulated controller is wired to: its axes
(speeds, accelerations, soft limits, start position, work offset), what each
input pin reads (a switch at an axis position, a sensor that follows an output
after a delay, a constant), and what each ADC channel reads. The format is
documented for users in docs/machine.md; the default machine is package data
(``resources/machine/default.toml``).

Lengths in the file are in mm (degrees for rotary axes), speeds in mm/min,
accelerations in mm/s², times in ms. The machine works in the PLC's units
(0.01 mm) and converts on load.

Every problem with a file raises :class:`ConfigError`, whose message names the
file, the line (where it can be found) and the key. ``plc-variables.xml`` is
read by :mod:`plcbuilder.controller.variables_xml`, with the same error.
"""

from __future__ import annotations

import math
from pathlib import Path
from types import MappingProxyType

from plcbuilder._support.records import dataclass, field
from plcbuilder._support.files import read_bounded
from plcbuilder._support.toml_errors import TomlLocator, decode_error
from plcbuilder._support.toml_errors import loads as toml_loads
from plcbuilder.bytecode.abi import AXES

from .pls_config import PlsConfig, parse_pls

TYPE_CHECKING = False               # (typing is not imported at run time: start-up)
if TYPE_CHECKING:
    from typing import Any, Mapping, Optional

MAX_PINS = 256          # 8 words of 32 pins
MAX_MACHINE_BYTES = 1 << 20   # a machine description file is at most 1 MiB
ADC_CHANNELS = 8


class ConfigError(ValueError):
    """A machine description or a plc-variables.xml that cannot be used.

    ``str(err)`` reads ``FILE:LINE: KEY: what is wrong`` (the parts that are known).
    """

    def __init__(self, message: str, file: Optional[str] = None, line: Optional[int] = None,
                 key: Optional[str] = None):
        self.message = message
        self.file = file
        self.line = line
        self.key = key
        where = ""
        if file is not None:
            where = f"{file}:{line}: " if line is not None else f"{file}: "
        elif line is not None:
            where = f"line {line}: "
        super().__init__(f"{where}{key + ': ' if key else ''}{message}")


# ----------------------------------------------------------------- dataclasses
@dataclass(frozen=True)
class AxisConfig:
    """One axis. Lengths in mm (degrees when rotary), as in the file."""
    name: str                       # "X" .. "W"
    rapid: float = 5000.0           # rapid (g0moveA) speed, mm/min; also the jog speed cap
    accel: float = 500.0            # acceleration, mm/s²
    jog: float = 1000.0             # jog speed before the PLC writes 8634, mm/min
    soft_min: Optional[float] = None   # soft limits, mm (None: unlimited)
    soft_max: Optional[float] = None
    start: float = 0.0              # machine position at power-on and reset, mm
    offset: float = 0.0             # work offset: program position = machine − offset
    rotary: bool = False

    @property
    def index(self) -> int:
        return AXES.index(self.name)


@dataclass(frozen=True)
class InputConfig:
    """What one input pin reads when nobody has set it by hand.

    kind "axis": ``active`` while the axis position is <= ``below`` and/or
    >= ``above`` (both given: while above <= position <= below);
    kind "output": ``active`` ``delay_ms`` after output ``output`` turns on,
    the other level ``off_delay_ms`` after it turns off;
    kind "constant": always ``value``.
    """
    pin: int
    kind: str                       # "axis" | "output" | "constant"
    name: str = ""
    active: int = 1                 # the level the pin reads when active
    axis: Optional[str] = None
    below: Optional[float] = None   # mm
    above: Optional[float] = None   # mm
    output: Optional[int] = None
    delay_ms: int = 0
    off_delay_ms: int = 0
    value: int = 0
    hard_limit: bool = False        # a limit switch: motion into it stops with an error
    home: bool = False              # the axis's home switch (where a job's G28 homes it)


@dataclass(frozen=True)
class OutputConfig:
    pin: int
    name: str = ""


@dataclass(frozen=True)
class AdcConfig:
    """What one ADC channel reads (before a manual override).

    source "constant": ``value``; "ramp": from ``start`` to ``end`` over
    ``period_ms``, then again (``repeat``) or holding ``end``; "axis":
    ``offset + scale × position in mm`` of ``axis``. Any source may add
    deterministic noise of ±``noise`` counts drawn from ``seed``, and is clamped
    to ``min``/``max`` when they are given.
    """
    channel: int
    source: str = "constant"
    name: str = ""
    value: int = 0
    start: float = 0.0
    end: float = 0.0
    period_ms: int = 1000
    repeat: bool = True
    axis: Optional[str] = None
    scale: float = 1.0
    offset: float = 0.0
    noise: int = 0
    seed: int = 0
    min: Optional[int] = None
    max: Optional[int] = None


@dataclass(frozen=True)
class MachineConfig:
    """A whole machine description. ``MachineConfig()`` is a bare board: 64
    inputs and outputs, no axes, nothing wired."""
    name: str = "machine"
    description: str = ""
    source: Optional[str] = None    # the file it came from, if any
    input_count: int = 64
    output_count: int = 64
    start_latency_ms: int = 2
    jog_watchdog_ms: int = 1000
    axes: Mapping[str, AxisConfig] = field(default_factory=dict)   # in X..W order (read-only)
    inputs: tuple[InputConfig, ...] = ()
    outputs: tuple[OutputConfig, ...] = ()
    adc: tuple[AdcConfig, ...] = ()
    pls: tuple[PlsConfig, ...] = ()  # programmable limit switches ([[pls]], controller/pls_config.py)
    input_preset: int = 0           # IO.DAT's INP: the level of inputs nothing wires
    dip: int = 0                    # IO.DAT's DIP (register IO_DAT_DIP)

    def input_names(self) -> dict[int, str]:
        return {i.pin: i.name for i in self.inputs if i.name}

    def output_names(self) -> dict[int, str]:
        return {o.pin: o.name for o in self.outputs if o.name}


# ----------------------------------------------------------------- parsing
class _Reader:
    def __init__(self, file: str, text: str):
        self.file = file
        self.loc = TomlLocator(text)

    def error(self, path: tuple, message: str) -> ConfigError:
        key = ".".join(str(p) if not isinstance(p, int) else f"[{p}]" for p in path)
        key = key.replace(".[", "[")
        return ConfigError(message, self.file, self.loc.line_of(path) if path else None, key or None)

    def table(self, d: Any, path: tuple) -> dict:
        if not isinstance(d, dict):
            raise self.error(path, f"expected a table, got {_kind(d)}")
        return d

    def known(self, d: dict, path: tuple, allowed: set[str]) -> None:
        for k in d:
            if k not in allowed:
                hint = ", ".join(sorted(allowed))
                raise self.error(path + (k,), f"unknown key (known keys here: {hint})")

    def tables(self, data: Any, name: str, allowed: set[str], required: str):
        """The array of tables ``[[name]]``, each as (index, path, table) with
        its keys checked against ``allowed`` and ``required`` among them: the
        array is checked now, each table as the caller comes to it."""
        if not isinstance(data, list):
            raise self.error((name,), f"expected an array of tables ([[{name}]])")
        return self._entries(data, name, allowed, required)

    def _entries(self, data: list, name: str, allowed: set[str], required: str):
        for k, item in enumerate(data):
            p = (name, k)
            d = self.table(item, p)
            self.known(d, p, allowed)
            if required not in d:
                raise self.error(p, f"missing key '{required}'")
            yield k, p, d

    def one_of(self, d: dict, path: tuple, choices: dict[str, str]) -> str:
        """The one key of ``choices`` (key: what it gives) that ``d`` has;
        none or more than one is an error naming them all."""
        has = [w for w in choices if w in d]
        if len(has) != 1:
            named = [f"'{k}' ({what})" for k, what in choices.items()]
            raise self.error(path, "give exactly one of " + ", ".join(named[:-1]) + " or "
                             + named[-1] + (f"; found {', '.join(has)}" if has else ""))
        return has[0]

    def integer(self, d: dict, key: str, path: tuple, default=None, lo=None, hi=None):
        if key not in d:
            return default
        v = d[key]
        if isinstance(v, bool) or not isinstance(v, int):
            raise self.error(path + (key,), f"expected an integer, got {_kind(v)}")
        self._range(v, key, path, lo, hi)
        return v

    def number(self, d: dict, key: str, path: tuple, default=None, lo=None, hi=None,
               positive=False, unit: str = ""):
        if key not in d:
            return default
        v = d[key]
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            raise self.error(path + (key,), f"expected a number, got {_kind(v)}")
        if not math.isfinite(v):
            raise self.error(path + (key,), "expected a finite number")
        if positive and v <= 0:
            raise self.error(path + (key,), f"must be greater than 0, got {v}"
                             + (f" (allowed: {_span(lo, hi, unit)})" if lo is not None else ""))
        self._range(v, key, path, lo, hi, unit)
        return float(v)

    def string(self, d: dict, key: str, path: tuple, default=None, choices=None):
        if key not in d:
            return default
        v = d[key]
        if not isinstance(v, str):
            raise self.error(path + (key,), f"expected a string, got {_kind(v)}")
        if choices is not None and v not in choices:
            raise self.error(path + (key,), f"{v!r} is not one of {', '.join(choices)}")
        return v

    def boolean(self, d: dict, key: str, path: tuple, default=None):
        if key not in d:
            return default
        v = d[key]
        if not isinstance(v, bool):
            raise self.error(path + (key,), f"expected true or false, got {_kind(v)}")
        return v

    def _range(self, v, key, path, lo, hi, unit: str = ""):
        if lo is not None and v < lo or hi is not None and v > hi:
            if unit:
                raise self.error(path + (key,), f"{v} is out of range (allowed: "
                                                f"{_span(lo, hi, unit)})")
            raise self.error(path + (key,), f"{v} is out of range ({lo}..{hi})")


def _span(lo, hi, unit: str) -> str:
    """``0.01 to 10000000 mm/min`` (a bound left open is not said)."""
    g = lambda x: f"{x:.12g}"       # noqa: E731
    if lo is None:
        return f"at most {g(hi)} {unit}"
    if hi is None:
        return f"at least {g(lo)} {unit}"
    return f"{g(lo)} to {g(hi)} {unit}"


def _kind(v: Any) -> str:
    if isinstance(v, bool):
        return f"boolean {str(v).lower()}"
    if isinstance(v, int):
        return f"integer {v}"
    if isinstance(v, float):
        return f"number {v}"
    if isinstance(v, str):
        return f"string {v!r}"
    if isinstance(v, dict):
        return "a table"
    if isinstance(v, list):
        return "an array"
    return type(v).__name__


_TOP_KEYS = {"name", "description", "io", "motion", "axes", "inputs", "outputs", "adc", "pls"}
_AXIS_KEYS = {"rapid", "accel", "jog", "min", "max", "start", "offset", "rotary"}
_INPUT_KEYS = {"pin", "name", "active", "axis", "below", "above", "output", "delay_ms",
               "off_delay_ms", "value", "hard_limit", "home"}
_ADC_KEYS = {"channel", "name", "source", "value", "start", "end", "period_ms", "repeat",
             "axis", "scale", "offset", "noise", "seed", "min", "max"}
_I32 = (-(1 << 31), (1 << 31) - 1)
_BIG_MM = 1e7       # 10 km: a position beyond this is certainly a typo
#: Physical bounds of an axis (docs/machine.md): below them a move would take
#: longer than any run, above them no machine moves; the motion code divides by
#: speeds and accelerations, so neither may be (or round to) 0.
RAPID_RANGE = (0.01, 1e7)        # mm/min
ACCEL_RANGE = (0.01, 1e7)        # mm/s²
JOG_RANGE = (0.0, 1e7)           # mm/min


def parse_machine(text: str, name: str = "<machine>", data: Optional[dict] = None) -> MachineConfig:
    """Parse a machine description from TOML text. ``name`` is the file name
    used in error messages; ``data``: the text as tomllib reads it, when known."""
    try:
        data = toml_loads(text) if data is None else data
    except ValueError as e:                    # tomllib.TOMLDecodeError
        msg, line = decode_error(e, text)
        raise ConfigError(f"TOML syntax error: {msg}", name, line) from None
    r = _Reader(name, text)
    r.known(data, (), _TOP_KEYS)
    mname = r.string(data, "name", (), "machine")
    desc = r.string(data, "description", (), "")

    io = r.table(data.get("io", {}), ("io",))
    r.known(io, ("io",), {"inputs", "outputs"})
    n_in = r.integer(io, "inputs", ("io",), 64, 1, MAX_PINS)
    n_out = r.integer(io, "outputs", ("io",), 64, 1, MAX_PINS)

    mo = r.table(data.get("motion", {}), ("motion",))
    r.known(mo, ("motion",), {"start_latency_ms", "jog_watchdog_ms"})
    latency = r.integer(mo, "start_latency_ms", ("motion",), 2, 0, 60000)
    watchdog = r.integer(mo, "jog_watchdog_ms", ("motion",), 1000, 1, 3600000)

    axes: dict[str, AxisConfig] = {}
    ax_tab = r.table(data.get("axes", {}), ("axes",))
    for key in ax_tab:
        if key not in AXES:
            raise r.error(("axes", key), f"unknown axis (axes are {', '.join(AXES)})")
    for aname in AXES:
        if aname not in ax_tab:
            continue
        p = ("axes", aname)
        a = r.table(ax_tab[aname], p)
        r.known(a, p, _AXIS_KEYS)
        rotary = r.boolean(a, "rotary", p, aname in ("A", "B", "C"))
        lo = r.number(a, "min", p, None, -_BIG_MM, _BIG_MM)
        hi = r.number(a, "max", p, None, -_BIG_MM, _BIG_MM)
        if lo is not None and hi is not None and lo > hi:
            raise r.error(p + ("min",), f"min {lo} is above max {hi}")
        axes[aname] = AxisConfig(
            name=aname,
            rapid=r.number(a, "rapid", p, 5000.0, *RAPID_RANGE, positive=True,
                           unit="mm/min"),
            accel=r.number(a, "accel", p, 500.0, *ACCEL_RANGE, positive=True, unit="mm/s²"),
            jog=r.number(a, "jog", p, 1000.0, *JOG_RANGE, unit="mm/min"),
            soft_min=lo, soft_max=hi,
            start=r.number(a, "start", p, 0.0, -_BIG_MM, _BIG_MM),
            offset=r.number(a, "offset", p, 0.0, -_BIG_MM, _BIG_MM),
            rotary=rotary,
        )

    inputs = []
    seen: dict[int, int] = {}
    for k, p, d in r.tables(data.get("inputs", []), "inputs", _INPUT_KEYS, "pin"):
        pin = r.integer(d, "pin", p, None, 0, n_in - 1)
        if pin in seen:
            raise r.error(p + ("pin",), f"input {pin} is already wired (inputs[{seen[pin]}])")
        seen[pin] = k
        tied = r.one_of(d, p, {"axis": "a position switch", "output": "follows an output",
                               "value": "a constant"})
        kind = {"axis": "axis", "output": "output", "value": "constant"}[tied]
        common = dict(pin=pin, name=r.string(d, "name", p, ""),
                      active=r.integer(d, "active", p, 1, 0, 1),
                      hard_limit=r.boolean(d, "hard_limit", p, False),
                      home=r.boolean(d, "home", p, False))
        for only, kinds in (("below", "axis"), ("above", "axis"), ("hard_limit", "axis"),
                            ("home", "axis"),
                            ("delay_ms", "output"), ("off_delay_ms", "output")):
            if only in d and kind != kinds:
                raise r.error(p + (only,), f"only for an input tied to an {kinds}")
        if kind == "axis":
            ax = r.string(d, "axis", p, choices=AXES)
            if ax not in axes:
                raise r.error(p + ("axis",), f"axis {ax} is not configured in [axes.{ax}]")
            below = r.number(d, "below", p, None, -_BIG_MM, _BIG_MM)
            above = r.number(d, "above", p, None, -_BIG_MM, _BIG_MM)
            if below is None and above is None:
                raise r.error(p, "an input tied to an axis needs 'below' and/or 'above' (mm)")
            if below is not None and above is not None and above > below:
                raise r.error(p + ("above",), f"above {above} is over below {below}: "
                                              "the switch could never be active")
            inputs.append(InputConfig(kind="axis", axis=ax, below=below, above=above, **common))
        elif kind == "output":
            out = r.integer(d, "output", p, None, 0, n_out - 1)
            inputs.append(InputConfig(
                kind="output", output=out,
                delay_ms=r.integer(d, "delay_ms", p, 0, 0, 3600000),
                off_delay_ms=r.integer(d, "off_delay_ms", p, 0, 0, 3600000), **common))
        else:
            if "active" in d:
                raise r.error(p + ("active",), "not for a constant input (give its 'value')")
            inputs.append(InputConfig(kind="constant", value=r.integer(d, "value", p, 0, 0, 1),
                                      **common))

    outputs = []
    seen = {}
    for k, p, d in r.tables(data.get("outputs", []), "outputs", {"pin", "name"}, "pin"):
        pin = r.integer(d, "pin", p, None, 0, n_out - 1)
        if pin in seen:
            raise r.error(p + ("pin",), f"output {pin} is already named (outputs[{seen[pin]}])")
        seen[pin] = k
        outputs.append(OutputConfig(pin=pin, name=r.string(d, "name", p, "")))

    adcs = []
    seen = {}
    for k, p, d in r.tables(data.get("adc", []), "adc", _ADC_KEYS, "channel"):
        ch = r.integer(d, "channel", p, None, 0, ADC_CHANNELS - 1)
        if ch in seen:
            raise r.error(p + ("channel",), f"ADC{ch} already has a source (adc[{seen[ch]}])")
        seen[ch] = k
        src = r.string(d, "source", p, "constant", ("constant", "ramp", "axis"))
        allowed = {"constant": {"value"}, "ramp": {"start", "end", "period_ms", "repeat"},
                   "axis": {"axis", "scale", "offset"}}[src]
        for key in ("value", "start", "end", "period_ms", "repeat", "axis", "scale", "offset"):
            if key in d and key not in allowed:
                raise r.error(p + (key,), f"not used by source {src!r}")
        ax = None
        if src == "axis":
            if "axis" not in d:
                raise r.error(p, "source 'axis' needs 'axis'")
            ax = r.string(d, "axis", p, choices=AXES)
            if ax not in axes:
                raise r.error(p + ("axis",), f"axis {ax} is not configured in [axes.{ax}]")
        lo = r.integer(d, "min", p, None, *_I32)
        hi = r.integer(d, "max", p, None, *_I32)
        if lo is not None and hi is not None and lo > hi:
            raise r.error(p + ("min",), f"min {lo} is above max {hi}")
        adcs.append(AdcConfig(
            channel=ch, source=src, name=r.string(d, "name", p, ""),
            value=r.integer(d, "value", p, 0, *_I32),
            start=r.number(d, "start", p, 0.0, *_I32), end=r.number(d, "end", p, 0.0, *_I32),
            period_ms=r.integer(d, "period_ms", p, 1000, 1, 1 << 30),
            repeat=r.boolean(d, "repeat", p, True), axis=ax,
            scale=r.number(d, "scale", p, 1.0, -1e9, 1e9),
            offset=r.number(d, "offset", p, 0.0, *_I32),
            noise=r.integer(d, "noise", p, 0, 0, 1 << 30),
            seed=r.integer(d, "seed", p, 0, 0, (1 << 63) - 1),
            min=lo, max=hi))

    pls = parse_pls(r, data.get("pls", []), axes, n_out)

    return MachineConfig(name=mname, description=desc, source=name, input_count=n_in,
                         output_count=n_out, start_latency_ms=latency, jog_watchdog_ms=watchdog,
                         axes=MappingProxyType(axes), inputs=tuple(inputs), outputs=tuple(outputs),
                         adc=tuple(adcs), pls=pls)


def load_machine(path) -> MachineConfig:
    """Read and parse a machine description file (TOML)."""
    p = Path(path)
    try:
        text = read_bounded(p, MAX_MACHINE_BYTES, "machine description").decode("utf-8")
    except OSError as e:
        raise ConfigError(f"cannot read the machine file: {e.strerror or e}", str(p)) from None
    except UnicodeDecodeError as e:
        raise ConfigError(f"not UTF-8 text ({e.reason} at byte {e.start})", str(p)) from None
    return parse_machine(text, str(p))


DEFAULT_MACHINE_RESOURCE = ("resources", "machine", "default.toml")


def default_machine_text() -> str:
    """The text of the built-in default machine description."""
    from plcbuilder._support.package_data import data_folder
    return data_folder(*DEFAULT_MACHINE_RESOURCE[:-1]).joinpath(
        DEFAULT_MACHINE_RESOURCE[-1]).read_text(encoding="utf-8")


_default_cache: Optional[MachineConfig] = None


def default_machine() -> MachineConfig:
    """The default machine (package data ``resources/machine/default.toml``)."""
    global _default_cache
    if _default_cache is None:
        text = default_machine_text()
        data = None
        try:        # read once by tomllib, kept as literals: no TOML parse at every start
            from plcbuilder.controller import default_machine_data as kept
            data = kept.DATA if kept.TEXT == text else None     # never a stale copy
        except ImportError:
            pass
        _default_cache = parse_machine(text, "<default machine>", data)
    return _default_cache


def default_machine_data_source() -> str:
    """The text of ``default_machine_data.py``: the default machine's file as
    tomllib reads it. Written by ``python -m plcbuilder.controller.machine_config``
    after a change to ``resources/machine/default.toml`` (a test says when)."""
    import tomllib
    text = default_machine_text()
    return ('"""The default machine (resources/machine/default.toml) as tomllib reads it,\n'
            "kept as literals so a command starts without tomllib. Generated by\n"
            "``python -m plcbuilder.controller.machine_config``; do not edit. It is used\n"
            'only while TEXT is the file\'s text."""\n\n'
            f"TEXT = {text!r}\n\nDATA = {tomllib.loads(text)!r}\n")


if __name__ == "__main__":
    _here = Path(__file__).with_name("default_machine_data.py")
    _here.write_text(default_machine_data_source(), encoding="utf-8")
    print(f"wrote {_here}")
