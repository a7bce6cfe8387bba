"""Code size limits of an image (defaults from the myCNC manual): what a
project's settings and Build All check each procedure against."""

from __future__ import annotations

from plcbuilder._support.records import dataclass
from plcbuilder.bytecode import abi
from plcbuilder.bytecode.kind import Kind

#: The largest limit a project may set (bytes).
MAX_LIMIT = 1 << 24


@dataclass(frozen=True)
class Limits:
    """Code size limits in bytes (defaults from the myCNC manual)."""

    hw_proc: int = abi.HW_PROC_LIMIT
    hw_total: int = abi.HW_TOTAL_LIMIT
    sw_proc: int = abi.SW_PROC_LIMIT

    def proc_limit(self, kind: Kind) -> int:
        return self.hw_proc if Kind(kind) is Kind.HARDWARE else self.sw_proc

    def as_dict(self) -> dict[str, int]:
        return {"hw_proc": self.hw_proc, "hw_total": self.hw_total, "sw_proc": self.sw_proc}

    def check(self) -> None:
        """ImageError unless every limit is a whole number from 1 to MAX_LIMIT."""
        for key, value in self.as_dict().items():
            if type(value) is not int or not 0 < value <= MAX_LIMIT:
                from plcbuilder.image.romfs import ImageError
                raise ImageError(f"limit {key} must be a whole number from 1 to {MAX_LIMIT}, "
                                 f"is {value!r}")
