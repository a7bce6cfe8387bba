"""Helpers for the controller tests: compile sources, run them, look at events."""

from __future__ import annotations

from pathlib import Path

from plcbuilder import api
from plcbuilder.bytecode.program import Kind, Program
from plcbuilder.controller.controller import Controller
from plcbuilder.controller.events import Ended, Fault, Message, Note, Print, Started

BACKENDS = ("fast", "reference")

#: The example project the package ships (the debugger's and rewind's tests run it).
EXAMPLE = Path(api.__file__).parent / "resources" / "example_project"

#: A procedure with a loop and a call to break, step and step back in (M10 there).
COUNT = """main()
{
  n = 0;

  do
  {
    n++;
    bump();
  }while(n < 1000);
  exit(99);
}

bump()
{
  total = total + n;
}
"""
# lines: 3 n=0 | 7 n++ | 8 bump() | 9 while | 10 exit | 15 total=...


def compile_proc(src: str, name: str = "M03", software: bool = False) -> Program:
    kind = Kind.SOFTWARE if software else Kind.HARDWARE
    r = api.compile_source(src, f"{name}.plc", api.CompileOptions(kind=kind))
    errors = [d for d in r.diagnostics if d.is_error]
    assert r.ok and r.program is not None, errors
    return r.program


def controller(*programs: Program, backend: str = "fast", **kw) -> Controller:
    c = Controller(backend=backend, **kw)
    c.load(programs)
    return c


def run_hw(src: str, ms: int = 1000, backend: str = "fast", eparam: int = 0,
           name: str = "M03", **kw) -> tuple[Controller, list]:
    """Compile a hardware procedure, start it at 0, run until it ends (at most ms)."""
    c = controller(compile_proc(src, name), backend=backend, **kw)
    c.start(name, eparam)
    c.run_until_idle(ms)
    return c, c.drain_events()


def of(events, cls) -> list:
    return [e for e in events if isinstance(e, cls)]


def ended(events, name: str | None = None) -> Ended:
    found = [e for e in events if isinstance(e, Ended) and (name is None or e.name == name)]
    assert found, f"no Ended event for {name}: {events}"
    return found[-1]


__all__ = ["BACKENDS", "EXAMPLE", "COUNT", "compile_proc", "controller", "run_hw", "of", "ended", "Ended", "Fault",
           "Message", "Note", "Print", "Started", "Kind"]
