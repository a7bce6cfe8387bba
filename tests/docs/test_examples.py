"""Every marked example of README.md and docs/*.md runs and prints what the
manual shows (tests/docs/examples.py says how examples are marked)."""

from __future__ import annotations

import pytest

from tests.docs.examples import all_examples, missing, run

EXAMPLES = all_examples()


def test_the_manual_has_examples():
    assert len(EXAMPLES) >= 25


@pytest.mark.parametrize("example", EXAMPLES, ids=lambda ex: ex.id)
def test_example(example, tmp_path):
    if "skip" in example.options:
        pytest.skip(example.options["skip"] or "marked skip")
    if missing(example):
        pytest.skip(f"{', '.join(missing(example))} is not installed here")
    problems = run(example, tmp_path)
    assert not problems, "\n\n".join(problems)
