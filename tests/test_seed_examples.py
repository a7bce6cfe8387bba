"""The manual's examples behave as the manual says, end to end through
``plcbuilder run`` on the default machine (the fixtures are tests/lang/golden/seed)."""

from pathlib import Path

from plcbuilder.api import RunOptions, run

SEED = Path(__file__).parent / "lang" / "golden" / "seed"


def report(name: str, **opts) -> dict:
    return run(SEED / name, RunOptions(**opts)).report


def test_pwm_example_clamps_eparam_into_pwm0():
    assert report("pwm.plc", eparam=70000)["pwm"][0] == 0xFFFF
    assert report("pwm.plc", eparam=-5)["pwm"][0] == 0
    assert report("pwm.plc", eparam=1234)["pwm"][0] == 1234


def test_message_example_reaches_the_host_with_its_command_and_parameter():
    rep = report("message.plc")
    (m,) = rep["messages"]
    assert (m["message"], m["name"], m["command"], m["parameter"]) == \
        (1100, "PLCCMD_REPLY_TO_MYCNC", 120, 0)
    assert rep["procedures"][0]["exit_name"] == "plc_exit_normal"


def test_probing_loop_stops_the_move_with_line_stop_on_contact():
    rep = report("probing.plc", ms=20000)
    stops = [m for m in rep["messages"] if m["name"] == "PLCCMD_LINE_STOP"]
    assert len(stops) == 1
    assert rep["procedures"][0]["exit_code"] == 99
    # the default machine's surface is at Z -50 mm: the move stopped near it,
    # far short of the 300 mm it asked for (from Z 20 mm)
    z = rep["axes"]["Z"]
    assert -5200 < z < -4900


def test_homing_example_finds_the_z_switch_on_the_default_machine():
    rep = report("homing_z.plc", ms=60000)
    (p,) = rep["procedures"]
    assert p["exit_code"] == 99 and p["ended_at_ms"] is not None
    v = rep["vars"]["homing_z"]
    assert v["statez"] == 2 and v["ready"] == 1
    # home switch closes at Z <= 0: the axis ends just off the switch
    assert 0 <= rep["axes"]["Z"] <= 100


def test_jog_example_moves_x_and_y_negative_because_2_plus_1_shift_8_is_768():
    rep = report("jog.plc", ms=10000)
    (p,) = rep["procedures"]
    assert p["exit_code"] == 99
    # X went + for 6 s, then X and Y both went - ((2+1)<<8 = 0x300 = X- and Y-), not X- and Y+
    assert rep["axes"]["Y"] < 10000
