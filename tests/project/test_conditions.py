"""Breakpoint conditions (and evaluated expressions) compiled by
``compile_condition``: bounded before the compiler sees them, so a hostile text
is refused at once with a clear reason (issue 24.2), and every message speaks
of the text the user wrote, never of the ``exit(...);`` it is wrapped in
(issue 25.4)."""

import time

import pytest

from plcbuilder.project.conditions import (MAX_CONDITION_CHARS, MAX_CONDITION_DEPTH,
                                           compile_condition)


def _messages(text: str) -> list[str]:
    r = compile_condition(text)
    assert isinstance(r, list), f"{text!r} compiled"
    return [d.message for d in r]


@pytest.mark.parametrize("n", [800, 1600, 3200])
def test_runs_of_open_brackets_are_refused_at_once(n):
    """800/1,600/3,200 '(' took 2.2/5.6/16.4 s in the compiler's error recovery."""
    compile_condition("1")
    t0 = time.perf_counter()
    r = compile_condition("(" * n)
    took = time.perf_counter() - t0
    assert isinstance(r, list) and len(r) == 1
    assert ("nest at most 16 deep" in r[0].message
            or "at most 1000 characters" in r[0].message), r[0].message
    assert took < 0.05, f"{took:.3f} s"


def test_the_limits_are_what_they_say():
    assert MAX_CONDITION_DEPTH == 16 and MAX_CONDITION_CHARS == 1000
    assert isinstance(compile_condition("(" * 16 + "1" + ")" * 16), bytes)
    too_deep = compile_condition("(" * 17 + "1" + ")" * 17)
    assert [d.message for d in too_deep] == ["a condition's brackets nest at most 16 deep"]
    assert too_deep[0].span.col == 17 and too_deep[0].span.file == "<condition>"
    long = "count + " * 124 + "count"            # 997 characters: compiles
    assert len(long) <= 1000 and isinstance(compile_condition(long), bytes)
    over = compile_condition("1 +" + " " * 1000 + "1")
    assert [d.message for d in over] == ["a condition is at most 1000 characters; this one "
                                         "has 1,004"]


def test_the_worst_text_within_the_limits_is_checked_quickly():
    """Everything the scan lets through is balanced and at most 16 deep: the
    compiler's recovery on it stays well under a second even on a busy machine
    (about 50 ms here with today's parser)."""
    compile_condition("1")
    units = ["(" * 16 + ")" * 16, "(" * 16 + "1 1" + ")" * 16, "(" * 16 + "a b c" + ")" * 16]
    worst = 0.0
    for unit in units:
        k = 1
        while len("+".join([unit] * (k + 1))) <= 1000:
            k += 1
        text = "+".join([unit] * k)
        t0 = time.perf_counter()
        r = compile_condition(text)
        worst = max(worst, time.perf_counter() - t0)
        assert isinstance(r, list) and r
    assert worst < 1.0, f"{worst:.3f} s"


@pytest.mark.parametrize("text, message, col", [
    ("nope(", "the '(' at column 5 is not closed: a ')' is missing", 5),
    ("count +", "expected an expression at the end of the condition", 8),
    ("a b", "unexpected 'b' after 'a'", 2),
    ("1)", "')' has no '(' before it to close", 2),
    ("(1]", "']' has no '[' before it to close (the '(' at column 1 is still open)", 3),
    ("1, 2", "',' separates arguments: a condition is one expression", 2),
    ("n == 1; m", "';' ends a statement: a condition is one expression", 7),
    ("{1}", "'{' starts a block: a condition is one expression", 1),
    ("#define X 1", "'#' starts a directive (#define, #include): a condition is one "
                    "expression", 1),
    ("if (n) 1", "unexpected 'if' at the start of the condition", 1),
    ("n /* open", "the comment '/*' is not closed", 3),
])
def test_messages_speak_of_the_users_text(text, message, col):
    r = compile_condition(text)
    assert isinstance(r, list)
    assert (r[0].message, r[0].span.col) == (message, col)


@pytest.mark.parametrize("text", ["nope(", "count +", "a b", "1)", "n ==", "1 1 1", "(a b)",
                                  "while", "do 1", "!", "portget(1) 2", "(((", ")"])
def test_no_message_mentions_what_the_user_did_not_type(text):
    for m in _messages(text):
        assert "';'" not in m and "exit" not in m, (text, m)


def test_a_comment_at_the_end_is_allowed():
    assert isinstance(compile_condition("count > 2 // the third pass"), bytes)
    assert isinstance(compile_condition("count /* passes */ > 2"), bytes)

