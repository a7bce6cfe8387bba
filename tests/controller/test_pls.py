"""Programmable limit switches (SPEC §9, "softMC I/O"; controller/pls.py).

Each rule is run end to end: a hardware procedure moves axis X through a list of
positions (real moves of the simulated motion, both ways, with small moves around
a switch point for noise) and prints the PLS output after each move; every test
runs on both VM backends. The seed's examples are the positions 100; 100, 200;
100, 200, 400, 600; and 0, 10 repeated every 100 (here in mm)."""

from __future__ import annotations

import pytest

from plcbuilder.bytecode import softmc
from plcbuilder.controller.controller import Controller
from plcbuilder.controller.machine import Machine
from plcbuilder.controller.machine_config import ConfigError, parse_machine
from plcbuilder.controller.pls import count_at, level

from tests.controller._sim import BACKENDS, Note, Print, compile_proc, of, run_hw

AXIS_X = """
[axes.X]
rapid = 60000.0
accel = 20000.0
min = -1000.0
max = 2000.0
start = 0.0
"""


def machine(pls: str = "") -> object:
    return parse_machine(AXIS_X + pls, "machine.toml")


def tour(targets_mm, read: str, setup: str = "", between: dict | None = None) -> str:
    """A procedure that runs ``setup``, then moves X to each target (mm) and
    prints ``gvarget(read)`` after each move (print register 20000 + index).
    ``between`` maps an index to statements run before that move."""
    body = [setup]
    for i, t in enumerate(targets_mm):
        if between and i in between:
            body.append(between[i])
        body.append(f"  d = {round(t * 100)};\n  go();\n  gvarset({20000 + i}, gvarget({read}));")
    return ("go()\n{\n  g0moveA(0x3, 1, d);\n  timer = 3;\n  do { timer--; } while (timer > 0);\n"
            "  do { w = gvarget(GVAR_CURRENT_MOTION_CODE); } while (w != 0x4d);\n}\n\n"
            "main()\n{" + "\n".join(body) + "\n  exit(99);\n}\n")


def run_tour(config, targets_mm, read: str, backend: str, setup: str = "",
             between: dict | None = None):
    """(the printed values in order, the controller, the events)."""
    c = Controller(config, backend=backend)
    c.load([compile_proc(tour(targets_mm, read, setup, between))])
    c.start("M03")
    c.run_until_idle(60_000)
    events = c.drain_events()
    assert c.idle()
    return [p.value for p in of(events, Print)], c, events


OUT5 = "0x405"               # gvarget(0x400 + 5): the state of output 5


# ------------------------------------------------------------ the seed's examples
@pytest.mark.parametrize("backend", BACKENDS)
def test_one_switch_position(backend):
    """SPEC §9: "an increasing list of positions where the output toggles". The
    seed's first figure: one switch position at 100, the output turns on there
    (polarity 1) — crossed both ways, with noise right at the point."""
    cfg = machine('[[pls]]\naxis = "X"\noutput = 5\npositions = [100.0]\npolarity = 1\n'
                  'enabled = true\n')
    targets = [50, 150, 99.99, 100, 99.98, 100.01, 0]
    got, c, _ = run_tour(cfg, targets, OUT5, backend)
    assert got == [0, 1, 0, 1, 0, 1, 0]
    assert c.machine.outputs_on() == []


@pytest.mark.parametrize("backend", BACKENDS)
def test_second_position_turns_it_back_off(backend):
    """SPEC §9: "an output (physical or virtual), an increasing list of positions
    where the output toggles". The seed: "to have the PLS ... turn back off at 200,
    simply add a second position at 200" — here driving a virtual output."""
    cfg = machine('[[pls]]\naxis = "X"\nvout = 2\npositions = [100.0, 200.0]\n'
                  'polarity = 1\nenabled = true\n')
    targets = [150, 250, 199.99, 200.02, 120, 99, 200]
    got, c, _ = run_tour(cfg, targets, "VOUT_2", backend)
    assert got == [1, 0, 1, 0, 1, 0, 0]
    assert c.machine.vio.vouts_on() == []


@pytest.mark.parametrize("backend", BACKENDS)
def test_four_positions(backend):
    """SPEC §9: "an increasing list of positions where the output toggles". The
    seed: on at 100, off at 200, on again at 400, off again at 600; the axis
    goes out and comes back."""
    cfg = machine('[[pls]]\naxis = "X"\noutput = 5\npositions = [100, 200, 400, 600]\n'
                  'polarity = 1\nenabled = true\n')
    targets = [150, 300, 500, 700, 500, 300, 150, 50]
    got, _, _ = run_tour(cfg, targets, OUT5, backend)
    assert got == [1, 0, 1, 0, 1, 0, 1, 0]


@pytest.mark.parametrize("backend", BACKENDS)
def test_repeat_interval(backend):
    """SPEC §9: "a repeat interval". The seed's figure: on at 0, off at 10, with a
    repeat of 100 — so on again from 100 to 110, 200 to 210, and (going back
    below the first position) from -100 to -90."""
    cfg = machine('[[pls]]\naxis = "X"\noutput = 5\npositions = [0.0, 10.0]\nrepeat = 100.0\n'
                  'polarity = 1\nenabled = true\n')
    targets = [5, 15, 105, 110, 209.99, 150, 100, 99.99, -95, -89]
    got, _, _ = run_tour(cfg, targets, OUT5, backend)
    assert got == [1, 0, 1, 0, 1, 0, 1, 0, 1, 0]


def test_odd_positions_with_repeat_still_toggle_at_each_point():
    """SPEC §9: "an increasing list of positions where the output toggles" with
    "a repeat interval": with an odd number of positions each repetition starts
    with the other level, so every point toggles."""
    pts2 = [0]                                      # one position at 0, doubled units
    levels = [level(1, count_at(pts2, 2 * 100, 2 * x)) for x in (-50, 50, 150, 250)]
    assert levels == [0, 1, 0, 1]


# ----------------------------------------------------------------- polarity
@pytest.mark.parametrize("backend", BACKENDS)
def test_polarity_zero_inverts(backend):
    """SPEC §9: "an initial polarity". The seed: polarity is the output "after the
    PLS is enabled and when the axis is located between the first and second PLS
    positions"; 0 inverts the pattern."""
    cfg = machine('[[pls]]\naxis = "X"\noutput = 5\npositions = [100.0, 200.0]\n'
                  'polarity = 0\nenabled = true\n')
    got, _, _ = run_tour(cfg, [50, 150, 250, 150, 50], OUT5, backend)
    assert got == [1, 0, 1, 0, 1]


@pytest.mark.parametrize("backend", BACKENDS)
def test_enabled_off_the_first_segment(backend):
    """SPEC §9: "polarity when enabled off the first segment". The seed: "If the
    axis position (when the PLS is enabled) is not located within this segment,
    the output polarity is set ... according to the current position so that when
    the axis reaches the first segment, the output polarity is as indicated."
    Defined and enabled from a procedure with X at 300 (past both positions)."""
    setup = """
  gvarset(PLS1_AXIS, 0);
  gvarset(PLS1_OUTPUT, 5);
  gvarset(PLS1_COUNT, 2);
  gvarset(PLS1_POSITION, 10000);
  gvarset(PLS1_POSITION + 1, 20000);
  gvarset(PLS1_POLARITY, 1);"""
    enable = "  gvarset(PLS1_ENABLE, 1);\n  gvarset(20099, gvarget(0x405));"
    got, c, events = run_tour(machine(), [300, 150, 50, 150], OUT5, backend, setup,
                              between={1: enable})
    at_enable = [p.value for p in of(events, Print) if p.register == 20099]
    assert at_enable == [0]                        # off at 300, so that ...
    assert got == [0, 0, 1, 0, 1]                  # ... it is 1 in the first segment
    assert c.machine.gvarget(softmc.pls_base(1) + softmc.F_STATUS) == 0


# ---------------------------------------------------------------- hysteresis
@pytest.mark.parametrize("backend", BACKENDS)
def test_hysteresis_split_by_direction(backend):
    """SPEC §9: "hysteresis split half each way by the direction of motion". The
    seed: with a hysteresis h "each transition of PLS position is moved forward
    h/2 units for positive motion and backward h/2 units for negative motion".
    h = 0.1 mm at 100 mm: going up it turns on at 100.05, going down off below
    99.95; noise of ±0.04 mm around 100 changes nothing."""
    cfg = machine('[[pls]]\naxis = "X"\noutput = 5\npositions = [100.0]\nhysteresis = 0.1\n'
                  'polarity = 1\nenabled = true\n')
    targets = [99.9, 100.0, 100.04, 99.96, 100.04, 100.05,     # up: on at 100.05
               100.0, 99.96, 100.04, 99.95, 99.94,             # down: off below 99.95
               100.02, 99.98, 100.1]                           # noise, then up again
    got, _, _ = run_tour(cfg, targets, OUT5, backend)
    assert got == [0, 0, 0, 0, 0, 1,
                   1, 1, 1, 1, 0,
                   0, 0, 1]


@pytest.mark.parametrize("backend", BACKENDS)
def test_stopped_on_a_position_noise_changes_nothing(backend):
    """SPEC §9: "hysteresis split half each way by the direction of motion". The
    seed: "If the axis driving the PLS is stopped directly on a PLS position and
    the inherent noise on the axis is less than the hysteresis, the PLS state does
    not change due to this noise." Stopped on 200 coming from above, jittering."""
    cfg = machine('[[pls]]\naxis = "X"\noutput = 5\npositions = [100.0, 200.0]\n'
                  'hysteresis = 0.2\npolarity = 1\nenabled = true\n')
    jitter = [200.0, 200.09, 199.91, 200.05, 199.95, 200.0]
    got, _, _ = run_tour(cfg, [250] + jitter + [150], OUT5, backend)
    assert got == [0] + [0] * len(jitter) + [1]


# ------------------------------------------------------- enable and refusals
@pytest.mark.parametrize("backend", BACKENDS)
def test_change_while_enabled_is_refused(backend):
    """SPEC §9: "changeable only while disabled (a change while enabled is
    refused)". From a procedure the write changes nothing, PLS<k>_STATUS reads
    PLS_REFUSED_ENABLED and the run log has a warning; after disabling, the same
    write is taken (status PLS_OK)."""
    src = """
main()
{
  gvarset(PLS1_POSITION, 20000);
  var00 = gvarget(PLS1_STATUS);
  var01 = gvarget(PLS1_POSITION);
  gvarset(PLS1_POLARITY, 0);
  var02 = gvarget(PLS1_POLARITY);
  var03 = gvarget(0x405);
  gvarset(PLS1_ENABLE, 0);
  gvarset(PLS1_POSITION, 20000);
  var04 = gvarget(PLS1_STATUS);
  var05 = gvarget(PLS1_POSITION);
  var06 = gvarget(0x405);
  exit(99);
}
"""
    cfg = machine('[[pls]]\naxis = "X"\noutput = 5\npositions = [-50.0]\npolarity = 1\n'
                  'enabled = true\n')
    c, events = run_hw(src, 100, backend, machine_config=cfg)
    v = c.variables()["M03"]
    assert v["var00"] == softmc.PLS_STATUS["PLS_REFUSED_ENABLED"]
    assert (v["var01"], v["var02"], v["var03"]) == (-5000, 1, 1)
    assert (v["var04"], v["var05"]) == (softmc.PLS_STATUS["PLS_OK"], 20000)
    assert v["var06"] == 1                          # disabling leaves the output as it is
    notes = [n.text for n in of(events, Note)]
    at = str(softmc.pls_base(1) + softmc.F_POSITION)
    assert any(at in t and "refused" in t and "enabled" in t for t in notes)


@pytest.mark.parametrize("backend", BACKENDS)
def test_enable_with_non_increasing_positions_is_refused(backend):
    """SPEC §9: "an increasing list of positions" — "a PLS with non-increasing
    positions" is refused when a procedure enables it: it stays disabled, the
    output does not change, the status reads PLS_BAD_POSITIONS."""
    src = """
main()
{
  gvarset(PLS2_OUTPUT, PLS_VOUT + 1);
  gvarset(PLS2_COUNT, 3);
  gvarset(PLS2_POSITION, 100);
  gvarset(PLS2_POSITION + 1, 300);
  gvarset(PLS2_POSITION + 2, 300);
  gvarset(PLS2_ENABLE, 1);
  var00 = gvarget(PLS2_STATUS);
  var01 = gvarget(PLS2_ENABLE);
  gvarset(PLS2_POSITION + 2, 301);
  gvarset(PLS2_REPEAT, 150);
  gvarset(PLS2_ENABLE, 1);
  var02 = gvarget(PLS2_STATUS);
  gvarset(PLS2_REPEAT, 0);
  gvarset(PLS2_ENABLE, 1);
  var03 = gvarget(PLS2_STATUS);
  var04 = gvarget(PLS2_ENABLE);
  exit(99);
}
"""
    c, events = run_hw(src, 100, backend, machine_config=machine())
    v = c.variables()["M03"]
    bad = softmc.PLS_STATUS["PLS_BAD_POSITIONS"]
    assert (v["var00"], v["var01"]) == (bad, 0)
    assert v["var02"] == bad                        # spans 2.01 mm, repeat 1.5 mm
    assert (v["var03"], v["var04"]) == (0, 1)
    assert c.machine.vio.vouts_on() == [1]          # X at 0: below 1 mm, polarity 0 -> 1
    notes = [n.text for n in of(events, Note)]
    assert any("position 3 (300) is not above position 2 (300)" in t for t in notes)


@pytest.mark.parametrize("backend", BACKENDS)
def test_enable_needs_an_output_and_a_present_axis(backend):
    """SPEC §9: a PLS has "an axis, an output (physical or virtual)". The seed's
    defaults after a PLS is declared: "A single PLS position exists at 0. ...
    PLSREPEAT is set to 0. The hysteresis is set to 0." and it is disabled; the
    polarity is the seed's default, "The default value for polarity is 0". Without an output, or on an axis the machine lacks,
    enabling is refused (PLS_NOT_READY); out-of-range values are refused
    (PLS_BAD_VALUE)."""
    src = """
main()
{
  var00 = gvarget(PLS3_COUNT) * 1000 + gvarget(PLS3_POSITION) * 100
          + gvarget(PLS3_POLARITY) * 10 + gvarget(PLS3_REPEAT) + gvarget(PLS3_HYSTERESIS)
          + gvarget(PLS3_ENABLE);
  gvarset(PLS3_ENABLE, 1);
  var01 = gvarget(PLS3_STATUS);
  gvarset(PLS3_OUTPUT, 64);
  var02 = gvarget(PLS3_STATUS);
  gvarset(PLS3_OUTPUT, 9);
  gvarset(PLS3_AXIS, 2);
  gvarset(PLS3_ENABLE, 1);
  var03 = gvarget(PLS3_STATUS);
  gvarset(PLS3_AXIS, 0);
  gvarset(PLS3_ENABLE, 1);
  var04 = gvarget(PLS3_STATUS);
  var05 = gvarget(0x409);
  gvarset(PLS3_STATE, 0);
  var06 = gvarget(PLS3_STATUS);
  gvarset(PLS3_STATUS, 0);
  var07 = gvarget(PLS3_STATUS);
  exit(99);
}
"""
    c, _ = run_hw(src, 100, backend, machine_config=machine())
    v = c.variables()["M03"]
    st = softmc.PLS_STATUS
    assert v["var00"] == 1000                       # one position at 0, polarity 0, rest 0
    assert v["var01"] == st["PLS_NOT_READY"]        # no output yet
    assert v["var02"] == st["PLS_BAD_VALUE"]        # the machine has outputs 0..63
    assert v["var03"] == st["PLS_NOT_READY"]        # this machine has no Z
    assert (v["var04"], v["var05"]) == (0, 0)       # X at 0 is at the position: polarity 0
    assert v["var06"] == st["PLS_BAD_VALUE"]        # the state is read-only
    assert v["var07"] == 0                          # writing the status clears it


@pytest.mark.parametrize("backend", BACKENDS)
def test_disabled_pls_does_not_drive_its_output(backend):
    """SPEC §9: "enabled and disabled at run time". The seed: "After being
    defined, a PLS is disabled (output pattern is not generated)"; disabled again,
    the output stays as the PLS left it while the axis moves on."""
    cfg = machine('[[pls]]\naxis = "X"\noutput = 5\npositions = [100.0]\npolarity = 1\n')
    between = {2: "  gvarset(PLS1_ENABLE, 1);", 4: "  gvarset(PLS1_ENABLE, 0);"}
    got, _, _ = run_tour(cfg, [150, 50, 150, 50, 50, 150], OUT5, backend, between=between)
    assert got == [0, 0, 1, 0, 0, 0]


@pytest.mark.parametrize("backend", BACKENDS)
def test_several_pls_on_one_axis_and_a_procedure_in_between(backend):
    """SPEC §9: PLSs "defined in the machine file or from a procedure" — the seed
    allows "Multiple PLSs per axis"; between two switch points a procedure may
    write the output itself (the PLS writes only when its level changes)."""
    cfg = machine('[[pls]]\naxis = "X"\noutput = 5\npositions = [100.0]\npolarity = 1\n'
                  'enabled = true\n[[pls]]\naxis = "X"\nvout = 32\npositions = [50.0, 150.0]\npolarity = 0\n'
                  'enabled = true\n')
    read = "VOUT_WORD"
    between = {2: "  portclear(5);"}
    got, c, _ = run_tour(cfg, [75, 125, 175, 125], read, backend, between=between)
    assert got == [0, 0, -(1 << 31), 0]            # VOUT.32: 0 in [50, 150), 1 above
    assert c.machine.outputs_on() == []             # cleared by hand at 125 -> 175 ...
    rep = c.machine.pls.report()
    assert [(p["pls"], p["output"], p["state"]) for p in rep] == \
        [(1, "output 5", 1), (2, "VOUT.32", 0)]


def test_evaluated_after_motion_each_ms():
    """SPEC §2: "At the end of every tick: ... the motion controller advances 1
    ms"; a PLS is evaluated right after, so during a move its output changes in
    the very ms the position crosses the point."""
    m = Machine(machine('[[pls]]\naxis = "X"\noutput = 5\npositions = [10.0]\n'
                        'polarity = 1\nenabled = true\n'))
    m.g0move(0x3, 1, 2000)
    crossed = None
    for _ in range(2000):
        m.advance()
        if m.outputs_on() == [5] and crossed is None:
            crossed = m.motion.ipos[0]
        if m.outputs_on() == [5]:
            assert m.motion.ipos[0] >= 1000
        else:
            assert m.motion.ipos[0] < 1000
    assert crossed is not None and m.motion.ipos[0] == 2000


# ----------------------------------------------------------- the machine file
@pytest.mark.parametrize("text, line, words", [
    ('[[pls]]\naxis = "X"\noutput = 5\npositions = [1.0, 3.0, 2.0]\n', 11,
     "positions must increase: position 3"),
    ('[[pls]]\naxis = "X"\noutput = 5\npositions = [1.0, 1.001]\n', 11,
     "0.01 mm resolution"),
    ('[[pls]]\naxis = "Z"\noutput = 5\npositions = [1.0]\n', 9, "axis Z is not configured"),
    ('[[pls]]\naxis = "X"\noutput = 5\nvout = 1\npositions = [1.0]\n', 8,
     "exactly one of 'output'"),
    ('[[pls]]\naxis = "X"\nvout = 33\npositions = [1.0]\n', 10, "out of range"),
    ('[[pls]]\naxis = "X"\noutput = 1\npositions = [0.0, 20.0]\nrepeat = 10.0\n', 12,
     "not less than the repeat interval"),
    ('[[pls]]\naxis = "X"\noutput = 1\npositions = []\n', 11, "non-empty array"),
    ('[[pls]]\naxis = "X"\noutput = 1\npositions = [1.0]\nhysteresis = -1.0\n', 12,
     "out of range"),
    ('[[pls]]\naxis = "X"\noutput = 1\npositions = [1.0]\ncolour = 2\n', 12, "unknown key"),
])
def test_machine_file_errors_name_file_and_line(text, line, words):
    """SPEC §9: "an increasing list of positions where the output toggles"; a
    machine file with non-increasing positions (or another bad [[pls]]) is refused
    naming the file, the line and the key (issue 15, "Bad input")."""
    with pytest.raises(ConfigError) as exc:
        machine(text)
    err = exc.value
    assert err.file == "machine.toml" and err.line == line, str(err)
    assert words in str(err) and str(err).startswith(f"machine.toml:{line}: pls")


def test_no_limit_on_the_number_of_pls_or_of_positions():
    """SPEC §9: "There is no limit of the number of positions or PLSs that can be
    defined": neither is capped. 40 PLSs of 50 positions each in the machine file;
    PLS40's registers follow the layout (softMC register map: PLS k at
    31000000 + 100000·k)."""
    pos = ", ".join(str(float(i)) for i in range(1, 51))
    one = f'[[pls]]\naxis = "X"\noutput = 1\npositions = [{pos}]\n'
    m = Machine(machine(one * 40))
    assert len(m.config.pls) == 40
    b = softmc.pls_base(40)
    assert b == 31_000_000 + 100_000 * 40
    assert m.gvarget(b + softmc.F_COUNT) == 50
    assert m.gvarget(b + softmc.F_POSITION + 49) == 5000
    assert [p["pls"] for p in m.pls.report()] == list(range(1, 41))


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_procedure_defines_a_pls_past_the_eighth_with_many_positions(backend):
    """SPEC §9: PLSs "defined in the machine file or from a procedure" — "There is
    no limit of the number of positions or PLSs that can be defined": PLS 100
    with 200 positions (PLS100_* are names like PLS1_*), toggling every mm."""
    setup = """
  gvarset(PLS100_AXIS, 0);
  gvarset(PLS100_OUTPUT, 5);
  gvarset(PLS100_COUNT, 200);
  i = 0;
  do { gvarset(PLS100_POSITION + i, 1000 + 100 * i); i++; } while (i < 200);
  gvarset(PLS100_POLARITY, 1);
  gvarset(PLS100_ENABLE, 1);
  gvarset(20090, gvarget(PLS100_STATUS));"""
    got, c, events = run_tour(machine(), [10.5, 11.5, 209.5, 250], OUT5, backend, setup)
    assert [p.value for p in of(events, Print) if p.register == 20090] == [0]
    assert got[1:] == [1, 0, 0, 0]               # 200 points: even past the last one
    assert [p["pls"] for p in c.machine.pls.report()] == [100]


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_position_outside_the_count_is_refused(backend):
    """The seed: "A call to CREATEPLSDATA creates an array of n positions ... The
    array is 1-based and an error is generated if you attempt to access an index
    outside of the array bounds." COUNT is CreatePLSData; position COUNT + 1 is
    refused (PLS_OUT_OF_BOUNDS), and taken once COUNT covers it."""
    src = """
main()
{
  gvarset(PLS1_COUNT, 2);
  gvarset(PLS1_POSITION + 2, 500);
  var00 = gvarget(PLS1_STATUS);
  var01 = gvarget(PLS1_POSITION + 2);
  gvarset(PLS1_COUNT, 3);
  gvarset(PLS1_POSITION + 2, 500);
  var02 = gvarget(PLS1_STATUS);
  var03 = gvarget(PLS1_POSITION + 2);
  exit(99);
}
"""
    c, events = run_hw(src, 100, backend, machine_config=machine())
    v = c.variables()["M03"]
    assert (v["var00"], v["var01"]) == (softmc.PLS_STATUS["PLS_OUT_OF_BOUNDS"], 0)
    assert (v["var02"], v["var03"]) == (0, 500)
    assert any("positions 1..2" in n.text for n in of(events, Note))


@pytest.mark.parametrize("backend", BACKENDS)
def test_delete_pls_and_the_axis_name_query(backend):
    """The seed: "Delete a PLS to remove it from the system only when the PLS is
    disable" (``DeletePLS MyPLS``) and "Query the name of the axis driving the
    PLS: ? MyPLS.PLSAxisName returns the axis associated with the PLS (A1)."
    DELETE refuses an enabled PLS, removes a disabled one (it reads as newly
    declared again); AXISNAME reads the axis letter ('X' = 88, 'Y' = 89)."""
    src = """
main()
{
  gvarset(PLS2_AXIS, 1);
  var00 = gvarget(PLS2_AXISNAME);
  gvarset(PLS2_AXIS, 0);
  gvarset(PLS2_OUTPUT, 5);
  gvarset(PLS2_ENABLE, 1);
  gvarset(PLS2_DELETE, 1);
  var01 = gvarget(PLS2_STATUS);
  var02 = gvarget(PLS2_OUTPUT);
  gvarset(PLS2_ENABLE, 0);
  gvarset(PLS2_DELETE, 1);
  var03 = gvarget(PLS2_OUTPUT);
  var04 = gvarget(PLS2_AXISNAME);
  exit(99);
}
"""
    c, _ = run_hw(src, 100, backend, machine_config=machine())
    v = c.variables()["M03"]
    assert v["var00"] == ord("Y")
    assert (v["var01"], v["var02"]) == (softmc.PLS_STATUS["PLS_REFUSED_ENABLED"], 5)
    assert (v["var03"], v["var04"]) == (softmc.PLS_NO_OUTPUT, ord("X"))
    assert c.machine.pls.report() == []          # deleted: no longer in the system


def test_machine_file_pls_in_the_registers():
    """SPEC §9: PLSs "defined in the machine file" are PLS1.. of the registers, in
    the PLC's units (0.01 mm)."""
    m = Machine(machine('[[pls]]\nname = "cam"\naxis = "X"\nvout = 3\n'
                        'positions = [1.5, 2.25]\nrepeat = 5.0\nhysteresis = 0.02\n'
                        'polarity = 0\n'))
    b = softmc.pls_base(1)
    f = softmc.PLS_FIELDS
    got = {k: m.gvarget(b + off) for k, off in f.items()}
    assert got == {"ENABLE": 0, "AXIS": 0, "OUTPUT": softmc.PLS_VOUT + 3, "POLARITY": 0,
                   "REPEAT": 500, "HYSTERESIS": 2, "COUNT": 2, "STATE": 0, "STATUS": 0,
                   "DELETE": 0, "AXISNAME": ord("X"), "POSITION": 150}
    assert m.gvarget(b + f["POSITION"] + 1) == 225
    assert m.pls.report() == [{"pls": 1, "name": "cam", "axis": "X", "output": "VOUT.3",
                               "enabled": False, "state": 0}]


def _walk_reference(points, repeat, h, polarity, xs):
    """The seed's hysteresis rule, point by point: going up a point p is passed
    once x >= p + h/2, going down once x < p - h/2 (the points of a repeating
    pattern listed far enough each way)."""
    reach = 2000 // repeat + 2 if repeat else 0       # enough repetitions for |x| <= 1500
    pts = sorted({p + m * repeat for p in points for m in range(-reach, reach + 1)}) \
        if repeat else list(points)
    c = sum(1 for p in pts if p <= xs[0])
    offset = sum(1 for p in pts if p < points[0]) if repeat else 0
    out = []
    for x in xs[1:]:
        while c < len(pts) and 2 * x >= 2 * pts[c] + h:
            c += 1
        while c > 0 and 2 * x < 2 * pts[c - 1] - h:
            c -= 1
        out.append(level(polarity, c - offset))
    return out


@pytest.mark.parametrize("seed", range(6))
def test_random_noisy_walks_follow_the_rule(seed):
    """SPEC §9: "hysteresis split half each way by the direction of motion" with
    "a repeat interval" and "an initial polarity": random walks with noise around
    the switch points give, tick by tick, the output of the rule walked point by
    point."""
    import random

    from plcbuilder.controller.pls import Pls

    rng = random.Random(seed)
    points = sorted(rng.sample(range(-300, 300), rng.randint(1, 6)))
    repeat = rng.choice([0, points[-1] - points[0] + rng.randint(1, 200)])
    h = rng.choice([0, 1, 2, 7, 30])
    p = Pls(1)
    p.count, p.positions[:len(points)] = len(points), points
    p.repeat, p.hysteresis, p.polarity, p.target = repeat, h, rng.randint(0, 1), 0
    xs = [rng.randint(-500, 500)]
    for _ in range(3000):
        step = rng.choice([-3, -2, -1, 0, 1, 2, 3]) if rng.random() < 0.7 else \
            rng.randint(-40, 40)
        xs.append(max(-1500, min(1500, xs[-1] + step)))
    p.start(xs[0])
    got = []
    for x in xs[1:]:
        p.follow(x)
        got.append(p.state)
    assert got == _walk_reference(points, repeat, h, p.polarity, xs)


def test_the_default_polarity_is_0():
    """The seed: "The default value for polarity is 0." (also "PLSPOLARITY
    defaults to OFF" and "The default output state of a PLS is 0"; its one
    "The initial output polarity is 1" is not followed: docs/targets.md). A
    machine-file PLS without `polarity`, and one a procedure declares, read 0."""
    m = Machine(machine('[[pls]]\naxis = "X"\noutput = 5\npositions = [10.0]\n'))
    assert m.gvarget(softmc.pls_base(1) + softmc.F_POLARITY) == 0
    assert m.gvarget(softmc.pls_base(7) + softmc.F_POLARITY) == 0
    m.gvarset(softmc.pls_base(7) + softmc.F_OUTPUT, 6)
    assert m.gvarget(softmc.pls_base(7) + softmc.F_POLARITY) == 0
