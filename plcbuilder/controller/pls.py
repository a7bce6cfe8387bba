"""Programmable limit switches (PLS), as the softMC seed describes them.

A PLS watches one axis and drives one output (physical, or virtual VOUT.n). It
has an increasing list of positions p1 < p2 < … < pn where its output toggles,
an initial polarity, a repeat interval and a hysteresis, and it is enabled and
disabled at run time. The rules (docs: the targets chapter):

* The output is a function of how many switch points lie at or below the axis
  position: with c of them, the output is ``polarity`` when c is odd (c = 1 is the
  first segment, p1 ≤ x < p2) and the other level when c is even. So enabling the
  PLS anywhere sets the output "according to the current position so that when
  the axis reaches the first segment, the output polarity is as indicated".
* The default polarity is 0: "The default value for polarity is 0", which the
  seed says three times ("PLSPOLARITY defaults to OFF", "The default output
  state of a PLS is 0"); one sentence of its set-up list says "The initial
  output polarity is 1" (docs/targets.md says why we follow the three).
* "There is no limit of the number of positions or PLSs that can be defined":
  PLS k exists for every k the register layout reaches (bytecode/softmc.py),
  made when the machine file defines it or a procedure first writes to it; its
  COUNT (the seed's ``CreatePLSData n``) sizes its positions, 1-based, and
  reading or writing one outside 1..COUNT is refused ("an error is generated
  if you attempt to access an index outside of the array bounds").
* ``DeletePLS``: writing its DELETE field removes a disabled PLS (refused while
  it is enabled); the next write to its registers declares it anew.
* With a repeat interval R > 0 the switch points are p_i + m·R for every integer
  m (the positions must span less than R), so each point still toggles.
* Hysteresis h moves every switch point h/2 forward for positive motion and h/2
  backward for negative motion: the count only rises once x ≥ p + h/2 and only
  falls once x < p − h/2, so noise smaller than h around a point changes nothing.
  (Positions are integers in 0.01 mm; the halves are kept exact by working in
  doubled units.)
* The output is written when the PLS is enabled (always) and then whenever its
  level changes — a procedure may write the same output between changes.
  Disabling leaves the output as it is.
* Properties change only while the PLS is disabled. A register write that would
  change one while it is enabled is refused: nothing changes, ``PLS<k>_STATUS``
  reads ``PLS_REFUSED_ENABLED`` and the run log gets a warning (once per PLS,
  field and reason until the machine resets). Every write sets
  the status (0 when taken). Enabling checks the positions (``PLS_BAD_POSITIONS``)
  and that the output and the axis exist (``PLS_NOT_READY``).

The machine calls :meth:`PlsBank.update` after the motion has advanced each ms,
so the evaluation is deterministic.
"""

from __future__ import annotations

import math
from bisect import bisect_right

from plcbuilder.bytecode import softmc
from plcbuilder.bytecode.abi import AXES
from plcbuilder.bytecode.softmc import (F_AXIS, F_AXISNAME, F_COUNT, F_DELETE, F_ENABLE,
                                        F_HYSTERESIS, F_OUTPUT, F_POLARITY, F_POSITION, F_REPEAT,
                                        F_STATE, F_STATUS)

from .pls_config import PlsConfig

TYPE_CHECKING = False               # (typing is not imported at run time: start-up)
if TYPE_CHECKING:
    from typing import Callable, Optional

OK, REFUSED_ENABLED, BAD_VALUE, BAD_POSITIONS, NOT_READY, OUT_OF_BOUNDS = (
    softmc.PLS_STATUS[k] for k in ("PLS_OK", "PLS_REFUSED_ENABLED", "PLS_BAD_VALUE",
                                   "PLS_BAD_POSITIONS", "PLS_NOT_READY", "PLS_OUT_OF_BOUNDS"))
_PROPERTY_FIELDS = (F_AXIS, F_OUTPUT, F_POLARITY, F_REPEAT, F_HYSTERESIS, F_COUNT)
_I32_MAX = (1 << 31) - 1


def count_at(points2: list[int], repeat2: int, y2: int) -> int:
    """How many switch points lie at or below ``y2`` (everything doubled), counted
    from the base pattern: with a repeat, points of earlier repetitions count
    negative, so that the count goes up by one at every point."""
    if not repeat2:
        return bisect_right(points2, y2)
    m, rest = divmod(y2 - points2[0], repeat2)
    return m * len(points2) + bisect_right(points2, points2[0] + rest)


def level(polarity: int, count: int) -> int:
    """The output for ``count`` points at or below the position."""
    return polarity if (count - 1) & 1 == 0 else 1 - polarity


class Pls:
    """One programmable limit switch: its properties and, while enabled, its state."""

    def __init__(self, number: int, name: str = ""):
        self.number = number
        self.name = name or f"PLS{number}"
        # the seed's state after "Common Shared MyPLS as PLS": one position at 0,
        # no repeat, no hysteresis, disabled (polarity: the seed's default, 0);
        # no output until one is set
        self.axis = 0
        self.target = softmc.PLS_NO_OUTPUT
        self.polarity = softmc.PLS_DEFAULT_POLARITY
        self.repeat = 0
        self.hysteresis = 0
        self.count = 1
        self.positions = [0]
        self.enabled = False
        self.state = 0
        self.status = OK
        self._points2: list[int] = []
        self._count = 0
        self._down = self._up = 0     # the band (doubled) in which the count stays

    @classmethod
    def from_config(cls, number: int, c: PlsConfig) -> "Pls":
        p = cls(number, c.name)
        p.axis = AXES.index(c.axis)
        p.target = c.target
        p.polarity = c.polarity
        p.repeat = c.repeat
        p.hysteresis = c.hysteresis
        p.count = len(c.positions)
        p.positions = list(c.positions)
        return p

    def resize(self, n: int) -> None:
        """COUNT := n (the seed's CreatePLSData n): the first positions kept, new ones 0."""
        self.count = n
        del self.positions[n:]
        self.positions += [0] * (n - len(self.positions))

    def points(self) -> list[int]:
        return self.positions[:self.count]

    def check_positions(self) -> Optional[str]:
        """Why the positions cannot be used, or None."""
        pts = self.points()
        for i in range(1, len(pts)):
            if pts[i] <= pts[i - 1]:
                return (f"position {i + 1} ({pts[i]}) is not above position {i} "
                        f"({pts[i - 1]})")
        if self.repeat and pts[-1] - pts[0] >= self.repeat:
            return (f"the positions span {pts[-1] - pts[0]}, not less than the repeat "
                    f"interval {self.repeat}")
        return None

    def start(self, x: int) -> int:
        """Enable at axis position ``x`` (0.01 mm); the output level to write."""
        self._points2 = [2 * p for p in self.points()]
        self._count = count_at(self._points2, 2 * self.repeat, 2 * x)
        self._band()
        self.enabled = True
        self.state = level(self.polarity, self._count)
        return self.state

    def _point2(self, i: int) -> float:
        """The i-th switch point (1-based over the whole repeated pattern), doubled;
        ±inf past the ends of a pattern that does not repeat."""
        pts = self._points2
        if self.repeat:
            m, j = divmod(i - 1, len(pts))
            return pts[j] + 2 * m * self.repeat
        if i < 1:
            return -math.inf
        return pts[i - 1] if i <= len(pts) else math.inf

    def _band(self) -> None:
        # the count changes only once 2x - h reaches the next point up, or 2x + h
        # drops below the point the count last passed
        self._down = self._point2(self._count)
        self._up = self._point2(self._count + 1)

    def follow(self, x: int) -> bool:
        """The axis is at ``x``: move the count within the hysteresis band. True
        when the output level changed."""
        y, h = 2 * x, self.hysteresis
        if self._down <= y + h and y - h < self._up:
            return False                        # inside the band: nothing to do
        pts, r2 = self._points2, 2 * self.repeat
        c = self._count
        lo = count_at(pts, r2, y - h)           # points passed going up (p + h/2 <= x)
        if c < lo:
            c = lo
        else:
            hi = count_at(pts, r2, y + h)       # points still below going down (p - h/2 <= x)
            if c > hi:
                c = hi
        if c == self._count:
            return False
        self._count = c
        self._band()
        new = level(self.polarity, c)
        if new == self.state:
            return False
        self.state = new
        return True

    def report(self) -> dict:
        return {"pls": self.number, "name": self.name, "axis": AXES[self.axis],
                "output": _target_text(self.target), "enabled": self.enabled,
                "state": self.state}


def _target_text(target: int) -> Optional[str]:
    if target >= softmc.PLS_VOUT:
        return f"VOUT.{target - softmc.PLS_VOUT}"
    if target >= 0:
        return f"output {target}"
    return None


class PlsBank:
    """The PLSs of a machine: their registers, their evaluation each ms.

    PLS k is made when the machine file defines it or a procedure first writes
    to it (a read of one never written gives a newly declared PLS's values).
    ``axis_present(i)``, ``position(i)`` and ``write(target, level)`` connect it to
    the machine; ``notes`` is the machine's list of (level, text) notes."""

    def __init__(self, configs: tuple[PlsConfig, ...], *, output_count: int,
                 axis_present: Callable[[int], bool], position: Callable[[int], int],
                 write: Callable[[int, int], None], notes: list):
        self._configs = configs
        self._output_count = output_count
        self._axis_present = axis_present
        self._position = position
        self._write = write
        self._notes = notes
        self.units: dict[int, Pls] = self._define()
        self.active: list[Pls] = []
        self._warned: set = set()
        #: what a PLS not declared yet reads
        self._blank = Pls(0)

    def _define(self) -> dict[int, Pls]:
        return {k + 1: Pls.from_config(k + 1, c) for k, c in enumerate(self._configs)}

    def reset(self) -> None:
        """Power-on: the machine file's PLSs as defined, no other, the ones
        marked ``enabled`` enabled at the start position (the machine calls it
        once its outputs and positions are reset)."""
        self._warned.clear()
        self.units = self._define()
        self.active = []
        for k, c in enumerate(self._configs):
            if c.enabled:
                self._enable(self.units[k + 1])

    def unit(self, k: int) -> Pls:
        """PLS k, declared now if it was not (k from 1 to softmc.PLS_NUMBER_MAX)."""
        p = self.units.get(k)
        if p is None:
            p = self.units[k] = Pls(k)
        return p

    # ---------------------------------------------------------------- run
    def update(self) -> None:
        """After the motion advanced: every enabled PLS follows its axis."""
        pos = self._position
        for p in self.active:
            if p.follow(pos(p.axis)):
                self._write(p.target, p.state)

    def report(self) -> list[dict]:
        """The PLSs that exist (the machine file's, and those a procedure declared), by number."""
        return [self.units[k].report() for k in sorted(self.units)]

    # ---------------------------------------------------------- registers
    def read_register(self, addr: int) -> int:
        """gvarget(addr) of a PLS register (softmc.pls_field(addr) is not None)."""
        k, off = softmc.pls_field(addr)
        return self.read(k, off)

    def write_register(self, addr: int, value: int) -> None:
        k, off = softmc.pls_field(addr)
        self.write(k, off, value)

    def read(self, k: int, off: int) -> int:
        p = self.units.get(k) or self._blank
        if off >= F_POSITION:
            i = off - F_POSITION
            if i >= p.count:
                if k in self.units:
                    self._refuse(p, off, None, OUT_OF_BOUNDS, self._bounds(p, i))
                return 0
            return p.positions[i]
        if off == F_AXISNAME:
            return ord(AXES[p.axis])
        return {F_ENABLE: int(p.enabled), F_AXIS: p.axis, F_OUTPUT: p.target,
                F_POLARITY: p.polarity, F_REPEAT: p.repeat, F_HYSTERESIS: p.hysteresis,
                F_COUNT: p.count, F_STATE: p.state, F_STATUS: p.status, F_DELETE: 0}[off]

    def write(self, k: int, off: int, value: int) -> None:
        """A procedure's gvarset on field ``off`` of PLS k."""
        p = self.unit(k)
        if off == F_STATUS:
            p.status = OK                       # writing the status clears it
            return
        if off in (F_STATE, F_AXISNAME):
            self._refuse(p, off, value, BAD_VALUE, "the field is read-only")
            return
        if off == F_ENABLE:
            if value and not p.enabled:
                self._enable(p, off)
            elif not value and p.enabled:
                p.enabled = False
                self.active.remove(p)
                p.status = OK
            else:
                p.status = OK
            return
        if p.enabled:
            self._refuse(p, off, value, REFUSED_ENABLED,
                         f"{p.name} is enabled; disable it (gvarset({softmc.pls_base(k)}, 0)) "
                         "to change it")
            return
        if off == F_DELETE:
            if value:
                del self.units[k]               # DeletePLS: declared anew by the next write
            else:
                p.status = OK
            return
        if off >= F_POSITION:
            i = off - F_POSITION
            if i >= p.count:
                self._refuse(p, off, value, OUT_OF_BOUNDS, self._bounds(p, i))
                return
            p.positions[i] = value
            p.status = OK
            return
        why = self._bad_value(off, value)
        if why:
            self._refuse(p, off, value, BAD_VALUE, why)
            return
        if off == F_COUNT:
            p.resize(value)
        else:
            setattr(p, {F_AXIS: "axis", F_OUTPUT: "target", F_POLARITY: "polarity",
                        F_REPEAT: "repeat", F_HYSTERESIS: "hysteresis"}[off], value)
        p.status = OK

    @staticmethod
    def _bounds(p: Pls, i: int) -> str:
        return (f"{p.name} has positions 1..{p.count} (PLS{p.number}_COUNT), not {i + 1}; "
                f"set its COUNT first (the seed's CreatePLSData)")

    def _bad_value(self, off: int, v: int) -> Optional[str]:
        if off == F_AXIS and not 0 <= v < len(AXES):
            return f"axis {v}: axes are 0..{len(AXES) - 1} (X..W)"
        if off == F_OUTPUT and not (v == softmc.PLS_NO_OUTPUT or 0 <= v < self._output_count
                                    or softmc.PLS_VOUT < v <= softmc.PLS_VOUT
                                    + softmc.VIRTUAL_BITS):
            return (f"output {v}: outputs are 0..{self._output_count - 1}, virtual outputs "
                    f"{softmc.PLS_VOUT + 1}..{softmc.PLS_VOUT + softmc.VIRTUAL_BITS} "
                    f"(PLS_VOUT + n), -1 none")
        if off == F_POLARITY and v not in (0, 1):
            return f"polarity {v}: 0 or 1"
        if off in (F_REPEAT, F_HYSTERESIS) and v < 0:
            return f"{v}: must not be negative"
        if off == F_COUNT and not 1 <= v <= softmc.PLS_POSITIONS_MAX:
            return f"{v} positions: at least 1 (the register layout has room for " \
                   f"{softmc.PLS_POSITIONS_MAX})"
        return None

    def _enable(self, p: Pls, off: int = F_ENABLE) -> None:
        if p.target == softmc.PLS_NO_OUTPUT or not self._axis_present(p.axis):
            what = "it has no output" if p.target == softmc.PLS_NO_OUTPUT else \
                f"axis {AXES[p.axis]} is not on this machine"
            self._refuse(p, off, 1, NOT_READY, f"cannot enable {p.name}: {what}")
            return
        bad = p.check_positions()
        if bad:
            self._refuse(p, off, 1, BAD_POSITIONS, f"cannot enable {p.name}: {bad}")
            return
        self._write(p.target, p.start(self._position(p.axis)))
        self.active.append(p)
        self.active.sort(key=lambda u: u.number)   # a fixed order: PLS1 first
        p.status = OK

    def _refuse(self, p: Pls, off: int, value: Optional[int], code: int, why: str) -> None:
        p.status = code
        addr = softmc.pls_base(p.number) + off
        key = (p.number, off, code)
        if key not in self._warned:
            self._warned.add(key)
            what = f"gvarset({addr}, {value})" if value is not None else f"gvarget({addr})"
            self._notes.append(("warning", f"{what} refused: {why}"))
