"""Real-time pacing (issue 17 point 1): after a stall the simulation skips the
lost time once and never runs ahead of the wall clock."""

import os
import signal
import sys
import time

import pytest

from plcbuilder.controller.controller import Controller
from plcbuilder.link.pacing import Simulation


class FakeClock:
    def __init__(self):
        self.now = 1000.0

    def __call__(self):
        return self.now


def paced(factor=1.0):
    sim = Simulation(Controller(), "realtime" if factor == 1.0 else "factor", factor)
    clock = FakeClock()
    sim.clock = clock
    sim.rebase()
    return sim, clock


def run_for(sim, clock, seconds, step=0.004):
    """Advance the fake clock in small steps, pacing after each, as the thread does."""
    end = clock.now + seconds
    while clock.now < end:
        clock.now = min(end, clock.now + step)
        for _ in range(1000):
            if sim.pace() is not None:
                break


def test_paced_ticks_follow_the_clock():
    sim, clock = paced()
    run_for(sim, clock, 1.0)
    assert sim.controller.t_ms == 1000
    assert sim.dropped_ms == 0


@pytest.mark.parametrize("stall", [1.5, 2.0, 30.0, 3600.0])
def test_after_a_stall_the_lost_time_is_skipped_once_and_never_run_ahead(stall):
    sim, clock = paced()
    run_for(sim, clock, 1.0)
    clock.now += stall                      # SIGSTOP, a suspended laptop, a long GC
    sim.pace()
    assert sim.dropped_ms == int(stall * 1000)
    t_after = sim.controller.t_ms
    run_for(sim, clock, 12.0)
    # simulated time moves as the wall clock after the stall, never faster
    assert sim.controller.t_ms - t_after == 12000
    assert sim.dropped_ms == int(stall * 1000)   # reported once, not doubling
    assert sim.controller.t_ms <= 1000 + 12000


def test_speed_10000_stays_bounded_when_it_cannot_keep_up():
    sim, clock = paced(10000.0)
    sim._tick_cost = 1e-3                   # slow ticks: a chunk is ~2 ticks
    rate = 10_000_000
    for _ in range(200):
        clock.now += 0.05
        sim.pace()
    wall = 200 * 0.05
    t, dropped = sim.controller.t_ms, sim.dropped_ms
    assert t + dropped <= wall * rate + 1  # never ahead of the wall clock
    assert dropped < (1 << 53) and t < (1 << 53)
    st = sim.controller.state()
    assert st.t_ms == t


@pytest.mark.skipif(sys.platform == "win32", reason="SIGSTOP is POSIX")
def test_a_stopped_and_continued_controller_keeps_answering(tmp_path):
    from plcbuilder.link.process import ControllerProcess
    proc = ControllerProcess.start(timeout=30)
    try:
        c = proc.connect()
        t0 = c.state().t_ms
        os.kill(proc.popen.pid, signal.SIGSTOP)
        time.sleep(1.6)
        os.kill(proc.popen.pid, signal.SIGCONT)
        time.sleep(1.0)
        a = time.monotonic()
        st = c.state()
        wall = (time.monotonic() - a + 2.6) * 1000
        assert st.speed["dropped_ms"] <= 2000
        assert st.speed["dropped_ms"] >= 500
        # the simulated time never ran ahead of the wall time since t0
        assert st.t_ms - t0 <= wall + 200
        time.sleep(0.5)
        st2 = c.state()
        assert st2.speed["dropped_ms"] == st.speed["dropped_ms"]
        assert 300 <= st2.t_ms - st.t_ms <= 1500
        c.close()
    finally:
        os.kill(proc.popen.pid, signal.SIGCONT)
        proc.stop()


def test_a_call_racing_the_stop_is_answered_at_once():
    """A request that reaches the simulation thread while it stops (a client
    leaving as the controller shuts down) is answered "stopped" at once, never
    left waiting out its timeout (it held a server's shutdown for 5 s)."""
    import threading

    from plcbuilder.link.pacing import SimulationDown

    for _ in range(40):
        sim = Simulation(Controller(), "pause")
        sim.start()
        waits: list[float] = []

        def caller():
            for _ in range(200):
                t0 = time.monotonic()
                try:
                    sim.call(lambda: None, timeout=5.0)
                except SimulationDown:
                    waits.append(time.monotonic() - t0)
                    return
        th = threading.Thread(target=caller)
        th.start()
        sim.stop(shutdown=False)
        th.join(10)
        assert not th.is_alive()
        assert all(w < 1.0 for w in waits), waits
