"""A folder that is not a project is not opened silently: the IDE says so and
offers to make one there (issue 13, defect 7: it opened an empty tree, and Build
All wrote an empty image and said "Build succeeded")."""

from PySide6.QtWidgets import QMessageBox

from plcbuilder.project.model import looks_like_project
from tests.ide.test_main_window import (make_window, project, prompts, settings,  # noqa: F401
                                        settle, win)

SB = QMessageBox.StandardButton


def test_declining_leaves_the_folder_unopened_and_untouched(win, tmp_path, prompts):  # noqa: F811
    folder = tmp_path / "photos"
    folder.mkdir()
    (folder / "holiday.jpg").write_bytes(b"\xff\xd8")
    prompts.answers.append(SB.No)
    assert not win.open_project(folder)
    assert win.project is None
    kind, title, text = prompts.calls[-1]
    assert kind == "question" and title == "Open Project"
    assert "is not a PLC Builder project" in text and "plcbuilder.toml" in text
    assert sorted(p.name for p in folder.iterdir()) == ["holiday.jpg"]


def test_an_empty_folder_becomes_the_example_project(win, tmp_path, prompts, qtbot):  # noqa: F811
    folder = tmp_path / "fresh"
    folder.mkdir()
    prompts.answers.append(SB.Yes)
    assert win.open_project(folder)
    assert win.project is not None and win.project.root == folder.resolve()
    assert (folder / "hardware" / "M03.plc").is_file()
    assert "Create a new project there" in prompts.calls[-1][2]
    settle(qtbot, win)
    assert win.problems.counts() == (0, 0)


def test_a_folder_with_other_files_gets_the_missing_parts(win, tmp_path, prompts):  # noqa: F811
    folder = tmp_path / "mine"
    folder.mkdir()
    (folder / "notes.txt").write_text("keep me")
    prompts.answers.append(SB.Yes)
    assert win.open_project(folder)
    assert looks_like_project(folder)
    assert (folder / "notes.txt").read_text() == "keep me"
    assert {p.name for p in folder.iterdir()} >= {"hardware", "software", "include",
                                                   "plcbuilder.toml", "machine.toml"}
    assert (folder / "include" / "pins.h").is_file()


def test_a_project_opens_without_a_question(win, project, prompts):  # noqa: F811
    assert win.open_project(project)
    assert not [c for c in prompts.calls if c[0] == "question"]
