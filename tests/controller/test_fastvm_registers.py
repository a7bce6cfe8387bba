"""The fast backend reads a constant plain register from the machine's
register store (``Host.registers``) instead of calling gvarget, while no
register is forced; a register the machine keeps itself (an input word, a
PLS field) or any read while a register is forced still calls gvarget. Both
backends read the same values through writes, forces and releases."""

from __future__ import annotations

import pytest

from plcbuilder.bytecode import softmc
from plcbuilder.controller import fastvm

from tests.controller._sim import BACKENDS, compile_proc, controller

PLS_AXIS = softmc.pls_base(1) + softmc.F_AXIS
SRC = f"""main()
{{
  do {{ a=gvarget(5000); b=gvarget(7180); c=gvarget({PLS_AXIS}); d=gvarget(5002); }} while(1);
}};
"""

#: (what is done before a software tick, the values a, b, c, d read in it; b as
#: it differs from the input word at the start: the default machine wires some on)
STEPS = [
    (None, (0, 0, 0, 0)),
    (("write", "gvar 5000", 7), (7, 0, 0, 0)),
    (("input", 0, 1), (7, 1, 0, 0)),
    (("write", f"gvar {PLS_AXIS}", 2), (7, 1, 2, 0)),
    (("force", "gvar 5000", 9), (9, 1, 2, 0)),
    (("write", "gvar 5000", 11), (11, 1, 2, 0)),     # forced: the forced value changes
    (("release", "gvar 5000", "restore"), (7, 1, 2, 0)),
    (("force", "gvar 5002", 4), (7, 1, 2, 4)),
    (("release", "gvar 5002", "keep"), (7, 1, 2, 4)),
    (("write", "gvar 5002", 5), (7, 1, 2, 5)),
]


def _run(backend: str):
    c = controller(compile_proc(SRC, "S00", software=True), backend=backend)
    m = c.machine
    called: list[tuple[int, int]] = []          # (step, address) of each gvarget call
    step_no = [0]
    own = m.gvarget

    def counting(addr):
        called.append((step_no[0], addr))
        return own(addr)

    m.gvarget = counting                        # the host's gvarget (PLC._host reads it)
    c.start("S00")
    c.step(1)
    b0 = own(7180)
    seen = []
    for k, (action, _want) in enumerate(STEPS):
        step_no[0] = k
        if action is not None:
            verb, *args = action
            if verb == "input":
                c.set_input(*args)
            else:
                getattr(c, verb)(*args)
        c.step(100)                              # one software tick
        v = c.variables()["S00"]
        seen.append((v["a"], v["b"] ^ b0, v["c"], v["d"]))
    return seen, called


@pytest.mark.parametrize("backend", BACKENDS)
def test_register_reads_follow_writes_forces_and_releases(backend):
    seen, _called = _run(backend)
    assert seen == [want for _action, want in STEPS]


def test_fast_backend_reads_a_plain_register_without_calling_while_nothing_is_forced():
    assert "_rget(5000, 0)" in fastvm.translate(compile_proc(SRC, "S00", software=True))
    _seen, called = _run("fast")
    forced = {4, 5, 7}                           # the steps with a register forced
    plain_calls = [(k, a) for k, a in called if a in (5000, 5002)]
    assert plain_calls and all(k in forced for k, _a in plain_calls)
    assert {a for _k, a in called} >= {7180, PLS_AXIS}     # the machine's own: always called
    _seen, ref_called = _run("reference")
    assert {a for _k, a in ref_called} == {5000, 7180, PLS_AXIS, 5002}
