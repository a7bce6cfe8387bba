"""The source editor, split by job:

* :mod:`.widget` — :class:`CodeEditor`, the Scintilla widget: text and
  positions, set-up, preferences, go to line, brace matching, occurrences,
  the context menu;
* :mod:`.style` — indicators, markers, margins, completion kinds, their images,
  and :class:`EditorPrefs`;
* :mod:`.keys` — typing help: auto-indent, closing braces, completion, call tips,
  comment toggling;
* :mod:`.search` — find, replace and highlighted matches;
* :mod:`.diagnostics` — squiggles, margin markers and hover text;
* :mod:`.find_bar` — the find/replace bar under the editors;
* :mod:`.files` — file keys and line ends.

Positions: Scintilla counts UTF-8 bytes, Python and the diagnostics count
characters. Every conversion goes through :mod:`plcbuilder.ide.offsets`.
"""

import sys

from plcbuilder._support.lazy import lazy_names

# The names load their module on first use (PEP 562): ``file_key`` or the
# marker numbers do not load Scintilla, pygments and the editor widget, which
# the main window does not need before its first paint (the first editor does);
# a name of __all__ not here comes from .marks.
_WHERE = {"file_key": "files", "normalise_newlines": "files", "same_file": "files",
          "CodeEditor": "widget"}


def is_editor(widget) -> bool:
    """Whether ``widget`` is a :class:`CodeEditor` (without loading the editor:
    before it loads, none exists)."""
    module = sys.modules.get(f"{__name__}.widget")
    return module is not None and isinstance(widget, module.CodeEditor)


def __dir__() -> list:
    return sorted(set(globals()) | set(__all__))


__all__ = ["CodeEditor", "EditorPrefs", "default_font_family", "file_key", "is_editor",
           "normalise_newlines", "same_file", "IND_ERROR", "IND_FIND", "IND_OCCURRENCE", "IND_WARNING", "KIND_CONSTANT",
           "KIND_DEFINE", "KIND_FUNCTION", "KIND_KEYWORD", "KIND_PREDEFINED", "KIND_PROCEDURE",
           "KIND_VARIABLE", "MK_COVERED", "MK_CURRENT", "MK_ERROR", "MK_UNCOVERED", "MK_WARNING",
           "MK_BREAKPOINT", "MK_BREAKPOINT_CONDITIONAL", "MK_BREAKPOINT_DISABLED",
           "MK_BREAKPOINT_UNVERIFIED", "MK_EXEC", "MK_EXEC_LINE", "MK_FRAME_LINE", "MK_LOGPOINT",
           "MK_WAIT", "MK_WAIT_LINE"]

__getattr__ = lazy_names(__name__, {**{name: "marks" for name in __all__}, **_WHERE})
