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


class Pattern:
    """``re.compile(pattern, flags)``, compiled the first time it is used: a
    module's patterns cost a command's start-up only when the command uses
    them (compiling one is a few hundredths of a millisecond to half of one).
    It answers what a compiled pattern answers (``match``, ``fullmatch``,
    ``search``, ``sub``, ``groups``, …): each name is taken from the compiled
    pattern when first asked for and kept, so later uses cost what the
    compiled pattern's do."""

    def __init__(self, pattern: str, flags: int = 0):
        self._source = (pattern, flags)

    def __getattr__(self, name: str):
        d = self.__dict__
        compiled = d.get("_compiled")
        if compiled is None:
            import re
            compiled = d["_compiled"] = re.compile(*d["_source"])
        value = getattr(compiled, name)
        d[name] = value
        return value

    def __repr__(self) -> str:
        return f"Pattern({self._source[0]!r}, {self._source[1]!r})"
