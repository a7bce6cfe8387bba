#!/usr/bin/env python3
"""The long fuzz run: programs generated from the grammar and mutated programs
through the whole compiler; anything but diagnostics is a failure.

    .venv/bin/python scripts/fuzz.py [--generated N] [--mutated N] [--seed S]

The normal suite runs 2,000 of each (tests/lang/test_fuzz.py); this runs more.
"""

from __future__ import annotations

import argparse
import random
import sys
import time
import traceback
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from hypothesis import HealthCheck, given, settings  # noqa: E402

from tests.lang.fuzzing import check_one, mutate, seeds  # noqa: E402
from tests.lang.test_fuzz import PROGRAMS  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--generated", type=int, default=10_000)
    ap.add_argument("--mutated", type=int, default=10_000)
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args()
    failures = 0
    count = 0
    t0 = time.perf_counter()

    @settings(max_examples=args.generated, deadline=None, database=None,
              suppress_health_check=list(HealthCheck))
    @given(PROGRAMS)
    def generated(text):
        nonlocal count
        count += 1
        check_one(text.encode("utf-8", "surrogatepass"))

    try:
        generated()
    except Exception:  # noqa: BLE001 - report and go on to the mutations
        failures += 1
        traceback.print_exc()
    print(f"generated: {count} programs, {time.perf_counter() - t0:.1f} s")

    t1 = time.perf_counter()
    rng = random.Random(args.seed)
    corpus = seeds()
    for i in range(args.mutated):
        data = mutate(rng.choice(corpus), rng)
        try:
            check_one(data, software=i % 5 == 0, strict=i % 7 == 0)
        except Exception:  # noqa: BLE001
            failures += 1
            print(f"mutated #{i} failed; input: {data!r}")
            traceback.print_exc()
    print(f"mutated: {args.mutated} programs, {time.perf_counter() - t1:.1f} s")
    print(f"{failures} failure(s)")
    return 1 if failures else 0


if __name__ == "__main__":
    raise SystemExit(main())
