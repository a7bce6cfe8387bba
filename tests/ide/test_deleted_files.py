"""Problems of a file deleted from disk leave the Problems panel and the status
bar's count at once, not at the next Build All (issue 13, defect 5)."""

from PySide6.QtWidgets import QMessageBox

from tests.ide.test_main_window import (make_window, project, prompts, settings,  # noqa: F401
                                        settle, win)

BROKEN = "main()\n{\n  a = ;\n  exit(99);\n};\n"


def _files_with_problems(win) -> set:
    return {d.span.file.rsplit("/", 1)[-1] for d in win.lint.store.all() if d.span is not None}


def test_a_file_deleted_outside_the_ide_takes_its_problems_along(win, project, qtbot):  # noqa: F811
    bad = project / "hardware" / "M07.plc"
    bad.write_text(BROKEN)
    win.open_project(project)
    settle(qtbot, win)
    qtbot.waitUntil(lambda: "M07.plc" in _files_with_problems(win), timeout=10000)
    assert win.problems.counts()[0] >= 1
    assert "1 error" in win.status.problems_button.text()
    bad.unlink()                                     # a file manager, a terminal, git
    qtbot.waitUntil(lambda: "M07.plc" not in _files_with_problems(win), timeout=10000)
    settle(qtbot, win)
    assert win.problems.counts() == (0, 0)
    assert "0 errors" in win.status.problems_button.text()


def test_a_deleted_open_file_closed_takes_its_problems_along(win, project, qtbot,  # noqa: F811
                                                             prompts):  # noqa: F811
    bad = project / "hardware" / "M07.plc"
    bad.write_text(BROKEN)
    win.open_project(project)
    win.open_file(str(bad))
    settle(qtbot, win)
    qtbot.waitUntil(lambda: "M07.plc" in _files_with_problems(win), timeout=10000)
    prompts.answers.append(QMessageBox.StandardButton.No)      # do not keep it open
    bad.unlink()
    win.editor_stack.check_disk()
    qtbot.waitUntil(lambda: win.editor_stack.editor_for(str(bad)) is None, timeout=10000)
    qtbot.waitUntil(lambda: "M07.plc" not in _files_with_problems(win), timeout=10000)
    assert win.problems.counts() == (0, 0)


def test_problems_of_a_deleted_header_go_with_it(win, project, qtbot):  # noqa: F811
    header = project / "include" / "mine.h"
    header.write_text("#define MY_PIN 3 +\n")        # breaks every use in M05
    win.open_project(project)
    settle(qtbot, win)
    qtbot.waitUntil(lambda: win.problems.counts()[0] >= 1, timeout=10000)
    win.build_all()
    qtbot.waitUntil(lambda: not win.run_actions.build_runner.running(), timeout=20000)
    settle(qtbot, win)
    header.unlink()
    # M05 no longer finds mine.h: one problem about the missing include, not the old ones
    qtbot.waitUntil(lambda: all("MY_PIN" not in d.message or "include" in d.message
                                for d in win.lint.store.all()), timeout=10000)
    assert not any(d.span is not None and d.span.file.endswith("mine.h")
                   for d in win.lint.store.all())
