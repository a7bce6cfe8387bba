"""The reference interpreter's coverage hook: it records every instruction
that runs, changes nothing about the run, and is not there when off."""

from __future__ import annotations

import pytest

from plcbuilder.api import compile_source
from plcbuilder.controller.controller import Controller, ControllerError
from plcbuilder.controller.coverage import (FELL_THROUGH, JUMPED, CodeCoverage, instruction_offsets,
                                           line_coverage)
from plcbuilder.controller.events import Ended

LOOP = """main()
{
  n=eparam;
  total=0;
  do
  {
    total=total+n;
    n--;
  }while(n>0);
  if (total>100)
  {
    total=100;
  };
  exit(total);
};
"""


def program(src=LOOP, name="P"):
    r = compile_source(src, f"{name}.plc")
    assert r.ok, r.diagnostics
    return r.program


def run(prog, eparam, coverage=None, backend="reference", ms=100):
    c = Controller(backend=backend, coverage=coverage)
    c.load([prog])
    c.start(prog.name, eparam)
    c.step(ms)
    return c.drain_events(), c.variables()


@pytest.mark.parametrize("eparam", [3, 20])
def test_a_run_with_coverage_is_the_same_run(eparam):
    p = program()
    plain = run(p, eparam)
    assert run(p, eparam, CodeCoverage()) == plain == run(p, eparam, backend="fast")


def test_the_lines_that_ran():
    p = program()
    cov = CodeCoverage()
    run(p, 3, cov)                                   # total 6: the if's body never runs
    (code, ran), = line_coverage(p, cov.hits["P"]).values()
    assert code == {3, 4, 7, 8, 9, 10, 12, 14}
    assert code - ran == {12}
    run(p, 20, cov)                                  # total 210: now it does
    (code, ran), = line_coverage(p, cov.hits["P"]).values()
    assert ran == code
    assert cov.hits["P"] == set(instruction_offsets(p))


def test_new_code_under_the_same_name_starts_afresh():
    cov = CodeCoverage()
    run(program(), 20, cov)
    p2 = program("main(){ exit(1); };\n")
    run(p2, 0, cov)
    assert cov.hits["P"] == set(instruction_offsets(p2))


def test_off_is_the_plain_interpreter():
    """Without coverage (and no breakpoint) the interpreter is given no coverage
    and watches no instruction."""
    p = program()
    c = Controller(backend="reference")
    c.load([p])
    c.start("P", 3)
    c.step(1)
    here = c.plc.hw.gen.gi_frame.f_locals
    assert here["cover"] is None and not any(here["watch"])
    assert c.plc.coverage is None


def test_coverage_needs_the_reference_backend():
    with pytest.raises(ControllerError, match="reference backend"):
        Controller(backend="fast", coverage=CodeCoverage())


def test_coverage_and_a_breakpoint_in_one_run():
    """The debugger and coverage share the interpreter's one hook: a breakpoint
    in the loop halts at every pass (the loop's condition jumps back each time,
    a branch coverage keeps watching until it falls through), coverage records
    every line the run reaches, and the run ends as it does with neither; a
    breakpoint removed while halted is not asked again."""
    p = program()
    cov = CodeCoverage()
    c = Controller(backend="reference", coverage=cov)
    c.load([p])
    c.debugger.set_breakpoints("P.plc", [{"line": 7}])
    c.start("P", 3)
    halts = []
    for _ in range(10):
        c.step(10)
        if c.debugger.halt is None:
            break
        st = c.debugger.halted_state()
        halts.append((st["line"], st["t_ms"]))
        if len(halts) == 2:
            c.debugger.set_breakpoints("P.plc", [])
        c.debugger.resume()
    assert halts == [(7, 0), (7, 1)]
    (code, ran), = line_coverage(p, cov.hits["P"]).values()
    assert code - ran == {12}
    # the if's jump went one way (total 6: over its body), the loop's both
    assert sorted(cov.branches["P"].values()) == [JUMPED, JUMPED | FELL_THROUGH]
    ended = [e for e in c.drain_events() if isinstance(e, Ended)]
    assert [e.exit_code for e in ended] == [6]
    assert ended == [e for e in run(p, 3)[0] if isinstance(e, Ended)]
