#!/usr/bin/env python3
"""Benchmarks, measured side by side in one run and printed as ratios.

    .venv/bin/python scripts/bench.py            # every section
    .venv/bin/python scripts/bench.py compile    # one section

Each section lives in scripts/bench_<name>.py and defines ``run() -> list[str]``
(lines to print, each a figure with its goal). Benchmarks are not tests: they
print, they never fail the suite.
"""

from __future__ import annotations

import argparse
import importlib
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
sys.path.insert(0, str(HERE))


def sections() -> list[str]:
    return sorted(p.stem.removeprefix("bench_") for p in HERE.glob("bench_*.py"))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("section", nargs="*", help=f"sections: {', '.join(sections())} (default: all)")
    args = ap.parse_args(argv)
    chosen = args.section or sections()
    unknown = [s for s in chosen if s not in sections()]
    if unknown:
        ap.error(f"unknown section(s): {', '.join(unknown)}; choose from {', '.join(sections())}")
    for name in chosen:
        mod = importlib.import_module(f"bench_{name}")
        print(f"== {name}")
        for line in mod.run():
            print("  " + line, flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
