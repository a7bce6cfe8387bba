import os

# CI has no display: every test (and every Qt import) runs offscreen.
os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
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
