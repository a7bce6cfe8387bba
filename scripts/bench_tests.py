"""Scenario-test benchmark: the example project's whole suite from the command
line (goal: under 2 s of wall time), and 100 tests of 10 s of simulated time
each, serial and across the cores (goal: under 10 s)."""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from plcbuilder.api import TestOptions, create_project, test


def _hundred(root: Path) -> None:
    blocks = []
    for i in range(100):
        blocks.append(f'[[test]]\nname = "spindle {i}"\nms = 10000\n'
                      f'scenario = "start M03:{1000 + i} @ {100 + i}"\n'
                      f'[[test.expect]]\nby_ms = {200 + i}\npwm = {{ 0 = {1000 + i} }}\n'
                      f'[[test.expect]]\nduring_ms = [{300 + i}, {5000 + i}]\n'
                      f'outputs_on = ["OUTPUT_SPINDLE"]\n'
                      f'[[test.expect]]\nat_end = true\nexit = {{ M03 = 99 }}\n')
    (root / "tests" / "hundred.toml").write_text("\n".join(blocks), encoding="utf-8")


def run() -> list[str]:
    lines = []
    with tempfile.TemporaryDirectory() as tmp:
        ex = create_project(Path(tmp) / "ex").root
        env = dict(os.environ, PYTHONPATH=str(Path(__file__).resolve().parents[1]))
        t0 = time.perf_counter()
        r = subprocess.run([sys.executable, "-m", "plcbuilder", "test", str(ex)],
                           capture_output=True, text=True, env=env)
        wall = time.perf_counter() - t0
        last = r.stdout.strip().splitlines()[-1] if r.stdout.strip() else r.stderr.strip()
        lines.append(f"example project, `plcbuilder test` from the command line: {wall:.2f} s "
                     f"wall ({last}; goal < 2 s)")
        tr = test(ex, TestOptions(jobs=1))
        lines.append(f"  of which running the tests: {tr.run.seconds:.2f} s "
                     f"({len(tr.results)} tests)")
        big = create_project(Path(tmp) / "big").root
        for p in (big / "tests").glob("*.toml"):
            p.unlink()
        _hundred(big)
        for jobs in (1, 2, None):
            t0 = time.perf_counter()
            tr = test(big, TestOptions(jobs=jobs))
            wall = time.perf_counter() - t0
            lines.append(f"100 tests x 10 s simulated, jobs={jobs or 'auto'} "
                         f"({tr.run.jobs} process{'es' if tr.run.jobs > 1 else ''}): "
                         f"{wall:.2f} s wall, "
                         f"{tr.run.passed} passed (goal < 10 s)")
    return lines
