"""The compiler changes no global state: the recursion limit is raised only
while a compile runs, and restored after."""

from __future__ import annotations

import subprocess
import sys
import threading
from pathlib import Path

import pytest

from plcbuilder.lang import pipeline
from plcbuilder.lang.pipeline import compile_source

ROOT = Path(__file__).resolve().parents[2]


def test_importing_the_compiler_leaves_the_recursion_limit_alone():
    code = ("import sys\n"
            "sys.setrecursionlimit(1234)\n"
            "import plcbuilder.lang.pipeline, plcbuilder.api\n"
            "print(sys.getrecursionlimit())\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                         cwd=ROOT).stdout
    assert out.strip() == "1234"


def define_chain(n: int) -> str:
    """#defines each naming the next: the preprocessor expands them one frame a link."""
    return ("".join(f"#define D{i + 1} D{i}\n" for i in range(n)) + "#define D0 7\n"
            f"main(){{ a=D{n}; exit(a); }};\n")


@pytest.fixture
def default_limit():
    """Python's default limit, whatever other tests did to it."""
    old = sys.getrecursionlimit()
    sys.setrecursionlimit(1000)
    yield 1000
    sys.setrecursionlimit(old)


def test_a_long_define_chain_compiles_and_the_limit_is_restored_after(default_limit):
    assert default_limit < 1500 < pipeline.RECURSION_LIMIT
    r = compile_source(define_chain(1500), "M1.plc")
    assert r.ok, [d.message for d in r.errors]
    assert r.program is not None
    assert sys.getrecursionlimit() == default_limit


def test_concurrent_compiles_restore_the_limit_once_all_have_ended(default_limit):
    results = []
    start = threading.Barrier(4)

    def work():
        start.wait()
        for _ in range(3):
            results.append(compile_source(define_chain(1200), "M1.plc").ok)

    threads = [threading.Thread(target=work) for _ in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert results == [True] * 12
    assert sys.getrecursionlimit() == default_limit


def test_the_collector_is_paused_while_compiling_and_back_after():
    """Issue 24.1/26: a compile pauses Python's cyclic garbage collector (it
    took a third of a compile's time going through the tokens and nodes a
    compile keeps) and puts it back as it was, concurrent compiles included."""
    import gc
    seen = []

    class Spy(pipeline.Checker):
        def run(self):
            seen.append(gc.isenabled())
            return super().run()

    old = pipeline.Checker
    pipeline.Checker = Spy
    try:
        assert gc.isenabled()
        assert compile_source("main(){ exit(99); };", "M1.plc").ok
        assert seen == [False] and gc.isenabled()
        gc.disable()                                  # a caller that had it off keeps it off
        compile_source("main(){ exit(99); };", "M1.plc")
        assert not gc.isenabled()
    finally:
        gc.enable()
        pipeline.Checker = old

    def work():
        for _ in range(5):
            compile_source(define_chain(50), "M1.plc")
    threads = [threading.Thread(target=work) for _ in range(3)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert gc.isenabled()
