"""Both VM backends halt identically (SPEC §6): the same halts at the same
ticks and lines, with the same call stacks and variables, on the golden
programs and on generated ones, for breakpoints on every line with code, hit
counts, and statement steps.

The fast backend runs watched code that asks the debugger at every statement
start and hands a halted procedure to the reference interpreter; these tests
are what holds the two to one behaviour."""

from __future__ import annotations

import random

import pytest

from plcbuilder.bytecode.program import Kind
from plcbuilder.controller.controller import Controller
from plcbuilder.controller.debugger import DebugError

from tests.controller._sim import compile_proc
from tests.controller._srcgen import random_source
from tests.lang.golden_util import compile_golden, goldens

LIMIT_MS = 3000
_RUNNABLE = [g for g in goldens() if not any(sev == "error" for _, sev, _ in g.diags)]


def _lines(program) -> list[tuple[str, int]]:
    return sorted({(program.files[e.file], e.line) for e in program.lines})


def _start(program, backend: str) -> Controller:
    c = Controller(backend=backend)
    c.load([program])
    c.debugger.halt_on_fault = True
    return c


def _go(c: Controller, program) -> None:
    if program.kind is Kind.HARDWARE and program.name not in c.plc.last:
        c.start(program.name)
    c.run_until_idle(LIMIT_MS)


def _snapshot(c: Controller):
    st = c.debugger.halted_state()
    if st is None:
        return None
    st = dict(st)
    st.pop("machine")                     # the machine is compared through its own tests
    return st


def _first_halt(program, backend: str, file: str, line: int, hit=None):
    c = _start(program, backend)
    spec = {"line": line, **({"hit": hit} if hit else {})}
    c.debugger.set_breakpoints(file, [spec])
    _go(c, program)
    return _snapshot(c), c.t_ms


def _halts_at_each_line(program, max_lines: int = 40) -> None:
    for file, line in _lines(program)[:max_lines]:
        for hit in (None, {"mode": "eq", "n": 3}):
            fast = _first_halt(program, "fast", file, line, hit)
            ref = _first_halt(program, "reference", file, line, hit)
            assert fast == ref, f"{program.name} {file}:{line} hit {hit}"


def _steps(program, kinds: str, max_steps: int = 40) -> None:
    """From the first halt at the first line with code, a series of steps."""
    file, line = _lines(program)[0]
    trails = {}
    for backend in ("fast", "reference"):
        c = _start(program, backend)
        c.debugger.set_breakpoints(file, [{"line": line}])
        _go(c, program)
        trail = [_snapshot(c)]
        c.debugger.set_breakpoints(file, [])
        for k in range(max_steps):
            if c.debugger.halt is None:
                break
            kind = {"i": "into", "o": "over", "u": "out", "t": "tick"}[kinds[k % len(kinds)]]
            try:
                c.debugger.step(kind)
            except DebugError as exc:      # nothing left to step in
                trail.append((kind, str(exc)))
                break
            if c.debugger.halt is None:
                _go(c, program)
            trail.append((kind, c.t_ms, _snapshot(c)))
        trails[backend] = trail
    assert trails["fast"] == trails["reference"]


@pytest.mark.parametrize("g", _RUNNABLE, ids=[g.id for g in _RUNNABLE])
def test_golden_programs_halt_identically_at_every_line(g):
    """"Execution halts *before* the first instruction of that line runs ... at
    that exact instruction — mid-tick", the same on both backends."""
    r = compile_golden(g)
    _halts_at_each_line(r.program)


@pytest.mark.parametrize("g", _RUNNABLE, ids=[g.id for g in _RUNNABLE])
def test_golden_programs_step_identically(g):
    """"step into / over / out (statement level, in the procedure that halted)",
    the same on both backends."""
    r = compile_golden(g)
    _steps(r.program, "iiioiutoiiu")


@pytest.mark.parametrize("seed", range(40))
def test_generated_programs_halt_and_step_identically(seed):
    rng = random.Random(9000 + seed)
    software = seed % 4 == 3
    program = compile_proc(random_source(rng, software), "S" if software else "M03", software)
    _halts_at_each_line(program, max_lines=25)
    _steps(program, "ioiuitoo" if seed % 2 else "iiiiiiiiiiuu", max_steps=30)
