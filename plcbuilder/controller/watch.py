"""Watched variables (SPEC §7): a procedure's variable recorded at the end of
every tick, so that a trace holds it and a trigger can fire on its bit or level.

    c.watch_variables(["M80.var03", "M80.timer"])   # ControllerError naming a bad one
    c.step(1000)                                    # one tick at a time while watching
    c.drain_events()                                # ... Watched(t_ms, name, value) events

A :class:`Watched` event goes out at the end of a tick where a watched value is
new or changed (the first tick after watching starts gives every value the
procedure has); a procedure that has not run yet, or whose image has no such
variable any more, gives none. The value is the one the procedure's latest run
holds, as ``Controller.variables()`` reads it.
"""

from __future__ import annotations

from plcbuilder.controller.events import Watched

TYPE_CHECKING = False               # (typing is not imported at run time: start-up)
if TYPE_CHECKING:
    from typing import Iterable, Optional


def split_name(name: str) -> tuple[str, str]:
    """``PROC.var`` -> (procedure, variable); ValueError naming what is wrong."""
    proc, dot, var = str(name).partition(".")
    if not dot or not proc or not var or "." in var:
        raise ValueError(f"{name}: name a variable as PROC.var (e.g. M80.var03)")
    return proc, var


def check_name(programs: dict, name: str) -> tuple[str, str]:
    """(procedure, variable) of ``name`` among the loaded ``programs`` (by
    name); ValueError naming what is wrong."""
    proc, var = split_name(name)
    program = programs.get(proc)
    if program is None:
        loaded = ", ".join(sorted(programs)) or "none"
        raise ValueError(f"{name}: no procedure named {proc} (loaded: {loaded})")
    if var not in set(program.slot_names().values()):
        raise ValueError(f"{name}: {proc} has no variable named {var}")
    return proc, var


class VariableWatch:
    """The variables one controller records each tick, and their last values."""

    def __init__(self, names: Iterable[str] = ()):
        self.names: list[str] = []
        self._parts: list[tuple[str, str, str]] = []
        self._slots: dict[tuple[str, str], tuple] = {}   # (proc, var) -> (program, slot)
        self._last: dict[str, int] = {}
        self._t = -1                      # the last tick read
        self.set(names)

    def __bool__(self) -> bool:
        return bool(self.names)

    def set(self, names: Iterable[str]) -> None:
        """Watch ``names`` (``PROC.var``; checked by the caller) from the next tick on."""
        self.names = list(dict.fromkeys(str(n) for n in names))
        self._parts = [(n, *split_name(n)) for n in self.names]
        self._last = {n: v for n, v in self._last.items() if n in self.names}

    def read(self, plc) -> list[Watched]:
        """The events of the tick that ended last (``plc.t - 1``), once a tick;
        nothing while the tick is halted before its end."""
        t = plc.t - 1
        if t <= self._t or t < 0 or plc.mid_tick:
            return []
        self._t = t
        out = []
        last = self._last
        for name, proc, var in self._parts:
            p = plc.last.get(proc)
            if p is None:
                continue
            slot = self._slot(p.program, var)
            if slot is None or slot >= len(p.slots):
                continue
            p.sync()
            v = p.slots[slot]
            if last.get(name) != v:
                last[name] = v
                out.append(Watched(t, name, v))
        return out

    def _slot(self, program, var: str) -> Optional[int]:
        key = (program.name, var)
        entry = self._slots.get(key)
        if entry is None or entry[0] is not program:      # a new image: look again
            slot = next((s for s, n in program.slot_names().items() if n == var), None)
            entry = self._slots[key] = (program, slot)
        return entry[1]
