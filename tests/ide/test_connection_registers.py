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
