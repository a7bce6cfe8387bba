"""The verbs (Service.handle_<type>) and the simulation thread, without sockets."""

import threading

import pytest

from plcbuilder.bytecode.program import Kind
from plcbuilder.controller.controller import Controller
from plcbuilder.controller.events import Ended, Print, Started
from plcbuilder.image.manifest import Limits, write_image
from plcbuilder.link import protocol
from plcbuilder.link.protocol import BadRequest, ProtocolError
from plcbuilder.link.pacing import Simulation, TelemetryQueue
from plcbuilder.link.service import Refused, Service, Session
from tests.link.linkkit import compile_programs, image_of, req, wait_for


def test_upload_reports_procedures_with_sizes_and_crcs(image):
    svc = Service(Simulation(Controller(), "pause"))
    r = svc.handle_upload({"type": "upload", "image": protocol.encode_image(image)}, Session())
    assert r["accepted"] and r["size"] == len(image)
    names = [p["name"] for p in r["procedures"]]
    assert names == sorted(names) and "M03" in names and "LUBE" in names
    m03 = next(p for p in r["procedures"] if p["name"] == "M03")
    assert m03["kind"] == "hardware" and m03["size"] > 0 and len(m03["crc32"]) == 8
    assert set(svc.sim.controller.programs) == set(names)


def test_start_by_name_and_mcode_then_it_runs(paused):
    r = req(paused, "start", name="M03", eparam=5)
    assert r["started"] == "M03" and r["eparam"] == 5
    req(paused, "step", ms=10)
    st = req(paused, "state")
    assert st["running"] == "M03" and 3 in st["outputs"]
    assert req(paused, "start", mcode=5)["started"] == "M05"
    req(paused, "step", ms=2)
    assert req(paused, "state")["running"] is None


@pytest.mark.parametrize("fields, err", [
    ({"name": "NOPE"}, Refused), ({"mcode": 77}, Refused), ({}, BadRequest),
    ({"name": "M03", "mcode": 3}, BadRequest), ({"name": 3}, BadRequest),
    ({"mcode": "3"}, BadRequest), ({"name": "M03", "eparam": 2 ** 31}, BadRequest),
    ({"name": "M03", "eparam": "1"}, BadRequest),
])
def test_bad_starts_are_refused_with_a_reason(paused, fields, err):
    with pytest.raises(err) as e:
        req(paused, "start", **fields)
    assert str(e.value)
    if err is Refused:
        assert "is loaded" in e.value.reason or "no hardware procedure" in e.value.reason


def test_stop_starts_m02_then_off(paused):
    req(paused, "start", name="M88")
    assert req(paused, "stop")["started"] == "M02"
    assert req(paused, "stop")["started"] == "OFF"


def test_input_and_adc(paused):
    req(paused, "start", name="M88")
    req(paused, "input", pin=5, value=1)
    req(paused, "step", ms=3)
    assert 4 in req(paused, "state")["outputs"]
    req(paused, "adc", channel=2, value=777)
    req(paused, "step", ms=1)
    assert req(paused, "state")["adc"][2] == 777
    for bad in ({"pin": 5, "value": 2}, {"pin": -1, "value": 1}, {"pin": 5}, {"value": 1},
                {"pin": True, "value": 1}):
        with pytest.raises(BadRequest):
            req(paused, "input", **bad)
    with pytest.raises(Refused, match="no input 5000"):
        req(paused, "input", pin=5000, value=1)


def test_state_has_the_contract_keys(paused):
    st = req(paused, "state")
    for key in ("image", "running", "software", "t_ms", "proc", "outputs", "speed", "image_crc32"):
        assert key in st
    assert st["speed"]["mode"] == "pause"
    assert {p["name"] for p in st["image"]} >= {"M03", "LUBE"}
    assert all({"name", "kind", "size", "crc32"} <= set(p) for p in st["image"])
    protocol.encode_frame({"type": "result", "result": st})       # JSON-ready


def test_variables_and_step(paused):
    t0 = req(paused, "state")["t_ms"]
    assert req(paused, "step", ms=1000)["t_ms"] == t0 + 1000
    v = req(paused, "variables")["variables"]
    assert v["LUBE"]["var02"] >= 9
    for bad in (0, -1, 10 ** 9, "5"):
        with pytest.raises(BadRequest):
            req(paused, "step", ms=bad)


def test_event_handlers(paused):
    assert req(paused, "event", handler="__HANDLER_GCODE_START")["started"] is True
    assert req(paused, "event", handler="__HANDLER_GCODE_STOP")["started"] is False
    with pytest.raises(BadRequest):
        req(paused, "event", handler="__HANDLER_EXIT")


def test_speed_modes(paused):
    assert req(paused, "speed", mode="factor", factor=20)["factor"] == 20
    assert req(paused, "speed", mode="realtime") == {"mode": "realtime", "factor": 1.0,
                                                     "dropped_ms": 0}
    assert req(paused, "speed", mode="max")["mode"] == "max"
    t = req(paused, "state")["t_ms"]
    wait_for(lambda: req(paused, "state")["t_ms"] > t + 100)
    assert req(paused, "speed", mode="pause")["mode"] == "pause"
    t = req(paused, "state")["t_ms"]
    assert req(paused, "state")["t_ms"] == t
    for bad in ({"mode": "warp"}, {"mode": "factor"}, {"mode": "factor", "factor": 0},
                {"mode": "factor", "factor": 1e9}, {}):
        with pytest.raises(BadRequest):
            req(paused, "speed", **bad)


def test_reset_reloads_the_image_at_time_zero(paused):
    req(paused, "step", ms=500)
    req(paused, "start", name="M88")
    assert req(paused, "reset")["t_ms"] == 0
    st = req(paused, "state")
    assert st["t_ms"] == 0 and st["running"] is None and st["image"]
    assert "LUBE" in req(paused, "state")["software"] or req(paused, "step", ms=100)
    svc = Service(Simulation(Controller(), "pause"))
    with pytest.raises(Refused, match="reset"):
        req(svc, "reset")


def test_unknown_types_are_not_dispatched(paused):
    for t in ("eval", "__init__", "dispatch", "load_image"):
        with pytest.raises(ProtocolError):
            req(paused, t)


def test_telemetry_queue_is_bounded_and_counts_what_it_drops():
    q = TelemetryQueue(max_samples=10, max_events=3)
    q.push(list(range(25)), ["a", "b"], 25)
    q.push([], ["c", "d", "e"], 26)
    samples, events, missed, missed_events, t = q.take()
    assert samples == list(range(15, 25)) and missed == 15
    assert events == ["c", "d", "e"] and missed_events == 2 and t == 26
    assert q.take() is None


def test_subscribers_get_samples_and_events(paused):
    s = Session()
    paused.handle_subscribe({"type": "subscribe"}, s)
    t0 = req(paused, "state")["t_ms"]
    req(paused, "start", name="M03")
    req(paused, "step", ms=250)
    samples, events, missed, _me, t = s.telemetry.take()
    # raw rows (t_ms, running, proc, message, fields), changes only: the first is where
    # things stood, then M03 sets its output once and runs, then it ends
    assert missed == 0 and t == t0 + 250
    assert 2 <= len(samples) < 20 and samples[0][0] == t0
    assert any(r[1] == "M03" and r[4]["outputs"][0] & 8 for r in samples)
    assert any(isinstance(e, Started) and e.name == "M03" for e in events)
    assert any(isinstance(e, Ended) and e.name == "M03" and e.exit_code == 99 for e in events)
    paused.end_session(s)
    assert paused.sim.subscribers == 0
    assert paused.sim.controller.record_samples is False      # nobody wants samples


def test_stop_runs_handler_exit_and_publishes_it(image):
    sim = Simulation(Controller(), "realtime")
    svc = Service(sim)
    svc.load_image(image)
    s = Session()
    svc.handle_subscribe({"type": "subscribe", "samples": False}, s)
    sim.start()
    sim.stop(shutdown=True)
    assert not sim.running
    _samples, events, *_ = s.telemetry.take()
    assert any(isinstance(e, Print) and e.register == 20002 for e in events)
    with pytest.raises(Refused, match="stopped"):
        req(svc, "state")


def test_a_controller_bug_pauses_the_simulation_instead_of_killing_it(image):
    class Broken(Controller):
        def step(self, ms=1):
            raise RuntimeError("boom")

    sim = Simulation(Broken(), "max")
    svc = Service(sim)
    sim.start()
    try:
        wait_for(lambda: sim.error)
        st = req(svc, "state")
        assert st["speed"]["mode"] == "pause" and "boom" in st["server"]["error"]
    finally:
        sim.stop()


def test_calls_from_many_threads_are_serialised(paused):
    errors = []

    def worker():
        try:
            for _ in range(50):
                req(paused, "step", ms=1)
                req(paused, "input", pin=5, value=1)
        except Exception as exc:  # noqa: BLE001
            errors.append(exc)

    threads = [threading.Thread(target=worker) for _ in range(4)]
    t0 = req(paused, "state")["t_ms"]
    for t in threads:
        t.start()
    for t in threads:
        t.join(30)
    assert not errors
    assert req(paused, "state")["t_ms"] == t0 + 200


def test_bad_image_leaves_the_previous_one(paused, programs):
    before = req(paused, "state")["image"]
    with pytest.raises(Refused, match="image refused"):
        paused.load_image(b"junk")
    over = compile_programs(["M03"], {"M03": (Kind.HARDWARE,
                                              "main(){" + "a=a+123456;" * 60 + "exit(1);}")},
                            code_limit=4096)
    assert over[0].code_size > 512
    big = write_image([(p.name, p.kind, p.to_bytes()) for p in over],
                      Limits(hw_proc=4096, hw_total=8192, sw_proc=16384))
    with pytest.raises(Refused, match="over the 512-byte limit"):
        paused.load_image(big)
    assert req(paused, "state")["image"] == before
    assert paused.refused == 2


def test_a_loader_bug_refuses_the_image_and_puts_the_old_one_back(image, programs):
    class Flaky(Controller):
        calls = 0

        def load(self, progs):
            progs = list(progs)
            Flaky.calls += 1
            if Flaky.calls == 2:
                super().load(progs[:1])          # half done, then a bug
                raise RuntimeError("loader bug")
            super().load(progs)

    sim = Simulation(Flaky(), "pause")
    svc = Service(sim)
    svc.load_image(image)
    names = set(sim.controller.programs)
    other = image_of(compile_programs(["M05"]))
    with pytest.raises(Refused, match="could not load it .RuntimeError: loader bug"):
        svc.load_image(other)
    assert set(sim.controller.programs) == names and svc.image.names() == sorted(names)


def test_a_long_step_stops_at_its_wall_time_budget(paused):
    paused.step_budget = 0.0            # one slice, then it answers
    req(paused, "start", name="M88")    # a procedure busy every tick: 600 s cannot fit one slice
    t0 = req(paused, "state")["t_ms"]
    r = req(paused, "step", ms=600_000)
    assert not r["complete"] and 0 < r["stepped"] < 600_000 and r["t_ms"] == t0 + r["stepped"]
    paused.step_budget = 2.0
    r = req(paused, "step", ms=10)
    assert r["complete"] and r["stepped"] == 10


def test_job_open_play_pause_stop_over_the_link(paused):
    """SPEC §10: the G-code job from the IDE (the ``job`` request): open and play
    a program, its M-code starts its procedure, the state says where it is; a
    line it cannot run is refused naming it."""
    r = req(paused, "job", verb="open", text="S7 M03\nG4 P1\nM05\n", file="job.nc", play=True)
    assert r["job"]["state"] in ("starting", "running") and r["job"]["file"] == "job.nc"
    req(paused, "step", ms=300)         # after __HANDLER_GCODE_START, if the image has it
    st = req(paused, "state")
    assert st["job"]["line"] == 2 and st["job"]["state"] == "running"
    assert req(paused, "job", verb="pause")["job"]["state"] == "paused"
    assert req(paused, "job", verb="stop")["job"]["state"] == "stopped"
    with pytest.raises(Refused) as e:
        req(paused, "job", verb="open", text="G2 X1\n", file="bad.nc")
    assert e.value.reason.startswith("bad.nc:1: G2 is not supported")
    with pytest.raises(BadRequest):
        req(paused, "job", verb="rewind")
