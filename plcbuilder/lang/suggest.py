""""Did you mean …?": the name in scope nearest a misspelled one.

Nearness is the edit distance (letters inserted, deleted, changed, or two
neighbours swapped), letter case aside; how far a name may be from what was
meant grows with its length, so that short names (``a1``, ``x2``), which
differ by one letter from many others on purpose, get no suggestion unless
only their case differs.
"""

from __future__ import annotations

TYPE_CHECKING = False               # (typing is not imported at run time: start-up)
if TYPE_CHECKING:
    from typing import Iterable, Optional


def max_distance(name: str) -> int:
    """How many edits a misspelling of a name this long may have."""
    n = len(name)
    return 0 if n <= 3 else 1 if n <= 5 else 2 if n <= 9 else 3


def distance(a: str, b: str, limit: int) -> int:
    """The edit distance of a and b (optimal string alignment), or ``limit + 1``
    when it is more than ``limit``."""
    if abs(len(a) - len(b)) > limit:
        return limit + 1
    prev2: list[int] = []
    prev = list(range(len(b) + 1))
    for i, ca in enumerate(a, 1):
        cur = [i] + [0] * len(b)
        best = i
        for j, cb in enumerate(b, 1):
            d = min(prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + (ca != cb))
            if i > 1 and j > 1 and ca == b[j - 2] and a[i - 2] == cb:
                d = min(d, prev2[j - 2] + 1)
            cur[j] = d
            best = min(best, d)
        if best > limit:
            return limit + 1
        prev2, prev = prev, cur
    return prev[-1]


def did_you_mean(name: str, candidates: "Iterable[str]") -> Optional[str]:
    """The candidate nearest ``name`` (not ``name`` itself), within
    :func:`max_distance`; the nearest first, then the one whose length is
    nearest, then alphabetical order. None when none is near."""
    low = name.lower()
    limit = max_distance(name)
    best: Optional[tuple] = None
    for c in candidates:
        if c == name:
            continue
        cl = c.lower()
        d = -1 if cl == low else distance(low, cl, limit)   # a change of case: nearest of all
        if d > limit:
            continue
        key = (d, abs(len(c) - len(name)), c)
        if best is None or key < best:
            best = key
    return None if best is None else best[2]
