"""Names a package loads from its modules when they are first used (PEP 562),
so that importing the package costs only what it needs now."""

from __future__ import annotations

import importlib
import sys

TYPE_CHECKING = False               # (typing is not imported at run time: start-up)
if TYPE_CHECKING:
    from typing import Callable, Mapping


def lazy_names(package: str, where: Mapping[str, str]) -> Callable[[str], object]:
    """A ``__getattr__`` for the module ``package``: a name of ``where`` is
    imported from its module (``package.where[name]``) the first time it is
    asked for, and kept in the package; any other name is an AttributeError."""
    def __getattr__(name: str):
        module = where.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(f"{package}.{module}"), name)
        setattr(sys.modules[package], name, value)
        return value
    return __getattr__
