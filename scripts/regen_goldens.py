#!/usr/bin/env python3
"""Regenerate the disassembly goldens (tests/lang/golden/**/*.dis) on purpose.

Run it after a deliberate change to the code generator, then read the diff:
    .venv/bin/python scripts/regen_goldens.py && git diff --stat tests/lang/golden
"""

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from tests.lang.golden_util import compile_golden, goldens, listing  # noqa: E402


def main() -> int:
    written = removed = 0
    for g in goldens():
        r = compile_golden(g)
        if r.program is None:
            if g.dis_path.exists():
                g.dis_path.unlink()
                removed += 1
            continue
        text = listing(g, r)
        if not g.dis_path.exists() or g.dis_path.read_text(encoding="utf-8") != text:
            g.dis_path.write_text(text, encoding="utf-8")
            written += 1
    print(f"{written} listing(s) written, {removed} removed")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
