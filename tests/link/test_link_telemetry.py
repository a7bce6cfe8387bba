"""Telemetry v2 (issue 14 point 3): changes only, MessagePack, lossless at Max."""

import random
import threading
import time

import numpy as np

from plcbuilder.controller.events import Sample
from plcbuilder.ide.panels.model import RunModel, StepSamples
from plcbuilder.link import protocol
from plcbuilder.link.client import Client
from plcbuilder.link.pacing import TelemetryQueue
from plcbuilder.link.server import ControllerServer
from tests.link.linkkit import TOGGLE, compile_programs, image_of, msg_frame, raw_connect


def _fields(rng, base=None):
    f = dict(base or {"inputs": (0,) * 8, "outputs": (0,) * 8, "pwm": (0,) * 8, "dac": (0,) * 8,
                      "adc": (0,) * 8, "axes": (0,) * 9, "velocities": (0,) * 9})
    for _ in range(rng.randint(0, 3)):
        k = rng.choice(list(f))
        v = list(f[k])
        v[rng.randrange(len(v))] = rng.randrange(-5, 1 << 32)
        f[k] = tuple(v)
    return f


def test_changes_round_trip_through_messagepack():
    rng = random.Random(7)
    enc, dec = protocol.ChangeEncoder(), protocol.ChangeDecoder()
    f = _fields(rng)
    rows = []
    for t in range(2000):
        if rng.random() < 0.3:
            f = _fields(rng, f)
        rows.append((t, rng.choice([None, "M03", "OFF"]), rng.randrange(3),
                     rng.choice([0, 0, 0, 5]), f))
    for i in range(0, len(rows), 97):
        part = rows[i:i + 97]
        missed = i % 3 == 0
        if missed:
            enc.reset()
        frame = protocol.encode_binary_frame({"type": "telemetry", "t_ms": 0, "missed": 0,
                                              "changes": [enc.encode(r) for r in part]})
        msg = protocol.decode_payload(frame[4:], binary=True)
        if missed:
            dec.reset()
        for r, c in zip(part, msg["changes"]):
            s = dec.decode(c)
            assert s == Sample(r[0], r[1], r[2], r[3], **r[4])


def test_a_server_never_accepts_messagepack_from_a_client(server):
    s = raw_connect(server.address)
    import msgpack
    payload = msgpack.packb({"type": "hello", "version": protocol.PROTOCOL_VERSION,
                             "token": server.token})
    s.sendall(len(payload).to_bytes(4, "big") + payload)
    r = protocol.recv_msg(s)
    assert r["type"] == "error" and r["code"] == "bad_frame"
    s.close()


def test_at_max_speed_a_lossless_subscriber_gets_every_edge():
    """An output that toggles every tick, at Max speed: no edge lost, as the IDE sees it."""
    with ControllerServer(port=0, speed="pause",
                          image=image_of(compile_programs(overrides=TOGGLE))) as srv:
        c = Client.connect(*srv.address, srv.token)
        sub = Client.connect(*srv.address, srv.token)
        steps, model = StepSamples(), RunModel(capacity=2_000_000)
        batches, lock = [], threading.Lock()

        def on_batch(b):
            with lock:
                batches.append(b)
                model.add_samples(steps.feed(b.samples, b.t_ms))
        sub.subscribe(on_batch, queue=20000, lossless=True)
        c.start("TOGGLE")
        c.speed("max")
        time.sleep(1.5)
        c.speed("pause")
        end = c.state().t_ms
        deadline = time.monotonic() + 10
        while time.monotonic() < deadline:
            with lock:
                if batches and batches[-1].t_ms >= end and \
                        (not model.time.view().size or model.t_end * 1000 >= end - 1):
                    break
            time.sleep(0.05)
        sub.close()
        c.close()
    assert sum(b.missed for b in batches) == 0
    t = np.rint(model.time.view() * 1000).astype(np.int64)
    bits = model.bit_series("outputs", 6)
    first = int(np.argmax(bits))              # the first tick the output is on
    t, bits = t[first:], bits[first:]
    # it ran, thousands of ticks (alone 100,000 and more; in the suite's two
    # workers once 7,047: the simulation and this subscriber share one interpreter)
    assert len(t) > 2_000, len(t)
    assert np.all(np.diff(t) == 1)            # a point every tick: each one a change
    assert np.all(bits[1:] != bits[:-1])      # and every edge is there
    assert t[-1] == end - 1


def test_a_subscriber_that_needs_nothing_new_gets_small_frames(server, client):
    s = raw_connect(server.address)
    from tests.link.linkkit import hello
    hello(s, server.token)
    s.sendall(msg_frame({"type": "subscribe", "id": 1}))
    dec = protocol.FrameDecoder()
    sizes, changes = [], 0
    end = time.monotonic() + 1.0
    while time.monotonic() < end:
        for p in dec.feed(s.recv(1 << 16)):
            m = protocol.decode_payload(p, binary=True)
            if m["type"] == "telemetry":
                sizes.append(len(p))
                changes += len(m["changes"])
    s.close()
    # time goes on (LUBE runs), nothing changes: the time about every 100 ms
    assert 5 <= len(sizes) <= 15 and changes <= 3
    assert max(sizes[1:]) < 80


def test_an_idle_controller_sends_its_time_rarely():
    """Nothing runs (no image): a small time-only frame about every
    TelemetryQueue.idle_time_interval (1 s), not one every 20 ms."""
    with ControllerServer(port=0, speed="factor", factor=50.0) as srv:
        sub = Client.connect(*srv.address, srv.token)
        batches = []
        sub.subscribe(batches.append)
        time.sleep(2.5)
        sub.close()
    assert 2 <= len(batches) <= 5, len(batches)
    assert batches[-1].t_ms > batches[0].t_ms   # the time still goes on


def test_time_only_takes_are_rare_while_idle_and_every_100_ms_while_running():
    """Only time went on: it goes out every 0.1 s while a procedure runs, every
    second while the controller is idle; a change goes out at once."""
    q = TelemetryQueue()
    q.push([], [], 10, active=True)
    assert q.take()[4] == 10
    q.push([], [], 20, active=True)
    assert q.take() is None                     # running: not again within 0.1 s
    q._time_only_at -= q.busy_time_interval
    assert q.take()[4] == 20                    # ... and then it does
    q.push([], [], 30, active=False)
    assert q.take() is None                     # idle: not again within the interval
    q.push([("row",)], [], 40, active=False)
    assert q.take()[0] == [("row",)]            # a change always goes out
    q._time_only_at -= q.idle_time_interval
    q.push([], [], 50, active=False)
    assert q.take()[4] == 50                    # idle, the interval over: the time goes out
    assert q.take() is None
