"""Projects for the targets of SPEC §9: the setting, its files, the examples."""

from __future__ import annotations

import pytest

from plcbuilder import api
from plcbuilder.project.model import ProjectError, Settings, parse_settings
from plcbuilder.project.parameters import load_parameters


def test_target_setting_defaults_to_mycnc_and_round_trips():
    """A project's settings name its `target`: `mycnc` (the default: §1–§3),
    `huazhong` or `tgmotion`."""
    assert parse_settings("").target == "mycnc"
    s = Settings(name="x", target="tgmotion", cycle_time_us=250,
                 program_periods_us=(100, 2000, 10_000), instruction_ns=5)
    again = parse_settings(s.to_toml())
    assert (again.target, again.cycle_time_us, again.program_periods_us, again.instruction_ns) \
        == ("tgmotion", 250, (100, 2000, 10_000), 5)
    assert "target" not in Settings(name="x").to_toml()      # a myCNC file is unchanged


@pytest.mark.parametrize("text,line,words", [
    ('name = "a"\ntarget = "fanuc"\n', 2, "unknown target 'fanuc'"),
    ('[tgmotion]\ncycle_time_us = 300\n', 2, "must be 250, 500 or 1000"),
    ('[tgmotion]\ncycle_time_us = 500\ncycle_time_program_02_us = 99\n', 3, "at least 100"),
    ('[tgmotion]\ninstruction_ns = 0\n', 2, "from 1 to 1000000"),
    ('[tgmotion]\ncycle_time_us = "500"\n', 2, "must be a whole number"),
    ('[huazhong]\nparameters = ""\n', 2, "must name a file"),
])
def test_bad_target_settings_name_file_and_line(text, line, words):
    """the project sets `cycle_time_us` (250, 500 or 1000) and
    `cycle_time_program_01_us` … `_03_us` (from 100)."""
    with pytest.raises(ProjectError) as info:
        parse_settings(text, "plcbuilder.toml")
    assert info.value.line == line and words in str(info.value)
    assert str(info.value).startswith(f"plcbuilder.toml:{line}: ")


def test_parameters_file(tmp_path):
    """`P[n]` (100 16-bit user parameters, from a project file)"""
    p = tmp_path / "parameters.toml"
    assert load_parameters(p) == [0] * 100                      # no file: all 0
    p.write_text("[P]\n0 = 5\n99 = 0xffff\n")
    vals = load_parameters(p)
    assert vals[0] == 5 and vals[99] == 65535 and sum(vals) == 65540
    for text, line, words in (("[P]\n0 = 1\n100 = 1\n", 3, "P[100] does not exist"),
                              ("[P]\n3 = 70000\n", 2, "from 0 to 65535"),
                              ("[P]\n3 = -1\n", 2, "from 0 to 65535"),
                              ("[Q]\n3 = 1\n", 1, "unknown table"),
                              ("[P]\n3 = \n", 2, "not valid TOML")):
        p.write_text(text)
        with pytest.raises(ProjectError) as info:
            load_parameters(p)
        assert info.value.line == line and words in str(info.value), str(info.value)


@pytest.mark.parametrize("target", ["huazhong", "tgmotion"])
def test_example_projects_build_run_and_pass_their_tests(tmp_path, target):
    """`plcbuilder new --target huazhong|tgmotion DIR` makes a working example
    project ... with tests (issue 15)."""
    project = api.create_project(tmp_path / target, target=target)
    assert project.target == target
    built = api.build_project(project)
    assert built.ok and built.image_written and not built.all_diagnostics
    run = api.run(project.root, api.RunOptions(ms=200))
    assert run.ok and run.report["faults"] == [] and run.report["target_profile"] == target
    tests = api.test(project.root, api.TestOptions(jobs=1))
    assert tests.exit_status == 0 and tests.run.failed == 0 and tests.run.passed >= 2


def test_one_program_in_hardware_and_no_software(tmp_path):
    """one source with `init()`, `plc1()` and `plc2()`"""
    project = api.create_project(tmp_path / "p", target="huazhong")
    (project.root / "hardware" / "zz.plc").write_text("init() { }\nplc1() { }\nplc2() { }\n")
    (project.root / "software").mkdir(exist_ok=True)
    (project.root / "software" / "LUBE.plc").write_text("main() { exit(99); }\n")
    built = api.build_project(project)
    problems = {pb.name: [d.message for d in pb.diagnostics if d.code == "target-project"]
                for pb in built.procedures}
    assert problems["plc"] == []
    assert "runs one program, plc.plc; this is a second one" in problems["zz"][0]
    assert "has no software PLC" in problems["LUBE"][0]
    assert not built.ok


def test_bad_parameters_file_stops_the_run(tmp_path):
    project = api.create_project(tmp_path / "p", target="huazhong")
    (project.root / "parameters.toml").write_text("[P]\n0 = 5\n7 = 99999\n")
    with pytest.raises(api.UsageError) as info:
        api.run(project.root, api.RunOptions(ms=10))
    assert "parameters.toml:3:" in str(info.value)


def test_b_kept_across_runs_with_a_state_file(tmp_path):
    """`B[n]` (100 16-bit words kept across controller restarts)"""
    project = api.create_project(tmp_path / "p", target="huazhong")
    state = tmp_path / "state.json"
    counts = []
    for _ in range(3):
        rep = api.run(project.root, api.RunOptions(ms=5, state=state)).report
        counts.append(rep["registers"]["B"]["0"])
    assert counts == [1, 2, 3]
    state.write_text("{not json")
    with pytest.raises(api.UsageError):
        api.run(project.root, api.RunOptions(ms=5, state=state))


def test_coverage_of_a_target_program(tmp_path):
    """plcbuilder test --coverage reports the target program's lines that ran."""
    project = api.create_project(tmp_path / "p", target="huazhong")
    run = api.test(project.root, api.TestOptions(coverage=True, jobs=1))
    assert run.exit_status == 0
    (cov,) = run.run.coverage
    d = cov.to_dict()
    assert d["name"] == "plc" and d["covered"] == d["lines"] > 10 and d["percent"] == 100.0


def test_a_program_period_has_no_upper_bound():
    """`cycle_time_program_01_us` … `_03_us` (from 100; the seed: "100 μs to
    10 000 μs (the upper value is not limited)")"""
    s = parse_settings('[tgmotion]\ncycle_time_program_01_us = 20000\n'
                       'cycle_time_program_03_us = 1000000\n', "plcbuilder.toml")
    assert s.program_periods_us == (20000, 1000, 1000000)


def test_the_tgmotion_example_initialises_in_program_ini_and_has_a_slow_program(tmp_path):
    """Issue 27 items 1 and 2 in the example a user starts from: TG Motion's seed,
    "The execution length of this function is not limited" (Program_Ini clears the
    TGM_Data words it uses, more than the 100 000 instructions a cyclic call may
    run), and "100 μs to 10 000 μs (the upper value is not limited)" (Program_01,
    the housekeeping program, runs every 20 000 µs)."""
    project = api.create_project(tmp_path / "tg", target="tgmotion")
    assert project.settings.program_periods_us == (20000, 1000, 1000)
    src = (project.root / "hardware" / "Program.plc").read_text()
    assert "Program_Ini" in src and "TGM_CLEARED" in src
    rep = api.run(project.root, api.RunOptions(ms=100)).report
    assert rep["faults"] == [] and rep["calls"]["Program_Ini"] == 1
    ini = next(p for p in rep["procedures"] if p["name"] == "Program")
    assert ini["exit_code"] is None                   # the program runs on after Program_Ini
    assert rep["vars"]["Program"]["i"] == 16384       # it cleared 16384 words in one call
    assert rep["calls"]["Program_01"] in (4, 5)       # every 20 ms in 100 ms
    assert rep["calls"]["Program_02"] > 90            # the others every 1 ms


def test_the_huazhong_example_uses_a_typed_view(tmp_path):
    """Issue 27 item 5 in the example: the seed's views "都指向同一块内存" (all point
    to the same memory): plc2() sends the first 16 inputs to the CNC as one word
    through X_ui[0], inputs 0..7 being X[0] and 8..15 X[1]."""
    project = api.create_project(tmp_path / "hz", target="huazhong")
    assert "X_ui[0]" in (project.root / "hardware" / "plc.plc").read_text()
    rep = api.run(project.root, api.RunOptions(ms=100, inputs=("9=1@0", "0=1@0"))).report
    x = rep["registers"]["X"]
    word = int(x.get("0", 0)) | int(x.get("1", 0)) << 8
    assert word & 0x0201 == 0x0201 and int(rep["registers"]["G"]["2"]) == word
