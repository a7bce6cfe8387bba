"""Step-back benchmark (SPEC §7): a ten-minute session of the example project
(its software procedures running, a hardware procedure started now and then,
an input toggled every second), then one step back of a tick, one of a
statement and a run back, each timed against the floor: the time to simulate
those ten minutes at Max speed (samples off), which is what running the
recording again costs at least.

    PYTHONPATH=. .venv/bin/python scripts/bench_rewind.py [--minutes 10] [--repeat 3]
    .venv/bin/python scripts/bench.py rewind            (ten minutes, three each)

Goal: a step back answers in well under a second (issue 11: <= 0.5 s). Run
back is timed with and without checkpoints, interleaved with the floor
measured again each time (medians of ``--repeat``).
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from plcbuilder import api  # noqa: E402
from plcbuilder.controller.controller import Controller  # noqa: E402
from plcbuilder.controller.rewind import Checkpoints, run_back, step_back  # noqa: E402

EXAMPLE = Path(api.__file__).parent / "resources" / "example_project"


def _programs():
    proj = api.Project.open(EXAMPLE)
    return [p for p in (pb.program() for pb in api.compile_all(proj)) if p is not None]


def session(minutes: float) -> tuple[Controller, float]:
    """The session, driven as the IDE drives it; returns it and its wall time."""
    programs = _programs()
    hw = sorted(p.name for p in programs if p.kind is api.Kind.HARDWARE)
    c = Controller(record_samples=False)
    end = int(minutes * 60_000)
    t0 = time.perf_counter()
    c.load(programs)
    k = 0
    while c.t_ms < end:
        if k % 10 == 0:
            try:
                c.start(hw[(k // 10) % len(hw)], 1000 + k)
            except api.ControllerError:
                pass
        c.set_input(3, k % 2)
        c.step(1000)
        k += 1
    return c, time.perf_counter() - t0


def run_backs(back: Controller, pool: Checkpoints, minutes: float, repeat: int) -> None:
    """Run back from ``back`` with and without checkpoints, interleaved with the
    floor (the session simulated again), ``repeat`` times each: the medians."""
    floors, plain, pooled = [], [], []
    for _ in range(repeat):
        floors.append(session(minutes)[1])
        t0 = time.perf_counter()
        a = run_back(back, Controller)
        plain.append(time.perf_counter() - t0)
        while pool.work(back, 1.0):            # the checkpoints the last one used up
            pass
        t0 = time.perf_counter()
        b = run_back(back, Controller, pool)
        pooled.append(time.perf_counter() - t0)
        sa, sb = a.debugger.halted_state(), b.debugger.halted_state()
        assert (a.t_ms, sa["line"], sa["procedure"]) == (b.t_ms, sb["line"], sb["procedure"])
    floor = statistics.median(floors)
    p, q = statistics.median(plain), statistics.median(pooled)
    say(f"run back (from {back.t_ms} ms to the hit at {a.t_ms} ms, median of {repeat}, "
          f"floor {floor:.3f} s):")
    say(f"  without checkpoints (from t = 0): {p:.3f} s ({p / floor:.2f}x the floor)")
    say(f"  from checkpoints: {q:.3f} s ({q / floor:.2f}x the floor; goal < 0.5 s)")


#: where the figures go: printed by main(), collected by run() (scripts/bench.py)
say = print


def run() -> list[str]:
    """Section ``rewind`` of scripts/bench.py: the figures as lines."""
    global say
    lines: list[str] = []
    say = lines.append
    try:
        figures(10.0, 3)
    finally:
        say = print
    return lines


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--minutes", type=float, default=10.0)
    ap.add_argument("--repeat", type=int, default=3, help="run backs timed each way (median)")
    args = ap.parse_args(argv)
    figures(args.minutes, args.repeat)
    return 0


def figures(minutes: float, repeat: int) -> None:
    c, floor = session(minutes)
    say(f"session: {c.t_ms} ms simulated, {len(c.recorder.actions)} actions recorded; "
          f"floor (simulating it at Max speed): {floor:.3f} s")
    pool = Checkpoints(Controller)
    t0 = time.perf_counter()
    while pool.work(c, 1.0):
        pass
    say(f"checkpoints every {pool.every_ms // 1000} s (the last {pool.keep}), made in "
          f"idle time: {time.perf_counter() - t0:.3f} s of work in all")
    t0 = time.perf_counter()
    back = step_back(c, Controller, "tick", pool)
    took = time.perf_counter() - t0
    say(f"step back one tick, from a checkpoint: {took:.3f} s (goal < 0.5 s)")
    t0 = time.perf_counter()
    back = step_back(c, Controller, "tick")
    took = time.perf_counter() - t0
    say(f"step back one tick, without checkpoints: {took:.3f} s "
          f"({took / floor:.2f}x the floor), now at {back.t_ms} ms")
    # LUBE (software) switches its pump on at line 12 and off at line 17, once a minute
    back.debugger.set_breakpoints("LUBE.plc", [{"line": 12}, {"line": 17}])
    back.debugger.resume()
    back.step(70_000)
    if back.debugger.halted:
        t0 = time.perf_counter()
        while pool.work(back, 1.0):            # again: the breakpoints changed
            pass
        say(f"checkpoints made again with these breakpoints: "
              f"{time.perf_counter() - t0:.3f} s of work")
        t0 = time.perf_counter()
        step_back(back, Controller, "statement", pool)
        took = time.perf_counter() - t0
        say(f"step back one statement (LUBE at {back.t_ms} ms), "
              f"from checkpoints: {took:.3f} s (goal < 0.5 s)")
        t0 = time.perf_counter()
        step_back(back, Controller, "statement")
        took = time.perf_counter() - t0
        say(f"step back one statement, without checkpoints (two runs): {took:.3f} s "
              f"({took / floor:.2f}x the floor)")
        run_backs(back, pool, minutes, repeat)


if __name__ == "__main__":
    raise SystemExit(main())
