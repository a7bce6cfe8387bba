"""The reference interpreter's coverage hook: it records every instruction
that runs, changes nothing about the run, and is not there when off."""

from __future__ import annotations

import pytest

from plcbuilder.api import compile_source
from plcbuilder.controller import vm
from plcbuilder.controller.controller import Controller, ControllerError
from plcbuilder.controller.coverage import CodeCoverage, instruction_offsets, line_coverage

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
    """Without coverage the interpreter runs the shared decoded table, unmarked."""
    p = program()
    c = Controller(backend="reference")
    c.load([p])
    c.start("P", 3)
    c.step(1)
    kinds = vm.decoded(p)[0]
    assert vm.K_COVER not in kinds
    assert c.plc.coverage is None


def test_coverage_needs_the_reference_backend():
    with pytest.raises(ControllerError, match="reference backend"):
        Controller(backend="fast", coverage=CodeCoverage())
