import atexit
import json
import os
import shutil
import tempfile

# CI has no display: every test (and every Qt import) runs offscreen, on a
# screen of a desktop's size (Qt's offscreen screen is 800 x 800 unless told:
# smaller than the windows the tests make, which a window fitted on its screen
# would then shrink); scripts/test says "offscreen"
if os.environ.get("QT_QPA_PLATFORM", "offscreen") == "offscreen":
    _folder = tempfile.mkdtemp(prefix="plcb-tests-")
    atexit.register(shutil.rmtree, _folder, True)
    _screen = os.path.join(_folder, "screen.json")
    with open(_screen, "w", encoding="utf-8") as _f:
        json.dump({"screens": [{"name": "screen", "x": 0, "y": 0, "width": 1920,
                                "height": 1200, "logicalDpi": 96, "dpr": 1}]}, _f)
    os.environ["QT_QPA_PLATFORM"] = f"offscreen:configfile={_screen}"
os.environ.setdefault("PYQTGRAPH_QT_LIB", "PySide6")


import signal  # noqa: E402

import pytest  # noqa: E402


@pytest.fixture(autouse=True)
def _sigpipe_stays_ignored():
    """Python ignores SIGPIPE (a write to a closed socket raises an error);
    a test, or a library it imports, that gives it back its default action
    makes the next such write kill the whole test process without a word."""
    yield
    assert signal.getsignal(signal.SIGPIPE) == signal.SIG_IGN, \
        "SIGPIPE is no longer ignored (import vcdvcd through tests.vcd_reader)"
