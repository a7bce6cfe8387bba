"""Line and branch coverage of a test run: per procedure, which source lines
ran, and which ways its conditions went.

The controller records the code offsets that ran and the ways each
conditional jump went (:class:`~plcbuilder.controller.coverage.CodeCoverage`,
on the reference interpreter); the program's line table turns them into
lines here. :func:`cobertura_xml` writes it as Cobertura XML, as pytest-cov's
``--cov-report xml`` does, for GitLab and Jenkins.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterable, Optional

from plcbuilder.controller.coverage import branch_coverage, line_coverage, ways_gone


@dataclass
class FileCoverage:
    file: str                       # as the line table names it (M03.plc)
    path: Optional[str]             # where it is on disk, when found
    lines: list[int]                # lines with code
    covered: list[int]              # lines of which an instruction ran
    #: line -> the ways each of its conditions went (JUMPED | FELL_THROUGH bits), in order
    conditions: dict[int, tuple] = field(default_factory=dict)

    @property
    def branches(self) -> dict[int, tuple[int, int]]:
        """line -> (the ways its conditions went, the ways they have: two a condition)."""
        return {n: ways_gone(seen) for n, seen in self.conditions.items()}

    @property
    def uncovered(self) -> list[int]:
        ran = set(self.covered)
        return [n for n in self.lines if n not in ran]

    @property
    def branches_total(self) -> int:
        return sum(2 * len(seen) for seen in self.conditions.values())

    @property
    def branches_covered(self) -> int:
        return sum(ways_gone(seen)[0] for seen in self.conditions.values())


@dataclass
class ProcedureCoverage:
    name: str
    kind: str
    files: list[FileCoverage] = field(default_factory=list)

    @property
    def lines(self) -> int:
        return sum(len(f.lines) for f in self.files)

    @property
    def covered(self) -> int:
        return sum(len(f.covered) for f in self.files)

    @property
    def percent(self) -> float:
        return 100.0 * self.covered / self.lines if self.lines else 100.0

    @property
    def branches(self) -> int:
        """The ways its conditions have (two a condition)."""
        return sum(f.branches_total for f in self.files)

    @property
    def branches_covered(self) -> int:
        """The ways they went."""
        return sum(f.branches_covered for f in self.files)

    def uncovered_text(self) -> str:
        """``M03.plc:12-14, 20`` (empty when every line ran)."""
        parts = []
        for f in self.files:
            if f.uncovered:
                parts.append(f"{f.file}:{ranges(f.uncovered)}")
        return "; ".join(parts)

    def to_dict(self) -> dict:
        return {"name": self.name, "kind": self.kind, "lines": self.lines,
                "covered": self.covered, "percent": round(self.percent, 1),
                "branches": self.branches, "branches_covered": self.branches_covered,
                "files": [{"file": f.file, "path": f.path, "lines": f.lines,
                           "covered": f.covered, "uncovered": f.uncovered,
                           "branches": [{"line": n, "covered": g, "total": t}
                                        for n, (g, t) in sorted(f.branches.items())]}
                          for f in self.files]}


def ranges(lines: Iterable[int]) -> str:
    """``3-5, 9``."""
    out: list[str] = []
    run: list[int] = []
    for n in sorted(lines):
        if run and n == run[-1] + 1:
            run.append(n)
            continue
        if run:
            out.append(f"{run[0]}-{run[-1]}" if len(run) > 1 else str(run[0]))
        run = [n]
    if run:
        out.append(f"{run[0]}-{run[-1]}" if len(run) > 1 else str(run[0]))
    return ", ".join(out)


def summarize(programs: Iterable, hits: dict[str, set[int]], project=None,
              branches: Optional[dict[str, dict[int, int]]] = None) -> list[ProcedureCoverage]:
    """Per procedure (in the order given): its files' lines with code and the
    ones that ran, and the ways their conditions went. File names are looked up
    in the procedure's folder, then the project's include folders, to give
    their paths."""
    out = []
    for p in programs:
        pc = ProcedureCoverage(p.name, p.kind.label)
        ways = branch_coverage(p, (branches or {}).get(p.name, {}))
        for file, (code, ran) in sorted(line_coverage(p, hits.get(p.name, set())).items()):
            pc.files.append(FileCoverage(file, _path_of(project, p, file), sorted(code),
                                         sorted(ran), dict(sorted(ways.get(file, {}).items()))))
        out.append(pc)
    return out


def totals(coverage: Iterable[ProcedureCoverage]) -> tuple[int, int, int, int]:
    """(lines with code, lines run, branch ways, ways gone) over every procedure."""
    cov = list(coverage)
    return (sum(c.lines for c in cov), sum(c.covered for c in cov),
            sum(c.branches for c in cov), sum(c.branches_covered for c in cov))


def _path_of(project, program, file: str) -> Optional[str]:
    if project is None:
        return None
    folders = [project.dir_for(program.kind), *project.include_dirs()]
    for d in folders:
        cand = Path(d) / file
        if cand.is_file():
            return str(cand.resolve())
    return None
