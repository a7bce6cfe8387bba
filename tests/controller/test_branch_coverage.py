"""Branch coverage (issue 25 item 8: Cobertura's branches): the reference
interpreter records the ways each conditional jump went, from the condition
it is about to test, exactly (a way is never inferred from the code it
leads to: an ``if`` without ``else`` whose condition always holds reaches
the code after it anyway)."""

from __future__ import annotations

import pytest

from plcbuilder.controller.controller import Controller
from plcbuilder.controller.coverage import (FELL_THROUGH, JUMPED, CodeCoverage,
                                            branch_coverage, line_coverage, ways_gone)
from tests.controller.test_coverage import LOOP, program, run

ALWAYS = """main()
{
  a=1;
  if (a==1)
  {
    b=2;
  };
  exit(b);
};
"""

EXIT_IN_BRANCH = """main()
{
  if (eparam==1)
  {
    exit(1);
  };
  exit(2);
};
"""


def ways(p, cov):
    """line -> (ways gone, ways)."""
    (per_line,) = branch_coverage(p, cov.branches.get(p.name, {})).values()
    return {n: ways_gone(seen) for n, seen in per_line.items()}


def test_a_condition_that_always_holds_went_one_way():
    p = program(ALWAYS)
    cov = CodeCoverage()
    run(p, 0, cov)
    assert ways(p, cov) == {4: (1, 2)}             # line 8 ran, but not by the jump
    (code, ran), = line_coverage(p, cov.hits["P"]).values()
    assert ran == code                              # every line ran: 100 % of the lines


def test_loops_and_ifs_as_the_runs_go():
    p = program(LOOP)
    cov = CodeCoverage()
    run(p, 3, cov)                                  # loops 3 times; total 6: no clamp
    assert ways(p, cov) == {9: (2, 2), 10: (1, 2)}
    run(p, 1, cov)
    assert ways(p, cov) == {9: (2, 2), 10: (1, 2)}
    run(p, 20, cov)                                 # total 210: clamped
    assert ways(p, cov) == {9: (2, 2), 10: (2, 2)}


def test_a_way_into_an_exit_is_recorded_and_the_other_way_later_too():
    """The procedure ends right after the jump fell through: the jump is marked
    again, so a later run that jumps is recorded (on the same controller, as a
    test that starts a procedure twice)."""
    p = program(EXIT_IN_BRANCH)
    cov = CodeCoverage()
    c = Controller(backend="reference", coverage=cov)
    c.load([p])
    c.start("P", 1)
    c.step(10)
    assert ways(p, cov) == {3: (1, 2)}
    (seen,) = cov.branches["P"].values()
    assert seen == FELL_THROUGH
    c.start("P", 2)
    c.step(10)
    assert [e.exit_code for e in c.drain_events() if e.type == "ended"] == [1, 2]
    assert ways(p, cov) == {3: (2, 2)}
    assert set(cov.branches["P"].values()) == {JUMPED | FELL_THROUGH}


def test_without_a_debugger_too():
    """The interpreter alone (no debugger's table): the lifted mark comes back."""
    from plcbuilder.controller import vm
    p = program(EXIT_IN_BRANCH)
    cov = CodeCoverage()
    for eparam in (1, 2, 1):
        c = Controller(backend="reference", coverage=cov)
        c.load([p])
        c._plc.debugger = None
        c.start("P", eparam)
        c.step(5)
    assert ways(p, cov) == {3: (2, 2)}
    assert vm.decoded(p)[0][4] == vm.K_JZ             # the shared decoded table untouched


@pytest.mark.parametrize("src,eparams", [(LOOP, (3, 20)), (EXIT_IN_BRANCH, (1, 2)),
                                         (ALWAYS, (0,))])
def test_recording_branches_changes_nothing_about_the_run(src, eparams):
    p = program(src)
    cov = CodeCoverage()
    for e in eparams:
        assert run(p, e, cov) == run(p, e) == run(p, e, backend="fast")


def test_merging_another_process_ways():
    cov = CodeCoverage()
    cov.merge({"P": {1}}, {"P": {4: JUMPED}})
    cov.merge({"P": {2}}, {"P": {4: FELL_THROUGH, 9: JUMPED}})
    assert cov.hits["P"] == {1, 2} and cov.branches["P"] == {4: 3, 9: 1}
