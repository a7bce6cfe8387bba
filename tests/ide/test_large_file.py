"""A 2.7 MB .plc file opens without freezing typing (issue 13, defect 12: the
first keystrokes queued for seconds): its compile waits for a pause in
typing, completion reads the lines around the caret, and the compile thread
hands the GIL back to the window often."""

import sys
import time

import pytest

from plcbuilder.ide import completion
from plcbuilder.ide.diagnostics_worker import GIL_SWITCH_S
from plcbuilder.ide.lint import LARGE_TEXT, NEAR_LINES
from scripts.bench_large_file import big_source
from tests.ide.test_main_window import (make_window, project, prompts, settings,  # noqa: F401
                                        settle, win)


@pytest.mark.slow
def test_typing_in_a_large_file_right_after_opening_it(win, project, qtbot, monkeypatch):  # noqa: F811
    big = project / "hardware" / "M10.plc"
    big.write_text(big_source(2.7))
    win.open_project(project)
    settle(qtbot, win)                      # the project's lint (M10 from disk) is done
    indexed = []
    real_index = completion.lang_symbols.index
    monkeypatch.setattr(completion.lang_symbols, "index",
                        lambda text, *a, **k: indexed.append(len(text)) or real_index(text, *a, **k))
    ed = win.open_file(str(big))
    assert ed.length() > LARGE_TEXT
    # not compiled at once: after typing pauses, a second a megabyte
    assert win.lint.defer_ms(ed) >= 3000
    assert sys.getswitchinterval() <= GIL_SWITCH_S
    ed.goto_line(5, 1)
    t0 = time.perf_counter()
    for ch in "abcdefghij":
        qtbot.keyClick(ed, ch)
    typed = time.perf_counter() - t0
    assert ed.line_text(4).startswith("abcdefghij")
    # completion read the lines around the caret, not 2.7 MB, and reused its index
    assert indexed and max(indexed) < (2 * NEAR_LINES + 1) * 200
    assert len(indexed) <= 2
    # ten keys: well under a second each (before: a minute each on a busy machine)
    assert typed < 10, typed
    assert win.lint.worker.pending()        # the compile is still waiting for the pause
    qtbot.waitUntil(lambda: not win.lint.worker.pending(), timeout=120_000)
    # past the compiler's token limit, the one diagnostic is that limit (issue 23.17:
    # no false "expected '}'" after it), for the text as typed
    assert [d.code for d in win.lint.store.for_file(str(big))] == ["too-large"]
