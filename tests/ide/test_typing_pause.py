"""A filter field over a long list filters once typing pauses (ide/typing_pause.py):
the Problems panel's filter with thousands of problems (each key rebuilt the
list: 150-240 ms a key at 5,000) and the run log's search (test_panels)."""

from __future__ import annotations

from PySide6.QtCore import Qt
from PySide6.QtWidgets import QLineEdit

from plcbuilder.api import Diagnostic, Severity, Span
from plcbuilder.ide.problems import FILTER_AT_ONCE, ProblemsPanel
from plcbuilder.ide.typing_pause import PAUSE_MS, TypingPause


def test_a_short_list_is_filtered_at_each_key_a_long_one_when_typing_pauses(qtbot):
    edit = QLineEdit()
    qtbot.addWidget(edit)
    runs, long = [], [False]
    TypingPause(edit, lambda: runs.append(edit.text()), lambda: long[0])
    edit.setText("a")
    edit.setText("ab")
    assert runs == ["a", "ab"]
    long[0] = True
    runs.clear()
    for text in ("abc", "abcd", "abcde"):
        edit.setText(text)
    assert runs == []
    qtbot.waitUntil(lambda: runs == ["abcde"], timeout=PAUSE_MS * 10)
    edit.setText("x")
    qtbot.keyClick(edit, Qt.Key.Key_Return)                 # Enter: at once
    assert runs == ["abcde", "x"]
    qtbot.wait(PAUSE_MS * 2)
    assert runs == ["abcde", "x"]                           # (not again after the pause)


def _problems(n: int) -> list[Diagnostic]:
    return [Diagnostic(Severity.ERROR, "syntax", f"expected ';' after '{i}'",
                       Span(f"/p/hardware/M{i // 5:04d}.plc", i % 50 + 1, 3, i % 50 + 1, 5))
            for i in range(n)]


def _shown(panel: ProblemsPanel) -> int:
    return sum(panel.tree.topLevelItem(i).childCount()
               for i in range(panel.tree.topLevelItemCount()))


def test_the_problems_filter_over_thousands_of_problems_waits_for_a_pause(qtbot):
    panel = ProblemsPanel()
    qtbot.addWidget(panel)
    panel.set_problems(_problems(FILTER_AT_ONCE + 500))
    assert _shown(panel) == FILTER_AT_ONCE + 500
    refills = []
    refill = panel._refill
    panel.typing.run = lambda: (refills.append(panel.filter_edit.text()), refill())
    for text in ("1", "12", "123"):
        panel.filter_edit.setText(text)
    assert refills == [] and _shown(panel) == FILTER_AT_ONCE + 500
    qtbot.waitUntil(lambda: refills == ["123"], timeout=PAUSE_MS * 10)
    assert _shown(panel) == sum("123" in f"expected ';' after '{i}'" or "123" in f"M{i // 5:04d}"
                                for i in range(FILTER_AT_ONCE + 500))
    # a short list: at each key
    panel.set_problems(_problems(10))
    refills.clear()
    panel.filter_edit.setText("after '3'")
    assert refills == ["after '3'"] and _shown(panel) == 1
