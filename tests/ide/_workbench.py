"""Fixtures for the tests of the workbench's features (navigation, build
insight, registers, help): a small project with a header of its own, a main
window on it, and a fake controller connection that records requests. The
pieces the main window's and the debugger's tests share are here too: the
recorded message boxes, the recording connection, the windows made and shut."""

from __future__ import annotations

from contextlib import contextmanager
from pathlib import Path

import pytest
from PySide6.QtCore import QObject, Qt, Signal
from PySide6.QtWidgets import QMainWindow, QMessageBox

from plcbuilder.ide.main_window import MainWindow
from plcbuilder.ide.settings import Settings

SB = QMessageBox.StandardButton

M03 = """// M03: spindle on
#include pins.h
#include mine.h

main()
{
  speed = eparam;
  pwm01 = speed;
  portset(MY_PIN);
  exit(99);
};
"""
M05 = """// M05: spindle off (MY_PIN in a comment is no reference)
#include mine.h

main()
{
  portclear(MY_PIN);
  exit(99);
};
"""
LONE = """#define MY_PIN 4
main()
{
  portset(MY_PIN);
  exit(99);
};
"""
MINE = "// mine.h: my pins\n#define MY_PIN 3\n"


def make_project(root: Path) -> Path:
    for d in ("hardware", "software", "include"):
        (root / d).mkdir(parents=True)
    (root / "hardware" / "M03.plc").write_text(M03)
    (root / "hardware" / "M05.plc").write_text(M05)
    (root / "hardware" / "LONE.plc").write_text(LONE)
    (root / "include" / "mine.h").write_text(MINE)
    return root


class Prompts:
    """Stands in for QMessageBox's static functions: records every prompt and
    answers from a queue (or with a safe default)."""

    def __init__(self, monkeypatch):
        self.calls = []
        self.answers = []
        for name, default in (("warning", SB.Discard), ("question", SB.No),
                              ("critical", SB.Ok), ("information", SB.Ok)):
            monkeypatch.setattr(QMessageBox, name, self._make(name, default))
        monkeypatch.setattr(QMessageBox, "about", lambda *a, **k: self.calls.append(("about", a[2])))

    def _make(self, name, default):
        def prompt(parent, title, text, *args, **kw):
            self.calls.append((name, title, text))
            return self.answers.pop(0) if self.answers else default
        return prompt

    def titles(self):
        return [c[1] for c in self.calls]


class RecordingConnection(QObject):
    """The controller connection's interface with no controller behind it: its
    signals, and each request named in VERBS recorded in ``calls``."""
    sig_connected = Signal(str)
    sig_disconnected = Signal(str)
    sig_state = Signal(object, int)
    sig_events = Signal(list)
    sig_samples = Signal(list)
    sig_error = Signal(str)
    VERBS = ("start_embedded", "connect_to", "upload", "start", "stop", "set_input",
             "set_adc", "set_speed", "reset", "shutdown")

    def __init__(self):
        super().__init__()
        self.calls = []
        self.connected = False
        self.embedded = True

    def __getattr__(self, name):
        if name in self.VERBS:
            return lambda *a: self.calls.append((name,) + a)
        raise AttributeError(name)


class FakeConnection(RecordingConnection):
    """A controller connection that records what it is asked, the register
    browser's request among it."""
    sig_registers = Signal(object)
    VERBS = RecordingConnection.VERBS + ("request_registers",)


def answer_no(monkeypatch) -> None:
    """Every message box (warning, question, critical, information) answers No, unseen."""
    for name in ("warning", "question", "critical", "information"):
        monkeypatch.setattr(QMessageBox, name, lambda *a, **k: SB.No)


@contextmanager
def windows(qtbot, settings: Settings, size: tuple[int, int] | None):
    """make(**kw): a shown MainWindow of this size (None: as it comes) on these
    settings (or kw's "settings"), with no controller and a 20 ms debounce
    unless kw says otherwise (``show=False``: not shown); every window made is
    shut down at the end."""
    made = []

    def make(**kw):
        kw.setdefault("start_controller", False)
        kw.setdefault("debounce_ms", 20)
        show = kw.pop("show", True)
        w = MainWindow(kw.pop("settings", settings), **kw)
        qtbot.addWidget(w)
        if size is not None:
            w.resize(*size)
        if show:
            w.show()
        made.append(w)
        return w
    yield make
    for w in made:
        w.shutdown()


def docked_run_panels(qtbot, connection, size: tuple[int, int], **kw):
    """RunPanels on ``connection`` (kw: RunPanels' own, as capacity) docked at
    the bottom of a plain main window of this size, shown: (window, panels)."""
    from plcbuilder.ide.panels import RunPanels    # pyqtgraph: only for who asks
    win = QMainWindow()
    qtbot.addWidget(win)
    panels = RunPanels(win, connection, **kw)
    for d in panels.docks():
        win.addDockWidget(Qt.DockWidgetArea.BottomDockWidgetArea, d)
    win.resize(*size)
    win.show()
    return win, panels


def settings_in(tmp_path: Path) -> Settings:
    return Settings(str(tmp_path / "config" / "settings.ini"))


@pytest.fixture
def settings(tmp_path):
    return settings_in(tmp_path)


@pytest.fixture
def prompts(monkeypatch):
    return Prompts(monkeypatch)


@pytest.fixture
def project(tmp_path):
    return make_project(tmp_path / "proj")


@pytest.fixture
def make_window(qtbot, tmp_path, prompts):
    with windows(qtbot, settings_in(tmp_path), (1300, 850)) as make:
        yield make


@pytest.fixture
def win(make_window, project, qtbot):
    w = make_window()
    w.open_project(project)
    settle(qtbot, w)
    return w


def settle(qtbot, w):
    qtbot.waitUntil(lambda: not w.busy(), timeout=10000)
    qtbot.wait(10)


def caret_on(ed, word: str, nth: int = 0) -> None:
    """Put the editor's caret inside the nth ``word`` of its text."""
    text = ed.text()
    i = -1
    for _ in range(nth + 1):
        i = text.index(word, i + 1)
    line = text.count("\n", 0, i) + 1
    col = i - (text.rfind("\n", 0, i) + 1) + 2
    ed.goto_line(line, col)
