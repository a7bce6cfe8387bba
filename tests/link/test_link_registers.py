"""The ``registers`` request: the values of global registers now (what the
IDE's register browser shows for the rows on screen)."""

import pytest

from plcbuilder.bytecode import abi
from plcbuilder.link import protocol
from plcbuilder.link.protocol import BadRequest
from tests.link.linkkit import req


def test_registers_reads_values_in_the_order_asked(paused):
    r = req(paused, "registers", addresses=[abi.MOTION_CODE, 12345, abi.GVAR_HW_PWM0])
    assert r["addresses"] == [abi.MOTION_CODE, 12345, abi.GVAR_HW_PWM0]
    assert r["values"] == [abi.MOTION_CODE_IDLE, 0, 0]


def test_registers_refuses_what_is_not_a_short_list_of_integers(paused):
    for bad in ("6060", [6060, "x"], [True], list(range(protocol.MAX_REGISTERS + 1)),
                [1 << 40]):
        with pytest.raises(BadRequest):
            req(paused, "registers", addresses=bad)
    with pytest.raises(BadRequest):
        req(paused, "registers")


def test_the_client_reads_registers(client):
    assert client.registers([abi.MOTION_CODE, 7]) == {abi.MOTION_CODE: abi.MOTION_CODE_IDLE,
                                                      7: 0}
