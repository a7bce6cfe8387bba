"""The fast backend knows the range of a procedure's variables (those it keeps
in locals) and leaves out the 32-bit wrap where the value cannot leave 32 bits.
Where it can (at 0x7fffffff, past a mask, below 0), the wrap stays, and both
backends agree tick by tick; a value written from outside between ticks that
breaks what the code assumes hands the procedure over to the reference
interpreter, which goes on exactly where it was."""

from __future__ import annotations

import pytest

from plcbuilder.controller import fastvm

from tests.controller._sim import BACKENDS, compile_proc, controller, ended

COUNT_UP = """
main()
{
  n=0; acc=0;
  do
  {
    acc=(acc+n*3)&0xffff;
    n++;
  }while(n<2000000000);
  exit(99);
};
"""

EDGES = {
    # n++ passes 0x7fffffff (wraps to -2147483648) and the loop ends there
    "wrap at INT_MAX": """main(){ n=2147483640; do { n++; m=n+1; } while(n>0);
                        gvarset(20000,n); gvarset(20001,m); exit(99); };""",
    # the bound is INT_MAX itself: n <= 0x7fffffff is always true, so n++ wraps
    "bound at INT_MAX": """main(){ n=2147483600; do { n++; k++; } while(n<=2147483647 && k<100);
                         gvarset(20000,n); exit(99); };""",
    # masks bound values; a sum of two masked values may still pass 32 bits
    "masks": """main(){ x=5; do { x=(x+2147483000)&0x7fffffff; y=x+x; z=(x&0xff)+1;
                w=(x&0xffff)*(x&0xffff); i++; } while(i<40);
                gvarset(20000,y); gvarset(20001,z); gvarset(20002,w); exit(99); };""",
    # counting down past -2147483648 wraps to 0x7fffffff, and d-1 wraps at the bottom
    "negative": """main(){ d=0-2147483640; do { d--; e=d-1; f=0-d; } while(d<0);
                 gvarset(20000,d); gvarset(20001,e); gvarset(20002,f); exit(99); };""",
    # a product that leaves 32 bits, then a loop on the wrapped value
    "products": """main(){ n=1; do { n=n+1; } while(n<10);
                 do { n=n*3; c++; } while(n<2000000000 && c<50);
                 gvarset(20000,n); exit(99); };""",
    # a refined range (a branch on the value) and its wrong side
    "branches": """main(){ do { if (a<100) { a=a+7; } else { a=a-250; }; b=a+2147483600; i++; }
                 while(i<60); gvarset(20000,b); exit(99); };""",
}


def _trace(src: str, backend: str, ticks: int = 200):
    c = controller(compile_proc(src, "M10"), backend=backend)
    c.start("M10")
    seen = []
    for _ in range(ticks):
        c.step(1)
        seen.append(c.variables()["M10"])
    return seen, c.drain_events()


def test_a_counter_bounded_by_its_loop_is_incremented_without_a_wrap():
    src = fastvm.translate(compile_proc(COUNT_UP, "M10"))
    assert "v22 += 1\n" in src and "v22 > 2147483647" not in src
    assert "2147483648 & 4294967295" not in src      # acc is masked, n*3 wraps in the mask


@pytest.mark.parametrize("name", sorted(EDGES))
def test_values_at_the_edges_of_32_bits_are_the_reference_interpreters(name):
    fast = _trace(EDGES[name], "fast")
    ref = _trace(EDGES[name], "reference")
    assert fast == ref
    assert ended(fast[1], "M10").exit_code == 99


def _slot(c, name):
    p = c._plc.hw
    return p, {n: s for s, n in p.program.slot_names().items()}[name]


@pytest.mark.parametrize("var, value, hands_over", [
    ("n", 2147483647, True), ("n", -2147483648, None), ("n", -5, False), ("n", 1000, False),
    ("n", 1999999000, False), ("acc", -1, True), ("acc", 65535, False)])
def test_a_value_written_between_ticks_goes_on_exactly(var, value, hands_over):
    """n written from outside (after a SYNC) to a value the loop's code does not
    expect: the fast backend hands over and wraps n++ exactly as the reference does."""
    runs = {}
    for b in BACKENDS:
        c = controller(compile_proc(COUNT_UP, "M10"), backend=b)
        c.start("M10")
        c.step(10)
        p, slot = _slot(c, var)
        p.sync()
        p.slots[slot] = value
        resume = p.resume
        seen = []
        for _ in range(30):
            c.step(1)
            seen.append(c.variables()["M10"])
        runs[b] = (seen, c.drain_events())
        if b == "fast" and hands_over is not None:
            assert (p.resume is not resume) == hands_over
    assert runs["fast"] == runs["reference"]
    if (var, value) == ("n", 2147483647):
        assert runs["fast"][0][0]["n"] == -2147483648


def test_a_value_written_on_the_way_out_is_kept():
    """The last tick's condition was false (the loop is leaving): a value written
    then is what the procedure ends with, on both backends."""
    src = "main(){ do { n++; } while(n<5); gvarset(20000,n); exit(99); };"
    runs = {}
    for b in BACKENDS:
        c = controller(compile_proc(src, "M10"), backend=b)
        c.start("M10")
        c.step(5)                         # n reached 5 in tick 4: it leaves in tick 5
        p, slot = _slot(c, "n")
        p.sync()
        p.slots[slot] = -7
        c.step(3)
        runs[b] = (c.variables()["M10"], c.drain_events())
    assert runs["fast"] == runs["reference"]
    assert runs["fast"][0]["n"] == -7
