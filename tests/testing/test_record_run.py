"""record_run: a test's run recorded again, every tick, for the IDE's "Open
Failing Run" (the same rerun as --trace-failed)."""

from __future__ import annotations

import pytest

from plcbuilder.controller.events import Ended, Message, Sample, Started
from plcbuilder.testing.runner import (RECORD_AFTER_MS, SuiteError, prepare, record_run,
                                       run_suite)

from tests.testing._proj import FAILING, LONG_FAILING, make_project


@pytest.fixture
def suite(tmp_path):
    return prepare(make_project(tmp_path / "p", {"long": LONG_FAILING, "b": FAILING}))


def test_records_every_tick_to_a_little_past_the_failing_tick(suite):
    rec = record_run(suite, "pulse too long")
    assert rec.failing_tick == 8 and not rec.result.passed
    assert rec.end_ms == 8 + 1 + RECORD_AFTER_MS
    assert all(isinstance(s, Sample) for s in rec.samples)
    assert [s.t_ms for s in rec.samples] == list(range(rec.end_ms))
    on = [s.t_ms for s in rec.samples if (s.outputs[0] >> 3) & 1]
    assert on == [5, 6, 7]                       # what made it fail, at tick 8
    kinds = [type(e) for e in rec.events]
    assert kinds[0] is Started and Ended in kinds
    assert next(e for e in rec.events if isinstance(e, Ended)).exit_code == 99


def test_the_run_ends_at_the_test_s_limit_and_has_its_events(suite):
    rec = record_run(suite, "branch two")        # fails at tick 1; ms = 40
    assert rec.failing_tick == 1 and rec.end_ms == 40
    assert rec.samples[-1].t_ms == 39
    assert rec.samples[1].pwm[0] == 20
    assert any(isinstance(e, Message) for e in rec.events)


def test_the_same_run_twice_and_the_result_of_the_suite(suite):
    a = record_run(suite, "pulse too long")
    b = record_run(suite, "pulse too long")
    assert a.samples == b.samples and a.events == b.events
    (r,) = [r for r in run_suite(suite, jobs=1).results if r.name == "pulse too long"]
    c = record_run(suite, "pulse too long", result=r)
    assert c.samples == a.samples and c.failing_tick == 8


def test_keep_bounds_the_samples_to_the_newest(suite):
    rec = record_run(suite, "pulse too long", keep=50)
    assert [s.t_ms for s in rec.samples] == list(range(rec.end_ms - 50, rec.end_ms))


def test_an_unknown_test_is_an_error(suite):
    with pytest.raises(SuiteError, match="no test named"):
        record_run(suite, "nope")
