"""Code coverage: which instructions of each procedure ran.

    cov = CodeCoverage()
    c = Controller(backend="reference", coverage=cov)
    ...                                  # run
    cov.hits["M03"]                      # code offsets that ran
    cov.branches["M03"]                  # conditional jump offset -> the ways it went
    line_coverage(program, hits)         # {file: (lines with code, lines that ran)}
    branch_coverage(program, branches)   # {file: {line: (ways each jump went, …)}}

The reference interpreter (:func:`plcbuilder.controller.vm.run_reference`)
records them: :meth:`CodeCoverage.table` gives it a copy of the program's
decoded kinds with every instruction marked ``K_COVER``; the first time an
instruction runs, the interpreter records its offset and puts its own kind
back, so each instruction costs one extra step once. A controller without
coverage runs exactly as before. The fast backend does not record coverage.
"""

from __future__ import annotations

from typing import Callable, Optional

from plcbuilder.bytecode.program import Program
from plcbuilder.controller.vm import K_COVER, K_END, K_JNZ, K_JZ, K_LOOP, decoded

#: the conditional jumps: K_JZ jumps when the condition is 0, the others when it is not
BRANCHES = frozenset({K_JZ, K_JNZ, K_LOOP})
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

    def table(self, program: Program, kinds: list) -> tuple[list, Callable]:
        """(the marked kinds the interpreter runs, the function it calls with the
        offset and the stack of a marked instruction about to run; it returns the
        instruction's own kind, or its complement (``~kind``, negative) for a
        conditional jump not yet seen both ways: keep it marked)."""
        entry = self._tables.get(program.name)
        if entry is None or entry[0] != program.code:
            hits = self.hits.setdefault(program.name, set())
            hits.clear()
            ways = self.branches.setdefault(program.name, {})
            ways.clear()
            marked = [K_COVER if k is not None and k != K_END else k for k in kinds]
            original = list(kinds)

            def hit(pc: int, stack: list, hits=hits, ways=ways, original=original) -> int:
                hits.add(pc)
                k = original[pc]
                if k not in BRANCHES:
                    return k
                jumps = (not stack[-1]) if k == K_JZ else bool(stack[-1])
                seen = ways[pc] = ways.get(pc, 0) | (JUMPED if jumps else FELL_THROUGH)
                return k if seen == JUMPED | FELL_THROUGH else ~k

            entry = (program.code, marked, hit)
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
    kinds = decoded(program)[0]
    out: dict[str, dict[int, tuple]] = {}
    for pc, k in enumerate(kinds):
        if k not in BRANCHES:
            continue
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
