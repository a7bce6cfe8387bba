"""plcbuilder build PROJECT [--strict] [--quiet]."""

import pytest

from plcbuilder.cli.main import main
from plcbuilder.image import read_image


@pytest.fixture
def project(tmp_path, capsys):
    assert main(["new", str(tmp_path / "p")]) == 0
    capsys.readouterr()
    return tmp_path / "p"


def test_build_reports_every_procedure_and_writes_the_image(project, capsys):
    assert main(["build", str(project), "--color", "never"]) == 0
    out = capsys.readouterr().out
    assert f"{project}/hardware/M03.plc: ok: 0 errors, 0 warnings; hardware procedure M03, " in out
    assert "/512 bytes" in out and "/16384 bytes" in out
    assert "hardware total: " in out and "/8192 bytes (11 procedures)" in out
    assert f"wrote {project}/build/eeprom.rom" in out
    assert out.rstrip().splitlines()[-1].startswith("Build All ok: 13 procedures, 0 errors")
    assert read_image((project / "build" / "eeprom.rom").read_bytes()).get("M80")
    # unchanged procedures are not compiled again
    assert main(["build", str(project), "--color", "never"]) == 0
    out = capsys.readouterr().out
    assert "(unchanged)" in out and "(0 compiled, 13 unchanged)" in out
    assert f"up to date: {project}/build/eeprom.rom" in out


def test_errors_exit_1_and_keep_the_image(project, capsys):
    assert main(["build", str(project)]) == 0
    image = (project / "build" / "eeprom.rom").read_bytes()
    (project / "hardware" / "M08.plc").write_text("main()\n{\n  portset(3)\n};\n")
    capsys.readouterr()
    assert main(["build", str(project), "--color", "never"]) == 1
    out = capsys.readouterr().out
    assert f"{project}/hardware/M08.plc:3:" in out and "error:" in out
    assert "M08.plc: failed: 1 error" in out
    assert "not written: 1 error; the previous eeprom.rom is kept" in out
    assert out.rstrip().splitlines()[-1].startswith("Build All failed")
    assert (project / "build" / "eeprom.rom").read_bytes() == image


def test_quiet_prints_only_problems(project, capsys):
    m05 = project / "hardware" / "M05.plc"
    m05.write_text(m05.read_text().replace("pwm01=0;", "pwm01=0; spare=1;"))
    assert main(["build", str(project), "-q", "--color", "never"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0].startswith(f"{project}/hardware/M05.plc:") and "warning:" in out[0]
    assert out[-1].startswith("Build All ok: 13 procedures, 0 errors, 1 warning")
    assert not any("hardware total" in line or ": ok:" in line for line in out)


def test_strict(project, capsys):
    m03 = project / "hardware" / "M03.plc"
    m03.write_text(m03.read_text().replace("if (speed<0) {speed=0;};",
                                           "if (speed<0) {speed=0;} else {speed=speed;};"))
    assert main(["build", str(project)]) == 0
    assert main(["build", str(project), "--strict", "--color", "never"]) == 1
    assert "error:" in capsys.readouterr().out


def test_bad_project(tmp_path, capsys):
    assert main(["build", str(tmp_path / "nope")]) == 1
    assert "plcbuilder build: error:" in capsys.readouterr().err
    (tmp_path / "plcbuilder.toml").write_text("[limits]\nhw_proc = -1\n")
    assert main(["build", str(tmp_path)]) == 1
    err = capsys.readouterr().err
    assert f"{tmp_path}/plcbuilder.toml:2: limits.hw_proc: must be from 1 to" in err


def test_a_folder_that_is_not_a_project_is_refused_and_nothing_is_written(tmp_path, capsys,
                                                                         monkeypatch):
    """Issue 23 (Also) and 24.5: `plcbuilder build DIR` on a folder with no
    plcbuilder.toml, hardware/ or software/ said "Build All ok: 0 procedures"
    and wrote DIR/build/eeprom.rom (in any folder, / included)."""
    stray = tmp_path / "etc"
    stray.mkdir()
    (stray / "passwd").write_text("root:x:0:0\n")
    assert main(["build", str(stray), "--color", "never"]) == 1
    out, err = capsys.readouterr()
    assert f"plcbuilder build: error: {stray}: not a project: it has no plcbuilder.toml, " \
           "hardware/ or software/" in err
    assert "Build All ok" not in out
    assert sorted(p.name for p in stray.iterdir()) == ["passwd"]
    monkeypatch.chdir(stray)                       # the default: the current folder
    assert main(["build"]) == 1
    assert "not a project" in capsys.readouterr().err
    assert sorted(p.name for p in stray.iterdir()) == ["passwd"]


@pytest.mark.parametrize("marker", ["plcbuilder.toml", "hardware", "software"])
def test_any_one_mark_of_a_project_is_enough(tmp_path, capsys, marker):
    root = tmp_path / "p"
    root.mkdir()
    if marker.endswith(".toml"):
        (root / marker).write_text('name = "x"\n')
    else:
        (root / marker).mkdir()
    assert main(["build", str(root), "--color", "never"]) == 0
    assert (root / "build" / "eeprom.rom").is_file()
