"""pyqtgraph's mirror of Qt, filled on demand.

pyqtgraph keeps its own ``pyqtgraph.Qt.QtCore``, ``QtGui`` and ``QtWidgets``
modules, and when it is imported it copies every name of PySide6's modules
into them (``pyqtgraph.Qt._copy_attrs``). PySide6 makes a class's Python type
the first time the class is looked up: the copy made all 720 of them, 0.2 s of
the 0.5 s that importing pyqtgraph took, on the way to the run panels (issue
26.5). :func:`install` (called by ``plcbuilder.ide`` before anything imports
pyqtgraph) puts mirrors in their place that look a name up in PySide6 the
first time pyqtgraph asks for it and keep it; while ``pyqtgraph.Qt`` runs,
PySide6's modules list no names, so its copy copies none. Everything pyqtgraph
sets on its mirrors stays theirs. Only for PySide6 (the IDE's binding).
"""

from __future__ import annotations

import sys
import types

QT_MODULES = ("QtCore", "QtGui", "QtWidgets")
TARGET = "pyqtgraph.Qt"


class Mirror(types.ModuleType):
    """A module of pyqtgraph's that takes a name from a PySide6 module the
    first time it is asked for (and keeps it)."""

    def __init__(self, name: str, source: types.ModuleType):
        super().__init__(name)
        self.__dict__["_mirror_of"] = source
        self.__path__ = []                   # a package, as pyqtgraph's own are

    def __getattr__(self, name: str):
        value = getattr(self.__dict__["_mirror_of"], name)
        self.__dict__[name] = value
        return value

    def __dir__(self):
        return sorted(set(dir(self.__dict__["_mirror_of"])) | set(self.__dict__))


def spec_once(finder, name, path, target):
    """For an import finder that changes how one module of pyqtgraph runs,
    asked for that module: the spec the other finders give it, the finder
    taken off ``sys.meta_path`` (it acts once); None with another binding
    than PySide6 (pyqtgraph as it comes) or when no finder knows the module."""
    if finder in sys.meta_path:
        sys.meta_path.remove(finder)
    if "PySide6" not in sys.modules:
        return None
    for other in sys.meta_path:
        find = getattr(other, "find_spec", None)
        spec = find(name, path, target) if find is not None else None
        if spec is not None:
            return spec
    return None


class _Finder:
    """Runs ``pyqtgraph.Qt`` with the mirrors in place (once)."""

    def find_spec(self, name, path, target=None):
        if name != TARGET:
            return None
        spec = spec_once(self, name, path, target)
        if spec is None:
            return None
        run = spec.loader.exec_module

        def exec_module(module):
            import importlib
            sources = {n: importlib.import_module(f"PySide6.{n}") for n in QT_MODULES}
            for n, src in sources.items():
                sys.modules.setdefault(f"{TARGET}.{n}", Mirror(f"{TARGET}.{n}", src))
            listed = {n: src.__dict__.get("__dir__") for n, src in sources.items()}
            for src in sources.values():
                src.__dir__ = list              # dir() of it: [] (pyqtgraph copies nothing)
            try:
                run(module)
            finally:
                for n, src in sources.items():
                    if listed[n] is None:
                        src.__dict__.pop("__dir__", None)
                    else:
                        src.__dir__ = listed[n]
        spec.loader.exec_module = exec_module
        return spec


def install() -> None:
    """Make the next import of pyqtgraph use mirrors filled on demand (a
    no-op when pyqtgraph's Qt namespace is already loaded)."""
    if TARGET in sys.modules or any(isinstance(f, _Finder) for f in sys.meta_path):
        return
    sys.meta_path.insert(0, _Finder())
