"""ControllerConnection against real controllers: an embedded child process
(spawned, killed, brought back) and an external server."""

from __future__ import annotations

import os
import signal

import pytest

pytest.importorskip("PySide6")

from plcbuilder.controller import events as ev  # noqa: E402
from plcbuilder.ide.connection import ControllerConnection  # noqa: E402
from plcbuilder.api import image_of as build_image  # noqa: E402

WAIT = 15_000      # ms: generous bounds for a loaded CI machine; passing runs take far less

COUNT = """\
main() {
  proc = plc_proc_spindle;
  portset(3);
  timer = 50; do { timer--; } while (timer > 0);
  gvarset(20000, 1234);
  exit(99);
}
"""


def _gone(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return True
    except PermissionError:
        return False
    # a zombie still answers kill(0): reaped children do not
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().split()[2] == "Z"
    except OSError:
        return True


@pytest.fixture
def conn(qtbot):
    c = ControllerConnection()
    pids = []
    c.sig_connected.connect(lambda _a: pids.append(c.child_pid))
    yield c
    c.shutdown()
    for pid in pids:
        if pid:
            qtbot.waitUntil(lambda pid=pid: _gone(pid), timeout=5000)


class Recorder:
    def __init__(self, c: ControllerConnection):
        self.events, self.samples, self.errors, self.states = [], [], [], []
        self.connected, self.disconnected, self.results = [], [], []
        c.sig_events.connect(self.events.extend)
        c.sig_samples.connect(self.samples.extend)
        c.sig_error.connect(self.errors.append)
        c.sig_state.connect(lambda st, missed: self.states.append(st))
        c.sig_connected.connect(self.connected.append)
        c.sig_disconnected.connect(self.disconnected.append)
        c.sig_result.connect(lambda verb, r: self.results.append((verb, r)))

    def ended(self, name: str):
        return [e for e in self.events if isinstance(e, ev.Ended) and e.name == name]


def test_embedded_upload_start_and_telemetry(qtbot, conn):
    rec = Recorder(conn)
    conn.start_embedded()
    qtbot.waitUntil(lambda: conn.connected, timeout=WAIT)
    assert rec.connected and rec.connected[0].startswith("127.0.0.1:")
    assert conn.child_pid and not _gone(conn.child_pid)
    conn.upload(build_image({"COUNT": COUNT}))
    qtbot.waitUntil(lambda: any(v == "upload" for v, _ in rec.results), timeout=WAIT)
    conn.start("COUNT", 7)
    qtbot.waitUntil(lambda: bool(rec.ended("COUNT")), timeout=WAIT)
    end = rec.ended("COUNT")[0]
    assert end.exit_code == 99 and end.exit_name == "plc_exit_normal"
    starts = [e for e in rec.events if isinstance(e, ev.Started) and e.name == "COUNT"]
    assert starts and starts[0].eparam == 7
    assert [e.value for e in rec.events if isinstance(e, ev.Print)] == [1234]
    assert end.t_ms - starts[0].t_ms == 50
    qtbot.waitUntil(lambda: any(s.t_ms >= end.t_ms for s in rec.samples), timeout=WAIT)
    during = [s for s in rec.samples if starts[0].t_ms <= s.t_ms < end.t_ms]
    assert during and all((s.outputs[0] >> 3) & 1 for s in during)
    assert all(s.proc == 70 for s in during)
    qtbot.waitUntil(lambda: bool(rec.states) and rec.states[-1].t_ms > end.t_ms,
                    timeout=WAIT)
    st = rec.states[-1]
    assert st.running is None and [p["name"] for p in st.image] == ["COUNT"]
    assert rec.errors == []


def test_refused_requests_are_reported(qtbot, conn):
    rec = Recorder(conn)
    conn.start_embedded()
    qtbot.waitUntil(lambda: conn.connected, timeout=WAIT)
    conn.upload(b"not an image")
    conn.start("NOPE", 0)
    qtbot.waitUntil(lambda: len(rec.errors) >= 2, timeout=WAIT)
    assert rec.errors[0].startswith("upload:")
    assert rec.errors[1].startswith("start:") and "NOPE" in rec.errors[1]
    conn.set_speed("warp")
    assert rec.errors[-1].startswith("speed:")
    assert conn.connected


def test_variables_and_speed(qtbot, conn):
    got = []
    conn.sig_variables.connect(got.append)
    rec = Recorder(conn)
    conn.start_embedded()
    qtbot.waitUntil(lambda: conn.connected, timeout=WAIT)
    conn.set_speed("max")
    conn.upload(build_image({"COUNT": COUNT}))
    conn.start("COUNT", 3)
    qtbot.waitUntil(lambda: bool(rec.ended("COUNT")), timeout=WAIT)
    conn.request_variables()
    qtbot.waitUntil(lambda: bool(got), timeout=WAIT)
    assert got[-1]["COUNT"]["eparam"] == 3 and got[-1]["COUNT"]["proc"] == 70
    qtbot.waitUntil(lambda: bool(rec.states) and rec.states[-1].speed["mode"] == "max",
                    timeout=WAIT)


def test_killed_child_is_reported_and_restarted(qtbot, conn):
    rec = Recorder(conn)
    conn.start_embedded()
    qtbot.waitUntil(lambda: conn.connected, timeout=WAIT)
    conn.upload(build_image({"COUNT": COUNT}))
    qtbot.waitUntil(lambda: any(v == "upload" for v, _ in rec.results), timeout=WAIT)
    first = conn.child_pid
    # while it is down, a start is refused at once rather than done later
    conn.sig_disconnected.connect(lambda _r: conn.start("COUNT", 0))
    os.kill(first, signal.SIGKILL)
    qtbot.waitUntil(lambda: bool(rec.disconnected), timeout=WAIT)
    assert "killed" in rec.disconnected[0] and "SIGKILL" in rec.disconnected[0]
    assert any(e.startswith("start: not connected") for e in rec.errors)
    conn.sig_disconnected.disconnect()
    qtbot.waitUntil(lambda: len(rec.connected) >= 2 and conn.connected, timeout=WAIT)
    assert conn.child_pid != first
    assert _gone(first)
    # the image came back with it: the procedure runs on the new controller
    conn.start("COUNT", 0)
    qtbot.waitUntil(lambda: bool(rec.ended("COUNT")), timeout=WAIT)
    assert rec.ended("COUNT")[0].exit_code == 99


def test_shutdown_ends_the_child(qtbot):
    c = ControllerConnection()
    try:
        c.start_embedded()
        qtbot.waitUntil(lambda: c.connected, timeout=WAIT)
        pid = c.child_pid
        with qtbot.waitSignal(c.sig_disconnected, timeout=WAIT):
            c.shutdown()
        assert not c.connected
        qtbot.waitUntil(lambda: _gone(pid), timeout=5000)
    finally:
        c.shutdown()


def test_connect_to_external_controller(qtbot, conn):
    from plcbuilder.link.server import ControllerServer
    srv = ControllerServer(port=0).start()
    try:
        rec = Recorder(conn)
        host, port = srv.address
        conn.connect_to(host, port, srv.token)
        qtbot.waitUntil(lambda: conn.connected, timeout=WAIT)
        assert rec.connected == [f"{host}:{port}"]
        assert conn.child_pid is None
        conn.upload(build_image({"COUNT": COUNT}))
        conn.start("COUNT", 0)
        qtbot.waitUntil(lambda: bool(rec.ended("COUNT")), timeout=WAIT)
        srv.close()
        qtbot.waitUntil(lambda: bool(rec.disconnected), timeout=WAIT)
        assert not conn.connected
    finally:
        srv.close()


def test_wrong_token_is_reported(qtbot, conn):
    from plcbuilder.link.server import ControllerServer
    srv = ControllerServer(port=0).start()
    try:
        rec = Recorder(conn)
        conn.connect_to(*srv.address, "wrong-token")
        qtbot.waitUntil(lambda: bool(rec.disconnected), timeout=WAIT)
        assert "token" in rec.disconnected[0].lower() or "unauthorized" in rec.disconnected[0]
        assert not conn.connected
    finally:
        conn.shutdown()
        srv.close()


def test_a_child_that_cannot_start_says_why(qtbot, conn, tmp_path):
    rec = Recorder(conn)
    conn.start_embedded(["--machine", str(tmp_path / "missing.toml")])
    qtbot.waitUntil(lambda: len(rec.disconnected) >= 2, timeout=WAIT)   # and it keeps trying
    assert "exited with status 1" in rec.disconnected[0]
    assert "missing.toml" in rec.disconnected[0]
    assert not conn.connected and rec.connected == []


def test_reset_starts_time_again(qtbot, conn):
    rec = Recorder(conn)
    conn.start_embedded()
    qtbot.waitUntil(lambda: conn.connected, timeout=WAIT)
    qtbot.waitUntil(lambda: bool(rec.samples) and rec.samples[-1].t_ms > 2000, timeout=WAIT)
    before = rec.samples[-1].t_ms
    conn.reset()
    qtbot.waitUntil(lambda: any(v == "reset" for v, _ in rec.results), timeout=WAIT)
    n = len(rec.samples)
    # an idle controller sends its time about once a second: wait for a new
    # point earlier than the last one before the reset (without the reset,
    # time only grows). Not a fixed bound: on a loaded machine the first
    # point after the reset can come late, its time already past 300 ms.
    qtbot.waitUntil(lambda: len(rec.samples) > n and rec.samples[-1].t_ms < before,
                    timeout=WAIT)
    assert all(a.t_ms <= b.t_ms for a, b in zip(rec.samples[n:], rec.samples[n + 1:]))


TOGGLE = "main(){ do{ if (t) { portclear(6); t = 0; } else { portset(6); t = 1; } }while(1); }"


def test_at_max_speed_the_ide_receives_every_edge(qtbot, conn):
    """Issue 14 point 3: an output that toggles every tick, at Max speed, through
    the IDE's own connection: every tick arrives and every edge is there."""
    import numpy as np
    from plcbuilder.ide.panels.model import RunModel
    from plcbuilder.link.server import ControllerServer
    srv = ControllerServer(port=0, speed="pause").start()
    try:
        model = RunModel(capacity=3_000_000)
        conn.sig_samples.connect(model.add_samples)
        states = []
        conn.sig_state.connect(lambda st, missed: states.append((st, missed)))
        conn.connect_to(*srv.address, srv.token)
        qtbot.waitUntil(lambda: conn.connected, timeout=WAIT)
        conn.upload(build_image({"TOGGLE": TOGGLE}))
        conn.start("TOGGLE", 0)
        conn.set_speed("max")
        qtbot.wait(1500)
        conn.set_speed("pause")
        qtbot.waitUntil(lambda: bool(states) and states[-1][0].speed.get("mode") == "pause",
                        timeout=WAIT)
        end = srv.controller.t_ms
        qtbot.waitUntil(lambda: len(model) and model.t_end * 1000 >= end - 1, timeout=WAIT)
        assert conn.missed == 0
        t = np.rint(model.time.view() * 1000).astype(np.int64)
        bits = model.bit_series("outputs", 6)
        first = int(np.argmax(bits))
        t, bits = t[first:], bits[first:]
        assert len(t) > 5000, len(t)
        assert np.all(np.diff(t) == 1)          # every tick (each one a change)
        assert np.all(bits[1:] != bits[:-1])    # no edge lost
    finally:
        srv.close()


def test_step_samples_hold_each_change_until_the_next():
    from plcbuilder.ide.panels.model import StepSamples
    s0 = ev.Sample(10, None, 0, 0, (0,) * 8, (0,) * 8, (0,) * 8, (0,) * 8, (0,) * 8, (0,) * 9,
                   (0,) * 9)
    s1 = ev.Sample(15, "M03", 0, 5, (0,) * 8, (8,) + (0,) * 7, (0,) * 8, (0,) * 8, (0,) * 8,
                   (0,) * 9, (0,) * 9)
    s2 = ev.Sample(25, "M03", 0, 0, (0,) * 8, (9,) + (0,) * 7, (0,) * 8, (0,) * 8, (0,) * 8,
                   (0,) * 9, (0,) * 9)
    steps = StepSamples()
    out = steps.feed([s0, s1], 20)
    assert [(s.t_ms, s.outputs[0], s.message) for s in out] == \
        [(10, 0, 0), (14, 0, 0), (15, 8, 5), (19, 8, 0)]
    out = steps.feed([s2], 30)                 # the next batch goes on where it left
    assert [(s.t_ms, s.outputs[0], s.message) for s in out] == \
        [(24, 8, 0), (25, 9, 0), (29, 9, 0)]
    assert steps.feed([], 30) == []            # nothing new, no time: nothing
    assert [s.t_ms for s in steps.feed([], 40)] == [39]


def test_every_verb_and_every_mail_has_its_method():
    """Issue 28.5: the connection dispatches by method (``_do_<verb>`` on the
    worker, ``_mail_<kind>`` on the GUI side), not by if/elif chains: each
    verb the GUI sends is a method, a debugger verb or a plain request the
    server knows, and each kind the worker posts has its method."""
    import inspect
    import re

    from plcbuilder.ide import connection as C
    from plcbuilder.ide.debug import requests as R
    from plcbuilder.link.protocol import REQUESTS

    text = inspect.getsource(C) + inspect.getsource(R)
    sent = set(re.findall(r'_send\("(\w+)"', text))
    assert sent, "no verb found"
    for verb in sent:
        assert (hasattr(C._Worker, "_do_" + verb) or verb in C.DEBUG_VERBS
                or verb in REQUESTS), verb
    posted = set(re.findall(r'self\.post\("(\w+)"', inspect.getsource(C._Worker)))
    assert posted
    for kind in posted - {"telemetry", "stopped"}:
        assert hasattr(C.ControllerConnection, "_mail_" + kind), kind
