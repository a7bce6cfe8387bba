"""The test file format (SPEC §8): what is accepted, and every mistake reported
as FILE:LINE: reason, never a traceback."""

from __future__ import annotations

import pytest

from plcbuilder.testing.runner import prepare
from plcbuilder.testing.spec import (CONDITIONS, SELECTORS, TestFileError, load_dir, parse,
                                     pin_names)

from tests.testing._proj import make_project

GOOD = """\
[[test]]
name = "pulse"
ms = 50
scenario = \"\"\"
start PULSE @ 0
input 4=1 @ 2
\"\"\"

[[test.expect]]
at_ms = 5
outputs_on = [3]

[[test.expect]]
during_ms = [5, 7]
outputs_on = [3]
pwm = { 0 = 0 }
"""


def error_of(text: str, tmp_path):
    """The one error of a project whose only test file is ``text``."""
    root = make_project(tmp_path / "p", {"t": text})
    suite = prepare(root)
    assert len(suite.errors) == 1, suite.errors
    return suite.errors[0]


def test_a_good_file_parses_with_lines():
    tests = parse(GOOD, "t.toml")
    assert len(tests) == 1
    t = tests[0]
    assert (t.name, t.ms, t.line) == ("pulse", 50, 1)
    assert [a.describe() for a in t.scenario.actions] == ["start PULSE:0 @ 0", "input 4=1 @ 2"]
    assert t.scenario_lines == [5, 6]
    ex1, ex2 = t.expectations
    assert (ex1.selector, ex1.lo, ex1.hi, ex1.line) == ("at_ms", 5, 5, 9)
    assert (ex2.selector, ex2.lo, ex2.hi) == ("during_ms", 5, 7)
    assert [(c.key, c.line, c.text) for c in ex2.conditions] == [
        ("outputs_on", 15, "outputs_on = [3]"), ("pwm", 16, "pwm = { 0 = 0 }")]
    assert ex2.conditions[1].value == {0: 0}


def test_names_and_numbers_are_both_accepted():
    t = parse('[[test]]\nname="x"\n[[test.expect]]\nat_end=true\nproc="plc_proc_spindle"\n'
              'message=["PLC_MESSAGE_PLASMA_OK", 1008]\nexit={ M03 = "plc_exit_normal" }\n'
              'print={ 20001 = 5 }\naxes={ z = [-10, 10], X = 5 }\n')[0]
    values = {c.key: c.value for c in t.expectations[0].conditions}
    assert values["proc"] == 70 and values["message"] == [101, 1008]
    assert values["exit"] == {"M03": 99} and values["print"] == {20001: 5}
    assert values["axes"] == {"Z": (-10, 10), "X": (5, 5)}


def test_bad_toml_gives_the_parsers_line(tmp_path):
    e = error_of("[[test]]\nname = \"x\"\nms = = 3\n", tmp_path)
    assert e.line == 3 and "not valid TOML" in e.message
    assert str(e).startswith(f"{tmp_path / 'p' / 'tests' / 't.toml'}:3: ")


def test_an_unknown_key_names_the_known_ones(tmp_path):
    e = error_of(GOOD.replace("pwm = { 0 = 0 }", "pwms = { 0 = 0 }"), tmp_path)
    assert e.line == 16 and "unknown key 'pwms'" in e.message
    assert all(k in e.message for k in SELECTORS + CONDITIONS)
    e = error_of(GOOD.replace('ms = 50', 'timeout = 50'), tmp_path / "b")
    assert e.line == 3 and "name, ms, machine, scenario, gcode, expect" in e.message


def test_two_time_selectors_are_refused(tmp_path):
    e = error_of(GOOD.replace("at_ms = 5\n", "at_ms = 5\nby_ms = 7\n"), tmp_path)
    assert e.line == 11 and "exactly one time selector" in e.message   # the second one
    assert "at_ms, by_ms" in e.message


def test_no_selector_or_no_condition_is_refused(tmp_path):
    e = error_of(GOOD.replace("at_ms = 5\n", ""), tmp_path)
    assert e.line == 9 and "needs one time selector" in e.message
    e = error_of(GOOD.replace("at_ms = 5\noutputs_on = [3]\n", "at_ms = 5\n"), tmp_path / "b")
    assert e.line == 9 and "one or more conditions" in e.message


def test_an_unknown_procedure_in_the_scenario(tmp_path):
    e = error_of(GOOD.replace("start PULSE @ 0", "start PULSES @ 0"), tmp_path)
    assert e.line == 5 and "no procedure named 'PULSES'" in e.message and "PULSE" in e.message


def test_an_unknown_procedure_in_exit_or_vars(tmp_path):
    e = error_of(GOOD + "\n[[test.expect]]\nat_end = true\nexit = { NOPE = 99 }\n", tmp_path)
    assert e.line == 20 and "no procedure named 'NOPE'" in e.message
    e = error_of(GOOD + '\n[[test.expect]]\nat_end = true\nvars = { "PULSE.nope" = 1 }\n',
                 tmp_path / "b")
    assert e.line == 20 and "PULSE has no variable 'nope'" in e.message and "timer" in e.message


def test_an_unknown_output_name(tmp_path):
    e = error_of(GOOD.replace("outputs_on = [3]\n\n", 'outputs_on = ["OUTPUT_SPINDEL"]\n\n'),
                 tmp_path)
    assert e.line == 11 and "unknown output name 'OUTPUT_SPINDEL'" in e.message
    assert "OUTPUT_SPINDLE" in e.message


def test_a_pin_name_becomes_its_number(tmp_path):
    root = make_project(tmp_path / "p", {"t": GOOD.replace("outputs_on = [3]\n\n",
                                                           'outputs_on = ["OUTPUT_FLOOD"]\n\n')})
    suite = prepare(root)
    assert not suite.errors
    assert suite.tests[0].expectations[0].conditions[0].value == [3]


@pytest.mark.parametrize("change, line, words", [
    (("at_ms = 5", "at_ms = 50"), 10, "after the test's last tick (49"),
    (("during_ms = [5, 7]", "during_ms = [7, 5]"), 14, "ends before it begins"),
    (("during_ms = [5, 7]", "during_ms = 5"), 14, "during_ms is [FROM, TO]"),
    (("at_ms = 5", "at_end = false"), 10, "at_end must be true"),
    (("ms = 50", "ms = 0"), 3, "ms must be a whole number from 1"),
    (("pwm = { 0 = 0 }", "pwm = { 9 = 0 }"), 16, "pwm channel 9 does not exist"),
    (('name = "pulse"', "name = 3"), 2, "name must be a non-empty string"),
    (("input 4=1 @ 2", "input 4=2 @ 2"), 6, "an input is 0 or 1"),
    (("outputs_on = [3]\n\n", 'outputs_on = [3]\nproc = "plc_proc_spindel"\n\n'), 12,
     "unknown proc state 'plc_proc_spindel'"),
])
def test_each_mistake_has_its_line(tmp_path, change, line, words):
    e = error_of(GOOD.replace(*change), tmp_path)
    assert (e.line, words in e.message) == (line, True), str(e)


def test_a_file_without_tests_and_a_duplicate_name(tmp_path):
    e = error_of("# nothing\n", tmp_path)
    assert "no [[test]] table" in e.message
    root = make_project(tmp_path / "q", {"a": GOOD, "b": GOOD})
    tests, errors = load_dir(root / "tests")
    assert len(tests) == 1 and len(errors) == 1
    assert "a second test named 'pulse'" in errors[0].message and errors[0].line == 1


def test_not_utf8_and_a_folder_are_reported_not_raised(tmp_path):
    root = make_project(tmp_path / "p", {"t": GOOD})
    (root / "tests" / "bin.toml").write_bytes(b'[[test]]\nname = "\xff"\n')
    (root / "tests" / "dir.toml").mkdir()
    tests, errors = load_dir(root / "tests")
    assert [t.name for t in tests] == ["pulse"]
    assert [(e.line, e.message) for e in errors] == [(2, "not UTF-8 text")]


def test_an_error_is_a_value_error_text():
    e = TestFileError("why", "f.toml", 3)
    assert str(e) == "f.toml:3: why" and e.to_dict() == {"file": "f.toml", "line": 3,
                                                         "message": "why"}


def test_pin_names_reads_defines():
    assert pin_names("#define OUTPUT_X 3 // c\n #define IN_Y 0x10\n#define Z foo\n") == \
        {"OUTPUT_X": 3, "IN_Y": 16}
