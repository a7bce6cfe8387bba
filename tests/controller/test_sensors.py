"""Sensors: inputs tied to axis positions and to outputs, constant inputs, ADC
sources, and manual overrides."""

from __future__ import annotations

from plcbuilder.controller.machine_config import parse_machine
from plcbuilder.controller.machine import Machine

AXIS = """
[motion]
start_latency_ms = 0
[axes.Z]
rapid = 60000
accel = 100000
start = 10
"""


def goto(m: Machine, z_units: int) -> None:
    m.gvarset(5525, 1)
    m.g0move(3, 4, z_units)
    for _ in range(3):
        m.advance()
    while m.gvarget(6060) == 0:
        m.advance()


def test_position_switches_with_active_level_and_band():
    """Inputs tied to positions (home and limit switches, a probe, plasma IHC
    contact, with active level)."""
    m = Machine(parse_machine(AXIS + """
[[inputs]]
pin = 0
axis = "Z"
below = 0.0
[[inputs]]
pin = 1
axis = "Z"
below = -5.0
active = 0
[[inputs]]
pin = 2
axis = "Z"
above = 20.0
[[inputs]]
pin = 3
axis = "Z"
above = 4.0
below = 6.0
"""))
    def pins():
        return [m.portget(p) for p in range(4)]
    assert pins() == [0, 1, 0, 0]               # Z 10
    goto(m, 0)
    assert pins() == [1, 1, 0, 0]               # at the threshold: active
    goto(m, 1)
    assert pins() == [0, 1, 0, 0]               # 0.01 mm above: not
    goto(m, -500)
    assert pins() == [1, 0, 0, 0]               # IHC-like: reads 0 on contact
    goto(m, 2000)
    assert pins() == [0, 1, 1, 0]
    goto(m, 500)
    assert pins() == [0, 1, 0, 1]               # inside the band
    goto(m, 601)
    assert pins() == [0, 1, 0, 0]


def test_switch_changes_while_the_axis_moves():
    m = Machine(parse_machine(AXIS + '[[inputs]]\npin = 0\naxis = "Z"\nbelow = 5.0\n'))
    m.g0move(3, 4, 0)
    seen = []
    for _ in range(200):
        seen.append((m.axis_positions()["Z"], m.portget(0)))
        m.advance()
    for z, v in seen:
        assert v == (1 if z <= 500 else 0)
    assert seen[0][1] == 0 and seen[-1][1] == 1


def test_input_follows_output_after_a_delay():
    """Inputs tied to outputs with a delay (arc-OK goes 1 N ms after
    OUTPUT_PLASMA on, 0 when off; coolant flow after flood)."""
    m = Machine(parse_machine("""
[[inputs]]
pin = 5
output = 4
delay_ms = 30
[[inputs]]
pin = 7
output = 3
delay_ms = 10
off_delay_ms = 20
[[inputs]]
pin = 8
output = 3
active = 0
"""))
    m.portset(4)
    m.portset(3)
    assert m.portget(8) == 0                    # zero delay, active low: at once
    trace = []
    for _ in range(40):
        trace.append((m.portget(5), m.portget(7)))
        m.advance()
    assert [a for a, _ in trace].index(1) == 30
    assert [b for _, b in trace].index(1) == 10
    m.portclear(4)
    m.portclear(3)
    assert m.portget(5) == 0 and m.portget(8) == 1
    off = []
    for _ in range(25):
        off.append(m.portget(7))
        m.advance()
    assert off.index(0) == 20


def test_output_toggled_back_before_the_delay_cancels():
    m = Machine(parse_machine("[[inputs]]\npin = 5\noutput = 4\ndelay_ms = 30\n"))
    m.portset(4)
    for _ in range(10):
        m.advance()
    m.portclear(4)
    for _ in range(100):
        m.advance()
        assert m.portget(5) == 0


def test_output_word_write_triggers_followers():
    m = Machine(parse_machine("[[inputs]]\npin = 5\noutput = 4\n"))
    m.gvarset(7184, 1 << 4)
    assert m.portget(5) == 1
    m.gvarset(7184, 0)
    assert m.portget(5) == 0


def test_constant_inputs():
    m = Machine(parse_machine("[[inputs]]\npin = 6\nvalue = 1\n[[inputs]]\npin = 8\nvalue = 0\n"))
    assert m.portget(6) == 1 and m.portget(8) == 0 and m.inputs_on() == [6]


def test_default_machine_sensors():
    """Air pressure OK by default; coolant flow after flood; the probe and IHC at
    the workpiece surface."""
    m = Machine()
    assert m.portget(6) == 1                    # INPUT_AIR_PRESSURE
    assert m.portget(7) == 0
    m.portset(3)                                # OUTPUT_FLOOD
    for _ in range(600):
        m.advance()
    assert m.portget(7) == 1                    # INPUT_COOLANT_FLOW


def test_adc_constant_and_ramp():
    """ADC sources (constant, ramp)."""
    m = Machine(parse_machine("""
[[adc]]
channel = 0
value = 100
[[adc]]
channel = 1
source = "ramp"
start = 0
end = 1000
period_ms = 100
[[adc]]
channel = 2
source = "ramp"
start = 500
end = 0
period_ms = 50
repeat = false
"""))
    vals = []
    for _ in range(250):
        vals.append(m.sample_fields()["adc"][:3])
        m.advance()
    assert all(v[0] == 100 for v in vals)
    assert [v[1] for v in vals[:3]] == [0, 10, 20]
    assert vals[99][1] == 990 and vals[100][1] == 0 and vals[150][1] == 500
    assert vals[25][2] == 250 and vals[50][2] == 0 and vals[249][2] == 0
    assert m.t_ms == 250 and m.gvarget(7197) == 500


def test_adc_tied_to_an_axis_position():
    """ADC sources (tied to an axis position)."""
    m = Machine(parse_machine(AXIS + """
[[adc]]
channel = 0
source = "axis"
axis = "Z"
scale = 10
offset = 1000
min = 0
max = 4095
"""))
    assert m.gvarget(7196) == 1100              # Z 10 mm
    goto(m, 5000)
    assert m.gvarget(7196) == 1500
    goto(m, -20000)
    assert m.gvarget(7196) == 0                 # clamped
    goto(m, 40000)
    assert m.gvarget(7196) == 4095


def test_adc_noise_is_deterministic():
    """ADC sources (noise from a seed — deterministic)."""
    text = '[[adc]]\nchannel = 2\nvalue = 2000\nnoise = 5\nseed = 42\n'

    def run():
        m = Machine(parse_machine(text))
        out = []
        for _ in range(300):
            out.append(m.gvarget(7198))
            m.advance()
        return out, m

    a, m = run()
    b, _ = run()
    assert a == b
    assert all(1995 <= v <= 2005 for v in a) and len(set(a)) > 5
    m.reset()
    c = []
    for _ in range(300):
        c.append(m.gvarget(7198))
        m.advance()
    assert c == a
    other = Machine(parse_machine(text.replace("42", "43")))
    d = []
    for _ in range(300):
        d.append(other.gvarget(7198))
        other.advance()
    assert d != a


def test_adc_set_by_hand_overrides_the_source():
    """An ADC value set by hand overrides its source from then on."""
    m = Machine(parse_machine('[[adc]]\nchannel = 1\nsource = "ramp"\nend = 1000\nperiod_ms = 10\n'))
    m.set_adc(1, 777)
    for _ in range(20):
        m.advance()
        assert m.gvarget(7197) == 777
    m.clear_adc(1)
    m.advance()
    assert m.gvarget(7197) != 777


def test_idle_default_machine_gives_no_notes():
    m = Machine()
    for _ in range(2000):
        assert m.advance() == []


def test_an_adc_value_saturates_at_32_bits():
    from plcbuilder.controller.machine_config import AdcConfig
    from plcbuilder.controller.sensors import AdcSource
    src = AdcSource(AdcConfig(0, "axis", axis="X", scale=1e9, offset=0.0))
    assert src.value(0, [10 ** 9] + [0] * 8) == (1 << 31) - 1
    assert src.value(0, [-10 ** 9] + [0] * 8) == -(1 << 31)
    noisy = AdcSource(AdcConfig(0, "constant", value=(1 << 31) - 1, noise=1 << 30))
    assert all(-(1 << 31) <= noisy.value(t, [0] * 9) < 1 << 31 for t in range(50))
