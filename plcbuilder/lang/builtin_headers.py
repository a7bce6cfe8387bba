"""The built-in headers (``resources/include``: the default ``pins.h`` and the
target headers) and how diagnostics name them (``<builtin>/NAME``); light, so
that the IDE opens one without loading the preprocessor."""

from __future__ import annotations

from importlib import resources
from typing import Optional

from plcbuilder.lang.source import normalise

BUILTIN_PREFIX = "<builtin>/"


def builtin_header(name: str) -> Optional[str]:
    """The text of a built-in header (resources/include/NAME), or None."""
    if "/" in name or "\\" in name or name.startswith("."):
        return None
    try:
        ref = resources.files("plcbuilder") / "resources" / "include" / name
        if ref.is_file():
            return normalise(ref.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError):
        return None
    return None


def builtin_header_names() -> list[str]:
    try:
        d = resources.files("plcbuilder") / "resources" / "include"
        return sorted(p.name for p in d.iterdir() if p.name.endswith(".h"))
    except OSError:
        return []
