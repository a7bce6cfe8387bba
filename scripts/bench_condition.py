#!/usr/bin/env python3
"""Breakpoint conditions under attack (issue 24.2): the time to check a hostile
condition against an ordinary one, and how long a cheap request waits in the
debug adapter behind a hostile one.

    .venv/bin/python scripts/bench.py condition
    PLCB_BENCH_OLD=/path/to/an/older/checkout .venv/bin/python scripts/bench.py condition

Each figure is the median of 3 rounds, interleaved (every case once per round,
and with PLCB_BENCH_OLD the older code's round beside this one's, each in a
child process with that checkout's package, e.g. ``git archive main plcbuilder
| tar -x -C /tmp/old``). Compile: ``compile_condition`` of
an ordinary condition, of 800/1,600/3,200 '(' and of the worst text the limits
let through (1000 characters of 16-deep brackets holding errors). Adapter: a
``plcbuilder dap`` with a launched project gets ``evaluate`` of n '(' and then
``threads``; the figure is how long ``threads`` waited for its answer.
"""

from __future__ import annotations

import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
ROUNDS = 3
HOSTILE = (800, 1600, 3200)
GOAL_MS = 50.0
WAIT_GOAL_MS = 100.0

_COMPILE = r"""
import json, sys, time
from plcbuilder.project.conditions import compile_condition
compile_condition("1")
worst = "+".join(["(" * 16 + "1 1" + ")" * 16] * 27)
cases = {"ordinary": "count > 3 && portget(1) == 0 || gvarget(6060) == 5",
         **{f"{n} (": "(" * n for n in (800, 1600, 3200)}, "worst within the limits": worst}
out = {}
for name, text in cases.items():
    t0 = time.perf_counter()
    compile_condition(text)
    out[name] = (time.perf_counter() - t0) * 1000
print(json.dumps(out))
"""

M03 = "main()\n{\n  count = 0;\n  do {\n    count = count + 1;\n  } while (count < 5);\n  exit(99);\n}\n"


#: Run code with the package of ``root``: the editable install's finder (a
#: meta path finder, ahead of PYTHONPATH) is taken out first.
_PRELUDE = ("import sys; sys.meta_path[:] = [f for f in sys.meta_path "
            "if 'editable' not in getattr(f, '__module__', '') and "
            "'editable' not in getattr(f, '__name__', '')]; sys.path.insert(0, {root!r}); ")


def _python(root: Path, code: str) -> list[str]:
    return [sys.executable, "-c", _PRELUDE.format(root=str(root)) + code]


def _compile_round(root: Path) -> dict:
    r = subprocess.run(_python(root, "exec(" + repr(_COMPILE) + ")"), capture_output=True,
                       text=True, timeout=600)
    return json.loads(r.stdout)


def _adapter_round(root: Path, project: Path) -> dict:
    sys.path.insert(0, str(HERE))
    from attack_dap import Adapter                # the attack's client (a reader thread)
    dap = Adapter(project, _python(root, "import runpy; sys.argv[1:] = ['dap']; "
                                         "runpy.run_module('plcbuilder', run_name='__main__')"))
    out = {}
    try:
        dap.request("initialize", {"adapterID": "plcbuilder"})
        dap.request("launch", {"project": str(project), "procedure": "M03"}, timeout=120)
        for n in HOSTILE:
            slow = dap.send("evaluate", {"expression": "(" * n, "context": "repl"})
            t0 = time.perf_counter()
            dap.request("threads", {}, timeout=600)
            out[f"threads after evaluate of {n} ("] = (time.perf_counter() - t0) * 1000
            assert dap.proc.poll() is None, "the adapter died"
            dap.wait(lambda m: m.get("request_seq") == slow, 600)
    finally:
        dap.close()
    return out


def run() -> list[str]:
    roots = {"now": ROOT}
    old = os.environ.get("PLCB_BENCH_OLD")
    if old:
        roots = {"before": Path(old), **roots}
    got: dict[str, dict[str, list[float]]] = {k: {} for k in roots}
    with tempfile.TemporaryDirectory() as tmp:
        project = Path(tmp) / "proj"
        (project / "hardware").mkdir(parents=True)
        (project / "plcbuilder.toml").write_text('name = "bench"\n')
        (project / "hardware" / "M03.plc").write_text(M03)
        for _ in range(ROUNDS):
            for label, root in roots.items():
                for case, ms in {**_compile_round(root), **_adapter_round(root, project)}.items():
                    got[label].setdefault(case, []).append(ms)
    lines = []
    for label in roots:
        med = {case: statistics.median(v) for case, v in got[label].items()}
        base = med["ordinary"]
        for case, ms in med.items():
            ratio = "" if case == "ordinary" else f" = {ms / base:,.1f}x the ordinary one"
            lines.append(f"{label:6} {case:34} {ms:10.2f} ms{ratio}")
        runs = max(ms for case, ms in med.items()
                   if case.endswith(" (") and not case.startswith("threads"))
        waits = max(ms for case, ms in med.items() if case.startswith("threads"))
        lines.append(f"{label:6} runs of '(': at most {runs:,.1f} ms (goal: under {GOAL_MS:.0f} "
                     f"ms: {'met' if runs < GOAL_MS else 'NOT met'}); a cheap request waited at "
                     f"most {waits:,.1f} ms (goal: under {WAIT_GOAL_MS:.0f} ms: "
                     f"{'met' if waits < WAIT_GOAL_MS else 'NOT met'})")
    return lines


if __name__ == "__main__":
    print("\n".join(run()))
