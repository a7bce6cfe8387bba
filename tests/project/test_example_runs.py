"""Every procedure of the example project runs on the default machine and does
what it says (built with Build All, loaded from the image as a controller would)."""

import pytest

from plcbuilder.bytecode import abi
from plcbuilder.image import read_image
from plcbuilder.project import build_project, create_project

controller = pytest.importorskip("plcbuilder.controller.controller")
machine_config = pytest.importorskip("plcbuilder.controller.machine_config")
variables_xml = pytest.importorskip("plcbuilder.controller.variables_xml")
events = pytest.importorskip("plcbuilder.controller.events")

# pins.h
SPINDLE, CCW, MIST, FLOOD, PLASMA, LUBE, CHARGE_PUMP = 0, 1, 2, 3, 4, 5, 6
IHC, ARC_OK, AIR = 4, 5, 6


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    p = create_project(tmp_path_factory.mktemp("example") / "proj")
    r = build_project(p)
    assert r.ok
    return p, read_image(p.image_path.read_bytes())


@pytest.fixture
def fresh(built):
    """A controller that has just loaded the image (nothing has run yet)."""
    project, image = built
    c = controller.Controller(machine_config.load_machine(project.machine_path),
                              variables=variables_xml.load_variables(project.variables_path),
                              record_samples=False)
    c.load([p.program for p in image.procedures])
    return c


@pytest.fixture
def ctl(fresh):
    """... after its first software tick (__HANDLER_INIT has switched everything off)."""
    fresh.step(150)
    fresh.drain_events()
    return fresh


def run(c, name, eparam=0, limit_ms=60_000):
    """Start a hardware procedure and run until it ends; returns its events."""
    c.drain_events()
    c.start(name, eparam)
    t0 = c.t_ms
    seen = []
    while c.t_ms - t0 < limit_ms:
        c.step(10)
        seen += c.drain_events()
        ended = [e for e in seen if isinstance(e, events.Ended) and e.name == name]
        if ended:
            assert not [e for e in seen if isinstance(e, events.Fault)]
            return ended[0], seen
    raise AssertionError(f"{name} did not end within {limit_ms} ms")


def messages(seen):
    return [(e.message, e.command, e.parameter) for e in seen if isinstance(e, events.Message)]


def test_handler_init_and_lube(fresh):
    ctl = fresh
    ctl.step(1)
    seen = ctl.drain_events()
    ctl.step(200)
    seen += ctl.drain_events()
    prints = [(e.register, e.value, e.source) for e in seen if isinstance(e, events.Print)]
    assert prints == [(20000, 1, "__HANDLER_INIT")]
    assert CHARGE_PUMP in ctl.state().outputs
    assert LUBE in ctl.state().outputs          # LUBE pumps first ...
    ctl.step(3_000)
    assert LUBE not in ctl.state().outputs      # ... for 3 s ...
    ctl.step(57_000)
    assert LUBE in ctl.state().outputs          # ... every 60 s
    assert "LUBE" in ctl.state().software


def test_upload_then_start_m03_at_once_leaves_the_spindle_on(fresh):
    """__HANDLER_INIT "begins in the tick of the first load, before any procedure
    started at that same tick, so 'upload, then start M03 at once' leaves the
    spindle on"."""
    ended, _seen = run(fresh, "M03", 12000)
    assert ended.exit_code == 99
    fresh.step(500)
    st = fresh.state()
    assert SPINDLE in st.outputs and st.pwm[0] == 12000


def test_spindle(ctl):
    ended, seen = run(ctl, "M03", 12000)
    assert ended.exit_code == 99
    st = ctl.state()
    assert SPINDLE in st.outputs and CCW not in st.outputs and st.pwm[0] == 12000
    assert messages(seen) == [(abi.PLCCMD["PLCCMD_REPLY_TO_MYCNC"],
                               abi.PLC_MESSAGE["PLC_MESSAGE_SPINDLE_SPEED_CHANGED"], 12000)]
    assert st.proc == abi.PROC["plc_proc_spindle"]
    run(ctl, "M03", 0x12345)                       # clamped to 0xffff
    assert ctl.state().pwm[0] == 0xFFFF
    ended, seen = run(ctl, "M05")
    st = ctl.state()
    assert ended.exit_code == 99 and SPINDLE not in st.outputs and st.pwm[0] == 0
    assert messages(seen)[0][2] == 0 and st.proc == 0


def test_coolant(ctl):
    assert run(ctl, "M07")[0].exit_code == 99
    assert MIST in ctl.state().outputs
    run(ctl, "M08")
    assert {MIST, FLOOD} <= set(ctl.state().outputs)
    run(ctl, "M09")
    assert not {MIST, FLOOD} & set(ctl.state().outputs)


@pytest.mark.parametrize("name, left_on", [("M02", {LUBE, CHARGE_PUMP}), ("OFF", {CHARGE_PUMP})])
def test_everything_off(ctl, name, left_on):
    for n, e in (("M03", 5000), ("M07", 0), ("M08", 0), ("M71", 0)):
        run(ctl, n, e)
    assert {SPINDLE, MIST, FLOOD, PLASMA} <= set(ctl.state().outputs)
    ended, _ = run(ctl, name)
    st = ctl.state()
    assert ended.exit_code == 99 and set(st.outputs) == left_on
    assert st.pwm[0] == 0 and st.proc == abi.PROC["plc_proc_idle"]


def test_stop_button_runs_m02_then_off(ctl):
    run(ctl, "M07")
    assert ctl.stop() == "M02"
    ctl.step(20)
    assert MIST not in ctl.state().outputs
    assert ctl.stop() == "OFF"


def test_z_homing(ctl):
    assert ctl.state().axes["Z"] == 2000        # the default machine starts at Z 20 mm
    ended, _ = run(ctl, "M80")
    st = ctl.state()
    assert ended.exit_code == 99
    assert 0 < st.axes["Z"] < 100               # just off the switch (active at Z <= 0)
    assert 2 not in st.inputs                   # INPUT_HOME_Z released
    assert st.proc == 0


def test_probing(ctl):
    ended, seen = run(ctl, "M81")
    assert ended.exit_code == 99
    assert abi.PLCCMD["PLCCMD_LINE_STOP"] in [m[0] for m in messages(seen)]
    z = ctl.state().axes["Z"]
    assert -5600 < z <= -5000                      # the surface is at Z -50 mm


def test_probing_without_a_surface_fails(ctl):
    ctl.set_input(IHC, 1)                          # never touches
    ended, seen = run(ctl, "M81")
    assert ended.exit_code == abi.EXIT["plc_exit_probe_error"]
    assert abi.PLC_MESSAGE["PLC_MESSAGE_ERR_PROBING"] in [m[0] for m in messages(seen)]


def test_plasma_start(ctl):
    ended, seen = run(ctl, "M71")
    assert ended.exit_code == 99 and PLASMA in ctl.state().outputs
    assert abi.PLC_MESSAGE["PLC_MESSAGE_PLASMA_OK"] in [m[0] for m in messages(seen)]
    assert ctl.state().proc == abi.PROC["plc_proc_cutting"]


def test_plasma_timeout(ctl):
    ctl.set_input(ARC_OK, 0)                       # the arc never comes
    t0 = ctl.t_ms
    ended, seen = run(ctl, "M71")
    assert ended.exit_code == abi.EXIT["plc_exit_plasma_timeout"] == 3
    assert ended.exit_name == "plc_exit_plasma_timeout"
    assert 3000 <= ended.t_ms - t0 <= 3010
    assert abi.PLC_MESSAGE["PLC_MESSAGE_ERR_PLASMA_TIMEOUT"] in [m[0] for m in messages(seen)]
    assert PLASMA not in ctl.state().outputs


def test_plasma_without_air(ctl):
    ctl.set_input(AIR, 0)
    ended, seen = run(ctl, "M71")
    assert ended.exit_code == abi.EXIT["plc_exit_gas_fail"]
    assert abi.PLC_MESSAGE["PLC_MESSAGE_ERR_SENSOR_AIR"] in [m[0] for m in messages(seen)]
    assert PLASMA not in ctl.state().outputs
