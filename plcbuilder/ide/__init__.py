"""The IDE (PySide6, Scintilla, pyqtgraph): ``plcbuilder gui``.

PySide6's import hook reads the source of every module imported after it;
:mod:`.pyside_imports` makes that quicker before anything else is imported;
:mod:`.pyqtgraph_qt` spares pyqtgraph's import from making every Qt class's
Python type, and :mod:`.pyqtgraph_parts` from loading the parts of pyqtgraph
the run panels do not use.

Start-up allocates tens of thousands of objects that live as long as the IDE
(modules, classes, Qt's wrappers and enums); with the default thresholds the
cyclic garbage collector walks them some eighty times before the window first
paints, which cost several percent of the start-up, and as many times again
(30 ms) while numpy and pyqtgraph load for the run panels. Until the run
panels are live (:func:`startup_done`), the youngest generation is collected
less often; then the usual thresholds come back.

numpy's linear algebra runs on one thread (below).
"""

import gc as _gc
import os as _os

import PySide6 as _PySide6  # noqa: F401 - loads PySide's import hook, made quicker here

from plcbuilder.ide.pyqtgraph_parts import install as _pyqtgraph_parts_on_demand
from plcbuilder.ide.pyqtgraph_qt import install as _pyqtgraph_on_demand
from plcbuilder.ide.pyside_imports import quick_source_check as _quick_source_check

_quick_source_check()
_pyqtgraph_on_demand()          # pyqtgraph's copy of Qt's names, made as it asks for them
_pyqtgraph_parts_on_demand()    # and its parts the run panels do not use, when asked for

# numpy (pyqtgraph's) starts OpenBLAS's threads at its import, one a core,
# which then spin for a while: the IDE does no linear algebra, and on a
# two-core machine they took a tenth of a second of the other core from the
# controller and the X server as the IDE started (a user's setting wins)
_os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

_THRESHOLDS = _gc.get_threshold()
_STARTUP_THRESHOLDS = (max(_THRESHOLDS[0], 50_000),) + tuple(_THRESHOLDS[1:])
_gc.set_threshold(*_STARTUP_THRESHOLDS)


def startup_done() -> None:
    """The IDE is up: the garbage collector's usual thresholds again (unless
    something else changed them meanwhile)."""
    if _gc.get_threshold() == _STARTUP_THRESHOLDS:
        _gc.set_threshold(*_THRESHOLDS)
