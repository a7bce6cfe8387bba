"""Diagnostics while typing: debounced, on a worker thread, stale results dropped."""

import time

import pytest

from plcbuilder import api
from plcbuilder.ide.diagnostics_worker import DiagnosticsWorker


@pytest.fixture
def worker(qtbot):
    w = DiagnosticsWorker(debounce_ms=40)
    yield w
    w.shutdown()


def test_debounce_compiles_only_the_last_text(worker, qtbot):
    results = []
    worker.sig_result.connect(lambda key, r: results.append((key, r)))
    texts = ["main() { a = ; }", "main() { a = 1 }", "main() { a = 1; exit(99); }"]
    for t in texts:
        worker.schedule("k", lambda t=t: ("/x/M01.plc", t, api.CompileOptions()))
    qtbot.waitUntil(lambda: len(results) == 1, timeout=5000)
    qtbot.wait(150)
    assert len(results) == 1
    key, r = results[0]
    assert key == "k" and r.ok and r.size is not None


def test_result_within_300_ms_of_the_last_keystroke(qtbot):
    w = DiagnosticsWorker()          # the real debounce
    try:
        got = []
        w.sig_result.connect(lambda k, r: got.append(time.perf_counter()))
        t0 = time.perf_counter()
        w.schedule("k", lambda: ("<f>", "main() { a = ; }", api.CompileOptions()))
        qtbot.waitUntil(lambda: bool(got), timeout=3000)
        assert got[0] - t0 < 1.0           # generous on a loaded machine; the bench measures it
    finally:
        w.shutdown()


def test_stale_results_are_dropped(worker, qtbot):
    results = []
    worker.sig_result.connect(lambda key, r: results.append(r))
    worker.submit("k", "<a>", "main() { a = ; }", api.CompileOptions())
    gen = worker.submit("k", "<a>", "main() { exit(99); }", api.CompileOptions())
    assert worker.generation("k") == gen
    qtbot.waitUntil(lambda: not worker.pending(), timeout=5000)
    qtbot.wait(50)
    assert results and all(r.ok for r in results)     # the first text's error never shows


def test_a_schedule_after_submit_makes_the_submitted_result_stale(worker, qtbot):
    results = []
    worker.sig_result.connect(lambda key, r: results.append(r))
    worker.submit("k", "<a>", "main() { a = ; }", api.CompileOptions())
    worker.schedule("k", lambda: ("<a>", "main() { exit(99); }", api.CompileOptions()))
    qtbot.waitUntil(lambda: bool(results), timeout=5000)
    qtbot.waitUntil(lambda: not worker.pending(), timeout=5000)
    assert [r.ok for r in results] == [True]


def test_cancel_forgets_a_file(worker, qtbot):
    results = []
    worker.sig_result.connect(lambda key, r: results.append(r))
    worker.schedule("k", lambda: ("<a>", "main() {}", api.CompileOptions()))
    worker.cancel("k")
    qtbot.wait(150)
    assert results == []
    assert not worker.pending()


def test_compile_from_disk_and_internal_errors(worker, qtbot, tmp_path, monkeypatch):
    f = tmp_path / "M05.plc"
    f.write_text("main() { exit(99); }\n")
    results = []
    worker.sig_result.connect(lambda key, r: results.append(r))
    worker.submit("d", str(f), None, api.CompileOptions())
    qtbot.waitUntil(lambda: bool(results), timeout=5000)
    assert results[0].ok and results[0].name == "M05"

    def boom(*a, **k):
        raise RuntimeError("kaput")
    monkeypatch.setattr(api, "compile_source", boom)
    worker.submit("e", "/x/M06.plc", "main() {}", api.CompileOptions())
    qtbot.waitUntil(lambda: len(results) == 2, timeout=5000)
    d, = results[1].diagnostics
    assert d.code == "internal" and "kaput" in d.message


def test_edits_of_an_open_file_compile_incrementally_to_the_same_result(worker, qtbot):
    results = []
    worker.sig_result.connect(lambda key, r: results.append(r))
    text = "main() { a = 1; exit(99); }\nfoo() { b = 2; }\n"
    for t in (text, text.replace("b = 2", "b = "), text, "\n" + text):
        results.clear()
        worker.submit("k", "/x/M01.plc", t, api.CompileOptions())
        qtbot.waitUntil(lambda: bool(results), timeout=5000)
        assert results[0].diagnostics == api.compile_source(t, "/x/M01.plc").diagnostics
    assert worker._incremental["k"].parsed is not None
    worker.cancel("k")
    assert "k" not in worker._incremental


def test_pending_while_a_later_job_is_still_compiling(worker, qtbot, tmp_path, monkeypatch):
    """The worker was idle as soon as the first of two results arrived, while
    the second was still compiling (the queue was empty by then): under load,
    a test that waited for "not busy" read the Problems before the header's
    error came in (test_problem_in_a_header_opens_the_header's flake)."""
    import threading
    started, release = threading.Event(), threading.Event()
    real = api.compile_file

    def slow(path, options):
        if path.endswith("B.plc"):
            started.set()
            release.wait(10)
        return real(path, options)
    monkeypatch.setattr(api, "compile_file", slow)
    for name in ("A", "B"):
        (tmp_path / f"{name}.plc").write_text("main() { exit(99); }\n")
    results = []
    worker.sig_result.connect(lambda key, r: results.append(key))
    worker.hold(True)
    worker.submit("a", str(tmp_path / "A.plc"), None, api.CompileOptions())
    worker.submit("b", str(tmp_path / "B.plc"), None, api.CompileOptions())
    worker.hold(False)
    assert started.wait(10)                  # A's result is on its way, B is compiling
    try:
        qtbot.waitUntil(lambda: results == ["a"], timeout=5000)
        assert worker.pending()              # B's result has not arrived
    finally:
        release.set()
    qtbot.waitUntil(lambda: results == ["a", "b"], timeout=5000)
    qtbot.waitUntil(lambda: not worker.pending(), timeout=5000)


def test_the_collector_waits_until_the_result_is_handled(worker, qtbot):
    """The cyclic garbage collector stays paused from the compile until its
    result has been handed over (the collection of the compile's objects is
    not in the keystroke's time), and is on again after."""
    import gc
    assert gc.isenabled()
    seen = []
    worker.sig_result.connect(lambda key, r: seen.append(gc.isenabled()))
    for text in ("main() { a = 1; exit(99); }", "main() { a = 2; exit(99); }"):
        worker.submit("k", "<a>", text, api.CompileOptions())
        qtbot.waitUntil(lambda: not worker.pending(), timeout=5000)
    assert seen == [False, False]
    assert gc.isenabled()
