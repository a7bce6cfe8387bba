"""Start-up of the command line (issue 26 items 1 and 2), against a bare
Python start measured beside it.

  each command / ``python -c pass``: ``plcbuilder --version``, ``check`` and
  ``compile`` of a 4-line procedure, ``run`` of it (one procedure)   (goal <= 3x)
  unchanged rebuild of 1,000 procedures through ``plcbuilder build``, end to
  end / the cold ``plcbuilder build`` of the same project          (goal <= 0.05)

Each round runs the bare start and every command back to back (interleaved:
a busy moment hits all alike); a figure is the median of the rounds' own
ratios (9 rounds; 5 for the rebuild). Wall time is what a user waits; the
processor time of the child (user + system) moves less on a shared machine,
so both are printed. Modules are compiled once first (as in an installed
package: ``PYTHONDONTWRITEBYTECODE`` is dropped for the children).

    python scripts/bench_startup.py [--rounds N] [--no-rebuild] [--tree DIR] [--before DIR]
    python scripts/bench.py startup
"""

from __future__ import annotations

import argparse
import os
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
SOURCE = "main()\n{\n  exit(99);\n};\n"
GOAL, REBUILD_GOAL = 3.0, 0.05


def _env(tree: Path | None) -> dict:
    env = dict(os.environ)
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    if tree is not None:
        env["PYTHONPATH"] = str(tree)
    return env


def timed(argv: list[str], env: dict, cwd: Path) -> tuple[float, float]:
    """(wall seconds, the child's processor seconds) of one run."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t = time.perf_counter()
    subprocess.run(argv, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env, cwd=cwd,
                   check=False)
    wall = time.perf_counter() - t
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime)


def _plcbuilder(tree: Path | None) -> list[str]:
    """The installed command (its console script), or ``python -m plcbuilder``
    for another checkout."""
    script = Path(sys.executable).with_name("plcbuilder")
    if tree is None and script.exists():
        return [str(script)]
    return [sys.executable, "-m", "plcbuilder"]


def commands(tmp: Path, tree: Path | None) -> dict[str, list[str]]:
    src = tmp / "M90.plc"
    src.write_text(SOURCE)
    cmd = _plcbuilder(tree)
    return {"--version": cmd + ["--version"],
            "check": cmd + ["check", str(src)],
            "compile": cmd + ["compile", str(src), "-o", str(tmp / "M90.bin")],
            "run (one procedure)": cmd + ["run", str(src)]}


def measure_startup(rounds: int = 9, tree: Path | None = None,
                    before: Path | None = None) -> dict:
    """Each command's start against a bare Python start in the same round.
    With ``before`` (another checkout's package), its commands run in every
    round too, as ``NAME (before)``, the two trees taking turns at going first
    (both started as ``python -m plcbuilder``)."""
    if before is not None and tree is None:
        tree = ROOT
    env = _env(tree)
    with tempfile.TemporaryDirectory(prefix="plc-startup-") as d:
        tmp = Path(d)
        cmds = {k: (v, env) for k, v in commands(tmp, tree).items()}
        if before is not None:
            old = {f"{k} (before)": (v, _env(before)) for k, v in commands(tmp, before).items()}
        else:
            old = {}
        bare = [sys.executable, "-c", "pass"]
        for argv, e in [(bare, env), *cmds.values(), *old.values()]:
            timed(argv, e, tmp)                            # compiles the modules
        base_w, base_c = [], []
        names = [*cmds, *old]
        walls = {k: [] for k in names}
        ratios = {k: [] for k in names}
        cpu_ratios = {k: [] for k in names}
        for i in range(rounds):
            bw, bc = timed(bare, env, tmp)
            base_w.append(bw)
            base_c.append(bc)
            for name, (argv, e) in _turns(cmds, old, i):
                w, c = timed(argv, e, tmp)
                walls[name].append(w)
                ratios[name].append(w / bw)
                cpu_ratios[name].append(c / bc if bc > 0 else float("nan"))
    med = statistics.median
    return {"bare_ms": med(base_w) * 1000, "bare_cpu_ms": med(base_c) * 1000,
            "commands": {k: {"ms": med(walls[k]) * 1000, "ratio": med(ratios[k]),
                             "cpu_ratio": med(cpu_ratios[k])} for k in names}}


def _turns(cmds: dict, old: dict, i: int) -> list:
    """One round's runs: each command of this tree beside the same command of
    the tree before, this one first in even rounds, the other in odd ones."""
    out = []
    for name, item in cmds.items():
        pair = [(name, item)]
        if old:
            pair.append((f"{name} (before)", old[f"{name} (before)"]))
        out += pair if i % 2 == 0 else pair[::-1]
    return out


def measure_rebuild(rounds: int = 5, tree: Path | None = None) -> dict:
    sys.path.insert(0, str(HERE))
    from bench_build import make_project
    env = _env(tree)
    cmd = _plcbuilder(tree)
    with tempfile.TemporaryDirectory(prefix="plc-rebuild-") as d:
        root = make_project(Path(d) / "p1000", 1000)
        time.sleep(2.5)                                    # let the sources age (racy stat)
        build = cmd + ["build", str(root)]
        timed(build, env, root)                            # warm the disk cache
        cold, again, ratios = [], [], []
        for _ in range(rounds):
            shutil.rmtree(root / "build", ignore_errors=True)
            c, _ = timed(build, env, root)
            a, _ = timed(build, env, root)
            cold.append(c)
            again.append(a)
            ratios.append(a / c)
    med = statistics.median
    return {"cold_s": med(cold), "again_ms": med(again) * 1000, "ratio": med(ratios)}


def lines(s: dict, r: dict | None) -> list[str]:
    out = [f"bare `python -c pass`: {s['bare_ms']:.0f} ms ({s['bare_cpu_ms']:.0f} ms of processor)"]
    for name, c in s["commands"].items():
        out.append(f"plcbuilder {name:<29} {c['ms']:6.0f} ms = {c['ratio']:.2f}x bare "
                   f"(processor {c['cpu_ratio']:.2f}x)   (goal <= {GOAL:g}x)")
    if r is not None:
        out.append(f"unchanged rebuild of 1,000 procedures, `plcbuilder build`: {r['again_ms']:.0f} ms "
                   f"= {r['ratio']:.3f} of the cold build's {r['cold_s']:.2f} s   "
                   f"(goal <= {REBUILD_GOAL})")
    return out


def run() -> list[str]:
    """Section ``startup`` of scripts/bench.py."""
    return lines(measure_startup(), measure_rebuild())


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--rounds", type=int, default=9)
    ap.add_argument("--no-rebuild", action="store_true")
    ap.add_argument("--tree", type=Path, help="run this checkout's code")
    ap.add_argument("--before", type=Path, metavar="DIR",
                    help="also run DIR's package (`git archive REV plcbuilder | tar -x -C DIR`) "
                         "in every round, interleaved, for before/after figures")
    args = ap.parse_args(argv)
    s = measure_startup(args.rounds, args.tree, args.before)
    r = None if args.no_rebuild else measure_rebuild(5, args.tree)
    print("\n".join(lines(s, r)))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
