"""Hostile sources against an ordinary one of the same size (issue 24 item 1),
through the command line: ``plcbuilder check FILE`` of each, in a child, the
files interleaved, the median of each round's ratio to the ordinary source.

    python scripts/bench_hostile.py [--size 400000 --size 100000] [--rounds 3]
                                    [--only WORD] [--timeout S] [--tree DIR]
    python scripts/bench.py hostile

The hostile sources are scripts/hostile_sources.py's (deep nesting, long runs
of one token, thousands of errors); the ordinary one has helper procedures
called from main (every stage runs on all of it). Goal: each within 2x.
``--tree DIR`` runs another checkout's code (``git archive REV | tar -x -C DIR``)
with this one's interpreter: the figures before a change, in the same run.
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from hostile_sources import hostile, ordinary  # noqa: E402

GOAL = 2.0


def _env(tree: Path | None) -> dict:
    env = dict(os.environ)
    env.pop("PYTHONDONTWRITEBYTECODE", None)     # as installed: modules compiled once
    if tree is not None:
        env["PYTHONPATH"] = str(tree)
    return env


def check_time(path: Path, env: dict, timeout: float) -> tuple[float, float]:
    """(wall seconds, processor seconds) ``plcbuilder check PATH`` takes (its
    output thrown away), or inf past the timeout."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t = time.perf_counter()
    try:
        subprocess.run([sys.executable, "-m", "plcbuilder", "check", str(path)],
                       stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env,
                       timeout=timeout)
    except subprocess.TimeoutExpired:
        return float("inf"), float("inf")
    wall = time.perf_counter() - t
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime)


def measure(sizes=(400_000, 100_000), rounds: int = 3, only: str = "", timeout: float = 120,
            tree: Path | None = None) -> list[dict]:
    env = _env(tree)
    rows = []
    with tempfile.TemporaryDirectory(prefix="plc-hostile-") as tmp:
        for size in sizes:
            base = Path(tmp) / f"ordinary-{size}.plc"
            base.write_text(ordinary(size))
            cases = {name: text for name, text in hostile(size).items()
                     if not only or only in name}
            files = {}
            for k, (name, text) in enumerate(cases.items()):
                files[name] = Path(tmp) / f"hostile-{size}-{k}.plc"
                files[name].write_text(text)
            check_time(base, env, timeout)                      # compiles the modules
            base_times, times = [], {name: [] for name in files}
            ratios = {name: [] for name in files}
            cpu_ratios = {name: [] for name in files}
            for _ in range(rounds):
                for name, path in files.items():
                    b, bc = check_time(base, env, timeout)
                    h, hc = check_time(path, env, timeout)
                    base_times.append(b)
                    times[name].append(h)
                    ratios[name].append(h / b)
                    cpu_ratios[name].append(hc / bc)
            for name in files:
                rows.append({"size": size, "name": name, "seconds": statistics.median(times[name]),
                             "ordinary": statistics.median(base_times),
                             "ratio": statistics.median(ratios[name]),
                             "cpu_ratio": statistics.median(cpu_ratios[name])})
    return rows


def lines(rows: list[dict]) -> list[str]:
    out = []
    for size in sorted({r["size"] for r in rows}, reverse=True):
        sub = [r for r in rows if r["size"] == size]
        base = statistics.median(r["ordinary"] for r in sub)
        out.append(f"{size // 1000} KB: ordinary source {base:.2f} s; each hostile one "
                   f"(check: seconds, ratio to the ordinary in wall and in processor time, "
                   f"medians of the rounds' ratios; goal <= {GOAL:g}x):")
        for r in sub:
            flag = "" if min(r["ratio"], r["cpu_ratio"]) <= GOAL else "   <-- over the goal"
            secs = "timeout" if r["seconds"] == float("inf") else f"{r['seconds']:.2f} s"
            out.append(f"  {r['name']:<40} {secs:>9} {r['ratio']:6.2f}x "
                       f"(processor {r['cpu_ratio']:.2f}x){flag}")
        worst = max(sub, key=lambda r: r["ratio"])
        worst_cpu = max(sub, key=lambda r: r["cpu_ratio"])
        out.append(f"  worst: {worst['name']} at {worst['ratio']:.2f}x; in processor time "
                   f"{worst_cpu['name']} at {worst_cpu['cpu_ratio']:.2f}x")
    return out


def run() -> list[str]:
    """Section ``hostile`` of scripts/bench.py."""
    return lines(measure())


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--size", type=int, action="append", help="bytes (repeatable)")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--only", default="", help="only the hostile sources whose name has WORD")
    ap.add_argument("--timeout", type=float, default=120.0)
    ap.add_argument("--tree", type=Path, help="run this checkout's code")
    args = ap.parse_args(argv)
    rows = measure(tuple(args.size or (400_000, 100_000)), args.rounds, args.only, args.timeout,
                   args.tree)
    print("\n".join(lines(rows)))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
