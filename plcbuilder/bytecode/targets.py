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
  gives the element as an unsigned number.
- TG Motion's ``TGM_Data`` (512 KiB) is 131072 32-bit words at
  ``TGM_DATA_BASE + i`` (word i holds bytes 4i … 4i+3).
"""

from __future__ import annotations

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
    """One Huazhong register bank."""
    name: str
    size: int            # elements
    bits: int            # element width
    base: int            # register of element 0 (a constant index)
    load: int            # indirect read: the element at the index latch
    store: int           # indirect write: gvarset(store, index) stores the value latch
    direction: str       # what it is for (docs, hover)

    @property
    def mask(self) -> int:
        return (1 << self.bits) - 1

    @property
    def last(self) -> int:
        return self.base + self.size - 1

    def holds(self, addr: int) -> bool:
        return self.base <= addr < self.base + self.size


HZ_BASE = 1_000_000
INDEX_LATCH = 1_009_000
VALUE_LATCH = 1_009_001

BANKS: dict[str, Bank] = {b.name: b for b in (
    Bank("X", 128, 8, HZ_BASE + 0, 1_009_010, 1_009_020, "machine -> PLC inputs: pin 8n+b is bit b"),
    Bank("Y", 128, 8, HZ_BASE + 1000, 1_009_011, 1_009_021, "PLC -> machine outputs: pin 8n+b is bit b"),
    Bank("R", 768, 8, HZ_BASE + 2000, 1_009_012, 1_009_022, "internal registers"),
    Bank("G", 256, 16, HZ_BASE + 3000, 1_009_013, 1_009_023, "PLC -> CNC words"),
    Bank("F", 256, 16, HZ_BASE + 4000, 1_009_014, 1_009_024, "CNC -> PLC words"),
    Bank("P", 100, 16, HZ_BASE + 5000, 1_009_015, 1_009_025, "user parameters (project file)"),
    Bank("B", 100, 16, HZ_BASE + 6000, 1_009_016, 1_009_026, "words kept across restarts"),
)}
#: banks the PLC reads in the batch at the start of a tick / writes at its end
HZ_READ_BANKS = ("X", "F", "P")
HZ_WRITE_BANKS = ("G", "Y", "B")
#: the CNC's side of G and F: plain global registers the batch copies to and from
CNC_G_BASE = HZ_BASE + 13_000
CNC_F_BASE = HZ_BASE + 14_000
HZ_PERIODS = ("plc1_time", "plc2_time")
HZ_DEFAULT_PERIODS = {"plc1_time": 16, "plc2_time": 32}
HZ_PROCEDURES = ("init", "plc1", "plc2")

TGM_DATA_BASE = 2_000_000
TGM_DATA_WORDS = 524_288 // 4
TGM_PROCEDURES = ("Program_Ini", "Program_01", "Program_02", "Program_03", "Program_04",
                  "Program_05")
TGM_CYCLE_TIMES = (250, 500, 1000)
TGM_PERIOD_RANGE = (100, 10_000)
TGM_DEFAULT_INSTRUCTION_NS = 20
#: slots per cycle, by cycle time (the seed's figures)
TGM_SLOTS = {250: 5, 500: 5, 1000: 10}
#: Program_04 runs in this slot (0-based: the fourth), after Program_05
TGM_P04_SLOT = 3
#: budgets: Program_04 a share of the cycle, Program_05 in µs, 01..03 a share of their period
TGM_P04_SHARE = 0.10
TGM_P05_BUDGET_US = 10.0
TGM_LOW_SHARE = 0.20


def bank_at(addr: int) -> Optional[tuple[Bank, int]]:
    """(bank, index) of a constant-index register, or None."""
    if HZ_BASE <= addr < HZ_BASE + 7000:
        for b in BANKS.values():
            if b.holds(addr):
                return b, addr - b.base
    return None


INDIRECT_LOAD = {b.load: b for b in BANKS.values()}
INDIRECT_STORE = {b.store: b for b in BANKS.values()}


def required_procedures(target: str) -> tuple[str, ...]:
    """The procedures a program of that target must define (exact names)."""
    return {HUAZHONG: HZ_PROCEDURES, TGMOTION: TGM_PROCEDURES}.get(target, ())
