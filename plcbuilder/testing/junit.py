"""JUnit XML of a test run, as Jenkins and GitLab read it (written with
``junitparser``): one ``<testsuite>`` named after the project, one
``<testcase>`` per test (``classname`` the test file, ``time`` its wall time),
a ``<failure>`` per failing test (its first failing condition as the message,
all of them as the text), an ``<error>`` for a test that could not run or a
test file that could not be read."""

from __future__ import annotations

from pathlib import Path
from typing import Iterable

from junitparser import Error, Failure, JUnitXml, TestCase, TestSuite

from plcbuilder._support.files import atomic_write


def junit_xml(suite_name: str, results: Iterable, errors: Iterable = ()) -> str:
    """The XML text: ``results`` are runner TestResults, ``errors`` TestFileErrors."""
    ts = TestSuite(suite_name)
    for r in results:
        case = TestCase(r.name, classname=_classname(r.file), time=round(r.seconds, 6))
        if r.error is not None:
            case.result = [Error(r.error, "error")]
        elif r.failures:
            f = Failure(r.failures[0].text(), "failure")
            f.text = "\n".join(x.text() for x in r.failures)
            case.result = [f]
        ts.add_testcase(case)
    for e in errors:
        case = TestCase(f"{Path(e.file).name}: cannot be read", classname=_classname(e.file),
                        time=0)
        case.result = [Error(str(e), "error")]
        ts.add_testcase(case)
    ts.update_statistics()
    xml = JUnitXml(suite_name)
    xml.add_testsuite(ts)
    xml.update_statistics()
    text = xml.tostring()
    return text.decode("utf-8") if isinstance(text, bytes) else text


def _classname(file: str) -> str:
    p = Path(file)
    return f"{p.parent.name}.{p.stem}" if p.parent.name else p.stem


def write_junit(path, suite_name: str, results: Iterable, errors: Iterable = ()) -> None:
    """Write :func:`junit_xml` to ``path`` (atomically)."""
    text = junit_xml(suite_name, results, errors)
    if not text.startswith("<?xml"):
        text = '<?xml version="1.0" encoding="utf-8"?>\n' + text
    atomic_write(Path(path), text)
