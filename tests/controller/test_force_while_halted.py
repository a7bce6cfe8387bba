"""Write and force meet the debugger: a variable forced while its procedure is
halted mid-tick at a breakpoint, or while it waits at a tick end, holds from
the very next instruction, on both backends (the procedure is handed to the
reference interpreter from exactly where it is)."""

from __future__ import annotations

import pytest

from tests.controller._sim import BACKENDS, compile_proc, controller

SRC = """main()
{
  x = 0;
  do {
    x = x + 1;
    y = x;
    z = y + x;
  } while (1);
}
"""


def _halted_at_y(backend):
    c = controller(compile_proc(SRC, "M03"), backend=backend)
    got = c.debugger.set_breakpoints("M03.plc", [{"line": 6, "hit": {"mode": "eq", "n": 3}}])
    assert got[0]["verified"]
    c.start("M03")
    c.step(10)
    st = c.debugger.halted_state()
    assert st["reason"] == "breakpoint" and st["line"] == 6
    assert st["procedures"][0]["vars"]["x"] == 3 and st["procedures"][0]["vars"]["y"] == 2
    return c


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_variable_forced_while_halted_holds_from_the_next_instruction(backend):
    """"**Force** holds it: every read returns the forced value and the program's
    writes are discarded until the force is released" — also when the force is
    set while the debugger holds the procedure before a line."""
    c = _halted_at_y(backend)
    c.force("M03.x", 1000)
    c.debugger.set_breakpoints("M03.plc", [])
    c.debugger.resume()
    c.step(3)
    v = c.variables()["M03"]
    assert v["y"] == 1000 and v["z"] == 2000 and v["x"] == 1000
    c.release("M03.x", "keep")
    c.step(2)
    assert c.variables()["M03"]["x"] == 1002                # released: it counts on from there


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_write_while_halted_is_what_the_next_line_reads(backend):
    """"**Write** sets a value once: a procedure's variable, …" — while halted
    at a breakpoint, the line about to run reads the written value."""
    c = _halted_at_y(backend)
    c.write("M03.x", 40)
    c.debugger.set_breakpoints("M03.plc", [])
    c.debugger.resume()
    v = c.variables()["M03"]
    assert (v["x"], v["y"], v["z"]) == (40, 40, 80)       # the rest of the halted tick
    c.step(1)
    v = c.variables()["M03"]
    assert (v["x"], v["y"], v["z"]) == (41, 41, 82)       # and the program goes on from it
