"""Motion (docs/machine.md, "Motion"): g0moveA, start latency, work offsets, stop messages,
jogs from the hardware and software PLC, soft and hard limits."""

from __future__ import annotations

import math

import pytest

from plcbuilder.bytecode import abi
from plcbuilder.controller.machine_config import parse_machine
from plcbuilder.controller.machine import Machine
from plcbuilder.controller.motion import Profile

BIG = """
[axes.X]
rapid = 6000
accel = 1000
[axes.Y]
rapid = 6000
accel = 1000
[axes.Z]
rapid = 3000
accel = 500
"""


def big(extra: str = "") -> Machine:
    """Axes without soft limits or switches, starting at 0."""
    return Machine(parse_machine(BIG + extra))


def run_until_idle(m: Machine, limit: int = 200000) -> list:
    notes = []
    for _ in range(3):
        notes += m.advance()
    while m.gvarget(6060) == 0:
        notes += m.advance()
        limit -= 1
        assert limit > 0, "motion did not end"
    return notes


def pos(m: Machine) -> tuple:
    return tuple(m.axis_positions().values())


# -------------------------------------------------------------- g0moveA
def test_axis_mask_bits():
    """Axes X, Y, Z, A, B, C, U, V, W are mask bits 1, 2, 4, … 256."""
    text = "".join(f"[axes.{a}]\nrapid = 60000\naccel = 10000\n" for a in abi.AXES)
    m = Machine(parse_machine(text))
    for i, a in enumerate(abi.AXES):
        m.g0move(0, 1 << i, 100 * (i + 1))
        run_until_idle(m)
    assert m.axis_positions() == {a: 100 * (i + 1) for i, a in enumerate(abi.AXES)}


def test_incremental_and_absolute():
    """flags bit 0 = absolute (0: incremental); distance in 0.01 mm."""
    m = big()
    m.g0move(0, 1, 1000)
    run_until_idle(m)
    m.g0move(0, 1, 1000)
    run_until_idle(m)
    assert m.axis_positions()["X"] == 2000
    m.g0move(1, 1, 500)
    run_until_idle(m)
    assert m.axis_positions()["X"] == 500
    m.g0move(1, 1, 500)                 # already there
    run_until_idle(m)
    assert m.axis_positions()["X"] == 500


def test_machine_and_program_coordinates():
    """flags bit 1 = machine coordinates (0: program coordinates).
    Program position = machine position − work offset."""
    m = Machine(parse_machine(BIG.replace("[axes.X]\n", "[axes.X]\noffset = 10.0\n")))
    m.g0move(1, 1, 5000)                # absolute program X 50 = machine 60
    run_until_idle(m)
    assert m.gvarget(17021) == 6000 and m.gvarget(17001) == 5000
    assert m.gvarget(5021) == 6000 and m.gvarget(5041) == 5000
    m.g0move(3, 1, 5000)                # absolute machine X 50
    run_until_idle(m)
    assert m.gvarget(17021) == 5000 and m.gvarget(17001) == 4000
    m.g0move(2, 1, 100)                 # incremental: the coordinates do not matter
    run_until_idle(m)
    assert m.gvarget(17021) == 5100


def test_work_offsets_are_zero_by_default():
    """Program position = machine position − work offset (offsets come from the
    machine description; 0 by default)."""
    m = Machine()
    for i in range(9):
        assert m.gvarget(17001 + i) == m.gvarget(17021 + i)
    assert m.program_positions() == m.axis_positions()


def test_delayed_start_example():
    """A call with bit 7 only records that target for the axes in its mask; the
    next call without bit 7 starts one move of every axis in its mask. So
    `g0moveA(0x81,1,10000); g0moveA(0x81,2,5000); g0moveA(0x81,4,2000);
    g0moveA(1,7,0);` moves to X 100, Y 50, Z 20 mm."""
    m = Machine()
    m.g0move(0x81, 1, 10000)
    m.g0move(0x81, 2, 5000)
    m.g0move(0x81, 4, 2000)
    for _ in range(10):
        m.advance()
    assert m.gvarget(6060) == 0x4D      # recording alone moves nothing
    m.g0move(1, 7, 0)
    run_until_idle(m)
    assert m.axis_positions() == {"X": 10000, "Y": 5000, "Z": 2000}
    m2 = Machine()
    m2.g0move(0x81, 1, 10000)
    m2.g0move(0x81, 2, 5000)
    m2.g0move(0x81, 4, 2000)
    m2.g0move(1, 7, 0)
    run_until_idle(m2)
    assert m2.axis_positions() == {"X": 10000, "Y": 5000, "Z": 2000}


def test_delayed_start_from_elsewhere_is_one_coordinated_move():
    """… each to its recorded target where it has one and to its own distance
    otherwise; one move of every axis in the mask (a straight line)."""
    m = big()
    m.g0move(0x81, 1, 30000)
    m.g0move(0x80, 2, 4000)             # incremental, recorded
    m.g0move(1, 7, 1000)                # Z has no recorded target: absolute 1000
    trail, vels = [], []
    for _ in range(3):
        m.advance()
    while m.gvarget(6060) == 0:
        trail.append(pos(m))
        vels.append(m.sample_fields()["velocities"][:3])
        m.advance()
    assert pos(m) == (30000, 4000, 1000)
    # straight line: every sample on the line from 0 to the target
    for x, y, z in trail:
        assert abs(x * 4000 - y * 30000) <= 30000 * 2
        assert abs(x * 1000 - z * 30000) <= 30000 * 2
    # all axes start and end together
    assert all(all(c > 0 for c in v) for v in vels[:-1])
    assert m.sample_fields()["velocities"][:3] == (0, 0, 0)


def test_probing_move_is_z_down_300mm():
    """The seed's probing move `g0moveA(0x0,0x4,0-30000)` is Z down 300 mm from
    where it is."""
    m = Machine(parse_machine(BIG.replace("[axes.Z]\n", "[axes.Z]\nstart = 12.34\n")))
    m.g0move(0x0, 0x4, 0 - 30000)
    run_until_idle(m)
    assert m.axis_positions() == {"X": 0, "Y": 0, "Z": 1234 - 30000}


def test_rapid_speed_and_acceleration():
    """Moves run at the machine's rapid speed with its acceleration."""
    m = big()                           # X: 6000 mm/min = 100 mm/s, 1000 mm/s²
    m.g0move(0, 1, 50000)               # 500 mm
    for _ in range(3):
        m.advance()
    vel = []
    while m.gvarget(6060) == 0:
        vel.append(m.sample_fields()["velocities"][0])
        m.advance()
    assert max(vel) == 10000            # 100 mm/s in 0.01 mm/s
    # reaching full speed takes 100 ms at 1000 mm/s²
    first_full = vel.index(10000)
    assert 99 <= first_full <= 101
    # 500 mm at 100 mm/s plus 0.1 s of ramps: about 5.1 s
    assert 5095 <= len(vel) <= 5105
    # a short move never reaches full speed (triangle profile)
    m.g0move(0, 1, 100)
    run = []
    for _ in range(3):
        m.advance()
    while m.gvarget(6060) == 0:
        run.append(m.sample_fields()["velocities"][0])
        m.advance()
    assert max(run) < 10000


def test_coordinated_move_respects_every_axis():
    m = big()
    m.g0move(0, 1 | 4, 10000)           # X and Z 100 mm each: Z (50 mm/s) limits
    for _ in range(3):
        m.advance()
    vx, vz = [], []
    while m.gvarget(6060) == 0:
        s = m.sample_fields()["velocities"]
        vx.append(s[0])
        vz.append(s[2])
        m.advance()
    assert max(vz) == 5000 and max(vx) == 5000
    assert pos(m) == (10000, 0, 10000)


def test_motion_begins_a_couple_of_ticks_after_the_call():
    """Motion begins a couple of ticks after the call (default 2 ms), which is
    why the seed first waits for 6060 to become 0."""
    m = big()
    m.g0move(0, 1, 10000)
    seen = []
    for _ in range(6):
        seen.append((m.gvarget(6060), m.sample_fields()["velocities"][0]))
        m.advance()
    assert [c for c, _ in seen] == [0x4D, 0x4D, 0, 0, 0, 0]
    assert [v for _, v in seen] [:3] == [0, 0, 0]
    assert all(v > 0 for _, v in seen[3:])


def test_start_latency_is_configurable():
    m = Machine(parse_machine("[motion]\nstart_latency_ms = 0\n" + BIG))
    m.g0move(0, 1, 100)
    assert m.gvarget(6060) == 0
    m = Machine(parse_machine("[motion]\nstart_latency_ms = 5\n" + BIG))
    m.g0move(0, 1, 100)
    codes = []
    for _ in range(7):
        codes.append(m.gvarget(6060))
        m.advance()
    assert codes == [0x4D] * 5 + [0, 0]


def test_a_move_that_goes_nowhere_is_busy_for_one_tick():
    m = big()
    m.g0move(0, 1, 0)
    codes = []
    for _ in range(5):
        codes.append(m.gvarget(6060))
        m.advance()
    assert codes == [0x4D, 0x4D, 0, 0x4D, 0x4D]


def test_moves_called_while_moving_wait_their_turn():
    m = big()
    m.g0move(0, 1, 1000)
    m.g0move(0, 2, 1000)
    for _ in range(3):
        m.advance()
    assert m.sample_fields()["velocities"][1] == 0
    run_until_idle(m)
    assert pos(m) == (1000, 1000, 0)


def test_unconfigured_axis_is_ignored_with_a_warning():
    m = Machine()
    m.g0move(0, 1 | 8, 1000)            # X and A; the default machine has no A
    notes = run_until_idle(m)
    assert m.axis_positions()["X"] == 11000
    assert m.gvarget(17024) == 0
    assert any("no A axis" in t for _, t in notes)


@pytest.mark.parametrize("name", ["PLCCMD_LINE_STOP", "PLCCMD_LINE_SOFT_STOP",
                                  "PLCCMD_MOTION_SKIP", "PLCCMD_MOTION_ABORT",
                                  "PLCCMD_MOTION_BREAK"])
def test_stop_messages_decelerate(name):
    """A PLCCMD_LINE_STOP, PLCCMD_LINE_SOFT_STOP, PLCCMD_MOTION_SKIP,
    PLCCMD_MOTION_ABORT or PLCCMD_MOTION_BREAK message stops the move in
    progress (decelerating)."""
    m = big()
    m.g0move(0, 1, 50000)
    for _ in range(1000):
        m.advance()
    x0 = m.axis_positions()["X"]
    assert m.sample_fields()["velocities"][0] == 10000
    m.on_message(abi.PLCCMD[name])
    vel = []
    while m.gvarget(6060) == 0:
        m.advance()
        vel.append(m.sample_fields()["velocities"][0])
    # decelerating at 1000 mm/s² from 100 mm/s: 100 ms, 5 mm
    assert 99 <= len(vel) <= 101
    assert all(a >= b for a, b in zip(vel, vel[1:]))
    assert abs(m.axis_positions()["X"] - (x0 + 500)) <= 2


def test_other_messages_do_not_stop():
    m = big()
    m.g0move(0, 1, 1000)
    m.on_message(abi.PLCCMD["PLCCMD_REPLY_TO_MYCNC"])
    m.on_message(abi.PLCCMD["PLCCMD_MOTION_CONTINUE"])
    run_until_idle(m)
    assert m.axis_positions()["X"] == 1000


def test_stop_before_motion_begins_cancels_the_move():
    m = big()
    m.g0move(0, 1, 1000)
    m.on_message(abi.PLCCMD["PLCCMD_LINE_STOP"])
    for _ in range(10):
        assert m.gvarget(6060) == 0x4D
        m.advance()
    assert m.axis_positions()["X"] == 0


def test_profile_stop_from_keeps_a_profile_already_stopping():
    p = Profile.trapezoid(1000.0, 10.0, 1.0)
    assert p.stop_from(p.t_end - 2, 1.0) is p
    q = p.stop_from(20.0, 1.0)
    s, v = p.at(20.0)
    assert math.isclose(q.s_end, s + v * v / 2) and q.at(q.t_end)[1] == 0.0


# ----------------------------------------------------------------- jogs
def jog_run(m: Machine, ms: int, refresh: int = 0, value: int = 0) -> list:
    notes = []
    for k in range(ms):
        if refresh and k and k % refresh == 0:
            m.gvarset(8635, value)
        notes += m.advance()
    return notes


def test_jog_direction_bits():
    """gvarset(8635, dir) jogs: bits 0..7 the axes moving +, bits 8..15 the axes
    moving −, 0 stops."""
    m = big()
    m.gvarset(8635, 2 | (1 << 8))       # Y+ and X- (the seed's intent)
    jog_run(m, 500)
    p = m.axis_positions()
    assert p["X"] < 0 and p["Y"] > 0 and p["Z"] == 0
    assert m.gvarget(6060) == 0
    m.gvarset(8635, 0)
    notes = run_until_idle(m)
    assert notes == []
    q = m.axis_positions()
    jog_run(m, 100)
    assert m.axis_positions() == q


def test_seed_jog_precedence_slip():
    """The seed's own `gvarset(8635,2+1<<8)` is (2+1)<<8 = 768: X- and Y-."""
    m = big()
    m.gvarset(8635, (2 + 1) << 8)
    jog_run(m, 300)
    p = m.axis_positions()
    assert p["X"] < 0 and p["Y"] < 0


def test_jog_speed_units_and_axis_speed():
    """gvarset(8632, v) jog speed units; gvarset(8634, (mask<<24) | speed) speed of
    the masked axes. The seed: `gvarset(8632,1000); //Jog Speed 1m/min` with a
    speed of 1000: a speed value is mm/min while 8632 is 1000 (or unset)."""
    m = big()
    m.gvarset(8632, 1000)
    m.gvarset(8634, (1 << 24) | 1000)   # X: 1000 mm/min
    m.gvarset(8634, (2 << 24) | 500)    # Y: 500 mm/min
    m.gvarset(8635, 1 | 2)
    jog_run(m, 500, 256, 1 | 2)
    v = m.sample_fields()["velocities"]
    assert v[0] == round(1000 / 60 * 100)     # 16.67 mm/s
    assert v[1] == round(500 / 60 * 100)
    m.gvarset(8632, 2000)               # a speed value now means 2 mm/min
    jog_run(m, 500, 256, 1 | 2)
    v = m.sample_fields()["velocities"]
    assert v[0] == round(2000 / 60 * 100) and v[1] == round(1000 / 60 * 100)
    m.gvarset(8634, (3 << 24) | 300)    # both masked axes at once
    jog_run(m, 500, 256, 1 | 2)
    v = m.sample_fields()["velocities"]
    assert v[0] == v[1] == round(600 / 60 * 100)


def test_jog_speed_is_capped_at_rapid():
    m = big()
    m.gvarset(8634, (4 << 24) | 100000)
    m.gvarset(8635, 4)
    jog_run(m, 500, 256, 4)
    assert m.sample_fields()["velocities"][2] == 5000     # Z rapid 3000 mm/min


def test_jog_acceleration_time():
    """gvarset(8631, ms) acceleration time."""
    for ms in (50, 200):
        m = big()
        m.gvarset(8631, ms)
        m.gvarset(8634, (1 << 24) | 600)
        m.gvarset(8635, 1)
        for _ in range(2):
            m.advance()
        vel = []
        for _ in range(400):
            m.advance()
            vel.append(m.sample_fields()["velocities"][0])
        full = round(600 / 60 * 100)
        assert vel.index(full) in (ms - 1, ms)
        m.gvarset(8635, 0)
        n = 0
        for _ in range(2):
            m.advance()
        while m.gvarget(6060) == 0:
            m.advance()
            n += 1
        assert ms - 2 <= n <= ms + 1


def test_jog_watchdog():
    """A jog that is not written again within 1000 ms stops."""
    m = big()
    m.gvarset(8635, 1)
    notes = jog_run(m, 999)
    assert m.gvarget(6060) == 0 and notes == []
    x = m.axis_positions()["X"]
    notes = jog_run(m, 1)
    assert any("watchdog" in t and lvl == "warning" for lvl, t in notes)
    notes += run_until_idle(m)
    assert m.axis_positions()["X"] > x
    assert m.gvarget(6060) == 0x4D


def test_jog_refreshed_every_256ms_keeps_going():
    """The seed's programs refresh the jog every 256 ms; such a jog keeps going."""
    m = big()
    m.gvarset(8634, (1 << 24) | 1000)
    m.gvarset(8635, 1)
    notes = jog_run(m, 5000, 256, 1)
    assert notes == [] and m.gvarget(6060) == 0
    # 1000 mm/min for about 5 s: about 83 mm
    assert 8000 < m.axis_positions()["X"] < 8400


def test_jog_direction_change_reverses():
    m = big()
    m.gvarset(8631, 50)
    m.gvarset(8635, 1)
    jog_run(m, 300)
    m.gvarset(8635, 1 << 8)
    jog_run(m, 300)
    assert m.sample_fields()["velocities"][0] < 0
    m.gvarset(8635, 0)
    run_until_idle(m)


def test_jog_ignored_while_a_move_runs():
    m = big()
    m.g0move(0, 1, 5000)
    for _ in range(5):
        m.advance()
    m.gvarset(8635, 2)
    notes = run_until_idle(m)
    assert m.axis_positions()["Y"] == 0
    assert any("jog ignored" in t for _, t in notes)


def test_software_jog():
    """Software procedures jog with `gvarset(100020 + axis, speed)` (negative speed
    via `0-X`); the jog goes on until the speed is set to 0 (no watchdog)."""
    m = big()
    m.soft_jog(2, 0 - 600)              # Z- at 600 mm/min
    notes = jog_run(m, 3000)
    assert notes == [] and m.gvarget(6060) == 0
    assert m.sample_fields()["velocities"][2] == -1000
    assert -3100 < m.axis_positions()["Z"] < -2900
    m.soft_jog(2, 0)
    run_until_idle(m)
    m.soft_jog(0, 300)
    jog_run(m, 100)
    assert m.sample_fields()["velocities"][0] == 500
    m.on_message(abi.PLCCMD["PLCCMD_MOTION_ABORT"])   # a stop message ends it too
    run_until_idle(m)
    assert m.gvarget(6060) == 0x4D


# --------------------------------------------------------------- limits
LIMITS = """
[axes.X]
rapid = 6000
accel = 1000
min = -10
max = 100
[[inputs]]
pin = 10
axis = "X"
below = -15
hard_limit = true
name = "LIMIT_MIN_X"
[[inputs]]
pin = 11
axis = "X"
above = 105
hard_limit = true
"""


def test_soft_limit_stops_a_move_at_the_limit():
    """Soft limits per axis: a move stops at the limit, with a note."""
    m = Machine(parse_machine(LIMITS))
    m.g0move(0, 1, 50000)
    notes = run_until_idle(m)
    assert m.axis_positions()["X"] == 10000
    assert [lvl for lvl, _ in notes] == ["warning"] and "soft limit" in notes[0][1]
    # and no further
    m.g0move(0, 1, 100)
    notes = run_until_idle(m)
    assert m.axis_positions()["X"] == 10000 and "soft limit" in notes[0][1]
    # moving back in is fine
    m.g0move(0, 1, -2000)
    assert run_until_idle(m) == [] and m.axis_positions()["X"] == 8000


def test_soft_limit_stops_a_jog_at_the_limit():
    m = Machine(parse_machine(LIMITS))
    m.gvarset(8634, (1 << 24) | 6000)
    m.gvarset(8635, 1 << 8)
    notes = jog_run(m, 3000, 256, 1 << 8)
    assert m.axis_positions()["X"] == -1000
    assert sum("soft limit" in t for _, t in notes) == 1
    assert m.sample_fields()["velocities"][0] == 0


def test_5525_disables_software_limits():
    """5525 = 1 disables software limits."""
    m = Machine(parse_machine(LIMITS))
    m.gvarset(5525, 1)
    m.g0move(1, 1, 10400)
    assert run_until_idle(m) == []
    assert m.axis_positions()["X"] == 10400
    m.gvarset(5525, 0)
    m.g0move(1, 1, 5000)                # back inside: allowed
    run_until_idle(m)
    assert m.axis_positions()["X"] == 5000


def test_hard_limit_switch_stops_motion_with_an_error():
    """Hard limit switches (inputs tied to positions): hitting one stops motion
    with an error note."""
    m = Machine(parse_machine(LIMITS))
    m.gvarset(5525, 1)                  # soft limits off, so the switch is reached
    m.g0move(1, 1, -5000)
    notes = run_until_idle(m)
    x = m.axis_positions()["X"]
    assert -1550 < x <= -1500           # stopped at the switch, abruptly
    assert [lvl for lvl, _ in notes] == ["error"]
    assert "hard limit" in notes[0][1] and "input 10" in notes[0][1]
    assert m.portget(10) == 1
    # moving away from the switch is allowed
    m.g0move(0, 1, 1000)
    assert run_until_idle(m) == []
    assert m.portget(10) == 0


def test_hard_limit_stops_a_jog_too():
    m = Machine(parse_machine(LIMITS))
    m.gvarset(5525, 1)
    m.gvarset(8634, (1 << 24) | 3000)
    m.gvarset(8635, 1)
    notes = jog_run(m, 5000, 256, 1)
    assert m.gvarget(6060) == 0x4D and 10500 <= m.axis_positions()["X"] < 10560
    assert any(lvl == "error" and "hard limit" in t for lvl, t in notes)


def test_hard_limit_set_by_hand_stops_motion():
    m = Machine(parse_machine(LIMITS))
    m.g0move(0, 1, -500)
    for _ in range(50):
        m.advance()
    m.set_input(10, 1)
    notes = m.advance()
    assert notes and notes[0][0] == "error"
    assert m.gvarget(6060) == 0x4D


def test_5521_disables_hardware_limits():
    """5521 = 1 disables hardware limits."""
    m = Machine(parse_machine(LIMITS))
    m.gvarset(5525, 1)
    m.gvarset(5521, 1)
    m.g0move(1, 1, -5000)
    assert run_until_idle(m) == []
    assert m.axis_positions()["X"] == -5000 and m.portget(10) == 1


def test_default_machine_limits_are_consistent():
    """Soft limits are inside the hard limit switches, and the home switches and
    the workpiece surface inside the soft limits."""
    m = Machine()
    c = m.config
    for name in "XYZ":
        ax = c.axes[name]
        home = next(i for i in c.inputs if i.name == f"INPUT_HOME_{name}")
        lo = next(i for i in c.inputs if i.name == f"INPUT_LIMIT_MIN_{name}")
        hi = next(i for i in c.inputs if i.name == f"INPUT_LIMIT_MAX_{name}")
        assert lo.below < ax.soft_min < home.below < ax.start < ax.soft_max < hi.above
    surface = next(i for i in c.inputs if i.name == "INPUT_IHC").below
    assert c.axes["Z"].soft_min < surface < c.axes["Z"].start
    assert c.axes["Z"].start - surface <= 300


# ------------------------------------------------------------ properties
from hypothesis import given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402


@settings(max_examples=60, deadline=None, database=None)
@given(dist=st.floats(0.0, 1e6), vmax=st.floats(0.01, 100.0), acc=st.floats(1e-4, 10.0))
def test_profile_is_a_sound_trapezoid(dist, vmax, acc):
    p = Profile.trapezoid(dist, vmax, acc)
    steps = min(int(p.t_end) + 2, 3000)
    prev_s, prev_v = 0.0, 0.0
    for t in range(steps):
        s, v = p.at(float(t))
        assert s >= prev_s - 1e-6 and s <= dist + 1e-6
        assert -1e-9 <= v <= vmax + 1e-9
        assert abs(v - prev_v) <= acc + 1e-9
        prev_s, prev_v = s, v
    assert p.at(p.t_end) == (dist, 0.0)


@settings(max_examples=25, deadline=None, database=None)
@given(moves=st.lists(st.tuples(st.integers(1, 7), st.integers(-20000, 20000)),
                      min_size=1, max_size=3))
def test_incremental_moves_land_exactly_and_never_overshoot(moves):
    m = big()
    expect = [0, 0, 0]
    for mask, d in moves:
        m.g0move(0, mask, d)
        start = list(expect)
        for i in range(3):
            if mask >> i & 1:
                expect[i] += d
        for _ in range(3):
            m.advance()
        while m.gvarget(6060) == 0:
            p = pos(m)
            for i in range(3):
                lo, hi = sorted((start[i], expect[i]))
                assert lo <= p[i] <= hi
            m.advance()
        assert list(pos(m)) == expect


def test_the_motion_code_cannot_divide_by_zero():
    """Issue 17 item 7: a zero (or subnormal) speed or acceleration that got past
    validation gives a slow move, never ZeroDivisionError."""
    for vmax, acc in ((0.0, 1.0), (1.0, 0.0), (5e-324, 5e-324), (float("nan"), 1.0)):
        prof = Profile.trapezoid(1000.0, vmax, acc)
        assert prof.t_end > 0 and prof.at(prof.t_end) == (1000.0, 0.0)
        prof.stop_from(1.0, 0.0)
    from dataclasses import replace
    from plcbuilder.controller.machine_config import AxisConfig
    conf = parse_machine(BIG)
    axes = dict(conf.axes)
    axes["Z"] = AxisConfig("Z", rapid=5e-324, accel=5e-324)   # as if validation had let it in
    m = Machine(replace(conf, axes=axes))
    m.g0move(0, 0b100, 100)
    for _ in range(50):
        m.advance()
    m.motion.stop()
    for _ in range(5):
        m.advance()
