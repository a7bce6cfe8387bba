"""softMC software I/O: 32 virtual inputs and 32 virtual outputs, and the DIP value.

Virtual inputs and outputs are plain bits that procedures (of any target), the
programmable limit switches and the host read and write; nothing in the machine
is wired to them. Each is reached as one bit (``VIN_n``/``VOUT_n``, 0 or 1) or all
32 at once as a word (``VIN_WORD``/``VOUT_WORD``, VIN.n being bit n-1), exactly as
the seed's ``System.VOut.1 = OFF`` and ``System.VOut = System.VIn``. Addresses:
:mod:`plcbuilder.bytecode.softmc`.
"""

from __future__ import annotations


from plcbuilder.bytecode import softmc
from plcbuilder.bytecode.semantics import wrap

_M32 = 0xFFFFFFFF
TYPE_CHECKING = False               # (typing is not imported at run time: start-up)
if TYPE_CHECKING:
    from typing import Callable
    Getter = Callable[[int], int]
    Setter = Callable[[int, int], None]


class VirtualIO:
    """The 32 virtual inputs and outputs (as unsigned 32-bit words) and the IO.DAT DIP value."""

    def __init__(self, dip: int = 0, on_change: Callable[[], None] = lambda: None):
        self.dip = dip
        self._on_change = on_change
        self.vin = 0
        self.vout = 0

    def reset(self) -> None:
        """Power-on: every virtual input and output 0."""
        self.vin = 0
        self.vout = 0

    def install(self, get: dict[int, Getter], put: dict[int, Setter],
                read_only: Setter) -> None:
        """Add the virtual I/O registers to a machine's register maps."""
        get[softmc.VIN_WORD] = lambda _a: wrap(self.vin)
        put[softmc.VIN_WORD] = lambda _a, v: self.set_vin_word(v)
        get[softmc.VOUT_WORD] = lambda _a: wrap(self.vout)
        put[softmc.VOUT_WORD] = lambda _a, v: self.set_vout_word(v)
        get[softmc.IO_DAT_DIP] = lambda _a: self.dip
        put[softmc.IO_DAT_DIP] = read_only
        for n in range(1, softmc.VIRTUAL_BITS + 1):
            get[softmc.VIN_BIT_BASE + n] = lambda _a, n=n: self.vin >> (n - 1) & 1
            put[softmc.VIN_BIT_BASE + n] = lambda _a, v, n=n: self.set_vin(n, v)
            get[softmc.VOUT_BIT_BASE + n] = lambda _a, n=n: self.vout >> (n - 1) & 1
            put[softmc.VOUT_BIT_BASE + n] = lambda _a, v, n=n: self.set_vout(n, v)

    # ------------------------------------------------------------- writes
    def set_vin(self, n: int, value: int) -> None:
        """VIN.n (1..32) := 1 if value else 0."""
        self._check(n)
        self.set_vin_word(_with_bit(self.vin, n, value))

    def set_vout(self, n: int, value: int) -> None:
        """VOUT.n (1..32) := 1 if value else 0."""
        self._check(n)
        self.set_vout_word(_with_bit(self.vout, n, value))

    def set_vin_word(self, value: int) -> None:
        value &= _M32
        if value != self.vin:
            self.vin = value
            self._on_change()

    def set_vout_word(self, value: int) -> None:
        value &= _M32
        if value != self.vout:
            self.vout = value
            self._on_change()

    # ------------------------------------------------------------- reads
    def vins_on(self) -> list[int]:
        """The virtual inputs that are 1, by number (1..32)."""
        return [n for n in range(1, softmc.VIRTUAL_BITS + 1) if self.vin >> (n - 1) & 1]

    def vouts_on(self) -> list[int]:
        """The virtual outputs that are 1, by number (1..32)."""
        return [n for n in range(1, softmc.VIRTUAL_BITS + 1) if self.vout >> (n - 1) & 1]

    @staticmethod
    def _check(n: int) -> None:
        if not 1 <= n <= softmc.VIRTUAL_BITS:
            raise ValueError(f"no virtual I/O {n} (they are numbered 1..{softmc.VIRTUAL_BITS})")


def _with_bit(word: int, n: int, value: int) -> int:
    bit = 1 << (n - 1)
    return word | bit if value else word & ~bit
