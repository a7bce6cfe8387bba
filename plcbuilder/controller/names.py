"""The ABI's names as the controller decodes them, for what reads its events
and state by name (scenario tests): messages, exit codes, proc states, axes,
the print registers. One place, from :mod:`plcbuilder.bytecode.abi`."""

from __future__ import annotations

from plcbuilder.bytecode import abi
from plcbuilder.bytecode.abi import exit_name, message_name, proc_name

__all__ = ["AXES", "EXITS", "MESSAGES", "PRINT_FIRST", "PRINT_LAST", "PROCS", "REPLY_TO_MYCNC",
           "exit_name", "message_name", "proc_name"]

#: every message name: PLCCMD_*, PLC_MESSAGE_*, PLC_BROADCAST_*
MESSAGES: dict[str, int] = {**abi.PLC_BROADCAST, **abi.PLC_MESSAGE, **abi.PLCCMD}
EXITS: dict[str, int] = dict(abi.EXIT)
PROCS: dict[str, int] = dict(abi.PROC)
AXES: tuple[str, ...] = abi.AXES
PRINT_FIRST, PRINT_LAST = abi.PRINT_FIRST, abi.PRINT_LAST
#: a message to myCNC: the message it carries is in ``command`` (var00)
REPLY_TO_MYCNC: int = abi.PLCCMD["PLCCMD_REPLY_TO_MYCNC"]
