"""The fast backend reads a host's pin state directly (``Host.io``): a constant
pin's ``portget`` reads ``io.in_bits``, and ``portset``/``portclr`` of a constant
pin are called only when they change ``io.out_bits`` — with the same outcome as
the reference interpreter, which calls every time."""

from __future__ import annotations

from plcbuilder.controller import fastvm, vm

from tests.controller._sim import compile_proc

SRC = """
main()
{
  n=0;
  do
  {
    s=portget(3);
    if (s!=0) { portset(7); } else { portclear(7); };
    portset(9);
    k=portget(n&1);
    n++;
  }while(n<6);
  exit(99);
};
"""


class _IO:
    """A pin state and a log of the port calls that reached it."""

    input_count = output_count = 64

    def __init__(self):
        self.in_bits = 0
        self.out_bits = 0
        self.calls: list[tuple[str, int]] = []

    def portset(self, pin):
        self.calls.append(("set", pin))
        self.out_bits |= 1 << pin

    def portclr(self, pin):
        self.calls.append(("clr", pin))
        self.out_bits &= ~(1 << pin)

    def portget(self, pin):
        self.calls.append(("get", pin))
        return (self.in_bits >> pin) & 1

    def host(self, with_io: bool) -> vm.Host:
        nothing = lambda *a: 0  # noqa: E731
        return vm.Host(portset=self.portset, portclr=self.portclr, portget=self.portget,
                       gvarget=nothing, gvarset=nothing, g0move=nothing,
                       io=self if with_io else None)


def _run(make, io: _IO, ticks: int, inputs: dict[int, int]):
    slots = [0] * 256
    step = make(slots, io).__next__
    outs = []
    try:
        for t in range(ticks):
            io.in_bits = inputs.get(t, io.in_bits)
            step()
            outs.append(io.out_bits)
    except vm.ProcExit as e:
        outs.append(("exit", e.code))
    return outs, slots[:40]


def test_constant_pins_read_and_test_the_host_io_directly():
    prog = compile_proc(SRC, "M10")
    src = fastvm.translate(prog, pins=(64, 64))
    assert "io.in_bits >> 3 & 1" in src and "io.out_bits & 128" in src
    assert "portget(3)" not in src
    assert "portget(" in src                       # n&1 is not a constant pin
    assert "io." not in fastvm.translate(prog)     # a host without io: calls only


def test_unchanged_output_writes_are_skipped_with_the_same_outcome():
    prog = compile_proc(SRC, "M10")
    inputs = {0: 0, 2: 1 << 3, 4: 0}
    io_fast, io_ref = _IO(), _IO()
    fast = _run(lambda s, io: fastvm.make_runner(prog, s, io.host(True)), io_fast, 10, inputs)
    ref = _run(lambda s, io: vm.run_reference(prog, s, io.host(True)), io_ref, 10, inputs)
    assert fast == ref
    sets = [c for c in io_fast.calls if c[0] != "get"]
    # output 9 written six times, reaching the host once; output 7 toggles on at 2, off at 4
    assert sets == [("set", 9), ("set", 7), ("clr", 7)]
    assert len([c for c in io_ref.calls if c[0] != "get"]) == 12


def test_out_of_range_constant_pins_still_call_the_host():
    prog = compile_proc("main(){ portset(70); a=portget(80); exit(a); };", "M11")
    src = fastvm.translate(prog, pins=(64, 64))
    assert "portset(70)" in src and "portget(80)" in src


class _WiredIO(_IO):
    """Input 3 follows output 7 at once: a port call can change what a pin reads."""

    def portset(self, pin):
        super().portset(pin)
        self.in_bits = (self.in_bits & ~8) | ((self.out_bits >> 7 & 1) << 3)

    def portclr(self, pin):
        super().portclr(pin)
        self.in_bits = (self.in_bits & ~8) | ((self.out_bits >> 7 & 1) << 3)


def test_a_pin_read_kept_on_the_stack_is_taken_before_a_later_port_call():
    """portget(3) pushed, then portset(7) (which turns input 3 on), then the
    value read is stored: it is the input before the call (the fast backend
    reads io where the value is used, so a call in between must fix it first)."""
    from plcbuilder.bytecode.opcodes import Op
    from tests.controller._asm import L, assemble
    r = 22
    items = [L("main"), (Op.PUSH8, 3), Op.PORTGET, (Op.PUSH8, 7), Op.PORTSET,
             (Op.PUSH8, 3), Op.PORTGET, Op.ADD, (Op.STORE, r),
             (Op.PUSH8, 3), Op.PORTGET, (Op.PUSH8, 7), Op.PORTCLR, (Op.STORE, r + 1),
             (Op.PUSH8, 99), Op.EXIT]
    prog = assemble(items, entry="main")
    results = []
    for make in (lambda s, io: fastvm.make_runner(prog, s, io.host(True)),
                 lambda s, io: vm.run_reference(prog, s, io.host(True))):
        io = _WiredIO()
        outs, slots = _run(make, io, 2, {})
        results.append((outs, slots[r], slots[r + 1]))
    assert results[0] == results[1]
    assert results[0][1:] == (1, 1)          # 0 before the set + 1 after; 1 before the clear


class _LevelsIO(_IO):
    """A pin state that also keeps a list per pin (as the machine does)."""

    def __init__(self):
        super().__init__()
        self.in_levels = [0] * 64
        self.out_on = [False] * 64

    def portset(self, pin):
        super().portset(pin)
        self.out_on[pin] = True

    def portclr(self, pin):
        super().portclr(pin)
        self.out_on[pin] = False


def test_a_host_io_with_a_list_per_pin_is_read_through_the_lists():
    prog = compile_proc(SRC, "M10")
    src = fastvm.translate(prog, pins=fastvm.io_shape(_LevelsIO()))
    assert "ins[3]" in src and "outs[7]" in src and "io.in_bits" not in src
    inputs = {0: 0, 2: 1 << 3, 4: 0}
    runs = []
    for make in (lambda s, io: fastvm.make_runner(prog, s, io.host(True)),
                 lambda s, io: vm.run_reference(prog, s, io.host(True))):
        io = _LevelsIO()
        slots = [0] * 256
        step = make(slots, io).__next__
        outs = []
        try:
            for t in range(10):
                io.in_bits = inputs.get(t, io.in_bits)
                io.in_levels[:] = [(io.in_bits >> k) & 1 for k in range(64)]
                step()
                outs.append(io.out_bits)
        except vm.ProcExit as e:
            outs.append(("exit", e.code))
        runs.append((outs, slots[:40]))
        if len(runs) == 1:
            assert [c for c in io.calls if c[0] != "get"] == [("set", 9), ("set", 7), ("clr", 7)]
    assert runs[0] == runs[1]
