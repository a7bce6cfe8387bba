"""The project folder model and its settings file."""

import os
import stat

import pytest

from plcbuilder.bytecode.program import Kind
from plcbuilder.image import Limits
from plcbuilder.project import Project, ProjectError, Settings, parse_settings


def write(path, text):
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)
    return path


def test_missing_settings_means_defaults(tmp_path):
    root = tmp_path / "mill"
    root.mkdir()
    p = Project.open(root)
    assert not p.settings_found
    assert p.name == "mill" and p.limits == Limits() and p.settings.machine == "machine.toml"
    assert p.procedures() == [] and p.include_dirs() == ()
    assert p.image_path == root / "build" / "eeprom.rom"
    assert p.machine_path == root / "machine.toml"
    assert p.variables_path == root / "plc-variables.xml"


def test_open_the_settings_file_itself(tmp_path):
    sp = write(tmp_path / "plcbuilder.toml", 'name = "x"\n')
    assert Project.open(sp).root == tmp_path


def test_open_refuses_what_is_not_a_folder(tmp_path):
    with pytest.raises(ProjectError, match="no such folder"):
        Project.open(tmp_path / "nope")
    f = write(tmp_path / "file.plc", "")
    with pytest.raises(ProjectError, match="this is a file"):
        Project.open(f)


def test_settings_are_read(tmp_path):
    write(tmp_path / "plcbuilder.toml", """
name = "Plasma table"
machine = "machines/table.toml"

[limits]
hw_proc = 600
hw_total = 9000

[controller]
address = "192.168.0.10:5700"

[build]
strict = true
""")
    p = Project.open(tmp_path)
    assert p.settings_found and p.name == "Plasma table"
    assert p.limits == Limits(hw_proc=600, hw_total=9000, sw_proc=16384)
    assert p.settings.controller_address == "192.168.0.10:5700"
    assert p.settings.strict is True
    assert p.machine_path == tmp_path / "machines" / "table.toml"


@pytest.mark.parametrize("text, line, what", [
    ('name = "x"\nmachine = \n', 2, "not valid TOML"),
    ('name = "x"\n\n[limits]\nhw_proc = 600\nhw_totl = 5\n', 5, "unknown setting \\[limits\\] 'hw_totl'"),
    ('colour = "red"\n', 1, "unknown setting 'colour'"),
    ('name = "x"\n[limits]\nhw_proc = "512"\n', 3, "limits.hw_proc: must be a whole number"),
    ('[limits]\nsw_proc = 0\n', 2, "must be from 1 to"),
    ('[limits]\nhw_total = true\n', 2, "must be a whole number, is true or false"),
    ('name = "x"\n[controller]\naddress = "no port"\n', 3, "address must be HOST:PORT"),
    ('name = "x"\nlimits = 5\n', 2, r"\[limits\] must be a table"),
    ('[build]\nstrict = "yes"\n', 2, "build.strict: must be true or false"),
    ('machine = ""\n', 1, "machine must name a file"),
    ('name = "a"\nname = "b"\n', 2, "not valid TOML"),
])
def test_bad_settings_name_file_and_line(tmp_path, text, line, what):
    sp = write(tmp_path / "plcbuilder.toml", text)
    with pytest.raises(ProjectError, match=what) as info:
        Project.open(tmp_path)
    err = info.value
    assert err.file == str(sp) and err.line == line
    assert str(err).startswith(f"{sp}:{line}: ")


def test_settings_that_are_not_text(tmp_path):
    (tmp_path / "plcbuilder.toml").write_bytes(b'name = "x"\nmachine = "\xff"\n')
    with pytest.raises(ProjectError, match="not UTF-8") as info:
        Project.open(tmp_path)
    assert info.value.line == 2


def test_settings_round_trip_and_save(tmp_path):
    s = Settings(name='odd "name" \\ here', machine="m.toml", limits=Limits(500, 8000, 16000),
                 controller_address="localhost:5700", strict=True)
    assert parse_settings(s.to_toml()) == s
    p = Project.open(tmp_path)
    p.save_settings(s)
    assert Project.open(tmp_path).settings == s
    assert [n for n in os.listdir(tmp_path) if n.endswith(".tmp")] == []


def test_procedures_are_listed_by_kind_and_name(tmp_path):
    for rel in ("hardware/M05.plc", "hardware/M03.plc", "hardware/notes.txt",
                "hardware/.hidden.plc", "software/LUBE.plc", "software/__HANDLER_INIT.plc",
                "include/pins.h"):
        write(tmp_path / rel, "main(){exit(99);};\n")
    (tmp_path / "hardware" / "dir.plc").mkdir()
    p = Project.open(tmp_path)
    got = [(x.name, x.kind) for x in p.procedures()]
    assert got == [("M03", Kind.HARDWARE), ("M05", Kind.HARDWARE),
                   ("LUBE", Kind.SOFTWARE), ("__HANDLER_INIT", Kind.SOFTWARE)]
    assert [x.name for x in p.procedures(Kind.SOFTWARE)] == ["LUBE", "__HANDLER_INIT"]
    init = p.procedure("__HANDLER_INIT")
    assert init.system and init.path == tmp_path / "software" / "__HANDLER_INIT.plc"
    assert not p.procedure("M03").system
    assert p.procedure("M99") is None
    assert p.include_dirs() == (tmp_path / "include",)
    assert p.new_procedure_path("M04", Kind.HARDWARE) == tmp_path / "hardware" / "M04.plc"


def test_build_include_setting(tmp_path):
    from plcbuilder.project.model import ProjectError, Settings, parse_settings
    s = parse_settings('[build]\ninclude = ["../shared", "/opt/h"]\n')
    assert s.include == ("../shared", "/opt/h")
    assert parse_settings(s.to_toml()) == s
    assert parse_settings(Settings().to_toml()).include == ()
    for bad in ('[build]\ninclude = "x"\n', '[build]\ninclude = [1]\n',
                '[build]\ninclude = [""]\n'):
        with pytest.raises(ProjectError) as ei:
            parse_settings(bad)
        assert ei.value.key == "build.include" and ei.value.line == 2
    (tmp_path / "include").mkdir()
    (tmp_path / "shared").mkdir()
    (tmp_path / "plcbuilder.toml").write_text('[build]\ninclude = ["shared", "missing"]\n')
    p = Project.open(tmp_path)
    assert p.include_dirs() == (tmp_path / "include", tmp_path / "shared")
    assert p.compile_options(tmp_path / "hardware" / "M03.plc").root == tmp_path


def test_existing_refuses_a_folder_that_is_not_a_project(tmp_path):
    """Project.open accepts any folder (defaults); building and launching ask
    for existing=True, which names what is missing."""
    assert Project.open(tmp_path).root == tmp_path
    with pytest.raises(ProjectError) as err:
        Project.open(tmp_path, existing=True)
    assert str(err.value) == (f"{tmp_path}: not a project: it has no plcbuilder.toml, "
                              "hardware/ or software/ (plcbuilder new DIR makes one in a new "
                              "or empty folder)")
    (tmp_path / "software").mkdir()
    assert Project.open(tmp_path, existing=True).root == tmp_path
