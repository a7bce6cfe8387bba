"""Target profiles for the compiler: what each controller of SPEC §9 adds to
the language, and what a program for it must define (docs/targets.md).

- ``mycnc`` (the default): §1 as it is; ``main()`` is where a procedure starts.
- ``huazhong``: one source with ``init()``, ``plc1()`` and ``plc2()``; the
  register banks ``X[n]`` … ``B[n]``, compound assignment; the periods
  ``plc1_time``/``plc2_time`` are ordinary variables the controller reads.
- ``tgmotion``: ``Program_Ini`` and ``Program_01`` … ``Program_05``, exactly
  so spelled (the seed: "mandatory, including the letter case"); compound
  assignment; shared memory through gvarget/gvarset (``tgmotion.h``).

The checker asks a :class:`Profile` what is allowed; a construct only a target
has is refused on the others with a hint that names the target that has it.
"""

from __future__ import annotations

from plcbuilder._support.records import dataclass
from plcbuilder.bytecode import targets as T

TYPE_CHECKING = False               # (typing is not imported at run time: start-up)
if TYPE_CHECKING:
    from typing import Optional

COMPOUND_OPS = ("|=", "&=", "^=", "+=", "-=")


@dataclass(frozen=True)
class Profile:
    name: str
    required: tuple[str, ...]          # procedures that must be defined, exactly so named
    banks: bool                        # X[n] register banks
    compound: bool                     # |= &= ^= += -=
    periods: tuple[str, ...] = ()      # variables the controller reads as periods (ms)

    @property
    def has_main(self) -> bool:
        """Whether programs start at main() (myCNC) rather than at the target's procedures."""
        return not self.required

    def roots(self, defined) -> list[str]:
        """The procedures the controller calls, in the order they are emitted."""
        if self.has_main:
            return ["main"] if "main" in defined else []
        return [n for n in self.required if n in defined]


PROFILES: dict[str, Profile] = {
    T.MYCNC: Profile(T.MYCNC, (), banks=False, compound=False),
    T.HUAZHONG: Profile(T.HUAZHONG, T.HZ_PROCEDURES, banks=True, compound=True,
                        periods=T.HZ_PERIODS),
    T.TGMOTION: Profile(T.TGMOTION, T.TGM_PROCEDURES, banks=False, compound=True),
}


def profile(target: str) -> Profile:
    """The profile of a target name (an unknown name is the project's error to
    report; here it falls back to myCNC)."""
    return PROFILES.get(target, PROFILES[T.MYCNC])


def targets_with(feature: str) -> list[str]:
    """The targets that accept a feature ("banks" or "compound")."""
    return [p.name for p in PROFILES.values() if getattr(p, feature)]


def feature_hint(feature: str) -> str:
    names = targets_with(feature)
    which = " or ".join(f'"{n}"' for n in names)
    return f"this is {' and '.join(names)} syntax: set target = {which} in plcbuilder.toml"


def near_miss(name: str, required: tuple[str, ...]) -> Optional[str]:
    """The required name that ``name`` misspells by letter case or by its
    number's zero (``program_01``, ``Program_1``), or None."""
    low = name.lower().replace("_0", "_")
    for r in required:
        if r != name and r.lower().replace("_0", "_") == low:
            return r
    return None


def slots_per_cycle(cycle_us: int) -> int:
    """TG Motion: the slots of one cycle (5 for 250 and 500 µs, 10 for 1000 µs)."""
    return T.TGM_SLOTS[cycle_us]


def bank_names() -> str:
    return ", ".join(f"{b.name}[0..{b.size - 1}]" for b in T.BANKS.values())
