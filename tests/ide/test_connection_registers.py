"""ControllerConnection.request_registers against a real embedded controller:
what the Registers dock shows as live values."""

from __future__ import annotations

import pytest

from plcbuilder.api import image_of as build_image
from plcbuilder.ide.connection import ControllerConnection

WAIT = 15_000
SET = "main() { gvarset(20000, 1234); pwm01 = 77; exit(99); }\n"


@pytest.fixture
def conn(qtbot):
    c = ControllerConnection()
    yield c
    c.shutdown()


def test_registers_come_back_as_a_signal(qtbot, conn):
    got, results = [], []
    conn.sig_registers.connect(got.append)
    conn.sig_result.connect(lambda verb, r: results.append(verb))
    conn.request_registers([6060])              # not connected yet: nothing is sent
    conn.start_embedded()
    qtbot.waitUntil(lambda: conn.connected, timeout=WAIT)
    conn.upload(build_image({"SET": SET}))
    conn.start("SET", 0)
    qtbot.waitUntil(lambda: "start" in results, timeout=WAIT)
    qtbot.wait(300)                             # a few ticks of real time: SET has run
    conn.request_registers([20000, 7278, 6060])
    conn.request_registers([1])                 # one still waiting: not repeated
    qtbot.waitUntil(lambda: bool(got), timeout=WAIT)
    assert got == [{20000: 1234, 7278: 77, 6060: 0x4D}]
    conn.request_registers([1])                 # answered: it may ask again
    qtbot.waitUntil(lambda: len(got) == 2, timeout=WAIT)
    assert got[1] == {1: 0}


def test_the_halted_state_asked_for_keeps_its_place_among_the_notifications():
    """The answer to debug_state is posted in the order the link read it: a
    ``halted`` notification read after a "not halted" answer comes after it in
    the GUI's inbox, even when the link's reader passes it on before the
    asking thread wakes (under load: the IDE then showed no halt, and a test
    waited 30 s for one)."""
    import queue

    from plcbuilder.ide.connection import _Worker

    class Client:                   # the reader reads the answer, then a notification,
        notification_callback = None    # all before request() returns

        def request(self, verb, on_reply=None, **_fields):
            result = {"t_ms": 5, "halted": None}
            if on_reply is not None:
                on_reply(result)
            self.notification_callback({"type": "halted", "state": {"line": 31}})
            return result

    inbox = queue.SimpleQueue()
    w = _Worker(inbox, embedded=False, address=("127.0.0.1", 1, ""))
    client = Client()
    client.notification_callback = lambda msg: w.post(str(msg.get("type")), msg)
    w._debug_state(client)
    kinds = []
    while not inbox.empty():
        kinds.append(inbox.get()[0])
    assert kinds == ["debug_state", "halted"]
