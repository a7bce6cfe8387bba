"""G-code programs for the simulated controller's job runner (SPEC §10).

A program is parsed and checked whole before it runs, so a job never stops
half-way on a word it cannot do: every problem is a :class:`GcodeError` that
names the file and the line.

Supported (docs/controller.md, "G-code jobs"): ``G0``/``G1`` with axis words
(``X Y Z A B C U V W``, mm or degrees) and ``F`` (mm/min), ``G4 P`` (a dwell of
P seconds), ``G28`` (home the axes named, or every axis with a home switch),
``G90``/``G91`` (absolute/incremental), ``S`` (the next ``M03``/``M04``'s eparam),
``Mnn`` (the procedure ``Mnn``), ``M2``/``M30`` (the end), ``N`` (line numbers,
ignored), ``(…)`` and ``;`` comments and ``%`` lines. On the Huazhong target
``S``, ``T`` and ``B`` (where the machine has no B axis) are functions too.

:func:`parse` gives :class:`Block` records; :mod:`plcbuilder.controller.job`
runs them.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from typing import Optional

from plcbuilder.bytecode.abi import AXES

MAX_GCODE_BYTES = 16 << 20
#: a word: a letter and a number (sign, digits, a decimal point)
_WORD = re.compile(r"([A-Za-z])\s*([+-]?(?:\d+\.?\d*|\.\d+))")
END_CODES = (2, 30)


class GcodeError(ValueError):
    """A G-code line that cannot be run; ``str()`` is ``FILE:LINE: message``."""

    def __init__(self, message: str, file: str = "", line: Optional[int] = None):
        self.message, self.file, self.line = message, file, line
        where = f"{file}:{line}: " if line is not None else (f"{file}: " if file else "")
        super().__init__(where + message)


@dataclass
class Block:
    """One line that does something, in the order its parts run: the settings
    (G90/G91, F, S), the functions (M, and S/T/B on Huazhong) in the order
    written, the dwell or the motion, and the end (M2/M30) last."""
    line: int
    text: str
    absolute: Optional[bool] = None          # G90 True, G91 False, None: unchanged
    feed: Optional[float] = None             # F, mm/min
    speed: Optional[int] = None              # S
    functions: list[tuple[str, int]] = field(default_factory=list)   # ("M", 3), ("S", 1200)
    motion: Optional[int] = None             # 0, 1 or 28 when the line moves
    modal: Optional[int] = None              # G0 / G1 set on this line
    axes: dict[int, float] = field(default_factory=dict)             # axis index -> mm
    dwell_ms: Optional[int] = None           # G4 P
    end: Optional[int] = None                # 2 or 30


@dataclass
class GcodeProgram:
    file: str
    lines: int                               # lines in the file
    blocks: list[Block]


def _number(text: str, letter: str, line: int, file: str) -> float:
    try:
        return float(text)
    except ValueError:                       # pragma: no cover - the pattern only matches numbers
        raise GcodeError(f"{letter}{text}: not a number", file, line) from None


def _code(value: float, letter: str, line: int, file: str) -> int:
    if value != int(value) or value < 0:
        raise GcodeError(f"{letter}{value:g}: {letter} takes a whole number", file, line)
    return int(value)


def parse(text: str, file: str = "job.nc", *, axes: tuple[str, ...] = AXES,
          functions: str = "M") -> GcodeProgram:
    """Check and parse a whole program. ``axes``: the machine's axis letters
    (a word for another axis is an error); ``functions``: the letters that are
    CNC functions on this target ("M" on myCNC, "MSTB" on Huazhong; S is the
    eparam of M03/M04 on myCNC)."""
    blocks: list[Block] = []
    lines = text.splitlines()
    modal = None
    feed = None
    for n, raw in enumerate(lines, 1):
        src = raw.strip()
        body = _strip_comments(src, n, file)
        if not body.strip() or body.strip() == "%":
            continue
        b = Block(n, src)
        pos = 0
        gs: list[int] = []
        p_value = None
        for m in _WORD.finditer(body):
            gap = body[pos:m.start()]
            if gap.strip():
                raise GcodeError(f"{gap.strip()!r} is not a G-code word (a letter and a number)",
                                 file, n)
            pos = m.end()
            letter, value = m.group(1).upper(), _number(m.group(2), m.group(1).upper(), n, file)
            word = f"{letter}{m.group(2)}"
            if letter == "N":
                continue
            if letter == "G":
                g = value
                if g not in (0, 1, 4, 28, 90, 91):
                    raise GcodeError(f"{word} is not supported (G0, G1, G4, G28, G90, G91 are)",
                                     file, n)
                gs.append(int(g))
            elif letter == "M":
                code = _code(value, "M", n, file)
                if code in END_CODES:
                    if b.end is not None:
                        raise GcodeError("two program ends on one line", file, n)
                    b.end = code
                else:
                    b.functions.append(("M", code))
            elif letter == "F":
                if value <= 0:
                    raise GcodeError(f"{word}: a feed rate is more than 0 (mm/min)", file, n)
                b.feed = value
            elif letter == "P":
                p_value = value
            elif letter in ("S", "T") or (letter == "B" and "B" not in axes):
                if letter != "S" and letter not in functions:
                    raise GcodeError(f"{word} is not supported on this target"
                                     + (" (the machine has no B axis)" if letter == "B" else ""),
                                     file, n)
                code = _code(value, letter, n, file)
                if letter == "S" and "S" not in functions:
                    b.speed = code
                else:
                    b.functions.append((letter, code))
            elif letter in AXES:
                if letter not in axes:
                    raise GcodeError(f"{word}: the machine has no {letter} axis (it has "
                                     f"{' '.join(axes) or 'none'})", file, n)
                i = AXES.index(letter)
                if i in b.axes:
                    raise GcodeError(f"{letter} twice on one line", file, n)
                b.axes[i] = value
            else:
                raise GcodeError(f"{word} is not supported (words: G M S F P X Y Z A B C U V W"
                                 f" N)", file, n)
        rest = body[pos:]
        if rest.strip():
            raise GcodeError(f"{rest.strip()!r} is not a G-code word (a letter and a number)",
                             file, n)
        for g in gs:
            if g in (90, 91):
                b.absolute = g == 90
            elif g in (0, 1):
                b.modal = modal = g
            elif g == 4:
                if p_value is None or p_value < 0:
                    raise GcodeError("G4 needs P, the dwell in seconds (G4 P0.5)", file, n)
                b.dwell_ms = round(p_value * 1000)
            elif g == 28:
                b.motion = 28
        if p_value is not None and b.dwell_ms is None:
            raise GcodeError("P is only G4's (the dwell in seconds)", file, n)
        if b.feed is not None:
            feed = b.feed
        motions = [g for g in gs if g in (4, 28)]
        if len(motions) > 1 or (b.dwell_ms is not None and b.axes):
            raise GcodeError("one motion a line: G4 takes no axis words", file, n)
        if b.axes and b.motion is None:
            b.motion = modal if modal is not None else 0
        if b.motion == 1 and feed is None:
            raise GcodeError("G1 needs a feed rate: give F (mm/min) on this line or before",
                             file, n)
        blocks.append(b)
    return GcodeProgram(file, len(lines), blocks)


def _strip_comments(line: str, n: int, file: str) -> str:
    out, depth = [], 0
    for ch in line:
        if depth:
            if ch == ")":
                depth = 0
            continue
        if ch == "(":
            depth = 1
            continue
        if ch == ";":
            break
        out.append(ch)
    if depth:
        raise GcodeError("a comment '(' is not closed on its line", file, n)
    return "".join(out)
