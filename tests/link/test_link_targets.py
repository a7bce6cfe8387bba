"""The served controller runs a target's program when the upload names the
target (docs/targets.md), and the variables request carries its registers."""

from __future__ import annotations

import time

import pytest

from plcbuilder.link.client import Client, RefusedError
from plcbuilder.link.server import ControllerServer
from tests.controller._targets import compiled
from tests.link.linkkit import image_of

HZ = """
init() { B[0] += 1; }
plc1() { plc1_time = 1; if (X[0] & 1) Y[0] |= 0x80; else Y[0] &= ~0x80; }
plc2() { }
"""


@pytest.fixture
def served():
    srv = ControllerServer(port=0, speed="factor", factor=50.0, frame_timeout=0.2,
                           hello_timeout=1.0)
    srv.sim.batch = 0.001
    srv.start()
    c = Client.connect(*srv.address, srv.token, timeout=10.0)
    yield srv, c
    c.close()
    srv.close()


def _wait(pred, seconds=20.0):
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        if pred():
            return True
        time.sleep(0.02)
    return False


def test_upload_with_a_target_runs_its_schedule_and_reports_registers(served):
    srv, c = served
    image = image_of([compiled(HZ, "huazhong")])
    c.upload(image, target={"name": "huazhong", "parameters": [7]})
    assert srv.sim.controller.target.name == "huazhong"
    c.set_input(0, 1)
    assert _wait(lambda: 7 in c.state().outputs)
    variables, report = c.variables_and_target()
    assert report["target_profile"] == "huazhong" and report["registers"]["P"] == {"0": 7}
    assert report["registers"]["B"] == {"0": 1} and "plc" in variables
    # a restart of the controller keeps B (reset: a new controller, the image loaded again)
    c.reset()
    assert _wait(lambda: c.variables_and_target()[1].get("registers", {}).get("B") == {"0": 2})


def test_upload_without_a_target_goes_back_to_mycnc(served):
    srv, c = served
    c.upload(image_of([compiled(HZ, "huazhong")]), target={"name": "huazhong"})
    with pytest.raises(RefusedError):                  # a huazhong program is not a myCNC image
        c.upload(image_of([compiled(HZ, "huazhong")]),
                 target={"name": "tgmotion", "cycle_time_us": 300})
    assert srv.sim.controller.target.name == "huazhong"
    from tests.link.linkkit import compile_programs
    c.upload(image_of(compile_programs(["M03"])))
    assert srv.sim.controller.target is None
    assert c.variables_and_target()[1] == {}


def test_b_kept_across_a_restart_of_the_server(tmp_path):
    """`B[n]` (100 16-bit words kept across controller restarts): the server's
    state file (plcbuilder controller --state FILE)."""
    state = tmp_path / "state.json"
    image = image_of([compiled(HZ, "huazhong")])
    seen = []
    for _ in range(2):
        srv = ControllerServer(port=0, speed="factor", factor=50.0, frame_timeout=0.2,
                               hello_timeout=1.0)
        srv.service.load_state(state)
        srv.sim.batch = 0.001
        srv.start()
        c = Client.connect(*srv.address, srv.token, timeout=10.0)
        try:
            c.upload(image, target={"name": "huazhong"})
            # init() runs in the first tick after the load: wait for ticks to pass
            # (B[0] may already be 1, kept from the run before, before init adds 1)
            t0 = c.state().t_ms
            assert _wait(lambda: c.state().t_ms >= t0 + 2)
            seen.append(c.variables_and_target()[1]["registers"]["B"])
        finally:
            c.close()
            srv.close()
    assert seen == [{"0": 1}, {"0": 2}]
    state.write_text("[1, 2")
    srv = ControllerServer(port=0)
    with pytest.raises(ValueError):
        srv.service.load_state(state)
    srv.close(shutdown=False)
    assert state.read_text() == "[1, 2"            # a file it could not read is left alone


def test_upload_carries_the_oscilloscopes_signals():
    """Item 9 of issue 27: the oscilloscope samples the signals the project picks
    ([tgmotion] oscilloscope), also on the controller the IDE uploads to."""
    from plcbuilder.controller.controller import Controller
    from plcbuilder.link import protocol
    from plcbuilder.link.pacing import Simulation
    from plcbuilder.link.service import Service, Session
    from tests.controller._targets import compiled, tgm
    from tests.link.linkkit import image_of
    svc = Service(Simulation(Controller(), "pause"))
    target = {"name": "tgmotion", "scope": ["in 9", "plc.n"]}
    msg = {"type": "upload", "image": protocol.encode_image(image_of([compiled(tgm(p04="n++;"),
                                                                               "tgmotion")])),
           "target": target}
    assert svc.handle_upload(msg, Session())["accepted"]
    c = svc.sim.controller
    c.step(2)
    assert c.target_report()["oscilloscope"]["signals"] == ["in 9", "plc.n"]
    bad = dict(msg, target={"name": "tgmotion", "scope": [3]})
    import pytest
    with pytest.raises(protocol.BadRequest):
        protocol.decode_target(bad)


HZ_CODES = """#include plc.h
init() { set_m_func(onm); set_s_func(ons); }
plc1() { plc1_time = 1; }
plc2() { }
onm() { m = gvarget(M_CODE); if (m == 3) Y[0] |= 0x01; if (m == 5) Y[0] &= ~0x01; }
ons() { G[5] = gvarget(S_CODE); }
"""


def test_the_code_request_issues_a_code_and_it_is_recorded(served):
    """``code {letter, value}``: the CNC issues M3 or S12000 as a scenario's
    ``code M3`` does; on Huazhong it reaches init()'s handler, and the
    recording has it (so replay and step back do it again)."""
    srv, c = served
    c.upload(image_of([compiled(HZ_CODES, "huazhong")]), target={"name": "huazhong"})
    assert _wait(lambda: c.variables_and_target()[1].get("handlers") == {"M": "onm", "S": "ons"})
    answer = c.issue_code("M", 3)
    assert answer["code"] == "M3" and answer["started"] is None
    assert _wait(lambda: 0 in c.state().outputs)
    assert c.issue_code("S", 12000)["code"] == "S12000"
    assert _wait(lambda: c.variables_and_target()[1]["registers"].get("G", {}).get("5") == 12000)
    text = c.request("recording")["text"]
    assert "code M3 @" in text and "code S12000 @" in text
    with pytest.raises(RefusedError, match="letter must be one of M, S, B, T"):
        c.request("code", letter="X", value=1)


def test_the_code_request_on_mycnc_starts_the_m_codes_procedure(client):
    answer = client.issue_code("M", 5)
    assert answer["started"] == "M05"
    assert "start M05" in client.request("recording")["text"]
    with pytest.raises(RefusedError, match="issues M codes only"):
        client.issue_code("S", 12000)
