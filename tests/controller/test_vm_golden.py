"""Every golden program that compiles runs on both backends with identical
traces, and does what its ``// expect:`` lines say."""

from __future__ import annotations

import re

import pytest

from plcbuilder.bytecode.program import Kind
from plcbuilder.controller.controller import Controller

from tests.lang.golden_util import compile_golden, goldens

RUN_LIMIT_MS = 30_000
_RUNNABLE = [g for g in goldens() if not any(sev == "error" for _, sev, _ in g.diags)]


def _run(program, backend: str):
    c = Controller(backend=backend)
    c.load([program])
    if program.kind is Kind.HARDWARE:
        c.start(program.name)
    c.run_until_idle(RUN_LIMIT_MS)
    return c, c.drain_events(), c.drain_samples()


@pytest.mark.parametrize("g", _RUNNABLE, ids=[g.id for g in _RUNNABLE])
def test_golden_runs_identically_and_as_expected(g):
    r = compile_golden(g)
    assert r.program is not None, [d.message for d in r.diagnostics]
    fast, ev, samples = _run(r.program, "fast")
    ref, ev_ref, samples_ref = _run(r.program, "reference")
    assert ev == ev_ref
    assert samples == samples_ref
    assert fast.variables() == ref.variables()
    check_expectations(g, r.program, fast, ev)


def check_expectations(g, program, c, events) -> None:
    name = program.name
    ended = [e for e in events if e.type == "ended" and e.name == name]
    variables = c.variables().get(name, {})
    outputs = set(c.state().outputs)
    for line, text in g.expects:
        where = f"{g.id}:{line}: expect {text}"
        words = text.split()
        if words[0] == "exit":
            assert ended and ended[-1].exit_code == int(words[1], 0), f"{where}; got {ended}"
        elif words[0] == "vexit":
            assert ended and ended[-1].vexit == int(words[1], 0), f"{where}; got {ended}"
        elif words[0] == "ends_at":
            assert ended and ended[-1].t_ms == int(words[1]), f"{where}; got {ended}"
        elif words[0] == "message":
            want = tuple(int(w, 0) for w in words[1:4])
            got = [(e.message, e.command, e.parameter) for e in events if e.type == "message"]
            assert want in got, f"{where}; got {got}"
        elif words[0] == "print":
            want = (int(words[1], 0), int(words[2], 0))
            got = [(e.register, e.value) for e in events if e.type == "print"]
            assert want in got, f"{where}; got {got}"
        elif words[0] == "output":
            on = words[2] == "on"
            assert (int(words[1]) in outputs) == on, f"{where}; outputs on: {sorted(outputs)}"
        elif words[0] == "fault":
            faults = [(e.line, e.text) for e in events if e.type == "fault"]
            assert any(ln == line and words[1] in txt for ln, txt in faults) or \
                any(ln == line and " ".join(words[1:]) in txt for ln, txt in faults), \
                f"{where}; got {faults}"
        elif len(words) == 3 and words[1] == "==":
            assert variables.get(words[0]) == int(words[2], 0), \
                f"{where}; got {words[0]} = {variables.get(words[0])}"
        else:
            raise AssertionError(f"{where}: unknown expectation")


def test_there_are_runnable_goldens():
    assert len(_RUNNABLE) >= 10
    assert any(re.search(r"fault", t) for g in _RUNNABLE for _, t in g.expects)
