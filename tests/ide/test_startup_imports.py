"""Issue 14 point 5: the main window's modules load without the heavy stages
(the compiler and lark, the test runner, pyqtgraph and numpy), so the first
paint does not wait for them; they load when first used."""

import subprocess
import sys

HEAVY = ("lark", "plcbuilder.lang.pipeline", "plcbuilder.testing.runner",
         "plcbuilder.controller.controller", "pyqtgraph", "numpy")


def test_importing_the_main_window_loads_no_heavy_stage():
    code = ("import sys; import plcbuilder.ide.main_window, plcbuilder.ide.connection; "
            f"print([m for m in {HEAVY!r} if m in sys.modules])")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                       env={**__import__("os").environ, "QT_QPA_PLATFORM": "offscreen"})
    assert r.returncode == 0, r.stderr
    assert r.stdout.strip() == "[]", r.stdout


def test_the_facade_still_gives_every_name():
    """``from plcbuilder.api import X`` works for every name of ``__all__``,
    loading its stage on first use."""
    from plcbuilder import api
    for name in api.__all__:
        assert getattr(api, name) is not None, name
    from plcbuilder.api import compile_source, run_suite   # noqa: F401
    r = compile_source("main(){ exit(99); }", "M90.plc")
    assert r.ok
