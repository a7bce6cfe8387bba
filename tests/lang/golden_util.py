"""Golden programs: .plc files with inline expectations, shared by the tests and
scripts/regen_goldens.py.

In a golden program:
- ``// options: --strict --software`` (first lines) sets compile options;
- ``// error: TEXT`` / ``// warning: TEXT`` on a line expects exactly one such
  diagnostic on that line whose message (or hint) contains TEXT; every other
  diagnostic in the file is a failure (so cascades fail the test);
- ``// expect: ...`` states what a run of the compiled procedure does:
  ``exit N``, ``ends_at MS``, ``VAR == N``, ``vexit N``, ``message M CMD PARAM``,
  ``print REG VALUE``, ``output PIN on|off``, and, on the line that faults,
  ``fault TEXT``.
A golden that compiles has its disassembly beside it (NAME.dis), regenerated
only on purpose by ``scripts/regen_goldens.py``.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

from plcbuilder.api import CompileOptions, Kind, compile_file, disassemble

GOLDEN = Path(__file__).parent / "golden"
_DIAG = re.compile(r"//\s*(error|warning):\s*(.+?)\s*$")
_EXPECT = re.compile(r"//\s*expect:\s*(.+?)\s*$")
_OPTIONS = re.compile(r"//\s*options:\s*(.+?)\s*$")


@dataclass
class Golden:
    path: Path
    options: CompileOptions
    diags: list[tuple[int, str, str]] = field(default_factory=list)    # (line, severity, text)
    expects: list[tuple[int, str]] = field(default_factory=list)       # (line, text)

    @property
    def id(self) -> str:
        return self.path.relative_to(GOLDEN).as_posix()

    @property
    def dis_path(self) -> Path:
        return self.path.with_suffix(".dis")


def goldens() -> list[Golden]:
    out = []
    for p in sorted(GOLDEN.rglob("*.plc")):
        text = p.read_text(encoding="utf-8")
        strict = software = False
        g = Golden(p, CompileOptions())
        for n, line in enumerate(text.split("\n"), 1):
            m = _OPTIONS.search(line)
            if m:
                strict |= "--strict" in m.group(1)
                software |= "--software" in m.group(1)
            m = _DIAG.search(line)
            if m:
                g.diags.append((n, m.group(1), m.group(2)))
            m = _EXPECT.search(line)
            if m:
                g.expects.append((n, m.group(1)))
        g.options = CompileOptions(kind=Kind.SOFTWARE if software else Kind.HARDWARE, strict=strict)
        out.append(g)
    return out


def compile_golden(g: Golden):
    return compile_file(g.path, g.options)


def listing(g: Golden, result) -> str:
    return disassemble(result.program, result.source_line)
