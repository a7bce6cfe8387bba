"""The fast backend and the reference interpreter behave identically: on over a
thousand generated programs (with faults, recursion, busy loops, values on the
stack across jumps, every builtin, gvarget latency, software procedures), the
full traces — every event, every per-tick sample, the final variables — are equal.
"""

from __future__ import annotations

import random

import pytest

from plcbuilder.bytecode.program import Kind
from plcbuilder.controller import fastvm
from plcbuilder.controller.controller import Controller

from tests.controller._vmgen import random_program, random_soup

CHUNKS = 8
PER_CHUNK = 130          # 8 x 130 = 1040 structured programs


def trace(prog, backend: str, ticks: int, latency: int):
    c = Controller(backend=backend, gvarget_latency_ms=latency, variables=range(3, 19))
    c.load([prog])
    if prog.kind is Kind.HARDWARE:
        c.start(prog.name, eparam=7)
    c.step(ticks)
    return c.drain_events(), c.drain_samples(), c.variables()


def assert_same(prog, ticks: int, latency: int, where: str) -> None:
    fast = trace(prog, "fast", ticks, latency)
    ref = trace(prog, "reference", ticks, latency)
    if fast != ref:
        for a, b in zip(fast[0], ref[0]):
            assert a == b, f"{where}: first different event"
        assert fast[0] == ref[0], f"{where}: events differ in number"
        assert fast[2] == ref[2], f"{where}: variables differ"
        assert fast[1] == ref[1], f"{where}: samples differ"


@pytest.mark.parametrize("chunk", range(CHUNKS))
def test_generated_programs_run_identically_on_both_backends(chunk):
    declined = []
    for seed in range(chunk * PER_CHUNK, (chunk + 1) * PER_CHUNK):
        rng = random.Random(seed)
        kind = Kind.SOFTWARE if rng.random() < 0.15 else Kind.HARDWARE
        prog = random_program(rng, kind)
        latency = rng.choice([0, 0, 0, 1, 4]) if kind is Kind.HARDWARE else 0
        reason = fastvm.unsupported_reason(prog, latency > 0)
        if reason:
            declined.append((seed, reason))
        assert_same(prog, 1000 if kind is Kind.SOFTWARE else 250, latency, f"seed {seed}")
    # structured programs are all translated (not silently run on the reference)
    assert not declined


def test_unstructured_code_runs_identically_too():
    """Instruction soup (underflows, jumps anywhere): declined by the translator
    where it must be, and the same either way."""
    translated = 0
    for seed in range(150):
        prog = random_soup(random.Random(10_000 + seed))
        translated += fastvm.unsupported_reason(prog) is None
        assert_same(prog, 60, 0, f"soup {seed}")
    assert translated > 0


def test_generated_programs_exercise_what_they_should():
    """The generator reaches faults of every kind, budget counting, recursion and
    message sending (so the comparison above means something)."""
    seen = set()
    for seed in range(400):
        prog = random_program(random.Random(seed))
        g = fastvm._Gen(prog, False)
        if g.budget:
            seen.add("budget")
        if g.tracked:
            seen.add("tracked")
        events = trace(prog, "fast", 250, 0)[0]
        for e in events:
            seen.add(e.type)
            if e.type == "fault":
                seen.add(e.text.split(" ")[0])
    assert {"budget", "tracked", "fault", "message", "print", "note", "division", "modulo",
            "more", "call", "ran"} <= seen
