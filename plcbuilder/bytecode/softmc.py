"""softMC software I/O and programmable limit switches: register addresses and names.

The softMC seed (``004_87c8f6c16dc5ce4a.txt``) gives every controller 32 virtual
inputs and 32 virtual outputs (VIN.1..32, VOUT.1..32) and programmable limit
switches (PLS). PLC Builder reaches them through ``gvarget``/``gvarset`` on the
addresses below, which lie in blocks that no myCNC register uses. The names are
built-in names of the language (:data:`NAMES`, and :func:`dynamic_name` for the
PLSs past the eighth); the users' table is in the manual (the targets chapter,
"softMC virtual I/O and programmable limit switches").

=========================  ===================================================
30000  VIN_WORD            the 32 virtual inputs as one word (VIN.n = bit n-1)
30001  VOUT_WORD           the 32 virtual outputs as one word (VOUT.n = bit n-1)
30002  IO_DAT_DIP          the DIP value of the project's IO.DAT (read-only)
30101..30132               VIN_1..VIN_32: one virtual input, 0 or 1
30201..30232               VOUT_1..VOUT_32: one virtual output, 0 or 1
31000000 + 100000·k + f    field f of PLS k (k = 1, 2, …), fields below
=========================  ===================================================

"There is no limit of the number of positions or PLSs that can be defined"
(the seed): the layout does not cap either. PLS k's block is 100000 registers
long, so PLS numbers go up to :data:`PLS_NUMBER_MAX` (21164) and a PLS up to
:data:`PLS_POSITIONS_MAX` (99900) positions before the 32-bit register
addresses run out; the machine file's PLSs are PLS1, PLS2, … in its order.

PLS fields (``PLS<k>_<FIELD>`` = 31000000 + 100000·k + offset): ENABLE 0, AXIS 1
(0..8 for X..W), OUTPUT 2 (n: physical output n; ``PLS_VOUT`` + n: VOUT.n; -1:
none), POLARITY 3, REPEAT 4 (0.01 mm, 0: none), HYSTERESIS 5 (0.01 mm), COUNT 6
(how many positions: the seed's ``CreatePLSData n``), STATE 7 (the PLS output
now, read-only), STATUS 8 (what the last write to this PLS did: ``PLS_OK`` or a
refusal code), DELETE 9 (writing 1 is the seed's ``DeletePLS``), AXISNAME 10
(the seed's ``PLSAxisName``: the axis letter's character code, 88 for X;
read-only), POSITION 100 + i - 1 (position i, 0.01 mm).
"""

from __future__ import annotations

from plcbuilder._support.lazy import Pattern

TYPE_CHECKING = False               # (typing is not imported at run time: start-up)
if TYPE_CHECKING:
    from typing import Optional

VIN_WORD = 30000
VOUT_WORD = 30001
IO_DAT_DIP = 30002
VIN_BIT_BASE = 30100       # VIN.n = 30100 + n (n = 1..32)
VOUT_BIT_BASE = 30200      # VOUT.n = 30200 + n
VIRTUAL_BITS = 32

PLS_BASE = 31_000_000      # PLS k: 31000000 + 100000·k
PLS_STRIDE = 100_000
PLS_POSITION_OFFSET = 100
#: the bounds the 32-bit register addresses set (the seed sets none)
PLS_NUMBER_MAX = ((1 << 31) - 1 - PLS_BASE) // PLS_STRIDE - 1
PLS_POSITIONS_MAX = PLS_STRIDE - PLS_POSITION_OFFSET
#: the PLSs whose register names are listed (completion, the register browser);
#: the names of every other PLS k work all the same (:func:`dynamic_name`)
PLS_NAMED = 8
PLS_VOUT = 1000            # OUTPUT = PLS_VOUT + n drives VOUT.n
PLS_NO_OUTPUT = -1

#: field name -> offset inside one PLS's block
PLS_FIELDS: dict[str, int] = {
    "ENABLE": 0, "AXIS": 1, "OUTPUT": 2, "POLARITY": 3, "REPEAT": 4, "HYSTERESIS": 5,
    "COUNT": 6, "STATE": 7, "STATUS": 8, "DELETE": 9, "AXISNAME": 10,
    "POSITION": PLS_POSITION_OFFSET,
}
F_ENABLE, F_AXIS, F_OUTPUT, F_POLARITY, F_REPEAT, F_HYSTERESIS, F_COUNT, F_STATE, F_STATUS, \
    F_DELETE, F_AXISNAME, F_POSITION = (
        PLS_FIELDS[k] for k in ("ENABLE", "AXIS", "OUTPUT", "POLARITY", "REPEAT", "HYSTERESIS",
                                "COUNT", "STATE", "STATUS", "DELETE", "AXISNAME", "POSITION"))
#: the seed's default polarity ("The default value for polarity is 0", docs/targets.md)
PLS_DEFAULT_POLARITY = 0

#: what PLS<k>_STATUS reads after a write to PLS k
PLS_STATUS: dict[str, int] = {
    "PLS_OK": 0,                  # the write was taken
    "PLS_REFUSED_ENABLED": 1,     # a property was written while the PLS is enabled
    "PLS_BAD_VALUE": 2,           # the value is out of range for that field
    "PLS_BAD_POSITIONS": 3,       # enable refused: positions not increasing / longer than REPEAT
    "PLS_NOT_READY": 4,           # enable refused: no output, or the axis is not on the machine
    "PLS_OUT_OF_BOUNDS": 5,       # a position outside 1..COUNT (the seed: "an error is generated")
}
PLS_STATUS_TEXT: dict[int, str] = {
    0: "ok",
    1: "refused: the PLS is enabled (disable it to change it)",
    2: "refused: value out of range",
    3: "enable refused: positions must increase (and span less than the repeat interval)",
    4: "enable refused: no output, or its axis is not on this machine",
    5: "refused: the position is outside 1..COUNT",
}


def pls_base(k: int) -> int:
    """The first address of PLS ``k`` (1, 2, …)."""
    return PLS_BASE + PLS_STRIDE * k


#: the addresses of every PLS's registers: [PLS_FIRST, PLS_END)
PLS_FIRST = pls_base(1)
PLS_END = pls_base(PLS_NUMBER_MAX + 1)
_FIELD_OFFSETS = frozenset(o for o in PLS_FIELDS.values() if o != PLS_POSITION_OFFSET)


def pls_field(addr: int) -> Optional[tuple[int, int]]:
    """``(k, offset)`` when ``addr`` is a field of PLS k (a position's offset is
    ``F_POSITION + i - 1``), else None."""
    if not PLS_FIRST <= addr < PLS_END:
        return None
    k, off = divmod(addr - PLS_BASE, PLS_STRIDE)
    if off in _FIELD_OFFSETS or off >= F_POSITION:
        return k, off
    return None


_DYNAMIC = Pattern(r"PLS([1-9][0-9]*)_([A-Z]+)")


def dynamic_name(name: str) -> Optional[int]:
    """The register of a ``PLS<k>_<FIELD>`` name for any PLS number k (PLS9_ENABLE
    and on are not listed in :data:`REGISTERS`, but are names all the same)."""
    m = _DYNAMIC.fullmatch(name)
    if m is None or m.group(2) not in PLS_FIELDS:
        return None
    k = int(m.group(1))
    return pls_base(k) + PLS_FIELDS[m.group(2)] if k <= PLS_NUMBER_MAX else None


#: the registers' built-in names
REGISTERS: dict[str, int] = {"VIN_WORD": VIN_WORD, "VOUT_WORD": VOUT_WORD, "IO_DAT_DIP": IO_DAT_DIP}
for _n in range(1, VIRTUAL_BITS + 1):
    REGISTERS[f"VIN_{_n}"] = VIN_BIT_BASE + _n
for _n in range(1, VIRTUAL_BITS + 1):
    REGISTERS[f"VOUT_{_n}"] = VOUT_BIT_BASE + _n
for _k in range(1, PLS_NAMED + 1):
    for _f, _off in PLS_FIELDS.items():
        REGISTERS[f"PLS{_k}_{_f}"] = pls_base(_k) + _off
#: the constants' built-in names (an OUTPUT value base, the STATUS codes)
CONSTANTS: dict[str, int] = {"PLS_VOUT": PLS_VOUT, "PLS_NO_OUTPUT": PLS_NO_OUTPUT, **PLS_STATUS}
#: every built-in name this module adds
NAMES: dict[str, int] = {**REGISTERS, **CONSTANTS}

_FIELD_TEXT = {
    F_ENABLE: "enable (1 on, 0 off)", F_AXIS: "axis (0..8 for X..W)",
    F_OUTPUT: "output (n: output n; PLS_VOUT+n: VOUT.n; -1: none)",
    F_POLARITY: "polarity in the first segment (0 or 1)",
    F_REPEAT: "repeat interval, 0.01 mm (0: none)", F_HYSTERESIS: "hysteresis, 0.01 mm",
    F_COUNT: "number of positions (CreatePLSData n)", F_STATE: "output state now (read-only)",
    F_STATUS: "result of the last write (0 ok; 1 enabled; 2 bad value; 3 bad positions; "
              "4 not ready; 5 position out of bounds)",
    F_DELETE: "write 1 to delete it (DeletePLS; only while disabled)",
    F_AXISNAME: "the axis name's character code, 88 for X (PLSAxisName; read-only)",
}


def describe(addr: int) -> Optional[str]:
    """What a softMC register is, in words, or None."""
    if addr == VIN_WORD:
        return "VIN_WORD: the 32 virtual inputs (VIN.n is bit n-1)"
    if addr == VOUT_WORD:
        return "VOUT_WORD: the 32 virtual outputs (VOUT.n is bit n-1)"
    if addr == IO_DAT_DIP:
        return "IO_DAT_DIP: the DIP value of the project's IO.DAT (read-only)"
    if VIN_BIT_BASE < addr <= VIN_BIT_BASE + VIRTUAL_BITS:
        return f"VIN_{addr - VIN_BIT_BASE}: virtual input {addr - VIN_BIT_BASE}"
    if VOUT_BIT_BASE < addr <= VOUT_BIT_BASE + VIRTUAL_BITS:
        return f"VOUT_{addr - VOUT_BIT_BASE}: virtual output {addr - VOUT_BIT_BASE}"
    kf = pls_field(addr)
    if kf is None:
        return None
    k, off = kf
    if off >= F_POSITION:
        return f"PLS{k} position {off - F_POSITION + 1} (0.01 mm)"
    return f"PLS{k} {_FIELD_TEXT[off]}"
