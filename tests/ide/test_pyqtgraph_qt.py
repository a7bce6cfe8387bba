"""pyqtgraph's mirror of Qt filled on demand (ide/pyqtgraph_qt.py, issue 26.5):
pyqtgraph sees the same Qt through it, and its import no longer makes a
Python type for every Qt class."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

pytest.importorskip("PySide6")
pytest.importorskip("pyqtgraph")

PROBE = r"""
import json, os, sys
if sys.argv[1] == "on":
    import plcbuilder.ide                      # installs the mirrors
import PySide6.QtCore, PySide6.QtGui, PySide6.QtWidgets
made_before = {n: len(getattr(PySide6, n).__dict__) for n in ("QtCore", "QtGui", "QtWidgets")}
import pyqtgraph as pg
made_after = {n: len(getattr(PySide6, n).__dict__) for n in ("QtCore", "QtGui", "QtWidgets")}
own, same, missing = {}, 0, []
for n in ("QtCore", "QtGui", "QtWidgets"):
    src, mirror = getattr(PySide6, n), getattr(pg.Qt, n)
    for name in dir(src):
        if name.startswith("__"):
            continue
        if not hasattr(mirror, name):
            missing.append(f"{n}.{name}")
        elif getattr(mirror, name) is getattr(src, name):
            same += 1
    # what pyqtgraph put on its mirror itself (not PySide6's)
    own[n] = sorted(k for k, v in vars(mirror).items()
                    if not k.startswith(("__", "_mirror")) and getattr(src, k, object()) is not v)
print(json.dumps({"own": own, "same": same, "missing": missing,
                  "made": {n: made_after[n] - made_before[n] for n in made_after}}))
"""


def _probe(mode: str) -> dict:
    env = dict(os.environ, QT_QPA_PLATFORM="offscreen", PYQTGRAPH_QT_LIB="PySide6")
    p = subprocess.run([sys.executable, "-c", PROBE, mode], capture_output=True, text=True,
                       env=env, timeout=120)
    assert p.returncode == 0, p.stderr
    return json.loads(p.stdout.strip().splitlines()[-1])


def test_pyqtgraph_sees_the_same_qt_through_mirrors_filled_on_demand():
    plain, mirrored = _probe("off"), _probe("on")
    assert mirrored["missing"] == [] and plain["missing"] == []
    assert mirrored["same"] == plain["same"] > 600          # every PySide6 name, the same object
    assert mirrored["own"] == plain["own"]                   # and what pyqtgraph adds, as it adds it
    # the copy no longer looked up every class of QtWidgets (PySide6 keeps a
    # class in its module's dict once its Python type is made)
    assert mirrored["made"]["QtWidgets"] < plain["made"]["QtWidgets"] / 2, (plain, mirrored)
