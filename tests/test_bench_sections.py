"""scripts/bench.py runs every scripts/bench_<name>.py as a section through its
run() (``bench.py rewind`` and ``bench.py`` with no argument stopped on an
AttributeError: bench_rewind had only a main())."""

from __future__ import annotations

import ast
from pathlib import Path

SCRIPTS = Path(__file__).resolve().parent.parent / "scripts"


def test_every_bench_section_has_a_run_function():
    sections = sorted(SCRIPTS.glob("bench_*.py"))
    assert len(sections) >= 8
    missing = []
    for path in sections:
        tree = ast.parse(path.read_text(encoding="utf-8"))
        if not any(isinstance(n, ast.FunctionDef) and n.name == "run" for n in tree.body):
            missing.append(path.name)
    assert missing == []
