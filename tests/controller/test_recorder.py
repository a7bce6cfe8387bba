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
