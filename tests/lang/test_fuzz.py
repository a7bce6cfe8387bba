"""Fuzzing in the normal suite: programs generated from the grammar and mutated
programs never give anything but diagnostics. (scripts/fuzz.py runs longer.)"""

import random

import lark
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra.lark import from_lark

from plcbuilder.lang.parser import grammar_text
from tests.lang.fuzzing import check_one, large_program, mutate, seeds

GRAMMAR = lark.Lark(grammar_text(), parser="lalr")
#: names that reach every part of the checker: main, built-ins, predefined
#: variables, built-in constants, and a few ordinary names
NAMES = st.sampled_from(["main", "main", "helper", "a", "b", "timer", "eparam", "message", "pwm01",
                         "adc01", "Param", "portset", "portget", "gvarget", "gvarset", "g0moveA",
                         "exit", "portclr", "PLCCMD_LINE_STOP", "plc_exit_normal", "x_1"])
NUMBERS = st.sampled_from(["0", "1", "2", "31", "32", "99", "0x4d", "0xffffffff", "2147483647",
                           "65536", "7278", "20000"])
PROGRAMS = from_lark(GRAMMAR, explicit={"NAME": NAMES, "NUMBER": NUMBERS,
                                        "WS": st.sampled_from([" ", "\n", "\t"]),
                                        "COMMENT": st.sampled_from(["//c\n", "/* c */"])})


@pytest.mark.slow
@settings(max_examples=2000, deadline=None, database=None,
          suppress_health_check=list(HealthCheck))
@given(PROGRAMS)
def test_grammar_generated_programs(text):
    check_one(text.encode("utf-8", "surrogatepass"))


@pytest.mark.slow
def test_mutated_programs():
    rng = random.Random(20261121)
    corpus = seeds()
    for i in range(2000):
        data = mutate(rng.choice(corpus), rng)
        check_one(data, software=i % 5 == 0, strict=i % 7 == 0)


@pytest.mark.slow
def test_large_programs():
    """Programs around and beyond what 16-bit code addresses reach (64 KiB of
    code, 32 KiB jumps), under the default and raised limits: a diagnostic,
    never an exception."""
    rng = random.Random(20261125)
    for target, limit in ((40_000, 65536), (80_000, None), (80_000, 1_000_000)):
        check_one(large_program(rng, target), software=True, code_limit=limit)
    check_one(mutate(large_program(rng, 70_000), rng), software=True, code_limit=1_000_000)
