"""JUnit XML as Jenkins and GitLab read it: valid against the Jenkins xUnit
plugin's ``junit-10.xsd`` (issue 25 item 6: ``skipped`` is not allowed on
``<testsuites>``), and well-formed XML 1.0 whatever the tests are called
(issue 24 item 8: a control character or U+FFFF in a name made it "not
well-formed (invalid token)")."""

from __future__ import annotations

import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from plcbuilder.testing.junit import junit_xml, write_junit, xml_text
from tests.cli._run import run_cli
from tests.testing._proj import FAILING, PASSING, make_project

XSD = Path(sys.prefix) / "share" / "plcbuilder-tests" / "junit-10.xsd"
needs_xsd = pytest.mark.skipif(
    not XSD.is_file(), reason=f"{XSD} is not installed: scripts/test_schemas.py fetches it "
                              f"from pytest's source distribution on PyPI (scripts/_venv.sh "
                              f"runs it when it installs the test extras)")

#: every character XML 1.0 cannot hold, some of each kind
HOSTILE = "".join(map(chr, [0, 1, 8, 0x0B, 0x0C, 0x1F, 0xFFFE, 0xFFFF, 0xD800, 0xDFFF]))


def _hostile_project(tmp_path) -> Path:
    """Tests named with control characters and U+FFFF (TOML's \\u escapes), one
    passing, one failing, and a test file that cannot be read."""
    passing = PASSING.replace('name = "pulse on in ticks 5..7"',
                              'name = "pulse \\u0001\\u001f\\uffff\\ufffe \\u0008 on"')
    failing = FAILING.replace('name = "branch two"', 'name = "branch\\u000b two\\u0000"')
    return make_project(tmp_path / "p\x01roj", {"a": passing, "b": failing,
                                               "c": "[[test]]\nname = \"\\uffff\n"})


def test_xml_text_escapes_what_xml_cannot_hold():
    assert xml_text("a\x01b\uffff\ud800c\t\n\r\u00e9\U0001F600") == \
        "a\\x01b\\uffff\\ud800c\t\n\r\u00e9\U0001F600"
    assert xml_text(HOSTILE) == ("\\x00\\x01\\x08\\x0b\\x0c\\x1f\\ufffe\\uffff"
                                 "\\ud800\\udfff")


def test_junit_is_well_formed_whatever_the_names(tmp_path, capsys):
    root = _hostile_project(tmp_path)
    path = tmp_path / "junit.xml"
    code, _out, err = run_cli(capsys, "test", root, "--junit", path)
    assert code == 2, err                           # c.toml cannot be read
    tree = ET.parse(path)                           # was: not well-formed (invalid token)
    cases = {c.get("name"): c for c in tree.iter("testcase")}
    assert "pulse \\x01\\x1f\\uffff\\ufffe \\x08 on" in cases
    assert cases["branch\\x0b two\\x00"].find("failure") is not None
    assert cases["c.toml: cannot be read"].find("error") is not None


def test_every_text_and_attribute_is_escaped():
    """The suite's name, a test's name, file, failure and error texts."""
    class R:
        name, file, seconds = "n" + HOSTILE, f"tests/f{HOSTILE}.toml", 0.1
        error = "e" + HOSTILE
        failures = []

    class F:
        def text(self):
            return "f" + HOSTILE

    class R2(R):
        error = None
        failures = [F(), F()]

    class E(Exception):
        file = f"tests/x{HOSTILE}.toml"

    text = junit_xml("s" + HOSTILE, [R(), R2()], [E("bad" + HOSTILE)])
    root = ET.fromstring(text.encode("utf-8"))
    esc = xml_text(HOSTILE)
    assert root.get("name") == "s" + esc
    assert all(esc in (c.get("name") + c.get("classname")) for c in root.iter("testcase"))
    assert [e.get("message") for e in root.iter("error")] == ["e" + esc, "bad" + esc]
    (f,) = root.iter("failure")
    assert f.get("message") == "f" + esc and f.text == f"f{esc}\nf{esc}"


@needs_xsd
def test_the_report_is_valid_against_junit_10_xsd(tmp_path, capsys):
    """Jenkins xUnit's schema: passing and failing tests, a test file that
    cannot be read, names XML cannot hold; a test that could not run (an
    ``<error>`` of its own) too."""
    import xmlschema
    schema = xmlschema.XMLSchema(str(XSD))
    root = make_project(tmp_path / "p", {"a": PASSING, "b": FAILING, "c": "x = 1\n"})
    path = tmp_path / "junit.xml"
    code, _out, err = run_cli(capsys, "test", root, "--junit", path)
    assert code == 2, err
    schema.validate(str(path))                      # was: 'skipped' not allowed on testsuites
    root2 = make_project(tmp_path / "q", {"a": PASSING})
    code, _out, err = run_cli(capsys, "test", root2, "--junit", path)
    assert code == 0, err
    schema.validate(str(path))
    hostile = _hostile_project(tmp_path)
    run_cli(capsys, "test", hostile, "--junit", path)
    schema.validate(str(path))

    class R:
        name, file, seconds, error, failures = "refused", "tests/a.toml", 0.5, "no M99", []
    write_junit(path, "p", [R()])
    schema.validate(str(path))
    assert ET.parse(path).find(".//error").get("message") == "no M99"


@needs_xsd
def test_times_have_at_most_three_decimals(tmp_path):
    """junit-10.xsd's SUREFIRE_TIME: ``0.0123456`` or ``1e-05`` are not times."""
    import xmlschema
    schema = xmlschema.XMLSchema(str(XSD))

    class R:
        name, file, error, failures = "t", "tests/a.toml", None, []
    for seconds in (0.0123456, 1e-05, 0.0, 12345.6789):
        r = R()
        r.seconds = seconds
        path = tmp_path / "t.xml"
        write_junit(path, "p", [r])
        schema.validate(str(path))
