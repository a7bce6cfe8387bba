"""pyqtgraph's package, its parts loaded when first asked for.

``import pyqtgraph`` runs the package's ``__init__``, which imports every part
of the library into its namespace: image views, parameter trees, colour-map
widgets, views of a remote process and more, 145 modules. The run panels use
the plot items, the views and the functions: 54 of them. The others took
0.08-0.1 s of the 0.2 s the import took, on the way to the live run panels
(issue 26.5).

:func:`install` (called by ``plcbuilder.ide`` before anything imports
pyqtgraph) makes the package run its own code with only the imports of the
modules in :data:`FIRST`. The package loads the other parts the first time
it is asked for a name it does not have yet (``pg.ImageView``), or for its
``dir()``. Their names then join the package as the whole import would have
put them there. Only for PySide6 (the IDE's binding), and only for the
package's own ``from .module import ...`` lines: anything else it does runs
as it comes.

:func:`rest_loaded` says whether the other parts have been loaded.
"""

from __future__ import annotations

import importlib
import importlib.util
import re
import sys
import threading

from plcbuilder.ide.pyqtgraph_qt import spec_once

PACKAGE = "pyqtgraph"

#: The package's modules whose imports run with it: what the run panels use
#: (the plots, their items, the views, the functions, the colours).
FIRST = frozenset({
    "Qt", "colors", "colormap", "functions", "Point", "GraphicsScene",
    "graphicsItems.AxisItem", "graphicsItems.BarGraphItem", "graphicsItems.GraphicsItem",
    "graphicsItems.GraphicsLayout", "graphicsItems.GraphicsObject",
    "graphicsItems.GraphicsWidget", "graphicsItems.InfiniteLine", "graphicsItems.LabelItem",
    "graphicsItems.LegendItem", "graphicsItems.PlotCurveItem", "graphicsItems.PlotDataItem",
    "graphicsItems.PlotItem", "graphicsItems.ScatterPlotItem", "graphicsItems.TextItem",
    "graphicsItems.ViewBox",
    "widgets.GraphicsLayoutWidget", "widgets.GraphicsView", "widgets.PlotWidget",
})

#: One of the package's imports of its own modules, on a line of its own.
_OWN_IMPORT = re.compile(r"^from \.([\w.]+) import [\w, *]+$")

_lock = threading.RLock()
_later: list[str] = []            # the imports not run yet (empty once run)
_loaded_rest = [False]
_loading: list[bool] = []        # (while the imports run)


def split(source: str) -> tuple[str, list[str]]:
    """The package's source without the imports of its modules outside
    :data:`FIRST` (each such line becomes ``pass``, so that the line numbers
    stay), and those imports in their order."""
    kept, later = [], []
    for line in source.splitlines():
        m = _OWN_IMPORT.match(line)
        if m and m.group(1) not in FIRST:
            later.append(line)
            kept.append("pass")
        else:
            kept.append(line)
    return "\n".join(kept) + "\n", later


def rest_loaded() -> bool:
    """Whether the package's other parts have been loaded (or never held back)."""
    return _loaded_rest[0]


def load_rest(package) -> None:
    """Run the package's imports held back, once, in their order, as its own
    code would have (a name asked for meanwhile, by the parts being loaded,
    is what the imports before it made)."""
    with _lock:
        if _loaded_rest[0] or _loading:
            return
        _loading.append(True)
        try:
            for line in _later:
                exec(line, package.__dict__)       # noqa: S102 - the package's own lines
        finally:
            _loading.clear()
        package.__dict__.pop("__getattr__", None)
        package.__dict__.pop("__dir__", None)
        _later.clear()
        _loaded_rest[0] = True


def _module_getattr(package):
    def __getattr__(name: str):                    # noqa: N807 - a module's own
        if not name.startswith("__"):
            # a module of the package (``from . import debug``, asked for by
            # the import system first): that module, as the import makes it
            if importlib.util.find_spec(f"{package.__name__}.{name}") is not None:
                return importlib.import_module(f"{package.__name__}.{name}")
            load_rest(package)
            if name in package.__dict__:
                return package.__dict__[name]
        raise AttributeError(f"module {package.__name__!r} has no attribute {name!r}")

    def __dir__():                                 # noqa: N807
        load_rest(package)
        return sorted(package.__dict__)
    return __getattr__, __dir__


class _Finder:
    """Runs pyqtgraph's package with its first parts (once)."""

    def find_spec(self, name, path, target=None):
        if name != PACKAGE:
            return None
        spec = spec_once(self, name, path, target)
        if spec is None:
            return None
        loader = spec.loader
        get_source = getattr(loader, "get_source", None)
        source = get_source(name) if get_source is not None else None
        if source is None:
            _loaded_rest[0] = True
            return spec
        kept, later = split(source)
        if not later:
            _loaded_rest[0] = True
            return spec

        def exec_module(module):
            code = compile(kept, spec.origin, "exec", dont_inherit=True)
            with _lock:
                _later[:] = later
            module.__getattr__, module.__dir__ = _module_getattr(module)
            exec(code, module.__dict__)                # noqa: S102 - the package's own code
        loader.exec_module = exec_module
        return spec


def install() -> None:
    """Make the next import of pyqtgraph load its first parts only (a no-op
    when it is already imported)."""
    if PACKAGE in sys.modules or any(isinstance(f, _Finder) for f in sys.meta_path):
        if PACKAGE in sys.modules and not _later:
            _loaded_rest[0] = True
        return
    sys.meta_path.insert(0, _Finder())
