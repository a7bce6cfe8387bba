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

from plcbuilder.ide.editor.files import file_key, normalise_newlines, same_file
from plcbuilder.ide.editor.style import (IND_ERROR, IND_FIND, IND_OCCURRENCE, IND_WARNING,
                                         KIND_CONSTANT, KIND_DEFINE, KIND_FUNCTION, KIND_KEYWORD,
                                         KIND_PREDEFINED, KIND_PROCEDURE, KIND_VARIABLE,
                                         MK_COVERED, MK_CURRENT, MK_ERROR, MK_UNCOVERED,
                                         MK_WARNING, EditorPrefs,
                                         MK_BREAKPOINT, MK_BREAKPOINT_CONDITIONAL,
                                         MK_BREAKPOINT_DISABLED, MK_BREAKPOINT_UNVERIFIED,
                                         MK_EXEC, MK_EXEC_LINE, MK_FRAME_LINE, MK_LOGPOINT,
                                         MK_WAIT, MK_WAIT_LINE,
                                         default_font_family)
from plcbuilder.ide.editor.widget import CodeEditor

__all__ = ["CodeEditor", "EditorPrefs", "default_font_family", "file_key", "normalise_newlines",
           "same_file", "IND_ERROR", "IND_FIND", "IND_OCCURRENCE", "IND_WARNING", "KIND_CONSTANT",
           "KIND_DEFINE", "KIND_FUNCTION", "KIND_KEYWORD", "KIND_PREDEFINED", "KIND_PROCEDURE",
           "KIND_VARIABLE", "MK_COVERED", "MK_CURRENT", "MK_ERROR", "MK_UNCOVERED", "MK_WARNING",
           "MK_BREAKPOINT", "MK_BREAKPOINT_CONDITIONAL", "MK_BREAKPOINT_DISABLED",
           "MK_BREAKPOINT_UNVERIFIED", "MK_EXEC", "MK_EXEC_LINE", "MK_FRAME_LINE", "MK_LOGPOINT",
           "MK_WAIT", "MK_WAIT_LINE"]
