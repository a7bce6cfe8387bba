"""The Trigger field belongs to the project: what was typed in one project's
trigger bar does not show in another opened after it, and each project's own
spec, pre/post and mode come back with it (kept in the IDE's settings)."""

from __future__ import annotations

from PySide6.QtCore import Qt

from tests.ide.test_docks_fit import prompts_off, runwin  # noqa: F401 - fixtures
from tests.ide.test_main_window import make_project


def _type(qtbot, field, text: str) -> None:
    field.setFocus()
    field.selectAll()
    qtbot.keyClick(field, Qt.Key.Key_Delete)
    qtbot.keyClicks(field, text)


def test_the_trigger_field_is_the_projects_own(runwin, qtbot, tmp_path):  # noqa: F811
    w, _conn = runwin
    a = w.project.root
    bar = w.run_panels.traces.bar
    assert bar.spec.text() == ""
    _type(qtbot, bar.spec, "out 7 rise")
    bar.pre.setValue(250)
    bar.mode.setCurrentIndex(bar.mode.findData("normal"))

    b = make_project(tmp_path / "other")
    assert w.open_project(b)
    assert bar.spec.text() == "" and bar.pre.value() == 100 and bar.post.value() == 500
    assert bar.mode.currentData() == "single" and not bar.arm.isChecked()
    _type(qtbot, bar.spec, "in 3 fall")

    assert w.open_project(a)
    assert (bar.spec.text(), bar.pre.value(), bar.mode.currentData()) == \
        ("out 7 rise", 250, "normal")
    assert w.open_project(b)
    assert (bar.spec.text(), bar.pre.value(), bar.mode.currentData()) == \
        ("in 3 fall", 100, "single")
    assert w.close_project()
    assert bar.spec.text() == ""
