"""The simulated machine: I/O and registers (docs/machine.md, "Registers"),
the default machine, and the manual's homing and probing examples driven at the
machine level (a Python loop imitates the PLC code, one iteration a tick)."""

from __future__ import annotations

import pytest

from plcbuilder.bytecode import abi
from plcbuilder.controller.machine_config import parse_machine
from plcbuilder.controller.machine import Machine

INPUT_HOME_Z, INPUT_PROBE, INPUT_IHC, INPUT_ARC_OK, INPUT_AIR = 2, 3, 4, 5, 6
OUTPUT_PLASMA = 4
LINE_STOP = abi.PLCCMD["PLCCMD_LINE_STOP"]


def bare(extra: str = "") -> Machine:
    return Machine(parse_machine(extra))


# ------------------------------------------------------------------ I/O
def test_64_inputs_and_outputs_by_default():
    """Inputs and outputs are numbered from 0 (64 of each by default)."""
    m = bare()
    assert (m.input_count, m.output_count) == (64, 64)
    m.portset(0)
    m.portset(63)
    assert m.outputs_on() == [0, 63]
    m.set_input(63, 1)
    assert m.portget(63) == 1
    m.portset(64)                       # no such pin: ignored, with one warning
    assert m.portget(64) == 0
    assert m.outputs_on() == [0, 63]
    notes = m.advance()
    assert [lvl for lvl, _ in notes] == ["warning", "warning"]
    assert "portset(64)" in notes[0][1]
    with pytest.raises(ValueError):
        m.set_input(64, 1)


def test_io_count_is_configurable():
    m = bare("[io]\ninputs = 256\noutputs = 40\n")
    m.set_input(255, 1)
    assert m.portget(255) == 1
    m.portset(39)
    assert m.outputs_on() == [39]


def test_portset_portclear_portget():
    """`portset(n)`, `portclear(n)`, `portget(n)`."""
    m = bare()
    m.portset(5)
    assert m.outputs_on() == [5]
    m.portclear(5)
    assert m.outputs_on() == []
    assert m.portget(7) == 0
    m.set_input(7, 1)
    assert m.portget(7) == 1


def test_output_state_register():
    """`gvarget(0x400 + n)` is the state of output n. Writes to outputs take
    effect at once (`portset(3); a=gvarget(0x403);` reads 1)."""
    m = bare()
    m.portset(3)
    assert m.gvarget(0x403) == 1
    assert m.gvarget(0x402) == 0
    m.portset(13)
    assert m.gvarget(0x40D) == 1
    m.portclear(3)
    assert m.gvarget(0x403) == 0
    assert not m.is_plain_register(0x403)


def test_input_words():
    """7180..7183 and 7188..7191: input words 0..7 (32 pins a word)."""
    m = bare("[io]\ninputs = 256\n")
    for pin in (0, 33, 95, 100, 140, 255):
        m.set_input(pin, 1)
    words = [m.gvarget(a) for a in abi.GVAR_HW_INPUTS]
    assert abi.GVAR_HW_INPUTS == [7180, 7181, 7182, 7183, 7188, 7189, 7190, 7191]
    assert words[0] == 1
    assert words[1] == 2
    assert words[2] == -(1 << 31)       # pin 95: bit 31 of word 2, a 32-bit value
    assert words[3] == 1 << 4           # pin 100
    assert words[4] == 1 << 12          # pin 140 -> 7188
    assert words[7] == -(1 << 31)
    assert m.sample_fields()["inputs"][2] == 1 << 31    # telemetry words are unsigned
    m.gvarset(7180, 0)                  # read-only: ignored
    assert m.gvarget(7180) == 1


def test_output_words_read_and_write():
    """7184..7187 and 7192..7195: output words 0..7 (32 pins a word); writing an
    output word sets those 32 outputs."""
    m = bare("[io]\noutputs = 256\n")
    m.portset(1)
    m.portset(32 + 4)
    m.portset(32 * 4 + 2)
    assert m.gvarget(7184) == 2
    assert m.gvarget(7185) == 16
    assert m.gvarget(7192) == 4
    m.gvarset(7184, 0x0000_00F0)        # outputs 4..7 on, 0..3 and 8..31 off
    assert m.outputs_on() == [4, 5, 6, 7, 36, 130]
    m.gvarset(7195, -1)                 # word 7: outputs 224..255
    assert m.outputs_on()[-32:] == list(range(224, 256))
    assert m.gvarget(0x400 + 230) == 1
    m.gvarset(7195, 0)
    assert m.outputs_on() == [4, 5, 6, 7, 36, 130]


def test_output_word_write_is_limited_to_existing_outputs():
    m = bare()                          # 64 outputs
    m.gvarset(7192, -1)                 # word 4 = outputs 128..159: none exist
    assert m.outputs_on() == []


def test_adc_registers():
    """7196..7203 ADC0..7."""
    m = bare('[[adc]]\nchannel = 0\nvalue = 11\n[[adc]]\nchannel = 7\nvalue = 77\n')
    assert [m.gvarget(7196 + ch) for ch in range(8)] == [11, 0, 0, 0, 0, 0, 0, 77]
    m.set_adc(3, 512)
    assert m.gvarget(7199) == 512
    assert m.sample_fields()["adc"] == (11, 0, 0, 512, 0, 0, 0, 77)
    m.gvarset(7196, 5)                  # read-only
    assert m.gvarget(7196) == 11


def test_dac_registers():
    """7270..7277 DAC0..7 (writes take effect at once, stored as written)."""
    m = bare()
    for ch in range(8):
        m.gvarset(7270 + ch, 100 * ch - 5)
    assert [m.gvarget(7270 + ch) for ch in range(8)] == [100 * ch - 5 for ch in range(8)]
    assert m.sample_fields()["dac"] == tuple(100 * ch - 5 for ch in range(8))


def test_pwm_registers():
    """7278..7285 PWM0..7 (writes take effect at once; the machine stores the value
    as written: the manual's PWM example clamps to 0..0xffff in PLC code)."""
    m = bare()
    for ch in range(8):
        m.gvarset(7278 + ch, 1000 + ch)
    assert [m.gvarget(7278 + ch) for ch in range(8)] == [1000 + ch for ch in range(8)]
    assert m.sample_fields()["pwm"] == tuple(1000 + ch for ch in range(8))
    m.gvarset(7278, 0x1FFFF)
    assert m.gvarget(7278) == 0x1FFFF
    assert not m.is_plain_register(7278)


def test_motion_code_idle_and_busy():
    """6060 (GVAR_CURRENT_MOTION_CODE): 0 while a move or jog that the PLC
    commanded is running, 0x4d when the motion controller is idle."""
    m = Machine()
    assert m.gvarget(6060) == 0x4D
    m.g0move(0, 1, 1000)
    codes = []
    for _ in range(400):
        codes.append(m.gvarget(6060))
        m.advance()
    assert codes[:2] == [0x4D, 0x4D]
    busy = [i for i, c in enumerate(codes) if c == 0]
    assert busy[0] == 2 and busy == list(range(2, busy[-1] + 1))
    assert codes[-1] == 0x4D
    # a jog too
    m.gvarset(8635, 1)
    m.advance(), m.advance()
    assert m.gvarget(6060) == 0
    m.gvarset(8635, 0)
    for _ in range(1000):
        m.advance()
    assert m.gvarget(6060) == 0x4D


def test_position_registers_x_to_c():
    """5021..5026 machine position X..C, 5041..5046 program position X..C."""
    m = Machine(parse_machine("""
[axes.X]
start = 1.5
offset = 1.0
[axes.Y]
start = -2
[axes.Z]
start = 3
offset = -4
[axes.A]
start = 90
[axes.B]
start = 5
[axes.C]
start = 6
offset = 6
"""))
    assert [m.gvarget(5021 + i) for i in range(6)] == [150, -200, 300, 9000, 500, 600]
    assert [m.gvarget(5041 + i) for i in range(6)] == [50, -200, 700, 9000, 500, 0]


def test_position_registers_all_nine_axes():
    """17001..17009 program and 17021..17029 machine position X,Y,Z,A,B,C,U,V,W,
    in 0.01 mm (0.01° for rotary axes)."""
    text = "".join(f"[axes.{a}]\nstart = {i + 1}\noffset = 0.5\n" for i, a in enumerate(abi.AXES))
    m = Machine(parse_machine(text))
    assert [m.gvarget(17021 + i) for i in range(9)] == [100 * (i + 1) for i in range(9)]
    assert [m.gvarget(17001 + i) for i in range(9)] == [100 * (i + 1) - 50 for i in range(9)]
    assert m.axis_positions() == {a: 100 * (i + 1) for i, a in enumerate(abi.AXES)}
    assert not m.is_plain_register(17029)
    m.gvarset(17021, 5)                 # read-only
    assert m.gvarget(17021) == 100


def test_unconfigured_axes_read_zero():
    m = Machine()
    assert m.gvarget(5024) == 0 and m.gvarget(17029) == 0
    assert m.axis_positions() == {"X": 10000, "Y": 10000, "Z": 2000}
    assert m.sample_fields()["axes"] == (10000, 10000, 2000, 0, 0, 0, 0, 0, 0)


def test_limit_switch_registers_read_back():
    """5521 = 1 disables hardware limits, 5525 = 1 disables software limits
    (the registers read back what was written)."""
    m = Machine()
    assert m.gvarget(5521) == 0 and m.gvarget(5525) == 0
    m.gvarset(5521, 1)
    m.gvarset(5525, 1)
    assert m.gvarget(5521) == 1 and m.gvarget(5525) == 1
    assert not m.is_plain_register(5521)


def test_5539_changes_nothing():
    """5539 is accepted and changes nothing."""
    a, b = Machine(), Machine()
    b.gvarset(5539, 1)
    for m in (a, b):
        m.g0move(0, 1, 5000)
        for _ in range(500):
            m.advance()
    assert a.axis_positions() == b.axis_positions()
    assert b.gvarget(5539) == 1


def test_plain_registers():
    """Every other address is a plain global register: it keeps what was written
    and reads 0 until written."""
    m = Machine()
    for addr in (0, 1, 100, 5000, 6061, 9121, 20000, 100020, 100040, 1 << 20, -5):
        assert m.gvarget(addr) == 0
        m.gvarset(addr, addr * 3 + 1)
        assert m.gvarget(addr) == addr * 3 + 1
        assert m.is_plain_register(addr)
    m.gvarset(9121, -7)
    assert m.gvarget(9121) == -7


def test_is_plain_register_marks_the_special_ones():
    """A host round-trip latency for gvarget of plain registers can be set: the
    machine says which addresses are plain."""
    m = Machine()
    special = ([0x400, 0x4FF, 6060, 5021, 5046, 17001, 17029, 5521, 5525, 8631, 8632, 8634, 8635]
               + abi.GVAR_HW_INPUTS + abi.GVAR_HW_OUTPUTS + list(range(7196, 7204))
               + list(range(7270, 7286)))
    assert not any(m.is_plain_register(a) for a in special)
    assert all(m.is_plain_register(a) for a in (5539, 8630, 7204, 7269, 7286, 0x3FF, 0x500))


def test_read_only_writes_warn_once():
    m = Machine()
    m.gvarset(6060, 1)
    m.gvarset(6060, 2)
    assert m.gvarget(6060) == 0x4D
    notes = m.advance()
    assert len(notes) == 1 and notes[0][0] == "warning" and "6060" in notes[0][1]


def test_manual_override_wins_over_wiring():
    """An input set by hand (a scenario, the IDE, the server) overrides the
    machine's own wiring of that pin from then on."""
    m = Machine()
    assert m.portget(INPUT_AIR) == 1
    m.set_input(INPUT_AIR, 0)
    assert m.portget(INPUT_AIR) == 0
    m.portset(OUTPUT_PLASMA)            # arc-OK wiring would turn pin 5 on...
    m.set_input(INPUT_ARC_OK, 0)        # ...but it is held at 0 by hand
    for _ in range(1000):
        m.advance()
    assert m.portget(INPUT_ARC_OK) == 0
    assert m.overrides() == {INPUT_ARC_OK: 0, INPUT_AIR: 0}
    m.clear_override(INPUT_ARC_OK)
    assert m.portget(INPUT_ARC_OK) == 1  # back to the wiring
    # a position switch held by hand stays held while the axis moves through it
    m.set_input(INPUT_HOME_Z, 0)
    m.gvarset(5525, 1)
    m.g0move(3, 4, -1000)
    run_until_idle(m)
    assert m.axis_positions()["Z"] == -1000 and m.portget(INPUT_HOME_Z) == 0
    m.clear_override(INPUT_HOME_Z)
    assert m.portget(INPUT_HOME_Z) == 1


def test_sample_fields_shape_and_caching():
    m = Machine()
    s = m.sample_fields()
    keys = ("inputs", "outputs", "pwm", "dac", "adc", "axes", "velocities", "vio")
    assert set(s) == set(keys)
    assert [len(s[k]) for k in keys] == [8, 8, 8, 8, 8, 9, 9, 2]
    assert all(isinstance(v, tuple) and all(isinstance(x, int) for x in v) for v in s.values())
    m.advance()
    assert m.sample_fields() is s       # nothing changed: the same object
    m.portset(2)
    s2 = m.sample_fields()
    assert s2 is not s and s2["outputs"][0] == 4 and s["outputs"][0] == 0
    # what did not change is the same tuple (a sample is cheap to make again)
    assert s2["inputs"] is s["inputs"] and s2["velocities"] is s["velocities"]
    m.set_input(40, 1)
    m.g0move(0, 1, 100)
    for _ in range(30):
        m.advance()
    s3 = m.sample_fields()
    assert s3["outputs"] is s2["outputs"] and s3["inputs"][1] == 1 << 8
    assert s3["velocities"][0] != 0 and s3["velocities"] == tuple(
        round(v * 1000) for v in m.motion.vel)


def test_advance_counts_milliseconds_and_reset():
    m = Machine()
    for _ in range(5):
        assert m.advance() == []
    assert m.t_ms == 5
    m.portset(1)
    m.gvarset(1234, 5)
    m.set_input(9, 1)
    m.g0move(0, 1, 100)
    for _ in range(50):
        m.advance()
    m.reset()
    assert m.t_ms == 0 and m.outputs_on() == [] and m.gvarget(1234) == 0
    assert m.portget(9) == 0 and m.axis_positions()["X"] == 10000 and m.overrides() == {}


# ------------------------------------------------------------ scenarios
def run_until_idle(m: Machine, limit: int = 100000) -> list:
    notes = []
    for _ in range(3):
        notes += m.advance()
    while m.gvarget(6060) == 0:
        notes += m.advance()
        limit -= 1
        assert limit > 0
    return notes


def probe_like_the_manual(m: Machine, input_pin: int = INPUT_IHC, contact: int = 0):
    """The manual's plasma probing loop, one iteration a tick::

        g0moveA(0x0,0x4,0-30000);
        do { code=gvarget(6060); }while(code!=0);
        do{ code=gvarget(6060); sens=portget(INPUT_IHC);
            if (sens==0) { message=PLCCMD_LINE_STOP; code=1; };
        }while (code==0);
    """
    notes = []
    m.g0move(0x0, 0x4, 0 - 30000)
    while True:                                     # wait till motion starts
        code = m.gvarget(6060)
        notes += m.advance()
        if code == 0:
            break
        assert m.t_ms < 100
    contact_at = None
    while True:
        code = m.gvarget(6060)
        sens = m.portget(input_pin)
        message = 0
        if sens == contact:
            message = LINE_STOP
            code = 1
            contact_at = (m.t_ms, m.axis_positions()["Z"])
        if message:
            m.on_message(message)                   # sent at the end of the tick
        notes += m.advance()
        if code != 0:
            break
        assert m.t_ms < 60000
    notes += run_until_idle(m)
    return contact_at, notes


def test_probing_example_stops_on_contact():
    """The seed's probing example runs unchanged on the default machine: the
    move down stops (decelerating) when the IHC input reads 0 on contact."""
    m = Machine()
    assert m.portget(INPUT_IHC) == 1
    contact, notes = probe_like_the_manual(m)
    assert contact is not None
    t, z_contact = contact
    assert z_contact == -5000                       # the surface of the default machine
    z = m.axis_positions()["Z"]
    assert -5000 - 1000 < z < -5000                 # stopped a little below, decelerating
    assert m.gvarget(6060) == 0x4D
    assert m.portget(INPUT_IHC) == 0 and m.portget(INPUT_PROBE) == 1
    assert notes == []


def test_probing_without_contact_ends_at_soft_limit():
    """Nothing to touch (IHC held at 1 by hand): the move ends at the soft limit
    with a note, and the loop ends because the motion finished."""
    m = Machine()
    m.set_input(INPUT_IHC, 1)
    contact, notes = probe_like_the_manual(m)
    assert contact is None
    assert m.axis_positions()["Z"] == -15000
    assert any("soft limit" in text for _, text in notes)


def test_homing_example_finds_the_z_switch():
    """The seed's Z homing example (jog Z- until INPUT_HOME_Z reads 1, then Z+
    slowly until it reads 0, refreshing 8635 every 256 ms) runs unchanged on the
    default machine."""
    m = Machine()
    notes = []
    assert m.portget(INPUT_HOME_Z) == 0
    m.gvarset(8631, 50)
    m.gvarset(5539, 1)
    # find_home_z()
    m.gvarset(5521, 1)
    m.gvarset(5525, 1)
    m.gvarset(8631, 50)
    statez, speed, speed_slow = 0, 500, 100
    direction = 4 << 8
    m.gvarset(8634, (4 << 24) | speed)
    m.gvarset(8635, direction)
    timer = 0
    found_at = None
    while True:
        changed = 0
        if statez == 0:
            if m.portget(INPUT_HOME_Z) != 0:
                statez = 1
                found_at = m.axis_positions()["Z"]
                m.gvarset(8634, (4 << 24) | speed_slow)
                changed = 1
        if statez == 1:
            if m.portget(INPUT_HOME_Z) == 0:
                statez = 2
                changed = 1
        if changed:
            direction = 0
            if statez == 0:
                direction |= 4 << 8
            if statez == 1:
                direction |= 4
            m.gvarset(8635, direction)
        if (timer & 0xFF) == 0:
            m.gvarset(8635, direction)
        timer += 1
        ready = statez == 2
        notes += m.advance()
        if ready:
            break
        assert m.t_ms < 30000, "homing did not finish"
    m.gvarset(8635, 0)
    notes += run_until_idle(m)                      # wait_move()
    assert found_at == 0                            # the switch is active at Z <= 0
    z = m.axis_positions()["Z"]
    assert 0 < z < 20                               # just off the switch
    assert m.portget(INPUT_HOME_Z) == 0
    assert m.gvarget(6060) == 0x4D
    assert not [n for n in notes if n[0] != "info"]
    # 500 mm/min from Z 20 mm: about 2.4 s to the switch
    assert 2300 < timer < 4000


def test_homing_x_and_y_together():
    """Simultaneous homing (the manual: XY with the jog from PLC) finds both switches."""
    m = Machine()
    m.gvarset(8631, 100)
    m.gvarset(8634, (3 << 24) | 3000)
    state = {0: 0, 1: 0}
    direction = (1 | 2) << 8
    m.gvarset(8635, direction)
    timer = 0
    while not (state[0] == 2 and state[1] == 2):
        changed = False
        for ax in (0, 1):
            sens = m.portget(ax)
            if state[ax] == 0 and sens:
                state[ax] = 1
                m.gvarset(8634, ((1 << ax) << 24) | 100)
                changed = True
            elif state[ax] == 1 and not sens:
                state[ax] = 2
                changed = True
        if changed:
            direction = 0
            for ax in (0, 1):
                if state[ax] == 0:
                    direction |= (1 << ax) << 8
                if state[ax] == 1:
                    direction |= 1 << ax
            m.gvarset(8635, direction)
        if timer & 0xFF == 0:
            m.gvarset(8635, direction)
        timer += 1
        m.advance()
        assert timer < 20000
    m.gvarset(8635, 0)
    run_until_idle(m)
    pos = m.axis_positions()
    assert 0 < pos["X"] < 30 and 0 < pos["Y"] < 30


def test_plasma_arc_ok_follows_the_torch_output():
    """Inputs tied to outputs with a delay, such as an arc-OK sensor, so that
    plasma procedures really run: arc-OK reads 1 a while after OUTPUT_PLASMA."""
    m = Machine()
    delay = next(i.delay_ms for i in m.config.inputs if i.name == "INPUT_ARC_OK")
    m.portset(OUTPUT_PLASMA)
    seen = []
    for _ in range(delay + 5):
        seen.append(m.portget(INPUT_ARC_OK))
        m.advance()
    assert seen.index(1) == delay and seen[delay:] == [1] * 5
    m.portclear(OUTPUT_PLASMA)
    assert m.portget(INPUT_ARC_OK) == 0             # the arc goes out at once
    assert m.portget(INPUT_AIR) == 1                # air pressure OK by default


# ------------------------------------------------------------ quiet and cheap
def test_writing_an_output_its_current_value_keeps_the_machine_quiet():
    """An unchanged output write changes nothing, so an idle machine stays idle
    (advance() is then only a clock tick)."""
    m = bare()
    m.portset(7)
    m.advance()
    m.advance()
    assert m.quiet
    for _ in range(3):
        m.portset(7)                    # already on
        m.portclear(8)                  # already off
        assert m.quiet
        assert m.advance() == []
    assert m.outputs_on() == [7]
    m.portclear(7)                      # a real change on an unwired pin: still nothing to do
    assert m.outputs_on() == []


def test_an_output_that_a_sensor_follows_wakes_the_machine():
    """A changed output that an input follows after a delay must be advanced."""
    m = bare("[[inputs]]\npin = 40\noutput = 41\ndelay_ms = 3\n")
    for _ in range(3):
        m.advance()
    assert m.quiet
    m.portset(41)
    assert not m.quiet
    for _ in range(2):
        m.advance()
    assert m.portget(40) == 0
    m.advance()
    assert m.portget(40) == 1


def test_the_per_pin_lists_follow_the_bits():
    """in_levels and out_on (what the fast backend reads) always equal in_bits and
    out_bits, whichever way a pin changes, and stay the same list objects."""
    m = bare("[io]\ninputs = 100\noutputs = 256\n")
    ins, outs = m.in_levels, m.out_on

    def check():
        assert m.in_levels is ins and m.out_on is outs
        assert ins == [(m.in_bits >> k) & 1 for k in range(100)]
        assert outs == [bool((m.out_bits >> k) & 1) for k in range(256)]

    check()
    m.portset(3); m.portset(200); m.portclear(3); m.portclear(3)
    check()
    m.gvarset(7184, -1); m.gvarset(7195, 0x0F0F)
    check()
    m.set_input(5, 1); m.set_input(99, 1); m.set_input(5, 0)
    check()
    m.reset()
    check()
    assert not any(outs) and not any(ins)
