#!/usr/bin/env python3
"""The long attack: every attack module's ``ATTACKS`` run in turn, and a table
``item | tried | refused | accepted | crashed``.

    .venv/bin/python scripts/attack.py                 # everything
    .venv/bin/python scripts/attack.py 17.4 fuzz       # items whose name contains a word
    PLCB_ATTACK_SECONDS=20 .venv/bin/python scripts/attack.py   # longer

Modules: ``attack_link`` (the controller server), ``attack_lsp`` (the
language server), and ``attack_image``, ``attack_files``, ``attack_sources``
(hostile PLC sources and breakpoint conditions) and ``attack_dap`` (the debug
adapter, Build All) when present; each defines ``ATTACKS: list[tuple[str,
callable]]`` whose callables return ``{"tried", "refused", "accepted",
"crashed"}``. ``accepted`` counts attacks that got through, ``crashed`` the
times the target died or stopped answering (an attack that raises counts as
one crash): both are 0 when the defences hold (exit status 1 if not). In a
fuzz row (its name says "fuzz"), ``accepted`` counts the random requests that
happened to be well-formed and were answered, which is not a defect; in a row
whose name says "must be accepted" (a documented limit), refusing is the defect.
"""

from __future__ import annotations

import importlib
import sys
import time
import traceback
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
sys.path.insert(0, str(HERE))

MODULES = ("attack_link", "attack_image", "attack_files", "attack_sources", "attack_dap",
           "attack_lsp")
KEYS = ("tried", "refused", "accepted", "crashed")


def attacks() -> list:
    out = []
    for name in MODULES:
        try:
            mod = importlib.import_module(name)
        except ModuleNotFoundError as exc:
            if exc.name == name:
                continue                    # not written (yet)
            raise
        out += list(mod.ATTACKS)
    return out


def main(argv=None) -> int:
    words = list(sys.argv[1:] if argv is None else argv)
    chosen = [(n, f) for n, f in attacks() if not words or any(w in n for w in words)]
    rows = []
    width = max([len(n) for n, _ in chosen] + [4])
    for name, fn in chosen:
        t0 = time.monotonic()
        print(f"  {name} ...", file=sys.stderr, flush=True)
        try:
            counts = fn()
        except Exception:  # noqa: BLE001 - the attack itself broke: say so, go on
            traceback.print_exc()
            counts = {"tried": 0, "refused": 0, "accepted": 0, "crashed": 1}
        rows.append((name, counts, time.monotonic() - t0))
    print(f"{'item':<{width}} | {'tried':>7} | {'refused':>7} | {'accepted':>8} | "
          f"{'crashed':>7} | seconds")
    print("-" * (width + 50))
    for name, c, secs in rows:
        print(f"{name:<{width}} | {c['tried']:>7} | {c['refused']:>7} | {c['accepted']:>8} | "
              f"{c['crashed']:>7} | {secs:7.1f}")
    def failed(name: str, c: dict) -> bool:
        if c["crashed"]:
            return True
        if "must be accepted" in name:      # a limit that must hold: refusing it is the defect
            return c["refused"] > 0
        return c["accepted"] > 0 and "fuzz" not in name
    bad = any(failed(name, c) for name, c, _ in rows)
    return 1 if bad else 0


if __name__ == "__main__":
    raise SystemExit(main())
