"""Build All benchmark: a generated project of 1,000 procedures (100 hardware,
900 software of ~45 lines) against lark's bare parse of the same files.

Every figure is a ratio to a floor measured side by side: each round runs
the floor and the build back to back, and the figure is the median of the
rounds' own ratios (5 rounds). A ratio of the medians moved from 0.77x to
1.61x between two runs of the same code on the shared machine: Build All
compiles on both cores, and the other core is not always free.

  cold Build All / single-core bare lark parse of every file     (goal <= 1.2x)
  (and the CPU time of both, every process counted: the work done)
  unchanged rebuild / cold Build All                              (goal <= 0.05)
  peak memory of Build All at 1,000 and 2,000 procedures, each in a fresh
  child process, against the floor: the same child importing everything and
  parsing one file with bare lark                                 (goal <= 60 MB,
                                                                   flat)

    python scripts/bench.py build
    python scripts/bench_build.py --child build PROJECT    (one measured child)
"""

from __future__ import annotations

import json
import os
import re
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
ROUNDS = 5
SETTINGS = "[limits]\nhw_proc = 16384\nhw_total = 1048576\nsw_proc = 16384\n"
_DIRECTIVE = re.compile(r"^[ \t]*#.*$", re.MULTILINE)


def make_project(root: Path, n: int) -> Path:
    """n procedures: a tenth hardware, the rest software, ~45 lines each."""
    sys.path.insert(0, str(HERE))
    from bench_compile import procedure

    from plcbuilder.project.new import PINS, _resource
    (root / "hardware").mkdir(parents=True)
    (root / "software").mkdir()
    (root / "include").mkdir()
    (root / "include" / "pins.h").write_bytes(_resource(PINS).read_bytes())
    (root / "plcbuilder.toml").write_text(SETTINGS)
    hw = n // 10
    for i in range(n):
        folder, name = ("hardware", f"M{1000 + i}") if i < hw else ("software", f"P{i:05d}")
        (root / folder / f"{name}.plc").write_text("#include pins.h\n" + procedure(45, i))
    return root


def _files(root: Path) -> list[Path]:
    return sorted((root / "hardware").glob("*.plc")) + sorted((root / "software").glob("*.plc"))


# ------------------------------------------------------------------ children

def _child(argv: list[str]) -> None:
    """One measurement in this (fresh) process; prints JSON."""
    what, root = argv[0], Path(argv[1])
    sys.path.insert(0, str(ROOT))
    if what == "floor":          # everything imported, one file parsed by bare lark
        from bench_compile import bare_lark

        import plcbuilder.project.build  # noqa: F401
        lark = bare_lark()
        lark.parse(_DIRECTIVE.sub("", _files(root)[0].read_text()))
        t, cpu0 = 0.0, time.process_time()
    elif what == "parse":        # the floor: bare lark parsing every file, one core
        from bench_compile import bare_lark
        lark = bare_lark()
        t0, cpu0 = time.perf_counter(), time.process_time()
        for p in _files(root):
            lark.parse(_DIRECTIVE.sub("", p.read_text()))
        t = time.perf_counter() - t0
    else:                        # "build": Build All (cold when build/ is gone)
        from plcbuilder.project import Project, build_project
        project = Project.open(root)
        t0, cpu0 = time.perf_counter(), time.process_time()
        r = build_project(project)
        t = time.perf_counter() - t0
        assert r.ok and r.image_written, r.image_message
    me = resource.getrusage(resource.RUSAGE_SELF)
    kids = resource.getrusage(resource.RUSAGE_CHILDREN)
    print(json.dumps({"t": t, "cpu": time.process_time() - cpu0 + kids.ru_utime + kids.ru_stime,
                      "rss_mb": me.ru_maxrss / 1024, "workers_mb": kids.ru_maxrss / 1024}))


def _run(what: str, root: Path) -> dict:
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    out = subprocess.run([sys.executable, str(Path(__file__).resolve()), "--child", what, str(root)],
                         check=True, capture_output=True, text=True, env=env, cwd=str(ROOT))
    return json.loads(out.stdout.strip().splitlines()[-1])


def _cold(root: Path) -> dict:
    shutil.rmtree(root / "build", ignore_errors=True)
    return _run("build", root)


def run() -> list[str]:
    with tempfile.TemporaryDirectory(prefix="bench-build-") as tmp:
        p1000 = make_project(Path(tmp) / "p1000", 1000)
        p2000 = make_project(Path(tmp) / "p2000", 2000)
        time.sleep(2.5)                       # let the sources age (racy-stat guard)
        _cold(p1000)                          # warm the disk cache
        parse, cold, again, floor, m1000, m2000 = [], [], [], [], [], []
        parse_cpu, cold_cpu = [], []
        for _ in range(ROUNDS):               # interleaved: a busy moment hits all alike
            b = _run("parse", p1000)
            parse.append(b["t"])
            parse_cpu.append(b["cpu"])
            c = _cold(p1000)
            cold.append(c["t"])
            cold_cpu.append(c["cpu"])
            again.append(_run("build", p1000)["t"])
            floor.append(_run("floor", p1000)["rss_mb"])
            m1000.append(c)
            m2000.append(_cold(p2000))
    med = statistics.median
    bare, c, u, fl = med(parse), med(cold), med(again), med(floor)
    cold_ratio = med(x / y for x, y in zip(cold, parse))
    again_ratio = med(x / y for x, y in zip(again, cold))
    cpu_ratio = med(x / y for x, y in zip(cold_cpu, parse_cpu))
    rss1, rss2 = med(m["rss_mb"] for m in m1000), med(m["rss_mb"] for m in m2000)
    w1, w2 = med(m["workers_mb"] for m in m1000), med(m["workers_mb"] for m in m2000)
    return [
        f"bare lark parse of 1,000 files, one core (floor): {bare:.2f} s",
        f"cold Build All of 1,000 procedures: {c:.2f} s = {cold_ratio:.2f}x the bare parse"
        f"   (goal <= 1.2x; the median of {ROUNDS} rounds' own ratios)",
        f"  CPU time, every process: {med(cold_cpu):.2f} s = {cpu_ratio:.2f}x "
        f"the bare parse's {med(parse_cpu):.2f} s (more cores help only when they are free)",
        f"unchanged rebuild: {u * 1000:.0f} ms = {again_ratio:.3f} of cold   (goal <= 0.05)",
        f"memory floor (imports + one bare parse): {fl:.0f} MB",
        f"peak memory, 1,000 procedures: {rss1:.0f} MB (+{rss1 - fl:.0f} over the floor; "
        f"largest worker {w1:.0f} MB)   (goal <= 60 MB)",
        f"peak memory, 2,000 procedures: {rss2:.0f} MB (+{rss2 - fl:.0f} over the floor; "
        f"largest worker {w2:.0f} MB)   (goal: flat, = 1,000's)",
    ]


if __name__ == "__main__":
    if sys.argv[1:2] == ["--child"]:
        _child(sys.argv[2:])
    else:
        sys.path.insert(0, str(ROOT))
        for line in run():
            print(line, flush=True)
