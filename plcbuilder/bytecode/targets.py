"""The target profiles' ABI: what the compiler and the controller agree on for
the controllers of SPEC §9 other than myCNC (docs/targets.md).

Neither VM has an opcode for them. A Huazhong register bank element and TG
Motion's shared memory are global registers, read with ``gvarget`` and
written with ``gvarset`` at the addresses below, so both VMs run target code
unchanged and only the controller's target scheduler gives the addresses
their meaning:

- ``X[n]`` with a constant ``n`` is the register ``bank.base + n``
  (``X[3]`` is ``gvarget(1000003)``; ``Y[0] = v`` is ``gvarset(1001000, v)``).
- ``X[e]`` with an index computed at run time goes through two latches, so
  that the controller sees the index itself and faults on one out of range:
  a read is ``gvarset(INDEX_LATCH, e); gvarget(bank.load)``, a write
  ``gvarset(VALUE_LATCH, v); gvarset(bank.store, e)`` (the value first, then
  the index: the index may read banks itself, the value latch is left alone).
- a write keeps the element's width (``Y[0] = 0x1ff`` stores 0xff); a read
  gives the element as its C type says (unsigned, or signed for ``_c``, ``_i``
  and ``_l``).
- the typed views of the seed (``R_uc``, ``R_c``, ``R_ui``, ``R_i``, ``R_ul``,
  ``R_l`` and the same of X, Y, F, G, P, B) are banks over the same bytes, with
  Borland C++ 3.1's widths (int 16 bits, long 32) and x86 byte order.
- TG Motion's ``TGM_Data`` (512 KiB) is 131072 32-bit words at
  ``TGM_DATA_BASE + i`` (word i holds bytes 4i … 4i+3).
"""

from __future__ import annotations

import re

from plcbuilder._support.lazy import Pattern
from plcbuilder._support.records import dataclass

TYPE_CHECKING = False               # (typing is not imported at run time: start-up)
if TYPE_CHECKING:
    from typing import Optional

MYCNC = "mycnc"
HUAZHONG = "huazhong"
TGMOTION = "tgmotion"
TARGETS = (MYCNC, HUAZHONG, TGMOTION)


@dataclass(frozen=True)
class Bank:
    """One Huazhong register bank, or one typed view of a bank's bytes
    (``R_ui`` reads R's bytes 2n, 2n+1 as an unsigned 16-bit number)."""
    name: str
    size: int            # elements
    bits: int            # element width
    base: int            # register of element 0 (a constant index)
    load: int            # indirect read: the element at the index latch
    store: int           # indirect write: gvarset(store, index) stores the value latch
    direction: str       # what it is for (docs, hover)
    signed: bool = False
    storage: str = ""    # the bank whose bytes it is (itself for X, Y, R, G, F, P, B)

    @property
    def mask(self) -> int:
        return (1 << self.bits) - 1

    @property
    def lo(self) -> int:
        return -(1 << (self.bits - 1)) if self.signed else 0

    @property
    def hi(self) -> int:
        return (1 << (self.bits - 1)) - 1 if self.signed else self.mask

    @property
    def width(self) -> int:
        """Bytes an element takes."""
        return self.bits // 8

    @property
    def last(self) -> int:
        return self.base + self.size - 1

    def holds(self, addr: int) -> bool:
        return self.base <= addr < self.base + self.size

    def fits(self, v: int) -> bool:
        """Whether v is stored as it is (within the element's C type)."""
        return self.lo <= v <= self.hi

    def stored(self, v: int) -> int:
        """What an element keeps of v: its low bits, sign-extended for a signed type."""
        v &= self.mask
        return v - (1 << self.bits) if self.signed and v > self.hi else v


HZ_BASE = 1_000_000
INDEX_LATCH = 1_009_000
VALUE_LATCH = 1_009_001

#: the banks: (name, bytes, the C type of the plain name's elements, what it is for)
_STORAGE = (
    ("X", 128, "uc", "machine -> PLC inputs: pin 8n+b is bit b"),
    ("Y", 128, "uc", "PLC -> machine outputs: pin 8n+b is bit b"),
    ("R", 768, "uc", "internal registers"),
    ("G", 512, "ui", "PLC -> CNC words"),
    ("F", 512, "ui", "CNC -> PLC words"),
    ("P", 200, "ui", "user parameters (project file)"),
    ("B", 200, "ui", "words kept across restarts"),
)
#: the seed's typed views: suffix -> (bits, signed, C type), with the widths of its
#: 16-bit compiler (Borland C++ 3.1: int is 16 bits, long 32)
VIEWS: dict[str, tuple[int, bool, str]] = {
    "uc": (8, False, "unsigned char"), "c": (8, True, "char"),
    "ui": (16, False, "unsigned"), "i": (16, True, "int"),
    "ul": (32, False, "unsigned long"), "l": (32, True, "long"),
}


def _banks() -> dict[str, Bank]:
    out: dict[str, Bank] = {}
    for k, (name, nbytes, plain, what) in enumerate(_STORAGE):
        bits, signed, _c = VIEWS[plain]
        out[name] = Bank(name, nbytes * 8 // bits, bits, HZ_BASE + 1000 * k, 1_009_010 + k,
                         1_009_020 + k, what, signed, name)
    for k, (name, nbytes, _plain, what) in enumerate(_STORAGE):
        for v, (suffix, (bits, signed, ctype)) in enumerate(VIEWS.items()):
            j = 6 * k + v
            out[f"{name}_{suffix}"] = Bank(
                f"{name}_{suffix}", nbytes * 8 // bits, bits, HZ_BASE + 20_000 + 1000 * j,
                1_009_100 + j, 1_009_200 + j, f"{name} as {ctype} ({what})", signed, name)
    return out


#: every bank name the language knows: X … B and their views X_uc … B_l (docs/targets.md)
BANKS: dict[str, Bank] = _banks()
#: the banks that hold bytes (the views alias them)
STORAGE_BANKS = tuple(name for name, *_ in _STORAGE)
STORAGE_BYTES = {name: nbytes for name, nbytes, *_ in _STORAGE}
#: banks the PLC reads in the batch at the start of a tick / writes at its end
HZ_READ_BANKS = ("X", "F", "P")
HZ_WRITE_BANKS = ("G", "Y", "B")
#: the CNC's side of G and F: plain global registers the batch copies to and from
CNC_G_BASE = HZ_BASE + 13_000
CNC_F_BASE = HZ_BASE + 14_000
HZ_PERIODS = ("plc1_time", "plc2_time")
HZ_DEFAULT_PERIODS = {"plc1_time": 16, "plc2_time": 32}
HZ_PROCEDURES = ("init", "plc1", "plc2")

#: axis_stat(x) is F_ui[x * 10] (the seed's macro): the CNC's status word of axis x,
#: with the seed's AX_* bits; x from 0 to 15 ("the system has at most 16 axes")
HZ_AXIS_STAT_STRIDE = 10
HZ_AXES_MAX = 16
AX_BITS: dict[str, int] = {
    "AX_SLSP": 0x0001,          # positive limit reached
    "AX_SLSN": 0x0002,          # negative limit reached
    "AX_HOME_LAMP": 0x0004,     # homing
    "AX_CMP_LAMP": 0x0008,      # backlash or pitch compensation running (never, here)
    "AX_HOME_FIN": 0x0010,      # homing finished
    "AX_FSTOP_LAMP": 0x0020,    # stopped in position
    "AX_HOME_GOING": 0x0040,    # homing
    "AX_MOVING_LAMP": 0x0080,   # moving
}
#: the M, S, B and T functions: init() registers a handler procedure with
#: set_m_func(proc) (and s, b, t), which is gvarset(HZ_FUNC_REGISTER[k], its id);
#: the handler reads the code the CNC issued at HZ_FUNC_CODE[k]
HZ_FUNCTIONS = ("M", "S", "B", "T")
HZ_FUNC_REGISTER = {k: 1_009_040 + i for i, k in enumerate(HZ_FUNCTIONS)}
HZ_FUNC_CODE = {k: 1_009_050 + i for i, k in enumerate(HZ_FUNCTIONS)}


def handler_id(name: str) -> int:
    """The number set_m_func(name) registers: a CRC-32 of the procedure's name
    (the controller finds the procedure among the program's by it)."""
    import zlib
    return zlib.crc32(name.encode("utf-8")) & 0x7FFF_FFFF


TGM_DATA_BASE = 2_000_000
TGM_DATA_WORDS = 524_288 // 4
#: the other shared memories of PLC_DATA (seed 002, 2.2), as far as the seed
#: documents them, mapped onto the machine model (docs/targets.md):
#: TGM_System: its HEADER, "The actual size of the shared memory is contained in
#: the TGM_System.HEADER.Mem_Size_Data register", and pHeader->Compatibility_Id
TGM_SYSTEM_BASE = 2_200_000
TGM_SYSTEM_FIELDS = {"Mem_Size_Data": 0, "Compatibility_Id": 1}
TGM_COMPATIBILITY_ID = 4                 # TG Motion "version 4"
#: TGM_Servo: one block per axis of the machine (X..W = servo 0..8): "the servo
#: drive positions and statuses" read, "the desired positions" written
TGM_SERVO_BASE = 2_300_000
TGM_SERVO_STRIDE = 100
TGM_SERVO_FIELDS = {"Act_Position": 0, "Status": 1, "Desired_Position": 2}
TGM_SERVO_STATUS = {"SERVO_ST_PRESENT": 0x1, "SERVO_ST_MOVING": 0x2,
                    "SERVO_ST_IN_POSITION": 0x4}
#: TGM_Dio: "the values of digital and analog inputs" and outputs, as words
TGM_DIO_BASE = 2_400_000
TGM_DIO_FIELDS = {"DI": 0, "DO": 8, "AI": 16, "AO": 24}      # 8 words each
#: TGM_Oscilloscope: "capture the values of desired registers ... and their saving into
#: the TGM_Oscilloscope shared memory": word 0 the samples taken, 1 + k signal k's last value
TGM_OSC_BASE = 2_500_000
TGM_OSC_SIGNALS_MAX = 64
#: the diagnostic prints of PLC_DATA.functions, as registers (a write prints the value)
TGM_RTW_STRING = 2_600_000
TGM_RTW_LONG = 2_600_001
TGM_RTW_EX_SEVERITY = 2_600_002
TGM_RTW_EX = 2_600_003
TGM_PROCEDURES = ("Program_Ini", "Program_01", "Program_02", "Program_03", "Program_04",
                  "Program_05")
TGM_CYCLE_TIMES = (250, 500, 1000)
#: Program_01..03's periods: at least 100 µs, no upper bound (the seed: "from 100 μs to
#: 10 000 μs (the upper value is not limited)")
TGM_PERIOD_MIN = 100
TGM_DEFAULT_INSTRUCTION_NS = 20
#: slots per cycle, by cycle time (the seed's figures)
TGM_SLOTS = {250: 5, 500: 5, 1000: 10}
#: Program_04 runs in this slot (0-based: the fourth), after Program_05
TGM_P04_SLOT = 3
#: budgets: Program_04 a share of the cycle, Program_05 in µs, 01..03 a share of their period
TGM_P04_SHARE = 0.10
TGM_P05_BUDGET_US = 10.0
TGM_LOW_SHARE = 0.20


_BY_BLOCK = {(b.base - HZ_BASE) // 1000: b for b in BANKS.values()}


def bank_at(addr: int) -> Optional[tuple[Bank, int]]:
    """(bank, index) of a constant-index register, or None."""
    b = _BY_BLOCK.get((addr - HZ_BASE) // 1000) if addr >= HZ_BASE else None
    if b is not None and b.holds(addr):
        return b, addr - b.base
    return None


INDIRECT_LOAD = {b.load: b for b in BANKS.values()}
INDIRECT_STORE = {b.store: b for b in BANKS.values()}


# ---------------------------------------------------- the oscilloscope's signals
#: what the oscilloscope samples when the project picks nothing
DEFAULT_SIGNALS = ("gvar 7180", "gvar 7184")      # input word 0, output word 0
_PIN = Pattern(r"^\s*(in|out|adc|pwm|dac|gvar)\s+(0[xX][0-9a-fA-F]+|-?[0-9]+)\s*$", re.I)
_VAR = Pattern(r"^\s*([A-Za-z_][A-Za-z0-9_]*)\.([A-Za-z_][A-Za-z0-9_]*)\s*$")
_LIMITS = {"in": 255, "out": 255, "adc": 7, "pwm": 7, "dac": 7}


class ScopeError(ValueError):
    """A signal the oscilloscope cannot sample; the message says why."""


@dataclass(frozen=True)
class Signal:
    kind: str             # in, out, adc, pwm, dac, gvar, var
    n: int = 0
    var: str = ""
    text: str = ""


def parse_signal(text: str) -> Signal:
    if not isinstance(text, str):
        raise ScopeError(f"a signal is a name (in N, out N, adc N, pwm N, dac N, gvar ADDR or "
                         f"PROGRAM.var), not {text!r}")
    m = _PIN.match(text)
    if m:
        kind, n = m.group(1).lower(), int(m.group(2), 0)
        if kind in _LIMITS and not 0 <= n <= _LIMITS[kind]:
            raise ScopeError(f"{text!r}: {kind} is 0..{_LIMITS[kind]}")
        return Signal(kind, n, text=f"{kind} {n}")
    m = _VAR.match(text)
    if m:
        return Signal("var", var=m.group(2), text=f"{m.group(1)}.{m.group(2)}")
    raise ScopeError(f"{text!r} is not a signal: name in N, out N, adc N, pwm N, dac N, "
                     f"gvar ADDR or PROGRAM.var")


def required_procedures(target: str) -> tuple[str, ...]:
    """The procedures a program of that target must define (exact names)."""
    return {HUAZHONG: HZ_PROCEDURES, TGMOTION: TGM_PROCEDURES}.get(target, ())
