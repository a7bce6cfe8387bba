"""softMC software I/O and programmable limit switches: register addresses and names.

The softMC seed (``004_87c8f6c16dc5ce4a.txt``) gives every controller 32 virtual
inputs and 32 virtual outputs (VIN.1..32, VOUT.1..32) and programmable limit
switches (PLS). PLC Builder reaches them through ``gvarget``/``gvarset`` on the
addresses below, which lie in a block (30000..31899) that no myCNC register uses.
The names are built-in names of the language (:data:`NAMES`); the users' table is
in the manual (the targets chapter, "softMC virtual I/O and programmable limit
switches").

=====================  ===================================================
30000  VIN_WORD        the 32 virtual inputs as one word (VIN.n = bit n-1)
30001  VOUT_WORD       the 32 virtual outputs as one word (VOUT.n = bit n-1)
30002  IO_DAT_DIP      the DIP value of the project's IO.DAT (read-only)
30101..30132           VIN_1..VIN_32: one virtual input, 0 or 1
30201..30232           VOUT_1..VOUT_32: one virtual output, 0 or 1
31000 + 100·k + f      field f of PLS k (k = 1..8), fields below
=====================  ===================================================

PLS fields (``PLS<k>_<FIELD>`` = 31000 + 100·k + offset): ENABLE 0, AXIS 1 (0..8
for X..W), OUTPUT 2 (n: physical output n; ``PLS_VOUT`` + n: VOUT.n; -1: none),
POLARITY 3, REPEAT 4 (0.01 mm, 0: none), HYSTERESIS 5 (0.01 mm), COUNT 6 (how
many positions, 1..16), STATE 7 (the PLS output now, read-only), STATUS 8 (what
the last write to this PLS did: ``PLS_OK`` or a refusal code), POSITION 10..25
(positions 1..16, 0.01 mm).
"""

from __future__ import annotations


TYPE_CHECKING = False               # (typing is not imported at run time: start-up)
if TYPE_CHECKING:
    from typing import Optional

VIN_WORD = 30000
VOUT_WORD = 30001
IO_DAT_DIP = 30002
VIN_BIT_BASE = 30100       # VIN.n = 30100 + n (n = 1..32)
VOUT_BIT_BASE = 30200      # VOUT.n = 30200 + n
VIRTUAL_BITS = 32

PLS_COUNT_MAX = 8          # PLS1..PLS8
PLS_BASE = 31000           # PLS k: 31000 + 100·k
PLS_STRIDE = 100
PLS_POSITIONS_MAX = 16
PLS_VOUT = 1000            # OUTPUT = PLS_VOUT + n drives VOUT.n
PLS_NO_OUTPUT = -1

#: field name -> offset inside one PLS's block
PLS_FIELDS: dict[str, int] = {
    "ENABLE": 0, "AXIS": 1, "OUTPUT": 2, "POLARITY": 3, "REPEAT": 4, "HYSTERESIS": 5,
    "COUNT": 6, "STATE": 7, "STATUS": 8, "POSITION": 10,
}
F_ENABLE, F_AXIS, F_OUTPUT, F_POLARITY, F_REPEAT, F_HYSTERESIS, F_COUNT, F_STATE, F_STATUS, \
    F_POSITION = (PLS_FIELDS[k] for k in ("ENABLE", "AXIS", "OUTPUT", "POLARITY", "REPEAT",
                                         "HYSTERESIS", "COUNT", "STATE", "STATUS", "POSITION"))

#: what PLS<k>_STATUS reads after a write to PLS k
PLS_STATUS: dict[str, int] = {
    "PLS_OK": 0,                  # the write was taken
    "PLS_REFUSED_ENABLED": 1,     # a property was written while the PLS is enabled
    "PLS_BAD_VALUE": 2,           # the value is out of range for that field
    "PLS_BAD_POSITIONS": 3,       # enable refused: positions not increasing / longer than REPEAT
    "PLS_NOT_READY": 4,           # enable refused: no output, or the axis is not on the machine
}
PLS_STATUS_TEXT: dict[int, str] = {
    0: "ok",
    1: "refused: the PLS is enabled (disable it to change it)",
    2: "refused: value out of range",
    3: "enable refused: positions must increase (and span less than the repeat interval)",
    4: "enable refused: no output, or its axis is not on this machine",
}


def pls_base(k: int) -> int:
    """The first address of PLS ``k`` (1..8)."""
    return PLS_BASE + PLS_STRIDE * k


def pls_field(addr: int) -> Optional[tuple[int, int]]:
    """``(k, offset)`` when ``addr`` is a field of PLS k, else None."""
    k, off = divmod(addr - PLS_BASE, PLS_STRIDE)
    if not 1 <= k <= PLS_COUNT_MAX:
        return None
    if off in PLS_FIELDS.values() or F_POSITION <= off < F_POSITION + PLS_POSITIONS_MAX:
        return k, off
    return None


#: the registers' built-in names
REGISTERS: dict[str, int] = {"VIN_WORD": VIN_WORD, "VOUT_WORD": VOUT_WORD, "IO_DAT_DIP": IO_DAT_DIP}
for _n in range(1, VIRTUAL_BITS + 1):
    REGISTERS[f"VIN_{_n}"] = VIN_BIT_BASE + _n
for _n in range(1, VIRTUAL_BITS + 1):
    REGISTERS[f"VOUT_{_n}"] = VOUT_BIT_BASE + _n
for _k in range(1, PLS_COUNT_MAX + 1):
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
    F_COUNT: "number of positions (1..16)", F_STATE: "output state now (read-only)",
    F_STATUS: "result of the last write (0 ok; 1 enabled; 2 bad value; 3 bad positions; "
              "4 not ready)",
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
