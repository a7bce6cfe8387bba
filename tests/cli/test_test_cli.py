"""``plcbuilder test``: SPEC §8's command line, output, exit statuses, JUnit XML
(parsed back) and JSON."""

from __future__ import annotations

import json

from junitparser import Error, Failure, JUnitXml

from tests.cli._run import run_cli
from tests.testing._proj import FAILING, PASSING, make_project


def test_all_pass_exits_0(tmp_path, capsys):
    root = make_project(tmp_path / "p", {"a": PASSING})
    code, out, err = run_cli(capsys, "test", root)
    assert code == 0, err
    assert out.splitlines() == ["PASS  pulse on in ticks 5..7", "1 passed, 0 failed"]


def test_a_failure_exits_1_with_condition_expected_actual_and_tick(tmp_path, capsys):
    root = make_project(tmp_path / "p", {"a": PASSING, "b": FAILING})
    code, out, _ = run_cli(capsys, "test", root)
    assert code == 1
    lines = out.splitlines()
    assert lines[0] == "PASS  pulse on in ticks 5..7"
    assert lines[1] == (f"FAIL  branch two: {root / 'tests' / 'b.toml'}:10: at_ms = 1: "
                        "pwm = { 0 = 10 }: expected pwm 0 = 10, actual pwm 0 = 20 at tick 1")
    assert lines[-1] == "1 passed, 1 failed"


def test_k_selects(tmp_path, capsys):
    root = make_project(tmp_path / "p", {"a": PASSING, "b": FAILING})
    code, out, _ = run_cli(capsys, "test", root, "-k", "PULSE")
    assert code == 0 and out.splitlines()[-1] == "1 passed, 0 failed"


def test_a_bad_test_file_exits_2_with_file_and_line_and_the_others_run(tmp_path, capsys):
    """Issue 25 item 7: the broken file is reported and the valid tests still run
    (they were all left out); the exit status stays 2 (SPEC §8)."""
    root = make_project(tmp_path / "p", {"a": PASSING, "b": FAILING.replace("at_ms", "at_mss")})
    code, out, err = run_cli(capsys, "test", root)
    assert code == 2
    assert out.splitlines() == ["PASS  pulse on in ticks 5..7", "1 passed, 0 failed"]
    assert f"{root / 'tests' / 'b.toml'}:9: unknown key 'at_mss'" in err
    assert "1 mistake in test files (above): those tests did not run" in err
    assert "Traceback" not in err


def test_no_such_project_exits_2(tmp_path, capsys):
    code, _, err = run_cli(capsys, "test", tmp_path / "nope")
    assert code == 2 and "no such folder" in err


def test_a_project_that_does_not_build_exits_1(tmp_path, capsys):
    root = make_project(tmp_path / "p", {"a": PASSING})
    (root / "hardware" / "BAD.plc").write_text("main(){ x = ; };\n")
    code, out, err = run_cli(capsys, "test", root)
    assert code == 1 and "BAD did not compile" in err and "BAD.plc:1" in err


def test_json_is_one_object(tmp_path, capsys):
    root = make_project(tmp_path / "p", {"a": PASSING, "b": FAILING})
    code, out, _ = run_cli(capsys, "test", root, "--json")
    assert code == 1
    doc = json.loads(out)
    assert (doc["passed"], doc["failed"]) == (1, 1)
    t = {x["name"]: x for x in doc["tests"]}
    (f,) = t["branch two"]["failures"]
    assert (f["expected"], f["actual"], f["tick"], f["line"]) == ("pwm 0 = 10", "pwm 0 = 20", 1, 10)
    assert t["pulse on in ticks 5..7"]["expectations"][0] == {
        "when": "during_ms = [5, 7]", "line": 5, "passed": True, "tick": 7}
    assert doc["coverage"] is None and doc["errors"] == []


def test_json_reports_file_errors(tmp_path, capsys):
    root = make_project(tmp_path / "p", {"a": "[[test]\n"})
    code, out, _ = run_cli(capsys, "test", root, "--json")
    doc = json.loads(out)
    assert code == 2 and doc["errors"][0]["line"] == 1 and doc["tests"] == []


def test_junit_xml_parses_back(tmp_path, capsys):
    root = make_project(tmp_path / "p", {"a": PASSING, "b": FAILING})
    xml_path = tmp_path / "out" / "junit.xml"
    xml_path.parent.mkdir()
    code, _, _ = run_cli(capsys, "test", root, "--junit", xml_path)
    assert code == 1
    xml = JUnitXml.fromfile(str(xml_path))
    (suite,) = list(xml)
    assert (suite.name, suite.tests, suite.failures, suite.errors) == ("p", 2, 1, 0)
    cases = {c.name: c for c in suite}
    assert cases["pulse on in ticks 5..7"].is_passed
    assert cases["pulse on in ticks 5..7"].classname == "tests.a"
    (res,) = cases["branch two"].result
    assert isinstance(res, Failure)
    assert "expected pwm 0 = 10, actual pwm 0 = 20 at tick 1" in res.message


def test_junit_lists_unreadable_files_as_errors_and_the_other_tests(tmp_path, capsys):
    """Issue 25 item 7: one unreadable tests/*.toml made the report one error
    case (CI showed 1 test instead of 16): the valid tests are there too."""
    many = "".join(PASSING.replace("pulse on in ticks 5..7", f"pulse {i}") for i in range(15))
    root = make_project(tmp_path / "p", {"a": many, "b": "x = 1\n", "c": FAILING})
    xml_path = tmp_path / "j.xml"
    code, out, _ = run_cli(capsys, "test", root, "--junit", xml_path)
    assert code == 2 and out.splitlines()[-1] == "15 passed, 1 failed"
    (suite,) = list(JUnitXml.fromfile(str(xml_path)))
    assert (suite.tests, suite.failures, suite.errors) == (17, 1, 1)
    cases = {c.name: c for c in suite}
    assert all(cases[f"pulse {i}"].is_passed for i in range(15))
    assert isinstance(cases["branch two"].result[0], Failure)
    err = cases["b.toml: cannot be read"].result[0]
    assert isinstance(err, Error) and "b.toml:1" in err.message
    code, out, _ = run_cli(capsys, "test", root, "--json")
    doc = json.loads(out)
    assert code == 2 and (doc["passed"], doc["failed"], len(doc["errors"])) == (15, 1, 1)


def test_coverage_prints_percentages_and_uncovered_lines(tmp_path, capsys):
    root = make_project(tmp_path / "p", {"b": FAILING})
    code, out, _ = run_cli(capsys, "test", root, "--coverage")
    assert code == 1
    cov = {line.split()[0]: line for line in out.splitlines() if line.startswith("  ")}
    assert "reference interpreter" in out
    assert "BRANCH" in cov and "PULSE" in cov
    assert "0.0%  0/" in cov["PULSE"]
    assert "not run: BRANCH.plc:6-7" in cov["BRANCH"]


def test_trace_failed_writes_the_failing_runs_trace(tmp_path, capsys):
    root = make_project(tmp_path / "p", {"a": PASSING, "b": FAILING})
    code, out, _ = run_cli(capsys, "test", root, "--trace-failed", tmp_path / "traces", "--json")
    assert code == 1
    t = {x["name"]: x for x in json.loads(out)["tests"]}
    assert t["pulse on in ticks 5..7"]["trace"] is None
    path = tmp_path / "traces" / "branch_two.csv"
    assert t["branch two"]["trace"] == str(path)
    rows = path.read_text().splitlines()
    assert rows[0].startswith("t_ms,proc,message,running,")
    assert [r.split(",")[0] for r in rows[1:]] == ["0", "1"]   # through the failing tick 1
    pwm0 = rows[0].split(",").index("pwm0")
    assert rows[2].split(",")[pwm0] == "20"
