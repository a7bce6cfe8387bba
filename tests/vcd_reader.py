"""``vcdvcd``: the independent VCD reader the tests check exports with,
imported without its side effect. For its own command line it sets SIGPIPE to
the default action when imported, and a test process whose SIGPIPE is no
longer ignored dies silently the next time any thread writes to a socket its
peer has closed: the xdist workers that crashed in the link tests."""

import signal

_saved = signal.getsignal(signal.SIGPIPE)
try:
    from vcdvcd import VCDVCD  # noqa: F401
finally:
    signal.signal(signal.SIGPIPE, _saved)

__all__ = ["VCDVCD"]
