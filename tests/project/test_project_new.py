"""plcbuilder new: the example project."""

from importlib import resources

import pytest

from plcbuilder.bytecode.program import Kind
from plcbuilder.project import Project, ProjectError, build_project, create_project

HW = ["M02", "M03", "M05", "M07", "M08", "M09", "M71", "M80", "M81", "M84", "OFF"]
SW = ["LUBE", "__HANDLER_INIT"]


def resource(*parts):
    ref = resources.files("plcbuilder")
    for p in parts:
        ref = ref / p
    return ref.read_bytes()


def test_new_project_layout(tmp_path):
    p = create_project(tmp_path / "router")
    assert isinstance(p, Project) and p.settings_found and p.name == "router"
    assert [x.name for x in p.procedures(Kind.HARDWARE)] == HW
    assert [x.name for x in p.procedures(Kind.SOFTWARE)] == SW
    assert (p.include_dir / "pins.h").read_bytes() == resource("resources", "include", "pins.h")
    assert p.machine_path.read_bytes() == resource("resources", "machine", "default.toml")
    assert p.variables_path.is_file()
    assert p.include_dirs() == (p.include_dir,)
    assert not p.build_dir.exists()
    assert [c.name for c in tmp_path.iterdir()] == ["router"]     # no temporary folder left


def test_new_project_name_and_empty_folder(tmp_path):
    (tmp_path / "empty").mkdir()
    p = create_project(tmp_path / "empty", "My table")
    assert p.name == "My table" and Project.open(tmp_path / "empty").name == "My table"


def test_new_refuses_to_overwrite(tmp_path):
    (tmp_path / "full").mkdir()
    (tmp_path / "full" / "keep.txt").write_text("mine")
    with pytest.raises(ProjectError, match="not empty"):
        create_project(tmp_path / "full")
    assert [c.name for c in (tmp_path / "full").iterdir()] == ["keep.txt"]
    (tmp_path / "f").write_text("")
    with pytest.raises(ProjectError, match="is a file"):
        create_project(tmp_path / "f")
    with pytest.raises(ProjectError, match="no such folder"):
        create_project(tmp_path / "missing" / "deeper")


def test_example_builds_cleanly_even_in_strict_mode(tmp_path):
    """Every example procedure compiles with no warning, also in --strict
    (controller compatibility): they would build for a real controller too."""
    p = create_project(tmp_path / "p")
    for strict in (False, True):
        r = build_project(p, strict=strict, use_cache=False)
        assert r.ok and r.all_diagnostics == [], [str(d) for d in r.all_diagnostics]
        assert r.hw_total <= 8192 and all(pb.size <= pb.limit for pb in r.procedures)


def test_example_machine_and_variables_load(tmp_path):
    machine_config = pytest.importorskip("plcbuilder.controller.machine_config")
    variables_xml = pytest.importorskip("plcbuilder.controller.variables_xml")
    p = create_project(tmp_path / "p")
    machine = machine_config.load_machine(p.machine_path)
    assert machine is not None
    assert variables_xml.load_variables(p.variables_path) == [0] * 16
