"""The LALR(1) tables of ``grammar.lark``, and what error recovery asks of them.

The tables are built by lark once (:mod:`plcbuilder.lang.lark_adapter`) and
kept as a module of literals, ``grammar_tables.py`` (Python keeps it
compiled): a command starts without importing lark or building tables. If the
module does not match the grammar (an edited ``grammar.lark`` whose tables
were not regenerated; the suite fails then), the tables are built from the
grammar instead, which needs lark and takes a quarter of a second.

- ``states[s]``: symbol -> action. A terminal's action is ``n >= 0`` (shift,
  go to state n) or ``-1 - r`` (reduce by rule r); a nonterminal's is the state
  to go to after reducing to it.
- ``rules[r]``: ``(origin, size, method, expand1, children)``: reducing pops
  ``size`` values and makes one: a helper list when ``method`` is None (the
  ``x*`` of the grammar), else the tree builder's ``method`` on the children
  (``children`` None: all of them; else ``(i, splice)`` pairs: the i-th value,
  spliced when it is a helper list); ``expand1``: a ``?rule`` whose only child
  is its value.

:func:`accepts` and :class:`Trial` run the tables on a copy-free view of a
state stack, as lark's interactive parser does on a copy, so error recovery
can try tokens without building anything or copying a deep stack.
"""

from __future__ import annotations

from _thread import allocate_lock
from pathlib import Path

TYPE_CHECKING = False               # (typing is not imported at run time: start-up)
if TYPE_CHECKING:
    from typing import Optional

_HERE = Path(__file__).resolve().parent
FORMAT = 1


class Tables:
    __slots__ = ("states", "rules", "start", "end", "list_state", "terminals")

    def __init__(self, data: dict):
        self.states: list[dict] = list(data["states"])
        self.rules: list[tuple] = [
            (o, n, m, e, None if c is None else tuple((i, bool(s)) for i, s in c))
            for o, n, m, e, c in data["rules"]]
        self.start: int = data["start_state"]
        self.end: int = data["end_state"]
        self.list_state: int = data["list_state"]
        #: the terminals of each state's row, in a fixed order
        self.terminals: list[tuple] = [tuple(sorted(k for k in row if k.isupper()))
                                       for row in self.states]


_lock = allocate_lock()
_tables: Optional[Tables] = None


def tables() -> Tables:
    """The grammar's tables (read once)."""
    global _tables
    if _tables is None:
        with _lock:
            if _tables is None:
                _tables = Tables(_load())
    return _tables


def _load() -> dict:
    grammar = (_HERE / "grammar.lark").read_text(encoding="utf-8")
    try:
        from plcbuilder.lang import grammar_tables as g
        if g.FORMAT == FORMAT and g.GRAMMAR == grammar:
            return {"states": g.STATES, "rules": g.RULES, "start_state": g.START_STATE,
                    "end_state": g.END_STATE, "list_state": g.LIST_STATE}
    except (ImportError, AttributeError):
        pass
    from plcbuilder.lang.lark_adapter import build_tables   # stale or missing: build them
    return build_tables(grammar)


class Trial:
    """A state stack as it would be after feeding some tokens, without
    changing (or copying) the real one: the real stack's first ``base`` states,
    then ``extra``."""

    __slots__ = ("stack", "base", "extra", "states", "rules", "end")

    def __init__(self, stack: list[int], t: Tables):
        self.stack, self.base, self.extra = stack, len(stack), []
        self.states, self.rules, self.end = t.states, t.rules, t.end

    def top(self) -> int:
        return self.extra[-1] if self.extra else self.stack[self.base - 1]

    def feed(self, kind: str) -> bool:
        """Feed a terminal (its reductions, then its shift; for the end of the
        input, ``$END``, its reductions up to the accepting state); False, with
        the trial left as it was at the failing reduction, when it is not
        accepted."""
        states, extra = self.states, self.extra
        is_end = kind == "$END"
        state = extra[-1] if extra else self.stack[self.base - 1]
        while True:
            act = states[state].get(kind)
            if act is None:
                return False
            if act >= 0:
                if is_end:
                    return False
                extra.append(act)
                return True
            origin, size = self.rules[-1 - act][:2]
            if size:
                ne = len(extra)
                if size <= ne:
                    del extra[ne - size:]
                else:
                    self.base -= size - ne
                    extra.clear()
            below = extra[-1] if extra else self.stack[self.base - 1]
            state = states[below][origin]
            extra.append(state)
            if is_end and state == self.end:
                return True


def accepts(stack: list[int], t: Tables) -> set[str]:
    """The terminals the parser with this state stack takes next (lark's
    ``InteractiveParser.accepts``: each terminal of the top state's row that
    survives its reductions; ``$END`` when the input may end here)."""
    out = set()
    for kind in t.terminals[stack[-1]]:
        if Trial(stack, t).feed(kind):
            out.add(kind)
    return out
