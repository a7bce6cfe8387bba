"""pyqtgraph's package with its parts loaded when first asked for
(ide/pyqtgraph_parts.py, issue 26.5): the run panels load 54 of its 145
modules, and the package, once asked for a name of another part, is what the
whole import would have made."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("PySide6")
pytest.importorskip("pyqtgraph")

ROOT = Path(__file__).resolve().parents[2]

#: What pyqtgraph's namespace holds, name by name (a description that two
#: processes can compare: the kind of value, where it was defined, its name),
#: and how many of its modules are loaded: argv 1 "whole" (pyqtgraph as it
#: comes) or "parts" (the IDE's). With "parts", also before anything asks for
#: a name of the other parts: the modules loaded, whether the rest is loaded,
#: and which of argv 2's names (JSON) the package lacks.
PROBE = r"""
import json, sys, types
import plcbuilder.ide
from plcbuilder.ide import pyqtgraph_parts
if sys.argv[1] == "whole":
    sys.meta_path[:] = [f for f in sys.meta_path if not isinstance(f, pyqtgraph_parts._Finder)]
import PySide6.QtWidgets
import pyqtgraph as pg
first = {}
if sys.argv[1] == "parts":
    first = {"modules": sorted(m for m in sys.modules if m.split(".")[0] == "pyqtgraph"),
             "rest": pyqtgraph_parts.rest_loaded(),
             "lacks": [n for n in json.loads(sys.argv[2]) if n not in vars(pg)]}
def describe(v):
    if isinstance(v, types.ModuleType):
        return "module " + v.__name__
    kind = type(v).__name__
    where = getattr(v, "__module__", None) if isinstance(v, (type, types.FunctionType)) else None
    return f"{kind} {where} {getattr(v, '__qualname__', '')}"
names = {n: describe(getattr(pg, n)) for n in dir(pg) if not n.startswith("__")}
print(json.dumps({"first": first, "names": names, "rest": pyqtgraph_parts.rest_loaded(),
                  "modules": len([m for m in sys.modules if m.split(".")[0] == "pyqtgraph"])}))
"""


def _used_names() -> list[str]:
    """Every ``pg.Name`` the IDE's code uses."""
    names = set()
    for f in (ROOT / "plcbuilder" / "ide").rglob("*.py"):
        if f.name == "pyqtgraph_parts.py":
            continue
        names |= set(re.findall(r"\bpg\.([A-Za-z_]\w*)", f.read_text(encoding="utf-8")))
    return sorted(names - {"exporters"})         # (imported where it is used)


def _probe(mode: str) -> dict:
    env = dict(os.environ, QT_QPA_PLATFORM="offscreen", PYQTGRAPH_QT_LIB="PySide6")
    p = subprocess.run([sys.executable, "-c", PROBE, mode, json.dumps(_used_names())],
                       capture_output=True, text=True, env=env, timeout=120, cwd=ROOT)
    assert p.returncode == 0, p.stderr
    return json.loads(p.stdout.strip().splitlines()[-1])


def test_the_package_once_asked_is_what_the_whole_import_makes():
    whole, parts = _probe("whole"), _probe("parts")
    # at first: what the IDE uses is there, and a third of the modules are loaded
    assert parts["first"]["lacks"] == [] and len(_used_names()) > 10
    assert parts["first"]["rest"] is False
    assert len(parts["first"]["modules"]) < whole["modules"] / 2, parts["first"]["modules"]
    assert "pyqtgraph.imageview" not in parts["first"]["modules"]
    # dir() loaded the rest: every name, the same value as the whole import's
    assert parts["rest"] is True and parts["modules"] == whole["modules"]
    differ = {n: (whole["names"].get(n), parts["names"].get(n))
              for n in set(whole["names"]) | set(parts["names"])
              if whole["names"].get(n) != parts["names"].get(n)}
    assert differ == {}
    assert len(whole["names"]) > 150


def test_a_name_of_another_part_loads_the_rest(monkeypatch):
    """In this process (the IDE's pyqtgraph): a name the first parts lack
    comes with the rest; a name no part has is an AttributeError; a module of
    the package is that module."""
    import plcbuilder.ide  # noqa: F401 - the parts' finder
    import pyqtgraph as pg
    from plcbuilder.ide import pyqtgraph_parts
    assert isinstance(pg.ImageView, type) and pg.ImageView.__module__.startswith("pyqtgraph.")
    assert pyqtgraph_parts.rest_loaded() or "ImageView" not in pyqtgraph_parts.FIRST
    with pytest.raises(AttributeError, match="no_such_name"):
        pg.no_such_name
    assert pg.debug is sys.modules["pyqtgraph.debug"]


def test_the_split_keeps_the_line_numbers_and_only_the_packages_own_imports():
    source = ("import os\nfrom .Qt import QtCore\nfrom .imageview import *\n"
              "from .widgets.RemoteGraphicsView import RemoteGraphicsView\n"
              "    from .imageview import *\nx = 1\n")
    from plcbuilder.ide.pyqtgraph_parts import split
    kept, later = split(source)
    assert kept.splitlines() == ["import os", "from .Qt import QtCore", "pass", "pass",
                                 "    from .imageview import *", "x = 1"]
    assert later == ["from .imageview import *",
                     "from .widgets.RemoteGraphicsView import RemoteGraphicsView"]


#: The IDE's main window on a project, a controller connection of its own
#: (tests/ide/_workbench.FakeConnection) sending one sample: once the run
#: panels have drawn it, every run dock's panel is made and shown, then a
#: trace of it is drawn in them. Prints whether pyqtgraph's other parts were
#: loaded by then, how many of its modules, and whether numpy's masked arrays.
_IDE_PROBE = r"""
import json, sys
from PySide6.QtCore import QTimer
from plcbuilder.controller import events as ev
from plcbuilder.ide import docks, pyqtgraph_parts
from plcbuilder.ide.app import create_application
from plcbuilder.ide.main_window import MainWindow, run_dock_panel
from plcbuilder.ide.settings import Settings
from plcbuilder.project.new import create_project
from tests.ide._workbench import FakeConnection
app = create_application()
conn = FakeConnection()
win = MainWindow(Settings(sys.argv[2]), connection=conn, start_controller=True)
win.resize(1400, 900)
win.show()
win.open_project(create_project(sys.argv[1]).root)
zeros = (0,) * 8
def sample(t):
    return ev.Sample(t_ms=t, running="", proc=t % 3, message=0, inputs=zeros, outputs=zeros,
                     pwm=zeros, dac=zeros, adc=zeros, axes=(0,) * 9, velocities=(0,) * 9)
def step(n=[0]):
    try:
        go(n)
    except BaseException:
        import traceback; traceback.print_exc()
        app.exit(1)
def go(n):
    n[0] += 1
    rp = win.run_panels
    if rp is not None:
        conn.sig_samples.emit([sample(n[0])])
        if rp.live and n[0] > 5:
            for spec in docks.DOCKS:
                if spec.run:
                    run_dock_panel(win, spec.key)
                    d = win.findChild(docks.QDockWidget, spec.name)
                    d.show(); d.raise_()
    if n[0] > 40:
        print(json.dumps({"live": bool(rp and rp.live), "rest": pyqtgraph_parts.rest_loaded(),
                          "numpy.ma": "numpy.ma" in sys.modules,
                          "modules": len([m for m in sys.modules
                                          if m.split(".")[0] == "pyqtgraph"])}))
        win.shutdown()
        app.quit()
    else:
        QTimer.singleShot(25, step)
QTimer.singleShot(0, step)
sys.exit(app.exec())
"""


def test_the_run_panels_all_shown_and_drawing_use_the_first_parts_only(tmp_path):
    env = dict(os.environ, QT_QPA_PLATFORM="offscreen", PYQTGRAPH_QT_LIB="PySide6")
    p = subprocess.run([sys.executable, "-c", _IDE_PROBE, str(tmp_path / "example"),
                        str(tmp_path / "settings.ini")], capture_output=True, text=True,
                       env=env, timeout=60, cwd=ROOT)
    assert p.returncode == 0, p.stderr
    out = json.loads(p.stdout.strip().splitlines()[-1])
    assert out["live"] is True
    assert out["rest"] is False, "a run panel asked pyqtgraph for a name of its other parts"
    assert out["modules"] < 70
    # (numpy's masked arrays load with np.unique: 18 ms on the way to live)
    assert out["numpy.ma"] is False
