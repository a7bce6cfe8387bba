"""JUnit XML of a test run, as Jenkins (its xUnit plugin's ``junit-10.xsd``)
and GitLab read it (written with ``junitparser``): one ``<testsuite>`` named
after the project, one ``<testcase>`` per test (``classname`` the test file,
``time`` its wall time), a ``<failure>`` per failing test (its first failing
condition as the message, all of them as the text), an ``<error>`` for a test
that could not run or a test file that could not be read.

The document is what ``junit-10.xsd`` allows (no ``skipped`` on
``<testsuites>``, times with at most three decimals) and well-formed XML 1.0
whatever the tests are called: a character XML 1.0 cannot hold (a control
character, U+FFFE, U+FFFF, a lone surrogate) is written as its escape,
``\\x01``, ``\\uffff``, in every text and attribute."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Iterable

from junitparser import Error, Failure, JUnitXml, TestCase, TestSuite

from plcbuilder._support.files import atomic_write

#: what XML 1.0 cannot hold (its Char production, section 2.2)
_NOT_XML = re.compile("[^\t\n\r\u0020-\ud7ff\ue000-\ufffd\U00010000-\U0010ffff]")


def xml_text(text) -> str:
    """``text`` as XML 1.0 can hold it: each character it cannot hold as its
    Python escape (``\\x01``, ``\\uffff``)."""
    def esc(m: re.Match) -> str:
        c = ord(m.group())
        return f"\\x{c:02x}" if c < 0x100 else f"\\u{c:04x}"
    return _NOT_XML.sub(esc, str(text))


def junit_xml(suite_name: str, results: Iterable, errors: Iterable = ()) -> str:
    """The XML text: ``results`` are runner TestResults, ``errors`` TestFileErrors."""
    name = xml_text(suite_name)
    ts = TestSuite(name)
    for r in results:
        case = TestCase(xml_text(r.name), classname=xml_text(_classname(r.file)),
                        time=round(r.seconds, 3))
        if r.error is not None:
            case.result = [Error(xml_text(r.error), "error")]
        elif r.failures:
            f = Failure(xml_text(r.failures[0].text()), "failure")
            f.text = xml_text("\n".join(x.text() for x in r.failures))
            case.result = [f]
        ts.add_testcase(case)
    for e in errors:
        case = TestCase(xml_text(f"{Path(e.file).name}: cannot be read"),
                        classname=xml_text(_classname(e.file)), time=0)
        case.result = [Error(xml_text(e), "error")]
        ts.add_testcase(case)
    ts.update_statistics()
    xml = JUnitXml(name)
    xml.add_testsuite(ts)
    # the totals junit-10.xsd allows on <testsuites> (not ``skipped``)
    xml.tests, xml.failures, xml.errors, xml.time = ts.tests, ts.failures, ts.errors, ts.time
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
