"""Code coverage: which instructions of each procedure ran.

    cov = CodeCoverage()
    c = Controller(backend="reference", coverage=cov)
    ...                                  # run
    cov.hits["M03"]                      # code offsets that ran
    cov.lines(program)                   # {file: (lines with code, lines that ran)}

The reference interpreter (:func:`plcbuilder.controller.vm.run_reference`)
records them: :meth:`CodeCoverage.table` gives it a copy of the program's
decoded kinds with every instruction marked ``K_COVER``; the first time an
instruction runs, the interpreter records its offset and puts its own kind
back, so each instruction costs one extra step once. A controller without
coverage runs exactly as before. The fast backend does not record coverage.
"""

from __future__ import annotations

from typing import Callable

from plcbuilder.bytecode.program import Program
from plcbuilder.controller.vm import K_COVER, K_END, decoded


class CodeCoverage:
    """The code offsets that ran, per procedure name (kept across runs and loads
    of the same code)."""

    def __init__(self):
        self.hits: dict[str, set[int]] = {}
        self._tables: dict[str, tuple[bytes, list, Callable[[int], int]]] = {}

    def table(self, program: Program, kinds: list) -> tuple[list, Callable[[int], int]]:
        """(the marked kinds the interpreter runs, the function it calls with the
        offset of an instruction that runs for the first time; it returns the
        instruction's own kind)."""
        entry = self._tables.get(program.name)
        if entry is None or entry[0] != program.code:
            hits = self.hits.setdefault(program.name, set())
            hits.clear()
            marked = [K_COVER if k is not None and k != K_END else k for k in kinds]
            original = list(kinds)

            def hit(pc: int, hits=hits, original=original) -> int:
                hits.add(pc)
                return original[pc]

            entry = (program.code, marked, hit)
            self._tables[program.name] = entry
        return entry[1], entry[2]

    def merge(self, hits: dict[str, set[int]]) -> None:
        """Add offsets recorded elsewhere (another process's run of the same code)."""
        for name, pcs in hits.items():
            self.hits.setdefault(name, set()).update(pcs)


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
