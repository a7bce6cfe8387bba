#!/usr/bin/env python3
"""The long fuzz run: programs generated from the grammar and mutated programs
through the whole compiler; anything but diagnostics is a failure. Then
sessions of random edits compiled incrementally, each compile compared with a
compile from scratch (what tests/lang/test_incremental.py does for a few
seconds); any difference is a failure.

    .venv/bin/python scripts/fuzz.py [--generated N] [--mutated N] [--edits N] [--seed S]

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
from tests.lang.test_incremental import _assert_same, _edit, _long_program, _programs  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--generated", type=int, default=10_000)
    ap.add_argument("--mutated", type=int, default=10_000)
    ap.add_argument("--edits", type=int, default=5_000, help="random edits compiled incrementally")
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
    t2 = time.perf_counter()
    failures += incremental_edits(args.edits, args.seed)
    print(f"incremental: {args.edits} edits, {time.perf_counter() - t2:.1f} s")
    print(f"{failures} failure(s)")
    return 1 if failures else 0


def incremental_edits(edits: int, seed: int) -> int:
    """Sessions of 60 random edits (a quarter of them undoing the one before)
    of golden programs and long ones, each compiled incrementally and from
    scratch; returns how many differed."""
    from plcbuilder.api import CompileOptions, compile_source
    from plcbuilder.lang.incremental import Incremental
    rng = random.Random(seed)
    corpus = [p.read_text(encoding="utf-8") for p in _programs()]
    failures = done = 0
    while done < edits:
        text = rng.choice(corpus) if rng.random() < 0.7 else _long_program(rng.randint(3, 40))
        inc, history = Incremental(), [text]
        for _ in range(min(60, edits - done)):
            text = history[-2] if len(history) > 2 and rng.random() < 0.25 else _edit(rng, text)
            history.append(text)
            done += 1
            try:
                _assert_same(compile_source(text, "P.plc", CompileOptions(), incremental=inc),
                             compile_source(text, "P.plc", CompileOptions()), "")
            except AssertionError:
                failures += 1
                print(f"incremental compile differs after the edit from {history[-2]!r} to {text!r}")
                break
    return failures


if __name__ == "__main__":
    raise SystemExit(main())
