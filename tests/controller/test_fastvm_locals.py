"""The fast backend keeps a tick-ending procedure's variables in Python locals
between tick ends, and writes them back to the slots when the controller asks
(``Process.sync``, done by ``variables()``), when the procedure ends however it
ends, and before it is ended from outside. What anyone reads is the same as on
the reference interpreter, at every tick."""

from __future__ import annotations

import pytest

from plcbuilder.controller import fastvm

from tests.controller._sim import BACKENDS, compile_proc, controller, ended

LOOP = """
main()
{
  n=0; acc=0;
  do
  {
    acc=(acc+n*3)&0xffff;
    n++;
    if (n==50) { message=1100; };
  }while(n<1000);
  exit(99);
};
"""

CALLS = """
count()
{
  do { k++; } while(k<5);
};
main()
{
  do { count(); j++; k=0; } while(j<4);
  exit(99);
};
"""


def test_a_loop_that_calls_nothing_keeps_its_variables_in_locals():
    prog = compile_proc(LOOP, "M10")
    src = fastvm.translate(prog)
    assert fastvm._SYNC_ANSWER in src and "v22 += 1" in src and "finally:" in src


@pytest.mark.parametrize("src", [LOOP, CALLS])
def test_variables_read_between_ticks_are_the_reference_interpreters(src):
    runs = {b: controller(compile_proc(src, "M10"), backend=b) for b in BACKENDS}
    for c in runs.values():
        c.start("M10")
    for _ in range(60):
        seen = {b: c.variables() for b, c in runs.items()}
        assert seen["fast"] == seen["reference"]
        for c in runs.values():
            c.step(1)
    assert runs["fast"].drain_events() == runs["reference"].drain_events()


def test_a_procedure_ended_from_outside_keeps_its_variables_as_they_were():
    prog = compile_proc(LOOP, "M10")
    other = compile_proc("main(){ exit(99); };", "M11")
    values = {}
    for b in BACKENDS:
        c = controller(prog, other, backend=b)
        c.start("M10")
        c.step(20)
        c.start("M11")                  # ends M10 with 100
        c.step(1)
        values[b] = c.variables()["M10"]
        assert ended(c.drain_events(), "M10").exit_code == 100
    assert values["fast"] == values["reference"]
    assert values["fast"]["n"] == 20


def test_a_value_written_to_the_slots_after_a_sync_is_seen_by_the_next_tick():
    for b in BACKENDS:
        c = controller(compile_proc(LOOP, "M10"), backend=b)
        c.start("M10")
        c.step(10)
        p = c._plc.hw
        p.sync()
        slot = {name: s for s, name in p.program.slot_names().items()}["n"]
        assert p.slots[slot] == 10
        p.slots[slot] = 990
        c.run_until_idle(100)
        e = ended(c.drain_events(), "M10")
        assert (e.t_ms, e.exit_code) == (10 + 10, 99), b


def test_a_translation_runs_without_compile_and_keeps_its_name(monkeypatch):
    """Issue 26.1: the translation is run with ``exec`` of its text (the first
    ``compile()`` of a process builds the ast module's types: a twentieth of
    ``plcbuilder run``'s start), and its code still carries the name a
    traceback shows, nested functions included."""
    import builtins

    def no_compile(*a, **k):
        raise AssertionError("compile() called")

    program = compile_proc(CALLS.replace("k<5", "k<6"), "M71")   # (not in the cache yet)
    with monkeypatch.context() as m:
        m.setattr(builtins, "compile", no_compile)
        make = fastvm.factory(program)
    assert make is not None

    def codes(code):
        yield code
        for c in code.co_consts:
            if hasattr(c, "co_filename"):
                yield from codes(c)

    names = {c.co_filename for c in codes(make.__code__)}
    assert len(list(codes(make.__code__))) > 1
    assert len(names) == 1 and names.pop().startswith("<plc M71 ")
    c = controller(program)
    c.start("M71")
    c.run_until_idle(1000)
    assert ended(c.drain_events(), "M71").exit_code == 99
