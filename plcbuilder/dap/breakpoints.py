"""``setBreakpoints``: a source's breakpoints as the client sends them
(line, ``condition``, ``hitCondition``, ``logMessage``) turned into the
debugger's (docs/editors.md, "What the debugger shows"): conditions compiled here
(:func:`~plcbuilder.project.conditions.compile_condition`), hit conditions
read as ``N`` / ``==N`` (the Nth hit), ``>=N`` (from the Nth on), ``>N`` and
``%N`` (every Nth). A breakpoint the debugger cannot take (a condition that
does not compile, a line with no code after it) comes back unverified with the
reason; the others are set. Breakpoints sent before the session has a
controller are kept and set when it connects.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Optional

from plcbuilder.link.client import LinkError
from plcbuilder.project.conditions import compile_condition

_HIT = re.compile(r"^\s*(==|>=|>|%)?\s*(\d+)\s*$")
_WHICH = re.compile(r"breakpoint (\d+)\b")


def parse_hit(text: str) -> dict:
    """A hit condition -> the debugger's {mode, n}; ValueError saying what is accepted."""
    m = _HIT.match(text or "")
    if m is None or int(m.group(2)) < 1:
        raise ValueError(f"hit condition {text!r}: write N or ==N (the Nth hit), >=N (from the "
                         "Nth on) or %N (every Nth), N from 1")
    op, n = m.group(1) or "==", int(m.group(2))
    if op == ">":
        return {"mode": "ge", "n": n + 1}
    return {"mode": {"==": "eq", ">=": "ge", "%": "every"}[op], "n": n}


class Breakpoints:
    def __init__(self, session):
        self.session = session
        self.by_file: dict[str, list[dict]] = {}
        self.pending: dict[str, list[dict]] = {}   # answers given before there was a controller
        self._client_id: dict[int, int] = {}       # the debugger's id -> the id the client knows
        self._next = 1_000_000                     # ids of breakpoints the debugger did not take

    def set(self, args: dict) -> list[dict]:
        source = args.get("source") or {}
        path = source.get("path") if isinstance(source, dict) else None
        if not isinstance(path, str) or not path:
            raise ValueError("setBreakpoints needs source.path (the file's path)")
        bps = args.get("breakpoints")
        if bps is None:
            bps = [{"line": ln} for ln in args.get("lines") or []]
        if not isinstance(bps, list) or not all(isinstance(b, dict) for b in bps):
            raise ValueError("breakpoints must be a list of objects")
        self.by_file[path] = bps
        if self.session.client is None:
            answers = [self._unverified(b, "set when the session connects to a controller")
                       for b in bps]
            self.pending[path] = answers
            return answers
        self.pending.pop(path, None)
        return self._apply(path, bps)

    def apply_pending(self) -> None:
        """Set the breakpoints sent before there was a controller, and tell the
        client (a ``breakpoint`` event for each, with the id it was given)."""
        pending, self.pending = self.pending, {}
        for path, told in pending.items():
            bps = self.by_file.get(path)
            if bps is None:
                continue
            for old, answer in zip(told, self._apply(path, bps)):
                if answer["id"] != old["id"]:
                    self._client_id[answer["id"]] = old["id"]
                answer = {**answer, "id": old["id"]}
                self.session.wire.event("breakpoint", {"reason": "changed", "breakpoint": answer})

    def clear_all(self) -> None:
        c = self.session.client
        for path in list(self.by_file):
            try:
                c.set_breakpoints(path, [])
            except LinkError:
                pass
        self.by_file.clear()
        self.pending.clear()
        self._client_id.clear()

    def dap_ids(self, engine_id: int) -> list[int]:
        """The ids the client knows for the debugger's breakpoint ``engine_id``."""
        return [self._client_id.get(engine_id, engine_id)]

    # ------------------------------------------------------------ private
    def _apply(self, path: str, bps: list[dict]) -> list[dict]:
        answers: list[Optional[dict]] = [None] * len(bps)
        specs: list[tuple[int, dict]] = []
        for k, b in enumerate(bps):
            try:
                specs.append((k, self._spec(path, b)))
            except ValueError as exc:
                answers[k] = self._unverified(b, str(exc))
        client = self.session.client
        while True:
            try:
                got = client.set_breakpoints(path, [s for _k, s in specs])
                break
            except LinkError as exc:
                # the debugger refuses the whole set for one bad breakpoint: say which, set the rest
                reason = str(exc)
                m = _WHICH.search(reason)
                i = int(m.group(1)) - 1 if m else -1
                if not 0 <= i < len(specs):
                    for k, _s in specs:
                        answers[k] = self._unverified(bps[k], reason)
                    return [a for a in answers if a is not None]
                k, _s = specs.pop(i)
                answers[k] = self._unverified(bps[k], reason.split(": ", 1)[-1])
        for (k, _s), r in zip(specs, got):
            answers[k] = {"id": r["id"], "verified": bool(r.get("verified")), "line": r["line"],
                          "source": {"path": path, "name": Path(path).name},
                          **({"message": r["reason"]} if r.get("reason") else {})}
        return [a for a in answers if a is not None]

    def _spec(self, path: str, b: dict) -> dict:
        line = b.get("line")
        if isinstance(line, bool) or not isinstance(line, int) or line < 1:
            raise ValueError(f"line must be a whole number from 1, not {line!r}")
        spec: dict = {"line": line}
        cond = b.get("condition")
        if isinstance(cond, str) and cond.strip():
            code = compile_condition(cond, path)
            if isinstance(code, list):
                raise ValueError("condition: " + "; ".join(d.message for d in code))
            spec["condition"] = {"text": cond, "code": code}
        hit = b.get("hitCondition")
        if isinstance(hit, str) and hit.strip():
            spec["hit"] = parse_hit(hit)
        log = b.get("logMessage")
        if isinstance(log, str) and log:
            spec["log"] = log
        return spec

    def _unverified(self, b: dict, message: str) -> dict:
        self._next += 1
        line = b.get("line") if isinstance(b.get("line"), int) else 0
        return {"id": self._next, "verified": False, "line": line, "message": message}
