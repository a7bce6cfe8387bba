"""Help: the manual from docs/ in its own window (found from a checkout, or
where PLCBUILDER_DOCS says), links between chapters, and the keyboard
shortcuts list made from the window's real actions."""

from pathlib import Path

import pytest

from PySide6.QtCore import QUrl
from PySide6.QtGui import QKeySequence

from plcbuilder.ide import help as ide_help
from plcbuilder.ide.actions import Act
from tests.ide import _workbench

# the fixtures
make_window, project, prompts, win = (_workbench.make_window, _workbench.project,
                                      _workbench.prompts, _workbench.win)

DOCS = Path(__file__).resolve().parents[2] / "docs"


def test_the_manual_is_found_in_a_checkout_and_where_the_environment_says(monkeypatch,
                                                                          tmp_path):
    assert ide_help.find_docs() == DOCS
    (tmp_path / "ide.md").write_text("# Elsewhere\n")
    monkeypatch.setenv("PLCBUILDER_DOCS", str(tmp_path))
    assert ide_help.find_docs() == tmp_path


def test_f1_opens_the_manual_at_the_ide_chapter(win, qtbot):
    win.action(Act.MANUAL).trigger()
    hw = win.workbench.help_window
    qtbot.waitUntil(hw.isVisible)
    assert hw.current == DOCS / "ide.md"
    assert hw.headings()[0] == "The IDE"
    titles = [hw.list.item(i).text() for i in range(hw.list.count())]
    assert titles[0] == "The IDE" and len(titles) == len(list(DOCS.glob("*.md")))
    assert all("`" not in t for t in titles)
    assert win.action(Act.MANUAL) in win.menuBar().actions()[-1].menu().actions()


def test_links_open_chapters_at_their_headings(qtbot):
    hw = ide_help.HelpWindow(folder=DOCS)
    qtbot.addWidget(hw)
    hw.show()
    hw.open_named("ide")
    target = DOCS / "language.md"
    heading = hw_heading = None
    for line in target.read_text().splitlines():
        if line.startswith("## "):
            heading = line[3:].strip()
            break
    hw._on_link(QUrl(f"language.md#{ide_help.slug(heading)}"))
    assert hw.current == target
    hw_heading = hw.browser.textCursor().block().text()
    assert hw_heading == heading.replace("`", "")
    hw._on_link(QUrl("#the-ide"))
    assert hw.current == target                          # an anchor of the same chapter


def test_pictures_fit_the_window(qtbot):
    hw = ide_help.HelpWindow(folder=DOCS)
    qtbot.addWidget(hw)
    hw.resize(700, 500)
    hw.show()
    hw.open_named("ide")
    assert hw.fit_images() >= 1                         # ide.md has screenshots wider than 700


def _images(hw) -> list[tuple[str, float]]:
    """(file, width drawn) of every picture in the chapter on show, in order."""
    out = []
    block = hw.browser.document().begin()
    while block.isValid():
        it = block.begin()
        while not it.atEnd():
            fmt = it.fragment().charFormat()
            if fmt.isImageFormat():
                for _ in range(it.fragment().length()):
                    out.append((fmt.toImageFormat().name(), fmt.toImageFormat().width()))
            it += 1
        block = block.next()
    return out


@pytest.mark.parametrize("chapter", ["ide", "traces", "debugging"])
def test_each_picture_is_drawn_once_at_the_width_of_the_view(qtbot, chapter):
    """Issue 23 point 7: Help › Manual drew each screenshot as a grid of tiny
    overlapping copies (Qt's Markdown reader makes one picture per piece of
    its alt text, a long one on several lines made a dozen)."""
    import re
    text = (DOCS / f"{chapter}.md").read_text(encoding="utf-8")
    wanted = re.findall(r"!\[[^\]]*\]\(([^)\s]+)", text)
    assert wanted, f"{chapter}.md has no pictures"
    hw = ide_help.HelpWindow(folder=DOCS)
    qtbot.addWidget(hw)
    hw.resize(900, 600)
    hw.show()
    hw.open_named(chapter)
    got = _images(hw)
    assert [name for name, _w in got] == wanted
    widest = hw.browser.viewport().width() - 40
    assert all(0 < w <= widest for _n, w in got), got


def test_a_missing_manual_says_where_it_looked(qtbot, tmp_path, monkeypatch):
    monkeypatch.setattr(ide_help, "find_docs", lambda: None)
    hw = ide_help.HelpWindow()
    qtbot.addWidget(hw)
    assert "was not found" in hw.browser.toPlainText()


def test_the_shortcuts_list_is_made_from_the_actions(win, qtbot):
    dlg = win.workbench.show_shortcuts()
    qtbot.addWidget(dlg)
    keyed = [a for a in win._actions.values() if any(not k.isEmpty() for k in a.shortcuts())]
    assert dlg.table.rowCount() == len(keyed)
    by_action = {dlg.table.item(r, 0).text(): dlg.table.item(r, 1).text()
                 for r in range(dlg.table.rowCount())}
    native = QKeySequence.SequenceFormat.NativeText
    assert by_action["Go Back"] == QKeySequence("Alt+Left").toString(native)
    assert by_action["Find References"] == QKeySequence("Shift+F12").toString(native)
    assert by_action["Rename Symbol"] == QKeySequence("F2").toString(native)
    assert by_action["Build, Upload and Start"] == QKeySequence("Ctrl+R").toString(native)
    assert by_action["Build All"] == QKeySequence("Ctrl+B").toString(native)
    dlg.search.setText("rename")
    shown = [r for r in range(dlg.table.rowCount()) if not dlg.table.isRowHidden(r)]
    assert [dlg.table.item(r, 0).text() for r in shown] == ["Rename Symbol"]


def test_no_two_actions_share_a_key(win):
    seen = {}
    for name, act in win._actions.items():
        for k in act.shortcuts():
            if not k.isEmpty():
                assert k.toString() not in seen, (name, seen.get(k.toString()))
                seen[k.toString()] = name


def test_pictures_follow_the_width_of_the_view(qtbot):
    """On a real desktop the manual's pictures stayed 200 px wide: they were
    fitted when the window was resized, not when the view was (laid out after
    it; or the splitter beside the chapters dragged)."""
    from PySide6.QtWidgets import QSplitter
    hw = ide_help.HelpWindow(folder=DOCS)
    qtbot.addWidget(hw)
    hw.resize(1200, 700)
    hw.show()
    qtbot.waitExposed(hw)
    hw.open_named("ide")
    split = hw.findChild(QSplitter)
    for left in (600, 150, 400):
        split.setSizes([left, 1200 - left])
        qtbot.wait(50)
        widest = hw.browser.viewport().width() - 40
        widths = [w for _n, w in _images(hw)]
        assert widths and all(abs(w - widest) <= 2 for w in widths), (left, widest, widths)
