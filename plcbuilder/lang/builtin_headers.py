"""The built-in headers (``resources/include``: the default ``pins.h`` and the
target headers) and how diagnostics name them (``<builtin>/NAME``); light, so
that the IDE opens one without loading the preprocessor."""

from __future__ import annotations

from plcbuilder._support.files import read_bounded
from plcbuilder._support.package_data import data_folder
from plcbuilder.lang.source import MAX_SOURCE_BYTES, normalise

TYPE_CHECKING = False               # (typing is not imported at run time: start-up)
if TYPE_CHECKING:
    from typing import Optional

BUILTIN_PREFIX = "<builtin>/"


def _folder():
    return data_folder("resources", "include")


def builtin_header(name: str) -> Optional[str]:
    """The text of a built-in header (resources/include/NAME), or None."""
    if "/" in name or "\\" in name or name.startswith("."):
        return None
    try:
        ref = _folder() / name
        if ref.is_file():
            return normalise(ref.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError):
        return None
    return None


def builtin_header_names() -> list[str]:
    try:
        return sorted(p.name for p in _folder().iterdir() if p.name.endswith(".h"))
    except OSError:
        return []


def source_text(name: str, limit: int = MAX_SOURCE_BYTES) -> Optional[str]:
    """The text of a file as diagnostics name it: a built-in header
    (``<builtin>/NAME``; None when there is no such header) or a file on disk
    (at most ``limit`` bytes, what is not UTF-8 replaced). Reading the disk
    raises OSError as :func:`read_bounded` does."""
    if name.startswith(BUILTIN_PREFIX):
        return builtin_header(name[len(BUILTIN_PREFIX):])
    return read_bounded(name, limit).decode("utf-8", "replace")
