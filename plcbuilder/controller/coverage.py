"""Code coverage: which instructions of each procedure ran.

    cov = CodeCoverage()
    c = Controller(backend="reference", coverage=cov)
    ...                                  # run
    cov.hits["M03"]                      # code offsets that ran
    cov.branches["M03"]                  # conditional jump offset -> the ways it went
    line_coverage(program, hits)         # {file: (lines with code, lines that ran)}
    branch_coverage(program, branches)   # {file: {line: (ways each jump went, …)}}

The reference interpreter (:func:`plcbuilder.controller.vm.run_reference`)
records them through its per-instruction hook: :meth:`CodeCoverage.watch`
gives it a list true at every instruction not yet seen and the function it
calls before running one; that records the offset and clears the mark (a
conditional jump's once it has gone both ways), so each instruction costs
one call once. A controller without coverage runs exactly as before. The fast
backend does not record coverage.
"""

from __future__ import annotations

from typing import Callable, Optional

from plcbuilder.bytecode.program import Program
from plcbuilder.bytecode.opcodes import COND_JUMPS, JUMPS_IF_ZERO, validate
from plcbuilder.controller.vm import K_END, decoded

#: the ways a conditional jump went (bits of CodeCoverage.branches' values)
JUMPED, FELL_THROUGH = 1, 2


class CodeCoverage:
    """The code offsets that ran, and the ways each conditional jump went, per
    procedure name (kept across runs and loads of the same code)."""

    def __init__(self):
        self.hits: dict[str, set[int]] = {}
        #: procedure -> {offset of a conditional jump: JUMPED | FELL_THROUGH, as seen}
        self.branches: dict[str, dict[int, int]] = {}
        self._tables: dict[str, tuple[bytes, list, Callable]] = {}

    def watch(self, program: Program) -> tuple[list, Callable]:
        """(a list per code offset, true at each instruction not yet seen; the
        function the interpreter calls with the offset and the stack of such
        an instruction before it runs: it records it and clears its mark, a
        conditional jump's once it has gone both ways). Kept across runs of
        the same code."""
        entry = self._tables.get(program.name)
        if entry is None or entry[0] != program.code:
            hits = self.hits.setdefault(program.name, set())
            hits.clear()
            ways = self.branches.setdefault(program.name, {})
            ways.clear()
            unseen = [k is not None and k != K_END for k in decoded(program)[0]]
            branch = branches(program)

            def seen(pc: int, stack: list, hits=hits, ways=ways, branch=branch,
                     unseen=unseen) -> None:
                hits.add(pc)
                if_zero = branch.get(pc)
                if if_zero is None:
                    unseen[pc] = False
                    return
                jumps = not stack[-1] if if_zero else bool(stack[-1])
                way = ways[pc] = ways.get(pc, 0) | (JUMPED if jumps else FELL_THROUGH)
                if way == JUMPED | FELL_THROUGH:
                    unseen[pc] = False

            entry = (program.code, unseen, seen)
            self._tables[program.name] = entry
        return entry[1], entry[2]

    def merge(self, hits: dict[str, set[int]],
              branches: Optional[dict[str, dict[int, int]]] = None) -> None:
        """Add offsets (and branch ways) recorded elsewhere (another process's run
        of the same code)."""
        for name, pcs in hits.items():
            self.hits.setdefault(name, set()).update(pcs)
        for name, ways in (branches or {}).items():
            mine = self.branches.setdefault(name, {})
            for pc, seen in ways.items():
                mine[pc] = mine.get(pc, 0) | seen


def branches(program: Program) -> dict[int, bool]:
    """The conditional jumps of ``program``: offset -> whether it jumps when its
    condition is 0 (JZ; JNZ and LOOP jump when it is not)."""
    return {ins.offset: ins.op in JUMPS_IF_ZERO
            for ins in validate(program.code, program.entry) if ins.op in COND_JUMPS}


def instruction_offsets(program: Program) -> list[int]:
    """The code offset of every instruction of ``program``."""
    kinds = decoded(program)[0]
    return [pc for pc, k in enumerate(kinds) if k is not None and k != K_END]


def line_coverage(program: Program, hits: set[int]) -> dict[str, tuple[set[int], set[int]]]:
    """Per source file named in the program's line table: (the lines that have
    code, the lines of which an instruction ran)."""
    out: dict[str, tuple[set[int], set[int]]] = {}
    for pc in instruction_offsets(program):
        loc = program.location(pc)
        if loc is None:
            continue
        file, line = loc
        code, ran = out.setdefault(file, (set(), set()))
        code.add(line)
        if pc in hits:
            ran.add(line)
    return out


def branch_coverage(program: Program, ways: dict[int, int]) -> dict[str, dict[int, tuple]]:
    """Per source file, per line with conditional jumps: the ways each went
    (``JUMPED | FELL_THROUGH`` bits, 0: it never ran), in code order."""
    out: dict[str, dict[int, tuple]] = {}
    for pc in sorted(branches(program)):
        loc = program.location(pc)
        if loc is None:
            continue
        file, line = loc
        per_line = out.setdefault(file, {})
        per_line[line] = per_line.get(line, ()) + (ways.get(pc, 0),)
    return out


def ways_gone(seen: tuple) -> tuple[int, int]:
    """(the ways the conditions went, the ways they have: two each)."""
    return sum(bin(w).count("1") for w in seen), 2 * len(seen)
