"""A procedure's kind: hardware (the 1 ms PLC core) or software (the host's
100 ms multitasking PLC). Its own module, apart from :mod:`.program` (which
re-exports it): a project, its settings and the IDE's window need the kind
long before anything decodes a binary."""

from __future__ import annotations

import enum

from plcbuilder.bytecode import abi


class Kind(enum.IntEnum):
    HARDWARE = 0
    SOFTWARE = 1

    @property
    def label(self) -> str:
        return self.name.lower()

    @property
    def code_limit(self) -> int:
        return abi.HW_PROC_LIMIT if self is Kind.HARDWARE else abi.SW_PROC_LIMIT
