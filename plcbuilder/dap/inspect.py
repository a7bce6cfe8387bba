"""The halted state as the Debug Adapter Protocol shows it
(docs/editors.md, "What the debugger shows"): threads (one per running
procedure), stack frames, scopes and variables, and the write target behind
each variable (``setVariable``).

Ids are small numbers kept for the session: a procedure keeps its thread id,
a frame id is ``thread * 100 + depth``, and a scope's ``variablesReference``
is ``frame * 10 + scope``, so every id can be decoded without tables that
would grow.

Pins and registers are *indexed* scopes (``indexedVariables``: a client pages
them with ``filter``/``start``/``count``), the others *named*. A variable's
``evaluateName`` is an expression that evaluates to its value (``count``,
``portget(3)``, ``adc01``, ``gvarget(6060)``); those with none (output pins,
axes) have no ``evaluateName``.
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path
from typing import Callable, Optional

#: The scopes of a frame, in order: (name, what they hold, expensive?, indexed?)
SCOPES = (("Variables", "vars", False, False), ("Inputs", "inputs", False, True),
          ("Outputs", "outputs", False, True), ("Analog", "analog", False, False),
          ("Axes", "axes", False, False), ("Registers", "registers", True, True))
_BUILTIN = "<builtin>/"
#: Analog channels a PLC expression names (adc01 is ADC 0, ...): the predefined
#: register-mapped variables (docs/language.md).
_ANALOG_NAMES = {"adc": ("adc01", "adc02"), "pwm": ("pwm01", "pwm02", "pwm03", "pwm04"),
                 "dac": ("dac01", "dac02")}


class Threads:
    """Procedure name <-> thread id, stable for the session."""

    def __init__(self):
        self.ids: dict[str, int] = {}

    def id_of(self, name: str) -> int:
        if name not in self.ids:
            self.ids[name] = len(self.ids) + 1
        return self.ids[name]

    def name_of(self, tid: int) -> Optional[str]:
        for n, i in self.ids.items():
            if i == tid:
                return n
        return None


class View:
    """One halted state, asked about by the client until the controller goes on."""

    def __init__(self, state: dict, threads: Threads, source_of: Callable[[str, str], Optional[Path]]):
        self.state = state
        self.threads = threads
        self.source_of = source_of          # (procedure, stored file name) -> a path
        self.procs = {p["name"]: p for p in state.get("procedures", ())}

    # ------------------------------------------------------------ threads
    def thread_list(self) -> list[dict]:
        return [{"id": self.threads.id_of(n), "name": n} for n in self.procs]

    def stopped_thread(self) -> int:
        name = self.state.get("procedure") or next(iter(self.procs), None)
        return self.threads.id_of(name) if name else 1

    # ------------------------------------------------------------ frames
    def stack(self, tid: int, start: int = 0, levels: int = 0) -> list[dict]:
        name = self.threads.name_of(tid)
        p = self.procs.get(name) if name else None
        if p is None:
            return []
        frames = []
        for depth, f in enumerate(p.get("stack") or []):
            frame = {"id": tid * 100 + depth, "name": f"{f.get('procedure') or 'main'}()",
                     "line": f.get("line") or 0, "column": 1}
            src = self._source(name, f.get("file"))
            if src is not None:
                frame["source"] = src
            if depth == 0 and p.get("at_loop_end"):          # its tick ended there
                frame["name"] += " (at the loop's end)"
            frames.append(frame)
        frames = frames[start:]
        return frames[:levels] if levels else frames

    def _source(self, proc: str, stored: Optional[str]) -> Optional[dict]:
        if not stored:
            return None
        path = self.source_of(proc, stored)
        if path is None:
            return {"name": stored.rsplit("/", 1)[-1]}
        return {"name": path.name, "path": str(path)}

    def frame_procedure(self, frame_id: int) -> Optional[str]:
        return self.threads.name_of(frame_id // 100)

    # ------------------------------------------------------------ scopes
    def scopes(self, frame_id: int) -> list[dict]:
        out = []
        for k, (name, _what, expensive, indexed) in enumerate(SCOPES):
            ref = frame_id * 10 + k + 1
            n = len(self._items(ref))
            out.append({"name": name, "variablesReference": ref, "expensive": expensive,
                        ("indexedVariables" if indexed else "namedVariables"): n})
        return out

    def variables(self, ref: int, filt: Optional[str] = None, start: int = 0,
                  count: int = 0) -> list[dict]:
        """The variables of a scope: those of ``filt`` (indexed or named: a scope
        is one or the other), from ``start``, at most ``count`` of them (0: all)."""
        k = ref % 10 - 1
        if filt is not None and 0 <= k < len(SCOPES) and SCOPES[k][3] != (filt == "indexed"):
            return []
        items = self._items(ref)[start:]
        out = []
        for n, v, _target, expr in items[:count] if count else items:
            var = {"name": n, "value": str(v), "variablesReference": 0}
            if expr is not None:
                var["evaluateName"] = expr
            out.append(var)
        return out

    def value_of(self, ref: int, name: str):
        for n, v, _t, _e in self._items(ref):
            if n == name:
                return v
        return None

    def target(self, ref: int, name: str) -> Optional[str]:
        """The write target (``PROC.var``, ``in N``, ``out N``, ``adc N``, ``pwm N``,
        ``dac N``, ``gvar N``) behind a variable, or None (axes are read only)."""
        for n, _v, target, _e in self._items(ref):
            if n == name:
                return target
        return None

    def _scope(self, ref: int) -> Optional[str]:
        k = ref % 10 - 1
        return SCOPES[k][1] if 0 <= k < len(SCOPES) else None

    def _items(self, ref: int) -> list[tuple[str, int, Optional[str], Optional[str]]]:
        """(name, value, write target, evaluateName) of each variable of a scope."""
        what = self._scope(ref)
        proc = self.frame_procedure(ref // 10)
        m = self.state.get("machine") or {}
        if what == "vars":
            p = self.procs.get(proc) or {}
            return [(n, v, f"{proc}.{n}", n) for n, v in (p.get("vars") or {}).items()]
        if what == "inputs":
            return [(f"in {i}", v, f"in {i}", f"portget({i})")
                    for i, v in enumerate(m.get("inputs") or ())]
        if what == "outputs":
            return [(f"out {i}", v, f"out {i}", None) for i, v in enumerate(m.get("outputs") or ())]
        if what == "analog":
            out = []
            for kind in ("adc", "pwm", "dac"):
                names = _ANALOG_NAMES[kind]
                out += [(f"{kind} {i}", v, f"{kind} {i}", names[i] if i < len(names) else None)
                        for i, v in enumerate(m.get(kind) or ())]
            return out
        if what == "axes":
            return [(axis, v, None, None) for axis, v in (m.get("axes") or {}).items()]
        if what == "registers":
            return [(f"gvar {a}", v, f"gvar {a}", f"gvarget({a})")
                    for a, v in (m.get("registers") or {}).items()]
        return []


def builtin_header(name: str) -> Optional[Path]:
    """The file of a built-in header (``<builtin>/pins.h``)."""
    if not name.startswith(_BUILTIN):
        return None
    try:
        ref = resources.files("plcbuilder") / "resources" / "include" / name[len(_BUILTIN):]
        return Path(str(ref)) if ref.is_file() else None
    except (OSError, TypeError, ValueError):
        return None
