"""One call of a target's procedure, run to its end, with the instructions it took.

A target calls a procedure (``plc1()``, ``Program_04()``) and the call runs to
completion: a loop's end does not end the tick as on myCNC, so the call goes
on through every loop iteration. It runs on the reference interpreter
(:func:`plcbuilder.controller.vm.run_reference`, the bytecode's definition)
from the procedure's code offset; returning from it ends the call with code 0,
``exit(n)`` with n.

The interpreter counts the instructions it runs in a local, ``count``, which
it resets where a tick ends. The count of the call is read from the
interpreter's frame: at every tick end (the suspended generator's frame) and
where the call ends (the frame in the traceback of ProcExit or VMFault). The
same frame gives the code offset, ``pc``, of a fault the host raised (a bank
index out of range), which the host cannot know. tests/controller/
test_target_calls.py pins this down, so a change in the interpreter that
moves those locals fails there, not in a run.

A call over :data:`CALL_LIMIT` instructions faults (SPEC §9: "a call over the
instruction limit faults"): the cyclic programs' calls. :class:`Call` runs a
call in pieces with no limit, for TG Motion's ``Program_Ini`` ("The execution
length of this function is not limited").
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Optional

from plcbuilder.bytecode.program import Program
from plcbuilder.bytecode.semantics import wrap
from plcbuilder.controller import vm
from plcbuilder.controller.vm import Host, ProcExit, VMFault

CALL_LIMIT = vm.TICK_BUDGET
FAULT_CALL_LIMIT = (f"more than {CALL_LIMIT} instructions in one call (a call runs to its end: "
                    "a loop that never ends?)")
_RUN_CODE = vm.run_reference.__code__


@dataclass
class CallResult:
    code: Optional[int]                 # the exit code; None when it faulted
    instructions: int
    fault: Optional[VMFault] = None


class Entries:
    """The programs that start at each procedure of one program (made once)."""

    def __init__(self, program: Program):
        self.program = program
        self._by_name = {name: dataclasses.replace(program, entry=off)
                         for name, off in program.procs}

    def __contains__(self, name: str) -> bool:
        return name in self._by_name

    def get(self, name: str) -> Program:
        return self._by_name[name]

    def line_of(self, name: str) -> tuple[Optional[str], Optional[int]]:
        """(file, line) where procedure ``name`` begins."""
        p = self._by_name.get(name)
        loc = self.program.location(p.entry) if p is not None else None
        return loc if loc else (None, None)


def _frame_of(tb):
    """The interpreter's frame in a traceback (the innermost one), or None."""
    frame = None
    while tb is not None:
        if tb.tb_frame.f_code is _RUN_CODE:
            frame = tb.tb_frame
        tb = tb.tb_next
    return frame


class Call:
    """One call in progress, run in pieces: :meth:`run` goes on from where the
    last piece stopped (a loop's end) until the call ends or has run at least
    ``budget`` more instructions. TG Motion's ``Program_Ini``, whose length the
    seed does not limit, runs so: a piece per tick, its modelled time passing
    as it goes."""

    def __init__(self, entry: Program, slots: list[int], host: Host, cover=None):
        self.gen = vm.run_reference(entry, slots, host, cover=cover)
        self.instructions = 0

    def run(self, budget: Optional[int] = None) -> Optional[CallResult]:
        """Run on; the CallResult when the call ended (or faulted), None when it
        stopped at a loop's end after ``budget`` instructions (None: no budget)."""
        gen = self.gen
        used = 0
        while True:
            try:
                next(gen)
            except ProcExit as exc:
                frame = _frame_of(exc.__traceback__)
                self.instructions += frame.f_locals["count"] if frame is not None else 0
                return CallResult(wrap(exc.code), self.instructions)
            except StopIteration:
                return CallResult(0, self.instructions)
            except VMFault as fault:
                frame = _frame_of(fault.__traceback__)
                if frame is not None:
                    self.instructions += frame.f_locals["count"]
                    if fault.pc < 0:           # raised by the host: the instruction that called it
                        fault.pc = frame.f_locals["pc"]
                return CallResult(None, self.instructions, fault)
            n = gen.gi_frame.f_locals["count"]  # suspended where a loop's iteration ends
            self.instructions += n
            used += n
            if budget is not None and used >= budget:
                return None

    @property
    def pc(self) -> int:
        """Where it stopped (the code offset of the loop's end)."""
        frame = self.gen.gi_frame
        return frame.f_locals["pc"] if frame is not None else 0

    def close(self) -> None:
        self.gen.close()


def call(entry: Program, slots: list[int], host: Host, limit: int = CALL_LIMIT,
         cover=None) -> CallResult:
    """Run the procedure ``entry`` starts at over ``slots`` to its end
    (``cover``: a CodeCoverage recording the instructions that run); more than
    ``limit`` instructions is a fault (SPEC §9: the cyclic programs' calls)."""
    c = Call(entry, slots, host, cover)
    r = c.run(limit + 1)
    if r is not None:
        return r
    fault = VMFault(c.pc, FAULT_CALL_LIMIT)
    c.close()
    return CallResult(None, c.instructions, fault)
