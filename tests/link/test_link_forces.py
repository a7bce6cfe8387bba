"""Write and force over the link: the requests, their errors, the forces event."""

import pytest

from plcbuilder.controller.events import Forces
from plcbuilder.link.client import RefusedError
from plcbuilder.link.protocol import BadRequest
from plcbuilder.link.service import Refused
from tests.link.linkkit import req


def test_force_write_release_and_list_through_the_service(paused):
    req(paused, "start", name="M88")
    req(paused, "step", ms=2)
    r = req(paused, "force", target="in 5", value=1)
    assert r["target"] == "in 5" and r["forces"] == [{"target": "in 5", "value": 1,
                                                      "since_ms": r["t_ms"]}]
    req(paused, "step", ms=2)
    assert 4 in req(paused, "state")["outputs"]            # M88 saw the forced input
    r = req(paused, "force", target="gvar 0x404", value=0)  # output 4 by its register
    assert r["target"] == "out 4"
    req(paused, "step", ms=2)
    assert 4 not in req(paused, "state")["outputs"]
    assert [f["target"] for f in req(paused, "forces")["forces"]] == ["in 5", "out 4"]
    r = req(paused, "write", target="M88.a", value=7)
    assert r["target"] == "M88.a"
    assert req(paused, "variables")["variables"]["M88"]["a"] == 7
    r = req(paused, "release", target="out 4", mode="restore")
    assert [f["target"] for f in r["forces"]] == ["in 5"]
    assert 4 in req(paused, "state")["outputs"]             # what M88 set
    r = req(paused, "release_all", mode="restore")
    assert r["released"] == ["in 5"] and r["forces"] == []


@pytest.mark.parametrize("mtype, fields, err, reason", [
    ("force", {"target": "NOPE.x", "value": 1}, Refused, "no procedure named NOPE"),
    ("force", {"target": "M88.zz", "value": 1}, Refused, "has no variable 'zz'"),
    ("force", {"target": "in 99", "value": 1}, Refused, "no input 99"),
    ("write", {"target": "adc 8", "value": 1}, Refused, "no ADC channel 8"),
    ("force", {"target": "in 3", "value": 5}, Refused, "0 or 1"),
    ("force", {"target": "in 3", "value": "1"}, BadRequest, "value"),
    ("force", {"target": "in 3", "value": 1.5}, BadRequest, "value"),
    ("force", {"target": "in 3"}, BadRequest, "value"),
    ("write", {"target": 4, "value": 1}, BadRequest, "target"),
    ("release", {"target": "in 3", "mode": "later"}, BadRequest, "keep, restore"),
    ("release_all", {"mode": 1}, BadRequest, "mode"),
])
def test_bad_requests_get_a_clear_error_and_change_nothing(paused, mtype, fields, err, reason):
    before = req(paused, "state")
    with pytest.raises(err, match=reason):
        req(paused, mtype, **fields)
    assert req(paused, "forces")["forces"] == []
    after = req(paused, "state")
    assert [after[k] for k in ("inputs", "outputs", "pwm", "adc")] == \
        [before[k] for k in ("inputs", "outputs", "pwm", "adc")]


def test_a_forces_event_reaches_subscribers_when_the_set_changes(client):
    client.speed("pause")
    client.subscribe(samples=False)
    client.force("in 5", 1)
    client.force("pwm 2", 300)
    client.release("in 5", "keep")
    with pytest.raises(RefusedError, match="no PWM channel 9"):
        client.force("pwm 9", 1)
    client.step(1)
    seen = []
    for batch in client.telemetry(timeout=2):
        seen += [e for e in batch.events if isinstance(e, Forces)]
        if len(seen) >= 3:
            break
    assert [[f["target"] for f in e.forces] for e in seen] == [["in 5"], ["in 5", "pwm 2"],
                                                               ["pwm 2"]]
    assert client.forces() == [{"target": "pwm 2", "value": 300, "since_ms": seen[1].t_ms}]
    assert client.release_all()["released"] == ["pwm 2"]
    assert client.write("out 1", 1)["forces"] == []
