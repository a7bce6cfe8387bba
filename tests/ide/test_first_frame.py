"""Issue 26.5: the first frame (plcbuilder.ide.first_frame).

Started with a project, the IDE first shows a plain window, where its own
will be, with the project's tree and the file that was in front; the main
window is made meanwhile and takes its place. Nothing typed meanwhile is
lost, closing the frame quits, and the frame needs none of the main window's
modules (nor the Qt namespace's 93 enum classes) before it paints.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
from PySide6.QtCore import Qt
from PySide6.QtWidgets import QApplication, QSplitter
from shiboken6 import isValid

from plcbuilder.ide import app as ide_app
from plcbuilder.ide.first_frame import FirstFrame, frame_title, session_files
from plcbuilder.ide.settings import Settings
from plcbuilder.project.new import create_project
from tests.ide import _workbench

prompts = _workbench.prompts            # (a fixture: the closing window's prompt answers Discard)

WAIT = 20_000
SMALL = (760, 540)


@pytest.fixture
def example(tmp_path):
    """(the example project's root, settings whose last session had M03 in
    front of LUBE)."""
    root = create_project(tmp_path / "ex", name="ex").root
    st = Settings(str(tmp_path / "s.ini"))
    st.add_recent_project(root)
    front = str(root / "hardware" / "M03.plc")
    st.save_session(root, [front, str(root / "software" / "LUBE.plc")], front)
    st.sync()
    return root, st


@pytest.fixture
def frames():
    """make(settings, root, **kw): a first frame; those still there at the
    end are closed (one that handed over is gone already)."""
    made = []

    def make(st, root, **kw) -> FirstFrame:
        f = FirstFrame(st, root, **kw)
        made.append(f)
        return f
    yield make
    for f in made:
        if isValid(f):
            f.close()
            f.deleteLater()


def _tree(frame) -> dict:
    """{group label: [item texts]} of the frame's tree, and the root's text."""
    root = frame.tree.topLevelItem(0)
    out = {"": [root.text(0)]}
    for i in range(root.childCount()):
        g = root.child(i)
        out[g.text(0)] = [g.child(k).text(0) for k in range(g.childCount())]
    return out


def test_the_frame_shows_the_projects_tree_tabs_and_front_file_read_only(qtbot, example, frames):
    root, st = example
    f = frames(st, root)
    tree = _tree(f)
    assert tree[""] == ["ex"]
    assert "M03" in tree["Hardware PLC"] and "M80" in tree["Hardware PLC"]
    assert tree["Software PLC"] == sorted(tree["Software PLC"]) and "LUBE" in tree["Software PLC"]
    assert tree["Headers"] == ["pins.h"]
    assert f.tree.currentItem().text(0) == "M03"           # the front file's procedure
    assert [f.tabs.tabText(i) for i in range(f.tabs.count())] == ["M03.plc", "LUBE.plc"]
    assert f.tabs.currentIndex() == 0
    # (every line of the file: the text is HTML's <pre>, which has no last empty line)
    assert f.text.toPlainText() == \
        (root / "hardware" / "M03.plc").read_text(encoding="utf-8").removesuffix("\n")
    assert f.text.isReadOnly()
    assert f.windowTitle() == "M03.plc[*] — ex — PLC Builder"
    assert f.statusBar().currentMessage() == "Opening ex…"
    assert [a.text() for a in f.menuBar().actions()] == \
        ["&File", "&Edit", "&Go", "&View", "&Build", "&Run", "&Debug", "&Help"]
    # no widget of its has a style sheet of its own: the start sets the light
    # theme's palette without setting their sheets again (app.apply_theme)
    from PySide6.QtWidgets import QWidget
    assert [w for w in [f, *f.findChildren(QWidget)] if w.styleSheet()] == []


def test_the_frames_menus_are_the_main_windows(qtbot, example, tmp_path, frames):
    from tests.ide._workbench import windows, settings_in
    root, st = example
    f = frames(st, root)
    with windows(qtbot, settings_in(tmp_path / "w"), (1300, 850)) as make:
        w = make()
        assert [a.text() for a in w.menuBar().actions()] == \
            [a.text() for a in f.menuBar().actions()]


def test_a_file_given_on_the_command_line_is_the_frames_front_file(qtbot, example, frames):
    root, st = example
    m05 = root / "hardware" / "M05.plc"
    f = frames(st, root, front=m05)
    assert f.current == str(m05)
    assert f.text.toPlainText() == m05.read_text(encoding="utf-8").removesuffix("\n")
    assert f.tabs.tabText(f.tabs.currentIndex()) == "M05.plc"


def test_files_gone_since_the_last_session_are_not_shown(qtbot, example, frames):
    root, st = example
    (root / "software" / "LUBE.plc").unlink()
    files, current = session_files(st, root)
    assert files == [str(root / "hardware" / "M03.plc")] and current == files[0]
    (root / "hardware" / "M03.plc").unlink()
    f = frames(st, root)
    assert f.current == "" and f.text.toPlainText() == "" and f.tabs.count() == 0
    assert f.windowTitle() == frame_title(None, "ex") == "ex — PLC Builder"


def test_a_folder_that_is_no_project_gives_an_empty_tree_not_an_error(qtbot, tmp_path, frames):
    st = Settings(str(tmp_path / "s.ini"))
    (tmp_path / "plain").mkdir()
    (tmp_path / "plain" / "plcbuilder.toml").write_text("name = [broken", encoding="utf-8")
    f = frames(st, tmp_path / "plain")
    tree = _tree(f)
    assert tree[""] == ["plain"] and tree["Hardware PLC"] == [] and tree["Headers"] == []


def _at(widget, window) -> tuple:
    p = widget.mapTo(window, widget.rect().topLeft())
    return (p.x(), p.y(), widget.width(), widget.height())


def test_the_window_keeps_where_its_tree_and_editors_were_when_it_closes(qtbot, example):
    from tests.ide._workbench import windows
    root, st = example
    with windows(qtbot, st, (1300, 850)) as make:
        w = make()
        w.open_project(root)
        qtbot.waitUntil(lambda: w.current_editor() is not None, timeout=WAIT)
        ed = w.current_editor()
        margins = sum(ed.marginWidthN(i) for i in range(5)) + ed.marginLeft()
        where = {"size": (w.width(), w.height()), "tree": _at(w.tree, w),
                 "editor": _at(w.editor_stack, w), "text": (margins, ed.textHeight(0))}
        assert margins > 20 and ed.textHeight(0) > 10
        w.close()
    assert Settings(st.qs.fileName()).frame_sketch() == where
    with windows(qtbot, st, (1300, 850)) as make:
        w = make()
        w.project_dock.hide()                  # no tree on screen: nothing to keep
        w.close()
    assert Settings(st.qs.fileName()).frame_sketch() is None


def test_the_frame_puts_the_tree_and_editor_where_the_window_had_them(qtbot, example, frames):
    root, st = example
    sketch = {"size": (1360, 860), "tree": (0, 70, 299, 289), "editor": (305, 54, 641, 514),
              "text": (69, 23)}
    st.save_frame_sketch(sketch)
    f = frames(st, root)                       # (no geometry kept: 1360x860)
    f.show()
    qtbot.waitExposed(f)
    assert _at(f.tree, f) == sketch["tree"] and _at(f.text.parentWidget(), f) == sketch["editor"]
    # the text starts where the editor's will, its lines as high as the editor's
    doc = f.text.document()
    assert f.text.viewportMargins().left() + doc.documentMargin() == 69
    block = doc.firstBlock()
    while block.isValid():
        assert block.blockFormat().lineHeight() == 23
        block = block.next()
    st.save_frame_sketch({k: v for k, v in sketch.items() if k != "text"})
    assert st.frame_sketch()["text"] == (0, 0)          # (kept by an older version: not known)


def test_without_a_sketch_of_that_size_the_frame_splits_itself(qtbot, example, frames):
    root, st = example
    st.save_frame_sketch({"size": (999, 555), "tree": (0, 60, 200, 400),
                          "editor": (205, 40, 700, 500)})
    f = frames(st, root)
    assert isinstance(f.centralWidget(), QSplitter)


@pytest.mark.parametrize("raw", ["size=1,2;tree=1,2,3;editor=1,2,3,4", "size=a,b;tree=1,2,3,4",
                                 "nonsense", "size=1,2;tree=1,2,-3,4;editor=1,2,3,4",
                                 "size=1,2;tree=1,2,3,4;editor=1,2,3,4;text=5"])
def test_a_damaged_sketch_is_none(tmp_path, raw):
    st = Settings(str(tmp_path / "s.ini"))
    st.qs.setValue("window/sketch", raw)
    assert st.frame_sketch() is None


def test_keys_typed_into_the_frame_go_to_the_editor_of_its_front_file(qtbot, example, frames,
                                                                      prompts):
    from tests.ide._workbench import windows
    root, st = example
    f = frames(st, root)
    f.show()
    qtbot.waitUntil(lambda: f.keys.watching, timeout=WAIT)
    qtbot.keyClicks(f.text, "xyz")
    qtbot.keyClick(f.text, Qt.Key.Key_S, Qt.KeyboardModifier.ControlModifier)
    assert f.text.toPlainText().startswith("// M03")        # the frame itself takes none
    assert [k[3] for k in f.keys.kept if k[3] and not k[2]] == ["x", "x", "y", "y", "z", "z"]
    m03 = root / "hardware" / "M03.plc"
    on_disk = m03.read_text(encoding="utf-8")
    with windows(qtbot, st, (1300, 850)) as make:
        w = make(show=False)
        w.show_when_made()
        w.open_project(root)
        f.hand_over(w)
        qtbot.waitUntil(lambda: not isValid(f) and w.isVisible(), timeout=WAIT)
        ed = w.editor_for(str(root / "hardware" / "M03.plc"))
        qtbot.waitUntil(lambda: ed.text().startswith("xyz// M03"), timeout=WAIT)
        assert w.current_editor() is ed
        # a command typed meanwhile is not run on the window (Ctrl+S: not saved), and says so
        assert m03.read_text(encoding="utf-8") == on_disk and w.is_modified(ed)
        assert w.statusBar().currentMessage() == \
            "Not run (typed while the window opened): Ctrl+S"


def test_a_window_shown_after_it_is_made_waits_for_its_paint_like_a_visible_one(
        qtbot, example):
    """With the frame, the main window opens the project before it is shown:
    what waits for a visible window's first paint (the project's check, the
    session's other editors, the tree's descriptions) waits all the same."""
    from tests.ide._workbench import windows
    root, st = example
    with windows(qtbot, st, (1300, 850)) as make:
        w = make(show=False)
        w.show_when_made()
        w.open_project(root)
        assert w._lint_due and w._editors_due is not None and w.tree.descriptions_held
        m03 = str(root / "hardware" / "M03.plc")
        assert [e.path for e in w.editors()] == [m03]
        # the open editor's own check waits too (a compile on the diagnostics
        # thread would take the interpreter from the window being made)
        qtbot.wait(400)
        assert w.lint.size_of(m03)[0] is None
        w.show()
        qtbot.waitUntil(lambda: len(w.editors()) == 2 and not w._lint_due, timeout=WAIT)
        qtbot.waitUntil(lambda: w.lint.size_of(m03)[0] is not None, timeout=WAIT)
        # the session's front editor has the keyboard, its other editors opened behind it
        assert w.current_editor() is w.editor_for(m03) and w.focusWidget() is w.editor_for(m03)


@pytest.mark.parametrize("frame", [False, True])
def test_the_front_editor_of_the_last_session_has_the_keyboard(qtbot, example, frame):
    """What the user types once the IDE is up goes to the file in front (it
    went nowhere until they clicked into it), with or without the first frame."""
    from tests.ide._workbench import windows
    root, st = example
    m03 = str(root / "hardware" / "M03.plc")
    with windows(qtbot, st, (1300, 850)) as make:
        w = make(show=not frame)
        if frame:
            w.show_when_made()
        w.open_project(root)
        if frame:
            w.show()
        qtbot.waitUntil(lambda: len(w.editors()) == 2 and w._editors_due is None, timeout=WAIT)
        w.activateWindow()
        qtbot.waitUntil(lambda: w.isActiveWindow(), timeout=WAIT)
        ed = w.editor_for(m03)
        assert w.current_editor() is ed and QApplication.focusWidget() is ed
        qtbot.keyClicks(QApplication.focusWidget(), "q")
        assert ed.text().startswith("q// M03")
        ed.undo()                           # (nothing to save at the end)
        assert not w.is_modified(ed)


#: ``plcbuilder gui --settings INI --no-controller`` (argv 1: INI), watched:
#: when the frame hands over, its geometry; once the window has painted and
#: the frame is gone, the window's geometry and project; then the window is
#: closed. Prints that and the command's exit status as JSON.
_COMMAND = r"""
import json, sys
from PySide6.QtCore import QTimer
from shiboken6 import isValid
from plcbuilder.ide import first_frame
seen = {}
hand_over = first_frame.FirstFrame.hand_over
def watched(self, win):
    seen["frame"] = list(self.geometry().getRect())
    hand_over(self, win)
    def watch():
        if win._after_paint_done and not isValid(self):
            seen["window"] = list(win.geometry().getRect())
            seen["project"] = str(win.project.root)
            seen["title"] = win.windowTitle()
            win.close()
        else:
            QTimer.singleShot(20, watch)
    QTimer.singleShot(0, watch)
first_frame.FirstFrame.hand_over = watched
from plcbuilder.cli.main import main
sys.argv[0] = "plcbuilder"
seen["status"] = main(["gui", "--settings", sys.argv[1], "--no-controller"])
print(json.dumps(seen))
"""


def _offscreen(tmp_path, width=1600, height=1000) -> dict:
    """The environment of a child process on an offscreen screen of this size."""
    conf = tmp_path / "screen.json"
    # (no window frames: where a frame would go is the window manager's business)
    conf.write_text(json.dumps({"windowFrameMargins": False,
                                "screens": [{"name": "screen", "x": 0, "y": 0, "width": width,
                                             "height": height, "logicalDpi": 96, "dpr": 1}]}),
                    encoding="utf-8")
    return {**os.environ, "QT_QPA_PLATFORM": f"offscreen:configfile={conf}"}


def test_the_command_starts_with_the_frame_and_the_window_takes_its_place(example, tmp_path):
    """``plcbuilder gui`` with a last project: the frame paints, the main
    window is made, shown where the frame is and the frame goes; closing the
    window ends the command with 0."""
    root, st = example
    r = subprocess.run([sys.executable, "-c", _COMMAND, st.qs.fileName()], capture_output=True,
                       text=True, timeout=120, cwd=str(tmp_path), env=_offscreen(tmp_path))
    assert r.returncode == 0, r.stderr
    seen = json.loads(r.stdout.splitlines()[-1])
    assert seen["status"] == 0 and seen["project"] == str(root)
    assert seen["window"] == seen["frame"], seen
    assert seen["title"] == "M03.plc[*] — ex — PLC Builder"


def test_with_the_preference_off_the_window_opens_without_the_frame(example, tmp_path):
    root, st = example
    st.save_preferences(st.preferences().with_changes(first_frame=False))
    st.sync()
    r = _closing(st, tmp_path, "count-frames")
    assert r.returncode == 0, r.stderr
    assert json.loads(r.stdout.splitlines()[-1]) == {"status": 0, "shown": [True], "made": True,
                                                     "frames": 0}


#: ``plcbuilder gui --settings INI --no-controller`` (argv 1: INI) with the
#: frame closed by the user (argv 2: "at-paint", before the main window is
#: made; "while-made", while it opens the project) or the main window failing
#: to be made ("broken"), or the frames made counted ("count-frames"); prints
#: the command's status and whether the main window was shown as JSON (an
#: exception ends the process as it would).
_CLOSING = r"""
import json, sys
from plcbuilder.ide import app as ide_app, first_frame
mode, shown, frames = sys.argv[2], [], []
if mode == "at-paint":
    painted_now = first_frame.FirstFrame._painted_now
    def close_first(self):
        self.close()
        painted_now(self)
    first_frame.FirstFrame._painted_now = close_first
elif mode == "while-made":
    open_window = ide_app._open_window
    def closing(app, settings, folder, file, start_controller, frame):
        from plcbuilder.ide.main_window import MainWindow
        opened = MainWindow.open_project
        def open_project(self, *a, **k):
            frame.close()
            return opened(self, *a, **k)
        MainWindow.open_project = open_project
        win = open_window(app, settings, folder, file, start_controller, frame)
        shown.append(win.isVisible())
        return win
    ide_app._open_window = closing
elif mode == "count-frames":
    from PySide6.QtCore import QTimer
    open_window = ide_app._open_window
    def counting(app, settings, folder, file, start_controller, frame):
        win = open_window(app, settings, folder, file, start_controller, frame)
        shown.append(win.isVisible())
        QTimer.singleShot(0, win.close)
        return win
    ide_app._open_window = counting
    made = first_frame.FirstFrame.__init__
    def init(self, *a, **k):
        frames.append(1)
        made(self, *a, **k)
    first_frame.FirstFrame.__init__ = init
else:
    def broken(*args):
        raise RuntimeError("no window today")
    ide_app._open_window = broken
from plcbuilder.cli.main import main
sys.argv[0] = "plcbuilder"
status = main(["gui", "--settings", sys.argv[1], "--no-controller"])
print(json.dumps({"status": status, "shown": shown,
                  "made": "plcbuilder.ide.main_window" in sys.modules,
                  **({"frames": len(frames)} if mode == "count-frames" else {})}))
"""


def _closing(st, tmp_path, mode: str):
    return subprocess.run([sys.executable, "-c", _CLOSING, st.qs.fileName(), mode],
                          capture_output=True, text=True, timeout=120, cwd=str(tmp_path),
                          env=_offscreen(tmp_path))


def test_closing_the_frame_before_the_window_is_made_quits_without_it(example, tmp_path):
    _root, st = example
    r = _closing(st, tmp_path, "at-paint")
    assert r.returncode == 0, r.stderr
    assert json.loads(r.stdout.splitlines()[-1]) == {"status": 0, "shown": [], "made": False}


def test_closing_the_frame_while_the_window_is_made_quits_without_showing_it(example, tmp_path):
    _root, st = example
    r = _closing(st, tmp_path, "while-made")
    assert r.returncode == 0, r.stderr
    assert json.loads(r.stdout.splitlines()[-1]) == {"status": 0, "shown": [False], "made": True}


def test_a_window_that_cannot_be_made_fails_the_command_as_without_the_frame(example, tmp_path):
    _root, st = example
    r = _closing(st, tmp_path, "broken")
    assert r.returncode == 1 and "RuntimeError: no window today" in r.stderr, r.stderr


def test_what_the_command_opens(example, tmp_path):
    root, st = example
    m05 = root / "hardware" / "M05.plc"
    assert ide_app._what_to_open(str(m05), st) == (root, m05)
    assert ide_app._what_to_open(str(root / "plcbuilder.toml"), st) == (root, None)
    assert ide_app._what_to_open(str(root), st) == (root, None)
    assert ide_app._what_to_open(None, st) == (root, None)          # the last project
    st.save_preferences(st.preferences().with_changes(open_last_project=False))
    assert ide_app._what_to_open(None, st) == (None, None)
    empty = Settings(str(tmp_path / "empty.ini"))
    assert ide_app._what_to_open(None, empty) == (None, None)


#: Launched with a project's settings (argv 1): at the frame's first paint,
#: which of the modules of argv 2 (JSON) are loaded and whether the Qt
#: namespace was resolved; printed as JSON.
_PROBE = r"""
import json, sys
import PySide6.QtCore as core
from plcbuilder.ide import first_frame
modules = json.loads(sys.argv[2])
orig = first_frame.FirstFrame._painted_now
def painted_now(self):
    print(json.dumps({"seen": sorted(m for m in modules if m in sys.modules),
                      "qt": "Qt" in core.__dict__, "text": bool(self.text.toPlainText())}),
          flush=True)
    import os
    os._exit(0)
first_frame.FirstFrame._painted_now = painted_now
from plcbuilder.cli.main import main
sys.argv[0] = "plcbuilder"
main(["gui", "--settings", sys.argv[1], "--no-controller"])
"""


def test_the_frame_paints_before_the_main_window_scintilla_or_the_qt_namespace(example, tmp_path):
    _root, st = example
    heavy = ["plcbuilder.ide.main_window", "pyside6_scintilla", "pygments", "lark", "numpy",
             "pyqtgraph", "plcbuilder.project.model", "plcbuilder.ide.editor.widget",
             "plcbuilder.link.client"]
    r = subprocess.run([sys.executable, "-c", _PROBE, st.qs.fileName(), json.dumps(heavy)],
                       capture_output=True, text=True, timeout=120,
                       cwd=str(Path(st.qs.fileName()).parent), env=_offscreen(tmp_path))
    assert r.returncode == 0, r.stderr
    seen = json.loads(r.stdout.splitlines()[-1])
    assert seen == {"seen": [], "qt": False, "text": True}, seen


def test_a_long_front_file_shows_its_start(qtbot, example, frames):
    from plcbuilder.ide import first_frame
    root, st = example
    m03 = root / "hardware" / "M03.plc"
    m03.write_text("".join(f"// line {i}\n" for i in range(5000)), encoding="utf-8")
    f = frames(st, root)
    shown = f.text.toPlainText().split("\n")
    assert len(shown) == first_frame.MAX_LINES and shown[0] == "// line 0"


def test_the_front_files_text_is_shown_as_it_is(qtbot, example, frames):
    root, st = example
    text = "main()\n{\n  if (a < b && c > d) {x=1;}; // <b>not bold</b> &amp;\n\ttab\n};\n"
    (root / "hardware" / "M03.plc").write_text(text, encoding="utf-8")
    f = frames(st, root)
    assert f.text.toPlainText() == text.removesuffix("\n")
