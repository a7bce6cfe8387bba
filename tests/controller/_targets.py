"""Helpers for the target tests: compile a program for a target, run it."""

from __future__ import annotations

from plcbuilder.api import CompileOptions, Controller, compile_source, default_machine
from plcbuilder.controller.events import Fault, Note
from plcbuilder.controller.targets import TargetConfig


def compiled(text: str, target: str, name: str = "plc"):
    r = compile_source(text, f"{name}.plc", CompileOptions(target=target))
    assert r.ok, [str(d) for d in r.diagnostics]
    return r.program


def controller(text: str, target: str, **config) -> Controller:
    c = Controller(default_machine(), target=TargetConfig(target, **config))
    c.load([compiled(text, target)])
    return c


def faults(c: Controller) -> list[Fault]:
    return [e for e in c.drain_events() if isinstance(e, Fault)]


def notes(events, level: str = "warning") -> list[str]:
    return [e.text for e in events if isinstance(e, Note) and e.level == level]


def tgm(p05="", p04="", p01="", p02="", p03="", ini="", head="") -> str:
    """A TG Motion program with these bodies (each ends with exit(1))."""
    def proc(name, body):
        return f"{name}() {{ {body} exit(1); }}\n"
    return (head + proc("Program_Ini", ini) + proc("Program_01", p01) + proc("Program_02", p02)
            + proc("Program_03", p03) + proc("Program_04", p04) + proc("Program_05", p05))
