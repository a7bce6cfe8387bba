"""PySide6 looks at every module imported after it: an import hook asks
whether the module's source mentions "PySide6" (for its ``__feature__``
switches), and answers through ``inspect.getsource``, which goes through
linecache and the module's loader for each of them. At the IDE's start that
was about 110 modules and 20 ms, a tenth of the start-up beyond a bare Qt
window. :func:`quick_source_check` answers the same question by reading the
file's bytes; for anything but a plain ``.py`` file it asks PySide's own check.
"""

from __future__ import annotations

import sys

_MARK = "_plcbuilder_quick"


def quick_source_check() -> bool:
    """Put the quicker check in PySide's place; whether it is in place (False
    where this PySide has no such hook: nothing to do)."""
    feature = sys.modules.get("shibokensupport.feature")
    original = getattr(feature, "_mod_uses_pyside", None)
    if original is None:
        return False
    if getattr(original, _MARK, False):
        return True

    def mentions_pyside(module) -> bool:
        path = getattr(module, "__file__", None)
        if isinstance(path, str) and path.endswith(".py"):
            try:
                with open(path, "rb") as f:
                    return b"PySide6" in f.read()
            except OSError:
                pass
        return original(module)

    setattr(mentions_pyside, _MARK, True)
    mentions_pyside.original = original
    feature._mod_uses_pyside = mentions_pyside
    return True
