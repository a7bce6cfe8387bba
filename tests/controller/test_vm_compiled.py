"""Real compiler output runs identically on both backends: random PLC sources
(procedures, if/else, do/while and while loops, short-circuit conditions, every
operator and builtin) are compiled and their full traces compared."""

from __future__ import annotations

import random

import pytest

from plcbuilder import api
from plcbuilder.controller import fastvm

from tests.controller._srcgen import random_source
from tests.controller.test_vm_equivalence import assert_same

CHUNKS = 4
PER_CHUNK = 100


@pytest.mark.parametrize("chunk", range(CHUNKS))
def test_compiled_random_sources_run_identically_on_both_backends(chunk):
    compiled = 0
    for seed in range(chunk * PER_CHUNK, (chunk + 1) * PER_CHUNK):
        rng = random.Random(seed)
        software = rng.random() < 0.2
        src = random_source(rng, software)
        kind = api.Kind.SOFTWARE if software else api.Kind.HARDWARE
        r = api.compile_source(src, "R.plc", api.CompileOptions(kind=kind))
        assert r.ok, (seed, src, [d.message for d in r.diagnostics if d.is_error])
        compiled += 1
        assert fastvm.unsupported_reason(r.program) is None, seed
        latency = 0 if software else rng.choice([0, 0, 2])
        assert_same(r.program, 1000 if software else 300, latency, f"source seed {seed}")
    assert compiled == PER_CHUNK
