"""Attacks on the compiler with hostile sources (issue 24 items 1 and 2,
issue 23 item 17), against the real command line: each case runs
``python -m plcbuilder check FILE`` (or ``run --break`` with a hostile
condition) in a child, with a timeout, beside an ordinary source of the same
size.

    ATTACKS: list[tuple[str, callable]]   name, attack() -> {"tried", "refused",
                                          "accepted", "crashed"}

Each case is classified:

- refused: the command answered (exit 1, an error naming the problem) within
  twice the ordinary source's time (the goal; a little slack for a busy
  machine);
- accepted: it answered, but took longer than that: the input stalled the tool;
- crashed: a traceback, "internal error", a RecursionError/MemoryError, a
  signal, or no answer within the timeout.

``scripts/attack.py`` imports ATTACKS and prints the table with the others;
run alone, this prints its own table (``--verbose`` lists every case).

    PLCB_ATTACK_SOURCE_KB=400 .venv/bin/python scripts/attack_sources.py -v
"""

from __future__ import annotations

import os
import sys
import tempfile
import time
from pathlib import Path
from typing import Callable

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from attack_files import Outcome, Tally, plcbuilder  # noqa: E402
from hostile_sources import hostile, ordinary  # noqa: E402

SIZE = int(os.environ.get("PLCB_ATTACK_SOURCE_KB", "100")) * 1000
GOAL = 2.0
SLACK_S = 0.3           # a child's start-up moves this much on a busy machine
TIMEOUT_S = float(os.environ.get("ATTACK_TIMEOUT_S", "60"))


def _timed(argv, cwd: Path) -> tuple[Outcome, float]:
    t = time.perf_counter()
    o = plcbuilder(*argv, cwd=cwd, timeout=TIMEOUT_S)
    return o, time.perf_counter() - t


def _errors(o: Outcome) -> list[str]:
    return [ln for ln in o.text.splitlines() if ": error: " in ln]


def attack_hostile_sources() -> dict:
    """Each hostile source is checked within twice an ordinary source of the
    same size, and says what is wrong in at most a screenful of errors."""
    tally = Tally("24.1")
    with tempfile.TemporaryDirectory(prefix="attack-sources-") as d:
        tmp = Path(d)
        base = tmp / "ordinary.plc"
        base.write_text(ordinary(SIZE))
        _timed(["check", base], tmp)                             # compile the modules
        budget = min(_timed(["check", base], tmp)[1] for _ in range(2)) * GOAL + SLACK_S
        for k, (name, text) in enumerate(hostile(SIZE).items()):
            path = tmp / f"hostile{k}.plc"
            path.write_text(text)
            o, secs = _timed(["check", path], tmp)
            errors = _errors(o)
            answered = o.rc in (0, 1) and (o.rc == 0 or errors)
            tally.case(f"{name} ({secs:.2f} s, budget {budget:.2f} s, {len(errors)} errors)", o,
                       refused=answered and secs <= budget and len(errors) <= 101)
    return tally.result()


def attack_cut_off_file() -> dict:
    """Issue 23.17: a file past the token limit reports that alone."""
    tally = Tally("23.17")
    with tempfile.TemporaryDirectory(prefix="attack-sources-") as d:
        tmp = Path(d)
        # (check refuses a file over 1 MiB before reading it; the IDE compiled a
        # 2.7 MB buffer: 900 KB is past the token limit too)
        for name, text in (("900 KB procedure", ordinary(900_000)),
                           ("one line of 300,000 tokens", "main(){ " + "x=1;" * 75_000 + "};")):
            path = tmp / "big.plc"
            path.write_text(text)
            o = plcbuilder("check", path, "--software", cwd=tmp, timeout=TIMEOUT_S)
            errors = _errors(o)
            one = len(errors) == 1 and "tokens" in errors[0]
            tally.case(f"{name}: {errors[:2]}", o, refused=o.rc == 1 and one)
    return tally.result()


def attack_breakpoint_conditions() -> dict:
    """Issue 24.2: a hostile breakpoint condition is refused in about the time
    a plain one takes to compile (the condition compile is linear and bounded)."""
    tally = Tally("24.2")
    with tempfile.TemporaryDirectory(prefix="attack-sources-") as d:
        tmp = Path(d)
        src = tmp / "M03.plc"
        src.write_text("main()\n{\n  x = 1;\n  exit(99);\n};\n")
        plain = min(_timed(["run", src, "--ms", "10", "--break", f"{src}:3:x == 1"], tmp)[1]
                    for _ in range(2))
        for name, cond in (("( x 800", "(" * 800), ("( x 1,600", "(" * 1_600),
                           ("( x 3,200", "(" * 3_200), ("( x 250 unclosed", "(" * 250 + "x"),
                           ("- x 900", "- " * 900 + "x"), ("x+ x 30,000", "x+" * 30_000 + "x"),
                           ("[ x 500", "x" + "[" * 500)):
            o, secs = _timed(["run", src, "--ms", "10", "--break", f"{src}:3:{cond}"], tmp)
            tally.case(f"{name} ({secs:.2f} s, a plain one {plain:.2f} s)", o,
                       refused=o.rc == 2 and "does not compile" in o.text
                       and secs <= GOAL * plain + SLACK_S)
    return tally.result()


ATTACKS: list[tuple[str, Callable[[], dict]]] = [
    ("24.1 hostile sources within 2x an ordinary one", attack_hostile_sources),
    ("23.17 a file past the token limit: one error", attack_cut_off_file),
    ("24.2 hostile breakpoint conditions", attack_breakpoint_conditions),
]


def main(argv: list[str]) -> int:
    import attack_files
    attack_files.VERBOSE = "--verbose" in argv or "-v" in argv
    wanted = [a for a in argv if not a.startswith("-")]
    rows = [(name, fn()) for name, fn in ATTACKS if not wanted or any(w in name for w in wanted)]
    attack_files.print_table(rows)
    return 1 if any(r["accepted"] or r["crashed"] for _, r in rows) else 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
