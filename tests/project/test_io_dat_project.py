"""A project's IO.DAT and its PLSs reach every way a project runs: ``plcbuilder
run`` (its JSON), ``plcbuilder test``, and the controller server the IDE starts."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from plcbuilder import api
from plcbuilder.bytecode import softmc
from plcbuilder.link.server import make_controller

from tests.testing._proj import make_project

#: lights output 7 when input 20 reads 1, VOUT.2 when the DIP value is 0x5A
PRESET = """main()
{
  if (portget(20)) portset(7);
  if (gvarget(IO_DAT_DIP) == 0x5A) gvarset(VOUT_2, 1);
  exit(50 + portget(20));
};
"""

MACHINE = """
[axes.X]
rapid = 60000.0
accel = 20000.0
start = 0.0
[[pls]]
name = "cam"
axis = "X"
vout = 5
positions = [10.0, 20.0]
polarity = 1
enabled = true
"""

#: moves X to 15 mm: inside the PLS's first segment
MOVE = """main()
{
  g0moveA(0x3, 1, 1500);
  timer = 3;
  do { timer--; } while (timer > 0);
  do { w = gvarget(GVAR_CURRENT_MOTION_CODE); } while (w != 0x4d);
  exit(99);
};
"""


@pytest.fixture
def project(tmp_path):
    root = make_project(tmp_path / "p", procs={"PRESET": PRESET, "MOVE": MOVE})
    (root / "IO.DAT").write_text("DIP=0x5A\nINP=0x100000\n", encoding="ascii")
    return root


def test_run_presets_inputs_from_io_dat(project):
    """SPEC §9: "physical inputs preset from an `IO.DAT` file in the project
    (`INP=0xXX`, `DIP=0xXX` lines, as the seed shows)" — in ``plcbuilder run``,
    whose JSON lists the virtual outputs on (``vouts``)."""
    r = api.run(project, api.RunOptions(starts=["PRESET@0"], ms=100))
    assert r.ok
    rep = r.report
    assert [p["exit_code"] for p in rep["procedures"] if p["name"] == "PRESET"] == [51]
    assert 7 in rep["outputs"] and rep["vouts"] == [2]


def test_run_refuses_a_bad_io_dat(project):
    """SPEC §9: "physical inputs preset from an `IO.DAT` file in the project
    (`INP=0xXX`, `DIP=0xXX` lines, as the seed shows)"; a bad file is refused
    naming the file and the line (issue 15, "Bad input"): the run does not start."""
    (project / "IO.DAT").write_text("INP=0x01\nINP 3\n", encoding="ascii")
    with pytest.raises(api.UsageError) as exc:
        api.run(project, api.RunOptions(starts=["PRESET@0"], ms=100))
    assert str(exc.value).startswith(f"{project / 'IO.DAT'}:2: expected KEY=VALUE")


def test_run_json_has_pls_states(project):
    """SPEC §9: PLSs "defined in the machine file" run in ``plcbuilder run``; its
    JSON has their states (``pls``) and the virtual outputs they drive."""
    (project / "machine.toml").write_text(MACHINE, encoding="utf-8")
    r = api.run(project, api.RunOptions(starts=["MOVE@0"], machine=project / "machine.toml",
                                        ms=2000))
    rep = r.report
    assert rep["pls"] == [{"pls": 1, "name": "cam", "axis": "X", "output": "VOUT.5",
                           "enabled": True, "state": 1}]
    assert rep["vouts"] == [5]


def test_cli_run_json(project, tmp_path):
    """SPEC §5/§9: ``plcbuilder run PROJECT --json`` prints ``vouts``, ``vins`` and
    ``pls`` with the rest."""
    machine = tmp_path / "m.toml"
    machine.write_text(MACHINE, encoding="utf-8")
    out = subprocess.run([sys.executable, "-m", "plcbuilder", "run", str(project), "--json",
                          "--start", "MOVE@0", "--start", "PRESET@500", "--machine",
                          str(machine), "--ms", "1000"],
                         capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    rep = json.loads(out.stdout)
    assert rep["vouts"] == [2, 5] and rep["vins"] == []
    assert [(p["name"], p["state"]) for p in rep["pls"]] == [("cam", 1)]


def test_scenario_tests_see_io_dat(project):
    """SPEC §9: "physical inputs preset from an `IO.DAT` file in the project" —
    in ``plcbuilder test`` too."""
    (project / "tests").mkdir()
    (project / "tests" / "preset.toml").write_text(
        '[[test]]\nname = "preset"\nms = 50\nscenario = "start PRESET @ 0"\n'
        '[[test.expect]]\nat_end = true\nexit = { PRESET = 51 }\n'
        '[[test.expect]]\nat_end = true\noutputs_on = [7]\n', encoding="utf-8")
    run = api.test(project, api.TestOptions(jobs=1))
    assert run.run is not None and run.run.passed, run.run


def test_scenario_tests_refuse_a_bad_io_dat(project):
    """SPEC §9: "physical inputs preset from an `IO.DAT` file in the project";
    with a bad one ``plcbuilder test`` refuses, naming the file and the line."""
    (project / "IO.DAT").write_text("\n\nDIP=0x1FF\n", encoding="ascii")
    (project / "tests").mkdir()
    (project / "tests" / "t.toml").write_text(
        '[[test]]\nname = "t"\nms = 5\nscenario = "start PRESET @ 0"\n'
        '[[test.expect]]\nat_end = true\nexit = { PRESET = 51 }\n', encoding="utf-8")
    with pytest.raises(api.UsageError, match=r"IO\.DAT:3: DIP: 0x1FF is too wide"):
        api.test(project, api.TestOptions(jobs=1))


def test_the_ides_controller_gets_io_dat(project):
    """SPEC §9: "physical inputs preset from an `IO.DAT` file in the project" —
    in the controller the IDE starts (``plcbuilder
    controller --io-dat``, built by make_controller)."""
    c = make_controller(None, None, project / "IO.DAT")()
    assert 20 in c.machine.inputs_on()
    assert c.machine.gvarget(softmc.IO_DAT_DIP) == 0x5A


def test_run_generates_the_projects_io_dat(tmp_path):
    """The seed: "File IO.DAT is generated automatically if it does not exist on
    the flash disk": ``plcbuilder run`` of a project without one writes it next
    to plcbuilder.toml (the simulated controller's flash disk) and notes it."""
    root = make_project(tmp_path / "g", procs={"PRESET": PRESET})
    assert not (root / "IO.DAT").exists()
    r = api.run(root, api.RunOptions(starts=["PRESET@0"], ms=10))
    assert (root / "IO.DAT").read_text(encoding="ascii") == "DIP=0x00\nINP=0x000000\n"
    assert any("generated" in n["text"] for n in r.report["notes"])
    again = api.run(root, api.RunOptions(starts=["PRESET@0"], ms=10))
    assert not any("generated" in n["text"] for n in again.report["notes"])


def test_the_controller_server_generates_io_dat(tmp_path):
    """The controller the IDE starts (``plcbuilder controller --io-dat FILE``)
    generates a missing IO.DAT the same way."""
    p = tmp_path / "IO.DAT"
    make_controller(io_dat=p)
    assert p.read_text(encoding="ascii") == "DIP=0x00\nINP=0x000000\n"
