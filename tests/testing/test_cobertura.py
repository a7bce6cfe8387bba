"""Coverage as Cobertura XML (issue 25 item 8): ``plcbuilder test PROJECT
--coverage-xml FILE`` writes lines and branches per .plc file as pytest-cov's
``--cov-report xml`` does, read back here by ``pycobertura`` (GitLab and
Jenkins read the same format); ``--coverage`` ends with a TOTAL line a CI
coverage regex reads."""

from __future__ import annotations

import re

from pycobertura import Cobertura
from pycobertura.filesystem import filesystem_factory

from tests.cli._run import run_cli
from tests.testing._proj import BRANCH, FAILING, PASSING, PULSE, make_project

#: the regex docs/tests.md gives for GitLab's ``coverage:`` keyword
GITLAB_REGEX = r"^\s*TOTAL\s+(\d+(?:\.\d+)?)%"

HEADER = """twice()
{
  if (v > 5)
  {
    v = v * 2;
  };
};
"""
USES_A = '#include "shared.h"\nmain()\n{\n  v=eparam;\n  twice();\n  exit(v);\n};\n'
USES_B = '#include "shared.h"\nmain()\n{\n  v=3;\n  twice();\n  exit(v);\n};\n'


def _report(tmp_path, capsys, root, *extra):
    xml = tmp_path / "coverage.xml"
    code, out, err = run_cli(capsys, "test", root, "--coverage", "--coverage-xml", xml, *extra)
    return code, out, err, Cobertura(str(xml), filesystem=filesystem_factory(str(root)))


def test_pycobertura_reads_lines_and_branches_per_file(tmp_path, capsys):
    root = make_project(tmp_path / "p", {"a": PASSING, "b": FAILING})
    code, out, err, cov = _report(tmp_path, capsys, root)
    assert code == 1, err
    assert cov.files() == ["hardware/BRANCH.plc", "hardware/DIVIDE.plc", "hardware/PULSE.plc"]
    assert cov.packages() == ["hardware"]
    # BRANCH with eparam 2: lines 6-7 (the first if's body) never ran; each if
    # went one way of two
    assert cov.total_statements("hardware/BRANCH.plc") == 10
    assert cov.missed_lines("hardware/BRANCH.plc") == [(4, "partial"), (6, "miss"), (7, "miss"),
                                                        (9, "partial")]
    assert cov.line_rate("hardware/BRANCH.plc") == 0.8
    assert cov.branch_rate("hardware/BRANCH.plc") == 0.5
    assert cov.line_rate("hardware/PULSE.plc") == 1.0 == cov.branch_rate("hardware/PULSE.plc")
    assert cov.line_rate("hardware/DIVIDE.plc") == 0.0
    assert cov.line_rate() == 0.75 and cov.branch_rate() == 0.75
    # the source is found where the report says it is
    src = cov.file_source("hardware/BRANCH.plc")
    assert src[3].source.strip() == "if (a==1)" and src[3].status == "partial"
    # the text report: the same numbers, and a TOTAL line a CI regex reads
    assert "  BRANCH   80.0%  8/10 lines  2/4 branches  not run: BRANCH.plc:6-7" in out
    m = re.search(GITLAB_REGEX, out, re.M)
    assert m and float(m.group(1)) == 75.0
    assert "  TOTAL    75.0%  15/20 lines  6/8 branches" in out


def test_a_header_several_procedures_include_is_one_file(tmp_path, capsys):
    test = """\
[[test]]
name = "both"
ms = 50
scenario = "start A:9 @ 0\\nstart B @ 20"
[[test.expect]]
at_end = true
exit = { A = 18, B = 3 }
"""
    root = make_project(tmp_path / "p", {"t": test}, {"A": USES_A, "B": USES_B})
    (root / "include" / "shared.h").write_text(HEADER)
    code, out, err, cov = _report(tmp_path, capsys, root)
    assert code == 0, err
    assert cov.files() == ["hardware/A.plc", "hardware/B.plc", "include/shared.h"]
    assert cov.packages() == ["hardware", "include"]
    # A took the if (9 > 5), B did not (3): every line of the header ran once
    # over both, and its condition went each way in one of them: the file counts once
    assert cov.line_rate("include/shared.h") == 1.0
    assert cov.branch_rate("include/shared.h") == 1.0
    assert re.search(GITLAB_REGEX, out, re.M)


def test_xml_only_prints_no_table_and_json_has_branches(tmp_path, capsys):
    root = make_project(tmp_path / "p", {"b": FAILING})
    xml = tmp_path / "c.xml"
    code, out, _ = run_cli(capsys, "test", root, "--coverage-xml", xml)
    assert code == 1 and "TOTAL" not in out and xml.stat().st_size > 0
    Cobertura(str(xml))
    code, out, _ = run_cli(capsys, "test", root, "--coverage", "--json")
    import json
    (branch,) = [c for c in json.loads(out)["coverage"] if c["name"] == "BRANCH"]
    assert (branch["branches"], branch["branches_covered"]) == (4, 2)
    assert branch["files"][0]["branches"] == [{"line": 4, "covered": 1, "total": 2},
                                              {"line": 9, "covered": 1, "total": 2}]


def test_a_pool_of_processes_gives_the_same_report(tmp_path, capsys):
    tests = {f"t{i}": PASSING.replace("pulse on in ticks 5..7", f"pulse {i}") for i in range(3)}
    tests["b"] = FAILING
    root = make_project(tmp_path / "p", tests, {"PULSE": PULSE, "BRANCH": BRANCH})
    reports = []
    for jobs in ("1", "2"):
        xml = tmp_path / f"c{jobs}.xml"
        run_cli(capsys, "test", root, "--coverage-xml", xml, "-j", jobs)
        reports.append(re.sub(r'timestamp="\d+"', "", xml.read_text()))
    assert reports[0] == reports[1]


def test_unwritable_coverage_xml_exits_2(tmp_path, capsys):
    root = make_project(tmp_path / "p", {"a": PASSING})
    code, _out, err = run_cli(capsys, "test", root, "--coverage-xml", tmp_path / "no" / "c.xml")
    assert code == 2 and "cannot write" in err
