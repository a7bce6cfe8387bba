"""Making a folder that holds other files a project (the IDE's offer when a
folder that is not a project is opened)."""

import pytest

from plcbuilder.project.model import Project, ProjectError, looks_like_project
from plcbuilder.project.new import init_project


def test_looks_like_project(tmp_path):
    assert not looks_like_project(tmp_path)
    assert not looks_like_project(tmp_path / "missing")
    (tmp_path / "software").mkdir()
    assert looks_like_project(tmp_path)


def test_init_project_adds_what_is_missing_and_keeps_the_rest(tmp_path):
    (tmp_path / "notes.txt").write_text("mine")
    (tmp_path / "include").mkdir()
    (tmp_path / "include" / "pins.h").write_text("#define MY_PIN 1\n")
    project = init_project(tmp_path, name="lathe")
    assert isinstance(project, Project) and project.name == "lathe"
    assert (tmp_path / "notes.txt").read_text() == "mine"
    assert (tmp_path / "include" / "pins.h").read_text() == "#define MY_PIN 1\n"
    assert (tmp_path / "hardware").is_dir() and (tmp_path / "software").is_dir()
    assert (tmp_path / "machine.toml").is_file()
    assert looks_like_project(tmp_path)
    assert project.procedures() == []
    again = init_project(tmp_path)                     # nothing to add: changes nothing
    assert again.name == "lathe"


def test_init_project_refuses_a_missing_folder(tmp_path):
    with pytest.raises(ProjectError, match="no such folder"):
        init_project(tmp_path / "nope")
