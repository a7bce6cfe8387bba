"""The doc-test runner itself: it finds the marked blocks, reads their options and
fails an example whose output is not what the manual shows."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.docs.examples import ROOT, ExampleError, examples, matches, run, steps

PAGE = ROOT / "docs" / "fake.md"


def _one(text: str):
    found = examples(PAGE, text)
    assert len(found) == 1
    return found[0]


def test_console_blocks_and_marked_blocks_are_examples_others_are_not():
    text = ("```sh\nrm -rf /\n```\n\n"
            "```console\n$ echo hi\nhi\n```\n\n"
            "<!-- example -->\n```sh\ntrue\n```\n\n"
            "```c\nmain() {};\n```\n")
    found = examples(PAGE, text)
    assert [(e.line, e.info) for e in found] == [(5, "console"), (11, "sh")]


def test_options_and_files_carry_to_later_examples():
    text = ("<!-- example: file=M03.plc -->\n```c\nmain() {};\n```\n"
            "<!-- example: project= cd=sub before=\"touch x\" -->\n"
            "```console\n$ ls\nx\n```\n")
    ex = _one(text)
    assert ex.options == {"project": "", "cd": "sub", "before": "touch x"}
    assert ex.files == {"M03.plc": "main() {};\n"}


def test_a_bad_marking_is_an_error_that_says_where():
    with pytest.raises(ExampleError, match=r"fake.md:1: unknown example option 'bogus=1'"):
        examples(PAGE, "<!-- example: bogus=1 -->\n```sh\ntrue\n```\n")
    with pytest.raises(ExampleError, match=r"fake.md:1: an example comment that no code block"):
        examples(PAGE, "<!-- example -->\nsome prose\n")


def test_steps_split_commands_continuations_and_output():
    got = steps("$ a \\\n  b\nout 1\n$ c\n")
    assert [(s.command, s.expected) for s in got] == [("a \\\n  b", ["out 1"]), ("c", [])]


def test_elisions():
    assert matches(["a", "…", "z"], "a\nb\nc\nz\n")
    assert matches(["a", "...", "z"], "a\nz\n")
    assert matches(["took … ms"], "took 12.5 ms\n")
    assert not matches(["a", "z"], "a\nb\nz\n")
    assert not matches(["took … ms"], "took 12 s\n")
    assert not matches(["a"], "a\nextra\n")


def test_the_runner_passes_a_true_example_and_fails_a_wrong_output(tmp_path):
    ok = _one("<!-- example: project= -->\n```console\n$ echo hello; echo oops >&2\n"
              "hello\noops\n$ echo $?\n0\n$ false\n$ echo $?\n1\n```\n")
    assert run(ok, tmp_path / "ok") == []
    wrong = _one("<!-- example: project= -->\n```console\n$ echo hello\nhullo\n```\n")
    problems = run(wrong, tmp_path / "wrong")
    assert len(problems) == 1
    assert "fake.md:2: $ echo hello" in problems[0]
    assert "--- the manual shows:\nhullo\n--- it prints:\nhello" in problems[0]


def test_the_runner_fails_a_wrong_plcbuilder_output_and_a_failing_command(tmp_path):
    wrong = _one("```console\n$ plcbuilder check myproject/hardware/M03.plc\n"
                 "myproject/hardware/M03.plc: ok: 0 errors, 0 warnings; hardware procedure M03, "
                 "99/512 bytes\n```\n")
    assert run(wrong, tmp_path / "a")
    failing = _one("<!-- example -->\n```sh\nplcbuilder build myproject\n"
                   "plcbuilder build nowhere\n```\n")
    problems = run(failing, tmp_path / "b")
    assert problems and "the commands failed (exit 1)" in problems[0]
    assert "nowhere: no such folder" in problems[0]


def test_background_jobs_end_with_the_block(tmp_path):
    ex = _one("<!-- example: project= -->\n```console\n$ sleep 30 &\n$ echo done\ndone\n```\n")
    import time
    t0 = time.monotonic()
    assert run(ex, tmp_path) == []
    assert time.monotonic() - t0 < 20


def test_a_failing_set_up_is_reported(tmp_path):
    ex = _one("<!-- example: project= before=\"echo nope; false\" -->\n"
              "```console\n$ echo hi\nhi\n```\n")
    problems = run(ex, tmp_path)
    assert problems and "the set-up before= failed:\nnope" in problems[0]


def test_a_background_command_shows_what_it_printed_when_ready(tmp_path):
    ex = _one("<!-- example: project= -->\n```console\n"
              "$ (sleep 0.5; echo ready; sleep 30) &\nready\n$ echo next\nnext\n```\n")
    assert run(ex, tmp_path) == []


def test_a_marked_python_block_runs_and_must_succeed(tmp_path):
    ok = _one("<!-- example: project= -->\n```python\nimport plcbuilder\n```\n")
    assert run(ok, tmp_path / "ok") == []
    bad = _one("<!-- example: project= -->\n```python\nfrom plcbuilder import nope\n```\n")
    problems = run(bad, tmp_path / "bad")
    assert problems and "ImportError" in problems[0]


def test_an_indented_block_in_a_list_item_is_an_example():
    ex = _one("- a list item:\n\n  <!-- example: project= -->\n  ```console\n  $ echo hi\n    hi\n  ```\n")
    assert ex.body == "$ echo hi\n  hi" and ex.options == {"project": ""}
    ex = _one("```console\n$ echo '  hi'\n  hi\n```\n")
    assert ex.body == "$ echo '  hi'\n  hi"
