"""debug_evaluate (docs/protocol.md, "Debugging"): an expression compiled as a
breakpoint condition is, evaluated over a running procedure's variables, for
the debug adapter's watch, hover and console."""

from __future__ import annotations

import time

import pytest

from plcbuilder import api
from plcbuilder.link.client import Client, RefusedError
from plcbuilder.link.server import ControllerServer
from tests.link.linkkit import image_of

SRC = """main()
{
  n = 0;
  do {
    n = n + 1;
    portset(3);
  } while (1);
}
"""


@pytest.fixture
def served():
    r = api.compile_source(SRC, "M10.plc", api.CompileOptions(kind=api.Kind.HARDWARE))
    assert r.ok
    srv = ControllerServer(port=0, speed="factor", factor=20.0, image=image_of([r.program]))
    srv.start()
    c = Client.connect(*srv.address, srv.token, timeout=10.0)
    yield srv, c
    c.close()
    srv.close()


def _code(text: str) -> bytes:
    code = api.compile_condition(text)
    assert isinstance(code, bytes), code
    return code


def test_evaluate_over_the_halted_procedures_variables(served):
    srv, c = served
    with pytest.raises(RefusedError, match="no procedure is running"):
        c.debug_evaluate(_code("1 + 1"))
    c.set_breakpoints("M10.plc", [{"line": 5, "condition": {"text": "n == 7",
                                                           "code": _code("n == 7")}}])
    c.start("M10")
    deadline = time.monotonic() + 10
    while c.debug_state() is None:
        assert time.monotonic() < deadline
        time.sleep(0.01)
    assert c.debug_evaluate(_code("n * 100 + portget(0) + gvarget(0x403)")) == 701
    assert c.debug_evaluate(_code("GVAR_CURRENT_MOTION_CODE"), "M10") == 6060
    with pytest.raises(RefusedError, match="'ghost', which is not a variable of M10"):
        c.debug_evaluate(_code("ghost + 1"))
    with pytest.raises(RefusedError, match="not base64"):
        c.request("debug_evaluate", code="%%%")
    with pytest.raises(RefusedError, match="is not running"):
        c.debug_evaluate(_code("1"), "M99")
    st = c.debug_state()
    assert st["procedures"][0]["vars"]["n"] == 7          # nothing was changed
