"""Record and replay (SPEC §7): a session's outside actions as a scenario file,
and its replay giving the identical trace, tick for tick."""

from __future__ import annotations

import random
from pathlib import Path

import pytest

from plcbuilder import api
from plcbuilder.controller.history import History
from plcbuilder.controller.recorder import image_id
from plcbuilder.controller.scenario import Scenario, ScenarioError
from plcbuilder.project.new import create_project


def _trace(h: History, t_end: int):
    h.advance_to(t_end)
    return h.snapshot(0, t_end)


def _live_session(project: Path, rng: random.Random, ms: int = 6000):
    """A session driven by hand, as the IDE or the server does: upload after a
    while, then starts, inputs, ADC, Stop, writes, forces and releases at
    random ticks, with the history recording every change."""
    proj = api.Project.open(project)
    programs = [pb.program() for pb in api.compile_all(proj)]
    programs = [p for p in programs if p is not None]
    c = api.Controller(api.load_machine(proj.machine_path) if proj.machine_path.is_file()
                       else api.default_machine())
    c.record_samples = True
    c.sample_changes_only = True
    h = History(c.machine)

    def run(n):
        c.step(n)
        h.feed(c.drain_sample_rows(), c.drain_events())

    run(rng.randint(0, 250))                  # the controller ran before the first upload
    c.load(programs)
    hardware = sorted(p.name for p in programs if p.kind is api.Kind.HARDWARE)
    while c.t_ms < ms:
        run(rng.randint(1, 120))
        what = rng.random()
        try:
            if what < 0.3:
                c.start(rng.choice(hardware), rng.randint(0, 20000))
            elif what < 0.5:
                c.set_input(rng.randint(0, 15), rng.randint(0, 1))
            elif what < 0.6:
                c.set_adc(rng.randint(0, 7), rng.randint(0, 4000))
            elif what < 0.65:
                c.stop()
            elif what < 0.75:
                c.force(f"in {rng.randint(0, 15)}", rng.randint(0, 1))
            elif what < 0.8:
                c.release_all(rng.choice(("keep", "restore")))
            elif what < 0.85:
                c.write(f"pwm {rng.randint(0, 7)}", rng.randint(0, 30000))
            elif what < 0.9:
                c.force(f"out {rng.randint(0, 9)}", rng.randint(0, 1))
            elif what < 0.93:
                c.load(programs)                # Build All and upload again
            else:
                c.event("GCODE_START")
        except api.ControllerError:
            pass
    run(1)                                    # the tick the last action applies to
    end = c.t_ms - 1
    return c, _trace(h, end), end


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_a_replayed_recording_gives_the_identical_trace(tmp_path, seed):
    """SPEC §7: 'a session records everything done to the controller from outside
    (image uploads, starts, stops, input and ADC changes, writes, forces, host
    events) with their ticks, as a scenario file … Replaying it with the same image
    and machine gives the identical trace, tick for tick.'"""
    create_project(tmp_path / "p")
    project = tmp_path / "p"
    c, live, end = _live_session(project, random.Random(seed))
    text = c.recorder.text(end, [f"image {image_id(c.programs.values())}"])
    rec = tmp_path / "rec.txt"
    rec.write_text(text)
    kinds = {a.kind for a in Scenario.load(rec).actions}
    assert {"upload", "start", "input", "force"} <= kinds
    hist = tmp_path / "replay.plctrace"
    r = api.run(project, api.RunOptions(scenario=rec, ms=end + 1, history=hist))
    assert r.ok
    assert not [n for n in r.report["notes"] if "this project builds image" in n["text"]]
    replay = api.load_trace(hist)
    diff = api.compare_traces(live, replay)
    assert diff.same, diff.text()
    assert (replay.t_start, replay.t_end) == (live.t_start, live.t_end)


def test_a_recording_names_what_was_done(tmp_path):
    create_project(tmp_path / "p")
    project = tmp_path / "p"
    proj = api.Project.open(project)
    programs = [p for p in (pb.program() for pb in api.compile_all(proj)) if p is not None]
    c = api.Controller(api.default_machine())
    c.step(5)
    c.load(programs)
    c.step(10)
    c.start("M03", 12000)
    c.set_input(4, 1)
    c.set_adc(1, 900)
    c.force("in 2", 1)
    c.write("pwm 0", 500)
    c.release("in 2", "keep")
    c.stop()
    c.event("GCODE_STOP")
    lines = [ln for ln in c.recorder.text(c.t_ms).splitlines() if not ln.startswith("#")]
    assert lines == [f"upload {image_id(programs)} @ 5", "start M03:12000 @ 15", "input 4=1 @ 15",
                     "adc 1=900 @ 15", "force in 2=1 @ 15", "write pwm 0=500 @ 15",
                     "release in 2 keep @ 15", "stop @ 15"]     # (no GCODE_STOP handler: nothing)
    back = Scenario.parse("\n".join(lines))
    assert [a.describe() for a in back.actions] == lines


def test_a_replay_with_another_image_says_so(tmp_path):
    create_project(tmp_path / "p")
    project = tmp_path / "p"
    rec = tmp_path / "rec.txt"
    rec.write_text("upload 0badc0de @ 3\nstart M03:100 @ 10\n")
    r = api.run(project, api.RunOptions(scenario=rec, ms=50))
    assert r.ok
    assert "the recording loaded image 0badc0de" in r.report["notes"][0]["text"]
    started = [p for p in r.report["procedures"] if p["name"] == "M03"]
    assert started and started[0]["started_at_ms"] == 10


@pytest.mark.parametrize("line,why", [("upload xyz @ 3", "8 hex digits"),
                                      ("upload 123 @ 3", "8 hex digits")])
def test_bad_upload_lines_say_why(line, why):
    with pytest.raises(ScenarioError, match=why):
        Scenario.parse(line)


# ------------------------------------------------- actions done mid-tick
#: reads inputs 3 and 9 and ADC1 early in each tick; halts are set later in it
MID_TICK = """main()
{
  do
  {
    x = portget(3) + portget(9) * 10 + adc02 - 2048;
    if (x == 0) {
      y = y + 1;
    };
    sub();
    gvarset(7282, x * 100 + y + w);
    if (portget(3)) portset(5); else portclear(5);
  } while (1);
}

sub()
{
  w = w + 1;
  if (portget(9)) portset(6); else portclear(6);
}
"""
# lines: 5 x=… (reads in 3, in 9, ADC1) | 7 y=y+1 | 9 sub() | 10 PWM4 | 11 out 5 | 18 w=w+1


def _halt_at(c, h, line: int, hit: int) -> None:
    """Run ``c`` until it halts at M10.plc line ``line`` (its ``hit``-th hit
    from now), feeding the history; then no breakpoint is left."""
    c.debugger.set_breakpoints("M10.plc", [{"line": line, "hit": {"mode": "eq", "n": hit}}])
    for _ in range(1000):
        c.step(1)
        h.feed(c.drain_sample_rows(), c.drain_events())
        if c.debugger.halted:
            break
    st = c.debugger.halted_state()
    assert st is not None and st["line"] == line
    c.debugger.set_breakpoints("M10.plc", [])


def test_a_recording_replays_actions_done_mid_tick_where_they_were_done(tmp_path, capsys):
    """SPEC §7: 'Replaying it with the same image and machine gives the identical
    trace, tick for tick': a write, a force, an input and a release given while
    the debugger held a tick halted at a statement (one of them inside a call)
    are saved with their place in the tick, and ``plcbuilder run --scenario``
    does them there, not at the start of the tick."""
    from tests.cli._run import run_cli
    project = tmp_path / "p"
    (project / "hardware").mkdir(parents=True)
    (project / "hardware" / "M10.plc").write_text(MID_TICK)
    proj = api.Project.open(project)
    programs = [p for p in (pb.program() for pb in api.compile_all(proj)) if p is not None]
    watch = ["M10.x", "M10.y", "M10.w"]
    c = api.Controller(api.default_machine())
    c.record_samples = True
    c.sample_changes_only = True
    c.watch_variables(watch, check=False)
    h = History(c.machine)

    def run(n):
        for _ in range(n):
            c.step(1)
            h.feed(c.drain_sample_rows(), c.drain_events())

    run(7)
    c.load(programs)
    c.start("M10")
    run(20)
    _halt_at(c, h, 7, 3)                       # after the tick read its inputs
    c.write("M10.x", 5)
    c.force("in 3", 1)
    c.debugger.resume()
    run(30)
    _halt_at(c, h, 18, 2)                      # inside sub(): a call deep
    c.set_input(9, 1)
    c.debugger.resume()
    run(25)
    c.set_adc(1, 2000)                         # between ticks, as before
    run(10)
    _halt_at(c, h, 10, 4)
    c.release("in 3", "restore")
    c.write("out 6", 1)
    c.debugger.resume()
    run(40)
    end = c.t_ms - 1
    live = _trace(h, end)

    text = c.recorder.text(end)
    placed = [ln for ln in text.splitlines() if " at M10:" in ln]
    assert len(placed) == 5, text
    assert any(" returns " in ln for ln in placed), text      # the one inside sub()
    rec = tmp_path / "rec.txt"
    rec.write_text(text)
    assert [a.at for a in Scenario.load(rec).actions] == [a.at for a in c.recorder.actions]
    hist = tmp_path / "replay.plctrace"
    code, out, err = run_cli(capsys, "run", project, "--scenario", rec, "--ms", end + 1,
                             "--history", hist, *[f"--watch={w}" for w in watch], "--json")
    assert code == 0, err
    replay = api.load_trace(hist)
    diff = api.compare_traces(live, replay)
    assert diff.same, diff.text()
    assert (replay.t_start, replay.t_end) == (live.t_start, live.t_end)
    assert not [e for e in replay.events if e.get("type") in ("halted", "resumed")]
    # the same recording done at the start of each tick (as it replayed before) differs
    flat = tmp_path / "flat.txt"
    flat.write_text("\n".join(ln.split(" at M10:")[0] for ln in text.splitlines()) + "\n")
    hist2 = tmp_path / "flat.plctrace"
    code, out, err = run_cli(capsys, "run", project, "--scenario", flat, "--ms", end + 1,
                             "--history", hist2, *[f"--watch={w}" for w in watch], "--json")
    assert code == 0, err
    assert not api.compare_traces(live, api.load_trace(hist2)).same


def test_a_position_within_the_tick_reads_back():
    lines = ["write M10.x=5 @ 12 at M10:18", "force in 3=1 @ 12 at M10:18",
             "input 4=1 @ 40 at sub:0 returns 27", "release all keep @ 50 at M10:40 returns 3,27",
             "start M03:0 @ 60"]
    sc = Scenario.parse("\n".join(lines))
    assert [a.at for a in sc.actions] == [("M10", 18, ()), ("M10", 18, ()), ("sub", 0, (27,)),
                                          ("M10", 40, (3, 27)), None]
    assert [a.describe() for a in sc.actions] == lines


@pytest.mark.parametrize("line,why", [
    ("write M10.x=5 @ 12 at M10", "at PROC:OFFSET"),
    ("write M10.x=5 @ 12 at 9x:3", "not a procedure name"),
    ("write M10.x=5 @ 12 at M10:-3", "code offset"),
    ("write M10.x=5 @ 12 at M10:3 returns 1,x", "return offset"),
    ("write M10.x=5 @ 12 at M10:3 returns " + ",".join(["1"] * 17), "at most 16 deep")])
def test_a_bad_position_within_the_tick_says_why(line, why):
    with pytest.raises(ScenarioError, match=why):
        Scenario.parse(line)
