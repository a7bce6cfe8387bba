"""Programmable limit switches in the machine file: the ``[[pls]]`` tables.

```toml
[[pls]]
name = "cam"                 # optional, for the report and the panels
axis = "X"                   # the axis whose position drives it
output = 7                   # a physical output ... or vout = 1..32 (a virtual one)
positions = [1.0, 2.0]       # mm, strictly increasing, as many as needed
polarity = 1                 # the output between positions 1 and 2 (default 0)
repeat = 0.0                 # mm: the pattern repeats every `repeat` (0: no repetition)
hysteresis = 0.0             # mm: split half each way by the direction of motion
enabled = false              # enabled at power-on
```

The k-th ``[[pls]]`` table is PLS k of the registers. Neither the tables nor
their positions are capped (the seed: "There is no limit of the number of
positions or PLSs that can be defined") beyond what the register layout
reaches (:data:`softmc.PLS_NUMBER_MAX`, :data:`softmc.PLS_POSITIONS_MAX`). The
polarity defaults to 0, the seed's "The default value for polarity is 0". Parsed by
:func:`parse_pls` with the machine file's reader, so every problem names the file,
the line and the key.
"""

from __future__ import annotations

from plcbuilder._support.records import dataclass
from plcbuilder.bytecode import softmc
from plcbuilder.bytecode.abi import AXES

TYPE_CHECKING = False               # (typing is not imported at run time: start-up)
if TYPE_CHECKING:
    from typing import Any, Optional

PLS_KEYS = {"name", "axis", "output", "vout", "positions", "polarity", "repeat", "hysteresis",
            "enabled"}
_BIG_MM = 1e7


@dataclass(frozen=True)
class PlsConfig:
    """One PLS of the machine file, in the PLC's units (0.01 mm)."""
    name: str
    axis: str
    output: Optional[int]           # a physical output, or None
    vout: Optional[int]             # VOUT.n (1..32), or None
    positions: tuple[int, ...]      # 0.01 mm, strictly increasing
    polarity: int = softmc.PLS_DEFAULT_POLARITY
    repeat: int = 0                 # 0.01 mm
    hysteresis: int = 0             # 0.01 mm
    enabled: bool = False

    @property
    def target(self) -> int:
        """The OUTPUT register's encoding of where it writes."""
        return softmc.PLS_VOUT + self.vout if self.vout is not None else self.output


def parse_pls(r, data: Any, axes, n_out: int) -> tuple[PlsConfig, ...]:
    """The ``[[pls]]`` tables; ``r`` is machine_config's reader, ``axes`` the
    configured axes, ``n_out`` the number of outputs."""
    entries = r.tables(data, "pls", PLS_KEYS, "axis")
    if len(data) > softmc.PLS_NUMBER_MAX:
        raise r.error(("pls", softmc.PLS_NUMBER_MAX),
                      f"{len(data)} programmable limit switches: the register layout has "
                      f"room for {softmc.PLS_NUMBER_MAX}")
    out = []
    for k, p, d in entries:
        ax = r.string(d, "axis", p, choices=AXES)
        if ax not in axes:
            raise r.error(p + ("axis",), f"axis {ax} is not configured in [axes.{ax}]")
        r.one_of(d, p, {"output": "a physical output", "vout": "a virtual output 1..32"})
        output = r.integer(d, "output", p, None, 0, n_out - 1)
        vout = r.integer(d, "vout", p, None, 1, softmc.VIRTUAL_BITS)
        positions = _positions(r, d, p)
        repeat = _length(r, d, "repeat", p)
        if repeat and positions[-1] - positions[0] >= repeat:
            raise r.error(p + ("repeat",), f"the positions span "
                          f"{(positions[-1] - positions[0]) / 100:g} mm, which is not less than "
                          f"the repeat interval {repeat / 100:g} mm")
        out.append(PlsConfig(
            name=r.string(d, "name", p, f"PLS{k + 1}"), axis=ax, output=output, vout=vout,
            positions=positions, polarity=r.integer(d, "polarity", p, softmc.PLS_DEFAULT_POLARITY, 0, 1), repeat=repeat,
            hysteresis=_length(r, d, "hysteresis", p),
            enabled=r.boolean(d, "enabled", p, False)))
    return tuple(out)


def _positions(r, d: dict, p: tuple) -> tuple[int, ...]:
    if "positions" not in d:
        raise r.error(p, "missing key 'positions' (mm, strictly increasing)")
    raw = d["positions"]
    if not isinstance(raw, list) or not raw:
        raise r.error(p + ("positions",), "expected a non-empty array of positions (mm)")
    if len(raw) > softmc.PLS_POSITIONS_MAX:
        raise r.error(p + ("positions",), f"{len(raw)} positions: the register layout has "
                                          f"room for {softmc.PLS_POSITIONS_MAX}")
    vals: list[int] = []
    for i, v in enumerate(raw):
        mm = r.number({"positions": v}, "positions", p, None, -_BIG_MM, _BIG_MM)
        c = round(mm * 100)
        if vals and c <= vals[-1]:
            raise r.error(p + ("positions",),
                          f"positions must increase: position {i + 1} ({v} mm) is not above "
                          f"position {i} ({raw[i - 1]} mm) at the machine's 0.01 mm resolution")
        vals.append(c)
    return tuple(vals)


def _length(r, d: dict, key: str, p: tuple) -> int:
    v = r.number(d, key, p, 0.0, 0.0, _BIG_MM, unit="mm")
    return round(v * 100)
