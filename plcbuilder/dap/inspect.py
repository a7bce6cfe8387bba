"""The halted state as the Debug Adapter Protocol shows it
(docs/editors.md, "What the debugger shows"): threads (one per running
procedure), stack frames, scopes and variables, and the write target behind
each variable (``setVariable``).

Ids are small numbers kept for the session: a procedure keeps its thread id,
a frame id is ``thread * 100 + depth``, and a scope's ``variablesReference``
is ``frame * 10 + scope``, so every id can be decoded without tables that
would grow.
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path
from typing import Callable, Optional

#: The scopes of a frame, in order: (name, what they hold, expensive?)
SCOPES = (("Variables", "vars", False), ("Inputs", "inputs", False),
          ("Outputs", "outputs", False), ("Analog", "analog", False),
          ("Axes", "axes", False), ("Registers", "registers", True))
_BUILTIN = "<builtin>/"


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
            if depth == 0 and p.get("at_loop_end"):
                frame["presentationHint"] = "label"
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
        for k, (name, _what, expensive) in enumerate(SCOPES):
            ref = frame_id * 10 + k + 1
            out.append({"name": name, "variablesReference": ref, "expensive": expensive,
                        "namedVariables": len(self._items(ref))})
        return out

    def variables(self, ref: int) -> list[dict]:
        return [{"name": n, "value": str(v), "variablesReference": 0,
                 "evaluateName": n if self._scope(ref) == "vars" else None}
                for n, v, _target in self._items(ref)]

    def target(self, ref: int, name: str) -> Optional[str]:
        """The write target (``PROC.var``, ``in N``, ``out N``, ``adc N``, ``pwm N``,
        ``dac N``, ``gvar N``) behind a variable, or None (axes are read only)."""
        for n, _v, target in self._items(ref):
            if n == name:
                return target
        return None

    def _scope(self, ref: int) -> Optional[str]:
        k = ref % 10 - 1
        return SCOPES[k][1] if 0 <= k < len(SCOPES) else None

    def _items(self, ref: int) -> list[tuple[str, int, Optional[str]]]:
        what = self._scope(ref)
        proc = self.frame_procedure(ref // 10)
        m = self.state.get("machine") or {}
        if what == "vars":
            p = self.procs.get(proc) or {}
            return [(n, v, f"{proc}.{n}") for n, v in (p.get("vars") or {}).items()]
        if what == "inputs":
            return [(f"in {i}", v, f"in {i}") for i, v in enumerate(m.get("inputs") or ())]
        if what == "outputs":
            return [(f"out {i}", v, f"out {i}") for i, v in enumerate(m.get("outputs") or ())]
        if what == "analog":
            out = []
            for kind in ("adc", "pwm", "dac"):
                out += [(f"{kind} {i}", v, f"{kind} {i}") for i, v in enumerate(m.get(kind) or ())]
            return out
        if what == "axes":
            return [(axis, v, None) for axis, v in (m.get("axes") or {}).items()]
        if what == "registers":
            return [(f"gvar {a}", v, f"gvar {a}") for a, v in (m.get("registers") or {}).items()]
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
