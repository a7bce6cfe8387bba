"""Line coverage of a test run on a program with known branches."""

from __future__ import annotations

from plcbuilder.testing.coverage import ranges
from plcbuilder.testing.runner import prepare, run_suite

from tests.testing._proj import make_project


def branch_test(name: str, eparam: int) -> str:
    return (f'[[test]]\nname = "{name}"\nms = 20\nscenario = "start BRANCH:{eparam} @ 0"\n'
            f'[[test.expect]]\nat_end = true\nexit = {{ BRANCH = {eparam} }}\n')


def coverage_of(tmp_path, *tests):
    root = make_project(tmp_path / "p", {f"t{i}": t for i, t in enumerate(tests)})
    suite = prepare(root)
    run = run_suite(suite, coverage=True, jobs=1)
    assert all(r.passed for r in run.results)
    assert run.backend == "reference"
    return {c.name: c for c in run.coverage}


def test_one_branch_leaves_the_other_uncovered(tmp_path):
    cov = coverage_of(tmp_path, branch_test("one", 1))
    b = cov["BRANCH"]
    (f,) = b.files
    assert f.lines == [3, 4, 6, 7, 9, 11, 12, 14, 15, 16]
    assert f.uncovered == [11, 12]
    assert (b.covered, b.lines, round(b.percent, 1)) == (8, 10, 80.0)
    assert b.uncovered_text() == "BRANCH.plc:11-12"
    assert f.path == str((tmp_path / "p" / "hardware" / "BRANCH.plc").resolve())
    assert (cov["PULSE"].covered, cov["PULSE"].lines) == (0, 7)


def test_both_branches_cover_every_line(tmp_path):
    cov = coverage_of(tmp_path, branch_test("one", 1), branch_test("two", 2))
    assert cov["BRANCH"].percent == 100.0 and cov["BRANCH"].uncovered_text() == ""


def test_ranges():
    assert ranges([9, 3, 4, 5, 11, 12]) == "3-5, 9, 11-12"
    assert ranges([]) == ""
