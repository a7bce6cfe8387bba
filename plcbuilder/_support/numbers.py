"""Whole numbers from text (command-line options, scenario lines), refused
outside their range instead of wrapping.

    parse_int_in(text, lo, hi, what)   decimal or 0x hex, lo <= value <= hi
    WORD32      -2147483648..4294967295: a 32-bit word, written signed or unsigned
    INT32       -2147483648..2147483647
    to_int32    a WORD32 value as the signed 32-bit value a register holds
"""

from __future__ import annotations

from .lazy import Pattern

INT32 = (-(1 << 31), (1 << 31) - 1)
WORD32 = (-(1 << 31), (1 << 32) - 1)

#: (compiled when first used: not at every start)
_NUM = Pattern(r"([-+]?)(?:0[xX]([0-9a-fA-F]+)|(\d+))")
_MAX_DIGITS = 100        # longer is certainly not a number we take


def range_text(lo: int, hi: int) -> str:
    return f"from {lo} to {hi}"


def parse_int_in(text: str, lo: int, hi: int, what: str) -> int:
    """The integer ``text`` says (decimal, or 0x hex), when ``lo <= value <= hi``;
    (``what`` empty: the message starts with ``must``)
    else ValueError: ``WHAT must be a whole number (decimal or 0x hex), not …``
    or ``WHAT must be from LO to HI, not TEXT``."""
    what = f"{what} " if what else ""
    t = str(text).strip()
    m = _NUM.fullmatch(t) if len(t) <= _MAX_DIGITS else None
    if m is None:
        raise ValueError(f"{what}must be a whole number (decimal or 0x hex), "
                         f"not {str(text)[:40]!r}")
    v = int(m.group(2), 16) if m.group(2) else int(m.group(3), 10)
    if m.group(1) == "-":
        v = -v
    if not lo <= v <= hi:
        raise ValueError(f"{what}must be {range_text(lo, hi)}, not {t}")
    return v


def to_int32(v: int) -> int:
    """A 32-bit word (signed or unsigned) as a signed 32-bit value."""
    v &= 0xFFFFFFFF
    return v - (1 << 32) if v >= 1 << 31 else v
