"""SPEC §9 "huazhong": the Huazhong built-in PLC's schedule, one test a rule."""

from __future__ import annotations

from plcbuilder.bytecode import targets as T
from plcbuilder.controller.events import Fault
from tests.controller._targets import compiled, controller, faults

SEED = """
init() { }
plc1() { plc1_time = 16; if (X[0]&0x01) Y[0]|=0x80; else Y[0]&=~0x80; }
plc2() { plc2_time = 32; }
"""


def test_seed_example_input_0_lights_output_7():
    """The seed's example works: with `if (X[0]&0x01) Y[0]|=0x80; else
    Y[0]&=~0x80;` in `plc1()`, input 0 lights output 7."""
    c = controller(SEED, "huazhong")
    c.set_input(0, 0)
    c.step(20)
    assert 7 not in c.machine.outputs_on()
    c.set_input(0, 1)
    c.step(20)
    assert 7 in c.machine.outputs_on()
    c.set_input(0, 0)
    c.step(20)
    assert 7 not in c.machine.outputs_on()
    assert faults(c) == []


def test_init_runs_once_then_periods_of_plc1_and_plc2():
    """`init()` runs once at start. ... variables `plc1_time` and `plc2_time` set
    their periods in ms (the seed recommends 16 and 32)."""
    c = controller("""
        init() { plc1_time = 10; plc2_time = 25; }
        plc1() { n1++; }
        plc2() { n2++; }""", "huazhong")
    c.step(100)                      # ticks 0..99: plc1 at 0,10,...,90; plc2 at 0,25,50,75
    assert c.plc.calls == {"init": 1, "plc1": 10, "plc2": 4}
    v = c.variables()["plc"]
    assert (v["n1"], v["n2"]) == (10, 4)


def test_default_periods_are_the_seeds_16_and_32():
    """variables `plc1_time` and `plc2_time` set their periods in ms (the seed
    recommends 16 and 32)."""
    c = controller("init() { }\nplc1() { a = plc1_time; }\nplc2() { b = plc2_time; }", "huazhong")
    c.step(64)
    assert c.plc.calls["plc1"] == 4 and c.plc.calls["plc2"] == 2
    assert c.variables()["plc"]["a"] == 16 and c.variables()["plc"]["b"] == 32


def test_batch_read_x_f_p_once_per_tick():
    """Then every 1 ms tick: read all X, F and P registers from the machine and
    the CNC in one batch"""
    c = controller("""
        init() { plc1_time = 1; }
        plc1() { x = X[1]; f = F[3]; p = P[2]; }
        plc2() { }""", "huazhong", parameters=(0, 0, 4321))
    c.set_input(9, 1)                           # pin 9 = bit 1 of X[1]
    c.machine.gvarset(T.CNC_F_BASE + 3, 0x12345)  # the CNC's F[3] (16 bits)
    c.step(2)
    v = c.variables()["plc"]
    assert (v["x"], v["f"], v["p"]) == (0x02, 0x2345, 4321)


def test_x_is_read_before_the_calls_not_during_them():
    """read all X, F and P registers from the machine and the CNC in one batch"""
    c = controller("""
        init() { plc1_time = 1; }
        plc1() { a = X[0] & 1; X[0] = 0; b = X[0]; }
        plc2() { }""", "huazhong")
    c.set_input(0, 1)
    c.step(3)
    v = c.variables()["plc"]
    assert v["b"] == 0                   # inside a call, X is the tick's copy: its own write
    assert v["a"] == 1                   # and each tick's batch read takes the input again


def test_plc1_then_plc2_in_the_same_tick():
    """if `plc1`'s period has elapsed, call `plc1()`; if `plc2`'s has, call `plc2()`"""
    c = controller("""
        init() { }
        plc1() { order = order * 10 + 1; }
        plc2() { order = order * 10 + 2; }""", "huazhong")
    c.step(1)
    assert c.variables()["plc"]["order"] == 12


def test_writes_reach_the_machine_only_in_the_batch_write():
    """then write all G, Y and B registers in one batch (a program's writes are
    not seen by the machine until then)."""
    c = controller("""
        init() { }
        plc1() { Y[0] = 0x80; seen = gvarget(0x400 + 7); G[5] = 0x1ff00; }
        plc2() { }""", "huazhong")
    c.step(1)
    assert c.variables()["plc"]["seen"] == 0        # output 7 was still off inside plc1()
    assert 7 in c.machine.outputs_on()              # on after the batch write
    assert c.machine.gvarget(T.CNC_G_BASE + 5) == 0xff00   # G to the CNC, 16 bits


def test_a_call_runs_to_completion_through_its_loops():
    """Each call runs to completion (no loop-end tick rule; a call over the
    instruction limit faults)."""
    c = controller("""
        init() { }
        plc1() { i = 0; do { i++; } while (i < 1000); R[0] = 1; }
        plc2() { }""", "huazhong")
    c.step(1)
    assert c.variables()["plc"]["i"] == 1000
    assert c.plc.banks["R"][0] == 1


def test_a_call_over_the_instruction_limit_faults():
    """Each call runs to completion (no loop-end tick rule; a call over the
    instruction limit faults)."""
    c = controller("init() { }\nplc1() {\n  do { n++; } while (1);\n}\nplc2() { }",
                   "huazhong")
    c.step(5)
    f = faults(c)
    assert len(f) == 1 and "instructions in one call" in f[0].text and f[0].line == 3
    assert c.idle()


def test_x_and_y_bit_layout():
    """`X[n]` (128 bytes, machine → PLC: input pin 8n+b is bit b of X[n]), `Y[n]`
    (128 bytes, PLC → machine outputs, same bit layout)"""
    c = controller("""
        init() { plc1_time = 1; }
        plc1() { Y[1] = X[0]; }
        plc2() { }""", "huazhong")
    for pin in range(8):
        c.set_input(pin, 1 if pin in (1, 3) else 0)
    c.step(2)
    assert [p for p in c.machine.outputs_on() if 8 <= p < 16] == [9, 11]


def test_b_kept_across_a_controller_restart():
    """`B[n]` (100 16-bit words kept across controller restarts)"""
    src = "init() { B[0] += 1; R[0] += 1; }\nplc1() { }\nplc2() { }"
    c = controller(src, "huazhong")
    c.step(3)
    kept = c.retained()
    assert kept[0] == 1
    again = controller(src, "huazhong", retained=tuple(kept))
    again.step(3)
    assert again.plc.banks["B"][0] == 2 and again.plc.banks["R"][0] == 1


def test_p_from_the_parameters():
    """`P[n]` (100 16-bit user parameters, from a project file)"""
    c = controller("init() { a = P[99]; }\nplc1() { }\nplc2() { }", "huazhong",
                   parameters=(0,) * 99 + (65535,))
    c.step(1)
    assert c.variables()["plc"]["a"] == 65535


def test_a_write_truncates_to_the_element_width():
    """A write truncates to the element's width"""
    c = controller("""
        init() { i = 2; }
        plc1() { R[0] = 0x1ff; G[0] = 0x12345; B[1] = 0 - 1; R[i] = 300; a = R[0]; }
        plc2() { }""", "huazhong")
    c.step(1)
    banks = c.plc.banks
    assert (banks["R"][0], banks["G"][0], banks["B"][1], banks["R"][2]) == (0xff, 0x2345, 0xffff, 44)
    assert c.variables()["plc"]["a"] == 0xff


def test_index_out_of_range_at_run_time_faults():
    """an index out of range is a compile error when constant, a runtime fault otherwise."""
    c = controller("init() { i = 128; }\nplc1() {\n  a = X[i];\n}\nplc2() { }", "huazhong")
    c.step(2)
    f = faults(c)
    assert len(f) == 1 and f[0].line == 3 and "X[128] is out of range" in f[0].text
    c = controller("init() { i = 0 - 1; }\nplc1() {\n  B[i] = 5;\n}\nplc2() { }", "huazhong")
    c.step(2)
    f = faults(c)
    assert len(f) == 1 and f[0].line == 3 and "B[-1] is out of range" in f[0].text


def test_compound_assignment_and_else_run():
    """Huazhong programs also use `|=`, `&=`, `^=`, `+=`, `-=` and `else`, which
    this target accepts."""
    c = controller("""
        init() { a = 12; a |= 1; a &= 0xd; a ^= 0x20; a += 100; a -= 1; R[1] = 7; R[1] -= 2; }
        plc1() { if (a == 0) b = 1; else b = 2; }
        plc2() { }""", "huazhong")
    c.step(1)
    v = c.variables()["plc"]
    assert v["a"] == ((12 | 1) & 0xd ^ 0x20) + 99 and v["b"] == 2
    assert c.plc.banks["R"][1] == 5


def test_a_period_set_to_zero_at_run_time_faults():
    """variables `plc1_time` and `plc2_time` set their periods in ms"""
    c = controller("init() { z = 0; }\nplc1() { plc1_time = z; }\nplc2() { }", "huazhong")
    c.step(3)
    f = [e for e in c.drain_events() if isinstance(e, Fault)]
    assert len(f) == 1 and "plc1_time is 0" in f[0].text
    assert c.idle()


def test_banks_run_the_same_on_both_vms():
    """Register banks are gvarget/gvarset registers (bytecode/targets.py): the fast
    backend runs the same code as the reference interpreter."""
    from plcbuilder.controller import fastvm, vm
    program = compiled("""
        init() { i = 3; R[i] = 9; R[i] += X[1]; Y[0] |= R[3]; G[i + 1] = R[i] * 2; }
        plc1() { }
        plc2() { }""", "huazhong")
    results = []
    for runner in (vm.run_reference, fastvm.make_runner):
        regs: dict[int, int] = {T.BANKS["X"].base + 1: 4}
        latch = {}

        def get(a):
            if a in T.INDIRECT_LOAD:
                b = T.INDIRECT_LOAD[a]
                return regs.get(b.base + latch[T.INDEX_LATCH], 0)
            return regs.get(a, 0)

        def put(a, v):
            if a in (T.INDEX_LATCH, T.VALUE_LATCH):
                latch[a] = v
            elif a in T.INDIRECT_STORE:
                b = T.INDIRECT_STORE[a]
                regs[b.base + v] = latch[T.VALUE_LATCH] & b.mask
            else:
                regs[a] = v
        host = vm.Host(portset=None, portclr=None, portget=None, gvarget=get, gvarset=put,
                       g0move=None)
        gen = runner(program, [0] * 256, host)
        try:
            next(gen)
        except vm.ProcExit:
            pass
        results.append(regs)
    assert results[0] == results[1]
    assert results[0][T.BANKS["R"].base + 3] == 13 and results[0][T.BANKS["G"].base + 4] == 26


def test_seed_null_program_runs():
    """The seed's plc_null.cld: the smallest program, which compiles and runs
    (and does nothing), in this language's spelling."""
    c = controller("""
        // plc_null: the PLC's empty frame
        init()
        {
        }
        plc1()
        {
            plc1_time = 16;
        }
        plc2()
        {
            plc2_time = 32;
        }""", "huazhong")
    c.step(100)
    assert faults(c) == [] and not c.idle()
    assert c.plc.calls == {"init": 1, "plc1": 7, "plc2": 4}
