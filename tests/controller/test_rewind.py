"""Stepping back and running back (SPEC §7): the state after a step back equals
the state the forward run had there, tick for tick and statement for statement."""

from __future__ import annotations

import pytest

from plcbuilder import api
from plcbuilder.controller.controller import Controller
from plcbuilder.controller.events import Forces
from plcbuilder.controller.rewind import Checkpoints, RewindError, run_back, step_back

from tests.controller._sim import BACKENDS, COUNT, EXAMPLE, compile_proc

SOFT = "main(){ do { k++; if (k % 3 == 0) { portset(5); } else { portclr(5); } } while(1); }"


def _example_programs():
    proj = api.Project.open(EXAMPLE)
    return [p for p in (pb.program() for pb in api.compile_all(proj)) if p is not None]


def _look(c: Controller) -> dict:
    """Everything a halted controller shows: time, machine, every procedure's
    line, stack and variables (pausing a running one between ticks to look)."""
    dbg = c.debugger
    paused = dbg.halt is None
    if paused:
        dbg.pause()
    st = dbg.halted_state()
    if paused:
        dbg.resume()
    s = c.state()
    return {"t_ms": c.t_ms, "outputs": s.outputs, "inputs": s.inputs, "pwm": s.pwm,
            "dac": s.dac, "adc": s.adc, "proc": s.proc, "running": s.running,
            "software": s.software, "axes": s.axes, "variables": c.variables(),
            "procedures": [(p["name"], p["line"], p["stack"], p["vars"])
                           for p in st["procedures"]],
            "machine": st["machine"]}


@pytest.mark.parametrize("backend", BACKENDS)
def test_stepping_back_a_tick_gives_the_forward_state_at_every_tick(backend):
    """SPEC §7: 'Step back (one tick, or one statement) … work[s] by deterministic
    re-execution from the recording'."""
    programs = _example_programs() + [compile_proc(SOFT, "S1", software=True)]
    hw = sorted(p.name for p in programs if p.kind is api.Kind.HARDWARE)

    def factory():
        return Controller(backend=backend)
    c = factory()
    seen = {}
    plan = {7: lambda: c.load(programs), 20: lambda: c.start(hw[0], 1200), 45: lambda: c.set_input(3, 1),
            60: lambda: c.force("out 7", 1), 90: lambda: c.set_adc(2, 900),
            110: lambda: c.write("pwm 1", 5000), 130: lambda: c.stop(),
            150: lambda: c.release_all("restore"), 170: lambda: c.start(hw[-1], 7)}
    end = 240
    while c.t_ms < end:
        seen[c.t_ms] = _look(c)              # before what is done at that tick
        if c.t_ms in plan:
            try:
                plan[c.t_ms]()
            except api.ControllerError:
                pass
        c.step(1)
    seen[c.t_ms] = _look(c)
    back = c
    for t in range(end - 1, -1, -1):
        back = step_back(back, factory, "tick")
        assert back.debugger.halted_state()["reason"] == "step"
        look = _look(back)
        assert look == seen[t], f"tick {t}"
        assert [a for a in back.recorder.actions if a.t_ms >= t] == []
    with pytest.raises(RewindError, match="nothing to go back to"):
        step_back(back, factory, "tick")


@pytest.mark.parametrize("backend", BACKENDS)
def test_stepping_back_a_statement_retraces_the_steps_forward(backend):
    """SPEC §7: 'Step back (one tick, or one statement) … work[s] by deterministic
    re-execution from the recording'."""
    def factory():
        return Controller(backend=backend)
    c = factory()
    c.step(3)
    c.load([compile_proc(COUNT, "M10"), compile_proc(SOFT, "S1", software=True)])
    c.step(2)
    c.start("M10")
    c.debugger.set_breakpoints("M10.plc", [{"line": 7, "hit": {"mode": "eq", "n": 3}}])
    c.step(50)
    assert c.debugger.halted_state()["line"] == 7
    path = []
    for _ in range(14):                       # across several ticks
        path.append(_look(c) | {"line": c.debugger.halted_state()["line"]})
        c.debugger.step("into")
        while not c.debugger.halted:            # the next statement is in the next tick
            c.step(1)
    back = c
    for want in reversed(path):
        back = step_back(back, factory, "statement")
        st = back.debugger.halted_state()
        assert _look(back) | {"line": st["line"]} == want
        assert st["procedure"] == "M10"
    # the procedure's first statement: nothing before it
    first = factory()
    first.load([compile_proc(COUNT, "M10")])
    first.debugger.set_breakpoints("M10.plc", [{"line": 3}])
    first.start("M10")
    first.step(5)
    assert first.debugger.halted_state()["line"] == 3
    with pytest.raises(RewindError, match="ran no statement before"):
        step_back(first, factory, "statement")
    first.debugger.resume()
    with pytest.raises(RewindError, match="needs a halt at a statement"):
        step_back(first, factory, "statement")


@pytest.mark.parametrize("backend", BACKENDS)
def test_running_back_halts_at_the_previous_breakpoint_hit(backend):
    """SPEC §7: '… and run back (to the previous breakpoint hit) work by
    deterministic re-execution from the recording'."""
    def factory():
        return Controller(backend=backend)
    c = factory()
    c.load([compile_proc(COUNT, "M10")])
    with pytest.raises(RewindError, match="no breakpoint is set"):
        run_back(c, factory)
    c.start("M10")
    c.debugger.set_breakpoints("M10.plc", [{"line": 15}])
    hits = []
    for _ in range(4):
        c.step(100)
        hits.append(_look(c))
        c.debugger.resume()
    c.step(100)
    back = c
    for want in reversed(hits):                 # halted at the 5th: back to the 4th, …
        back = run_back(back, factory)
        assert back.debugger.halted_state()["reason"] == "breakpoint"
        assert _look(back) == want
        assert back.recorder.actions == c.recorder.actions[:len(back.recorder.actions)]
    with pytest.raises(RewindError, match="no breakpoint was hit before now"):
        run_back(back, factory)


def test_what_cannot_be_run_again_is_refused():
    c = Controller()
    with pytest.raises(RewindError, match="session is at its start"):
        step_back(c, Controller, "tick")
    with pytest.raises(RewindError, match="unknown step back"):
        step_back(c, Controller, "line")
    c.load([compile_proc(COUNT, "M10")])
    c.step(10)
    c.recorder.dropped = 3
    with pytest.raises(RewindError, match="lost its first 3 actions"):
        step_back(c, Controller, "tick")
    assert c.t_ms == 10


def test_a_step_back_from_a_checkpoint_equals_one_from_the_start():
    """SPEC §7: '… with checkpoints so that stepping back in a ten-minute session
    answers in well under a second.' A checkpoint is a controller that already ran
    the session; a step back from it gives the same state as one from t = 0."""
    programs = _example_programs() + [compile_proc(SOFT, "S1", software=True)]
    c = Controller()
    seen = {}
    plan = {3: lambda: c.load(programs), 40: lambda: c.set_input(3, 1),
            95: lambda: c.force("out 7", 1), 160: lambda: c.set_adc(1, 77)}
    while c.t_ms < 230:
        seen[c.t_ms] = _look(c)
        if c.t_ms in plan:
            plan[c.t_ms]()
        c.step(1)
    pool = Checkpoints(Controller, every_ms=50, keep=8)
    while pool.work(c, 1.0):
        pass
    assert sorted(pool.ready) == [50, 100, 150, 200]
    back = step_back(c, Controller, "tick", pool)
    assert _look(back) == seen[229]
    assert 200 not in pool.ready                    # used up
    back = step_back(back, Controller, "tick", pool)
    assert _look(back) == seen[228] and 150 not in pool.ready
    # after the session went on anew, the checkpoints after that are made again
    back.debugger.resume()
    back.set_input(4, 1)
    back.step(5)
    while pool.work(back, 1.0):
        pass
    assert 200 in pool.ready
    again = step_back(back, Controller, "tick", pool)
    assert again.t_ms == 232 and 200 not in pool.ready
    assert _look(again)["inputs"] == _look(step_back(back, Controller, "tick"))["inputs"]
    # nor one made with other breakpoints
    while pool.work(back, 1.0):
        pass
    back.debugger.set_breakpoints("S1.plc", [{"line": 1, "hit": {"mode": "eq", "n": 10 ** 6}}])
    assert pool.take(back, 232) is None


@pytest.mark.parametrize("backend", BACKENDS)
def test_running_back_from_checkpoints_equals_running_back_from_the_start(backend):
    """SPEC §7: '… run back (to the previous breakpoint hit) work by deterministic
    re-execution from the recording, with checkpoints so that stepping back in a
    ten-minute session answers in well under a second.' Run back starts from the
    checkpoints; a breakpoint's hit count counts the hits before the checkpoint
    too, and where it halts equals where running the session again from t = 0
    halts: time, machine, lines, variables and every breakpoint's hits."""
    def factory():
        return Controller(backend=backend)
    from_zero = []

    def counted():                      # run back's own fresh controllers (t = 0)
        from_zero.append(1)
        return factory()
    c = factory()
    c.step(3)
    c.load([compile_proc(COUNT, "M10")])
    c.start("M10")
    # both lines run once a tick; every 40th time each halts: two halts in one tick
    c.debugger.set_breakpoints("M10.plc", [{"line": 7, "hit": {"mode": "every", "n": 40}},
                                           {"line": 15, "hit": {"mode": "every", "n": 40}}])
    hits = []
    while c.t_ms < 430:
        c.step(1)
        if c.debugger.halted:
            hits.append(_look(c) | {"line": c.debugger.halted_state()["line"]})
            c.debugger.resume()
            c.debugger.settle()
            while c.debugger.halted:       # the other line, later in the same tick
                hits.append(_look(c) | {"line": c.debugger.halted_state()["line"]})
                c.debugger.resume()
    assert [h["line"] for h in hits[:4]] == [7, 15, 7, 15] and hits[0]["t_ms"] == hits[1]["t_ms"]
    c.step(2)
    pool = Checkpoints(factory, every_ms=20, keep=32)
    back = plain = c
    for want in reversed(hits):
        while pool.work(back, 1.0):
            pass
        before = len(from_zero)
        back = run_back(back, counted, pool)
        plain = run_back(plain, factory)
        look = _look(back) | {"line": back.debugger.halted_state()["line"]}
        assert look == want
        assert look == _look(plain) | {"line": plain.debugger.halted_state()["line"]}
        assert back.debugger.breakpoints() == plain.debugger.breakpoints()
        assert back.recorder.actions == plain.recorder.actions
        if want["t_ms"] >= 100:            # checkpoints before it: none from t = 0
            assert len(from_zero) == before, f"run back to {want['t_ms']} ms ran from t = 0"
    with pytest.raises(RewindError, match="no breakpoint was hit before now"):
        run_back(back, counted, pool)


#: reads input 3 and ADC1 (2048 on the default machine) early in each tick,
#: halts later in it (line 7)
READS_EARLY = """main()
{
  do
  {
    x = portget(3) + adc02 - 2048;
    if (x == 0) {
      y = y + 1;
    };
    z = x + y;
  } while (1);
}
"""
# lines: 5 x=… | 6 if | 7 y=y+1 | 9 z=x+y | 10 while


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("action", [
    ("write", "M10.x", 5), ("write", "in 3", 1), ("force", "in 3", 1), ("force", "M10.x", 4),
    ("force-release", "in 3", 1), ("input", 3, 1), ("adc", 1, 7), ("write", "gvar 7000", 9)])
def test_an_action_done_while_halted_mid_tick_is_done_there_again(backend, action):
    """Issue 23 point 4: a write, a force, a release, an input or an ADC value
    given while halted at a statement (mid-tick) changes the rest of that tick
    only; the session run again does it at that same statement, not at the start
    of the tick, so stepping back by a statement retraces the run forward."""
    def factory():
        return Controller(backend=backend)
    c = factory()
    c.load([compile_proc(READS_EARLY, "M10")])
    c.start("M10")
    c.debugger.set_breakpoints("M10.plc", [{"line": 7, "hit": {"mode": "eq", "n": 3}}])
    c.step(50)
    assert c.debugger.halted_state()["line"] == 7
    kind, target, value = action
    if kind in ("write", "force"):
        getattr(c, kind)(target, value)
    elif kind == "force-release":
        c.force(target, value)
        c.release(target, "keep")
    elif kind == "input":
        c.set_input(target, value)
    else:
        c.set_adc(target, value)
    path = []
    for _ in range(5):                        # on past the tick end, into the next tick
        path.append(_look(c) | {"line": c.debugger.halted_state()["line"]})
        c.debugger.step("into")
        while not c.debugger.halted:
            c.step(1)
    back = c
    for want in reversed(path):
        back = step_back(back, factory, "statement")
        assert _look(back) | {"line": back.debugger.halted_state()["line"]} == want
    # the step back to where the action was done kept it, at that statement
    assert [(a.kind, a.t_ms) for a in back.recorder.actions][-1][1] == path[0]["t_ms"]
    again = step_back(back, factory, "tick")              # the start of that tick: not done
    assert again.t_ms == path[0]["t_ms"]
    assert all(a.t_ms < again.t_ms for a in again.recorder.actions if a.kind != "start")
    # what is forced there is told (the IDE's lists follow it), also when nothing is
    told = [e for e in again.drain_events() if isinstance(e, Forces)]
    assert told and list(told[-1].forces) == again.forces() == []


def test_checkpoints_move_on_from_the_one_before_not_from_the_start():
    """Issue 23 point 3: a checkpoint is made from the latest one before it, so
    moving the window on runs the session over the window, not from t = 0 again
    for each new checkpoint (a long session kept a core busy doing that); and
    what it gives equals a step back from t = 0."""
    programs = _example_programs() + [compile_proc(SOFT, "S1", software=True)]
    fresh = []

    def counted():
        fresh.append(1)
        return Controller()
    c = Controller()
    c.load(programs)
    c.step(230)
    pool = Checkpoints(counted, every_ms=50, keep=4)
    while pool.work(c, 1.0):
        pass
    assert sorted(pool.ready) == [50, 100, 150, 200] and len(fresh) == 4
    c.set_input(3, 1)
    c.step(60)                                    # t = 290: the window is 100..250
    while pool.work(c, 1.0):
        pass
    assert sorted(pool.ready) == [100, 150, 200, 250]   # each from the one before
    assert len(fresh) == 4                        # none ran from t = 0 again
    back = step_back(c, Controller, "tick", pool)
    assert _look(back) == _look(step_back(c, Controller, "tick"))


def test_after_a_long_run_without_checkpoints_only_the_latest_is_made():
    """After a long run with no idle time (Max speed), making the window's older
    checkpoints would run the whole session once for each: only the latest is
    made (one run of the session), and it moves on with the session."""
    c = Controller()
    c.load([compile_proc(SOFT, "S1", software=True)])
    c.step(2000)
    fresh = []

    def counted():
        fresh.append(1)
        return Controller()
    pool = Checkpoints(counted, every_ms=50, keep=4)
    while pool.work(c, 1.0):
        pass
    assert sorted(pool.ready) == [1950] and len(fresh) == 1
    c.step(100)
    while pool.work(c, 1.0):
        pass
    assert sorted(pool.ready) == [2050] and len(fresh) == 1
    assert _look(step_back(c, counted, "tick", pool)) == _look(step_back(c, Controller, "tick"))
    assert len(fresh) == 1
