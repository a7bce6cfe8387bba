"""A broken define in a header: the procedures' errors say where the macro came
from, in the Problems panel and on hover, and the header is flagged in the
Problems panel and the project tree (issue 13, defect 6)."""

from plcbuilder.ide.editor import file_key
from tests.ide.test_main_window import (make_window, project, prompts, settings,  # noqa: F401
                                        settle, win)


def test_a_broken_define_flags_the_header_and_names_itself(win, project, qtbot):  # noqa: F811
    (project / "include" / "mine.h").write_text("// mine.h: my pins\n#define MY_PIN 3 +\n")
    win.open_project(project)
    settle(qtbot, win)
    qtbot.waitUntil(lambda: win.problems.counts()[0] >= 1, timeout=10000)
    items = win.problems.problem_items()
    by_group = {}
    for it in items:
        by_group.setdefault(it.parent().text(0), []).append(it.text(0))
    proc_rows = by_group.get("hardware/M05.plc", [])
    assert proc_rows and all("expanded from MY_PIN: #define MY_PIN 3 + (mine.h:2)" in t
                             for t in proc_rows), by_group
    assert any("MY_PIN (#define MY_PIN 3 +) gives an error where it is used" in t
               for t in by_group.get("include/mine.h", [])), by_group
    assert file_key(str(project / "include" / "mine.h")) in win.tree._problems
    # hovering the error in the procedure shows the note too
    ed = win.open_file(str(project / "hardware" / "M05.plc"))
    settle(qtbot, win)
    qtbot.waitUntil(lambda: any(d.related for _s, _e, d in ed._diag_ranges), timeout=10000)
    pos = next(start for start, _e, d in ed._diag_ranges if d.related)
    assert "note: mine.h:2: expanded from MY_PIN" in ed.hover_text_at(pos)
