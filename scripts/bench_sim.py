"""Simulator benchmark (section ``sim`` of scripts/bench.py):

1. real-time factor of the controller running 1 hardware and 20 software
   procedures headless (samples off), on the default machine and with the
   machine stubbed out (the PLC core alone);               goal >= 3000x
2. one loop run as a bare generator (no controller) by the fast backend, the
   reference interpreter and hand-written Python, side by side (best of 5,
   interleaved), with a stub host:                         goals <= 2x, <= 20x native
3. the workload of issue 14: a hardware procedure that reads an input and
   writes an output every tick (WORKLOAD_HW) with 20 looping software
   procedures, 1,800 s simulated through ``plcbuilder run`` (a subprocess; its
   start-up, a 1 ms run of the same project, is subtracted), against the same
   hardware loop written as plain Python (FLOOR_LOOP: its state in locals, its
   pins in an object's two ints, as a Python programmer would write it):
                                                           goal <= 2.5x
4. the same hardware loop as a bare fast-backend generator (with the machine's
   pins readable, as the controller runs it) against FLOOR_LOOP:  goal <= 1.2x
5. the workload of 3. (in-process) whose hardware procedure writes an output
   its current value every tick, against the same workload without the write:
                                                           goal <= 1.10x
5b. issue 26.6: a whole project through ``plcbuilder run``, two simulated
   hours: a hardware procedure reading an input and writing an output every
   tick and a global every 256 ticks (SIM26_HW) beside 20 software procedures
   each looping on ``gvarget`` (SIM26_SW), against the same work written as
   plain Python (sim26_floor: the hardware loop and the 20 software loops,
   interleaved as the controller runs them: the software ones every 100th
   tick), median of >= 5 interleaved pairs, start-up subtracted:
                                                           goal <= 1.5x
6. the debugger (SPEC §6), the workload of 1. (default machine) run three ways
   in each round: with the debugger detached (the controller as it was
   before it had one), with the debugger and no breakpoint set
                                                           goal >= 0.95x the speed
   detached, and with a breakpoint on a line the hardware procedure runs
   every tick (a hit count that is never reached: asked at every tick, no
   halt), and one in each software procedure's loop too
                                                           goal >= 0.33x
7. a one-hour simulated run of the example project (its software procedures,
   and a hardware procedure watching an input all the time) with ``--trace``
   streamed to disk, in a fresh process: wall time, trace size, peak memory
   (goal < 200 MB).

    .venv/bin/python scripts/bench.py sim

Every ratio is the median of interleaved rounds, each measured against its
floor in the same round (the machine is shared: absolute times move 2-3x).
"""

from __future__ import annotations

import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from plcbuilder import api
from plcbuilder.controller import fastvm, vm
from plcbuilder.controller.controller import Controller

ROOT = Path(__file__).resolve().parent.parent

# the seed's M88 shape: watch an input every ms (until it changes)
HARDWARE = """
#include pins.h
main()
{
  do
  {
    sens=portget(INPUT_PROBE);
    timer++;
  }while(sens==0);
  message=PLCCMD_LINE_STOP;
  timer=2;do{timer--;}while(timer>0);
  exit(99);
};
"""
# software procedures like the seed's: a lube timer, a button toggle, a counter
SOFTWARE = [
    """main(){ do { portset(5); timer=30; do{timer--;}while(timer>0);
                 portclear(5); timer=570; do{timer--;}while(timer>0); } while(1); };""",
    """main(){ last=0; do { b=portget(9); if (b!=0 && last==0) { s=gvarget(0x407);
                 if (s!=0) {portclear(7);} else {portset(7);}; }; last=b; } while(1); };""",
    """main(){ do { n++; gvarset(4000+Param, n); if (n>100000) {n=0;}; } while(1); };""",
    """main(){ do { e=portget(8); if (e!=0) { message=PLC_MESSAGE_PRESSED_ALARM_KEY; }; }
                 while(1); };""",
]
LOOP = """
main()
{
  n=0; hits=0;
  do
  {
    s=portget(3);
    if (s!=0) { hits++; };
    n++;
    if ((n&0xff)==0) { gvarset(8635,hits); };
  }while(n<1000000000);
  exit(99);
};
"""


def native(portget, gvarset):
    """LOOP written by hand in Python, one yield a tick like the VM."""
    n = 0
    hits = 0
    while True:
        s = portget(3)
        if s != 0:
            hits += 1
        n += 1
        if (n & 0xff) == 0:
            gvarset(8635, hits)
        yield
        if not n < 1000000000:
            break


# issue 14's workload: an input read and an output written every tick, a little arithmetic
WORKLOAD_HW = """
main()
{
  n=0; acc=0;
  do
  {
    s=portget(3);
    if (s!=0) { portset(7); } else { portclear(7); };
    acc=(acc+n*3)&0xffff;
    n++;
  }while(n<2000000000);
  exit(99);
};
"""
WORKLOAD_MS = 1_800_000


class _Pins:
    """A machine's pins as plain Python would keep them: two ints."""
    input_count = output_count = 64

    def __init__(self):
        self.in_bits = 0
        self.out_bits = 0


def floor_loop(io):
    """WORKLOAD_HW written as plain Python: one yield a tick."""
    n = 0
    acc = 0
    while True:
        s = io.in_bits >> 3 & 1
        if s != 0:
            io.out_bits |= 128
        else:
            io.out_bits &= ~128
        acc = (acc + n * 3) & 0xffff
        n += 1
        yield
        if not n < 2000000000:
            break


def _floor_seconds(ticks: int) -> float:
    step = floor_loop(_Pins()).__next__
    t0 = time.perf_counter()
    for _ in range(ticks):
        step()
    return time.perf_counter() - t0


def _workload_project(root: Path) -> Path:
    (root / "hardware").mkdir(parents=True)
    (root / "software").mkdir()
    (root / "plcbuilder.toml").write_text('name = "workload"\n')
    (root / "hardware" / "M10.plc").write_text(WORKLOAD_HW)
    for i in range(20):
        (root / "software" / f"S{i:02d}.plc").write_text(SOFTWARE[i % len(SOFTWARE)])
    return root


def _cli_run_seconds(proj: Path, ms: int) -> float:
    exe = Path(sys.executable).with_name("plcbuilder")
    cmd = [str(exe) if exe.exists() else sys.executable, *([] if exe.exists() else
           ["-m", "plcbuilder"]), "run", str(proj), "--start", "M10@0", "--ms", str(ms), "--json"]
    t0 = time.perf_counter()
    subprocess.run(cmd, check=True, capture_output=True, env=dict(os.environ, PYTHONPATH=str(ROOT)))
    return time.perf_counter() - t0


def workload_ratio(rounds: int = 3) -> tuple[float, float, float]:
    """(median ratio, median run seconds beyond start-up, median floor seconds)."""
    ratios, runs, floors = [], [], []
    with tempfile.TemporaryDirectory() as d:
        proj = _workload_project(Path(d) / "w")
        for _ in range(rounds):
            floor = _floor_seconds(WORKLOAD_MS)
            full = _cli_run_seconds(proj, WORKLOAD_MS)
            start = _cli_run_seconds(proj, 1)
            runs.append(full - start)
            floors.append(floor)
            ratios.append((full - start) / floor)
    return statistics.median(ratios), statistics.median(runs), statistics.median(floors)


def fast_loop_ratio(rounds: int = 5, ticks: int = 300_000) -> tuple[float, float]:
    """(median ratio of the fast backend's WORKLOAD_HW generator to floor_loop, floor ns/tick)."""
    prog = _compile(WORKLOAD_HW, "M10")
    nothing = lambda *a: 0  # noqa: E731
    ratios, floors = [], []
    for _ in range(rounds):
        pins = _Pins()
        host = vm.Host(portset=nothing, portclr=nothing, portget=nothing, gvarget=nothing,
                       gvarset=nothing, g0move=nothing, io=pins)
        step = fastvm.make_runner(prog, [0] * 256, host).__next__
        t0 = time.perf_counter()
        for _ in range(ticks):
            step()
        fast = time.perf_counter() - t0
        floor = _floor_seconds(ticks)
        ratios.append(fast / floor)
        floors.append(floor / ticks * 1e9)
    return statistics.median(ratios), statistics.median(floors)


# the workload's procedure with its output write (input 3 stays off, so every
# tick clears output 7, which is already off) and without it
UNCHANGED_WITH = WORKLOAD_HW
UNCHANGED_WITHOUT = WORKLOAD_HW.replace(
    "    if (s!=0) { portset(7); } else { portclear(7); };\n", "")
assert UNCHANGED_WITHOUT != UNCHANGED_WITH


def unchanged_write_ratio(rounds: int = 5, ms: int = 300_000) -> float:
    """Median ratio: the workload (WORKLOAD_HW and the 20 software procedures)
    whose hardware procedure writes an output its current value every tick / the
    same workload without the write."""
    sws = [_compile(SOFTWARE[i % len(SOFTWARE)], f"S{i:02d}", True) for i in range(20)]
    progs = {k: _compile(src, "M10") for k, src in (("with", UNCHANGED_WITH),
                                                      ("without", UNCHANGED_WITHOUT))}
    ratios = []
    for _ in range(rounds):
        took = {}
        for k, prog in progs.items():
            c = Controller(record_samples=False)
            c.load([prog, *sws])
            c.start("M10")
            c.step(10)
            t0 = time.perf_counter()
            c.step(ms)
            took[k] = time.perf_counter() - t0
        ratios.append(took["with"] / took["without"])
    return statistics.median(ratios)


# issue 26.6: the hardware loop writes a global every 256 ticks; each software
# procedure loops on gvarget (one iteration a software tick)
SIM26_HW = """
main()
{
  n=0; hits=0;
  do
  {
    s=portget(3);
    if (s!=0) { portset(7); hits++; } else { portclear(7); };
    n++;
    if ((n&0xff)==0) { gvarset(5000,hits); };
  }while(n<2000000000);
  exit(99);
};
"""
SIM26_SW = """main(){ seen=0; do { v=gvarget(5000); if (v!=seen) { seen=v; k++; }; } while(1); };"""
SIM26_MS = 7_200_000


def _sim26_hw(io, glob):
    """SIM26_HW as plain Python: one yield a tick."""
    n = 0
    hits = 0
    while True:
        s = io.in_bits >> 3 & 1
        if s != 0:
            io.out_bits |= 128
            hits += 1
        else:
            io.out_bits &= ~128
        n += 1
        if (n & 0xff) == 0:
            glob[5000] = hits
        yield
        if not n < 2000000000:
            break


def _sim26_sw(glob):
    """SIM26_SW as plain Python: one yield an iteration."""
    seen = 0
    k = 0
    while True:
        v = glob.get(5000, 0)
        if v != seen:
            seen = v
            k += 1
        yield


def sim26_floor(ms: int) -> float:
    """Seconds for plain Python to do SIM26's work for ``ms`` ticks: the hardware
    loop every tick, the 20 software loops every 100th tick (in that tick, first)."""
    glob: dict = {}
    hw = _sim26_hw(_Pins(), glob).__next__
    sws = [_sim26_sw(glob).__next__ for _ in range(20)]
    t0 = time.perf_counter()
    for t in range(0, ms, 100):
        for sw in sws:
            sw()
        for _ in range(min(100, ms - t)):
            hw()
    return time.perf_counter() - t0


def _sim26_project(root: Path) -> Path:
    (root / "hardware").mkdir(parents=True)
    (root / "software").mkdir()
    (root / "plcbuilder.toml").write_text('name = "sim26"\n')
    (root / "hardware" / "M10.plc").write_text(SIM26_HW)
    for i in range(20):
        (root / "software" / f"S{i:02d}.plc").write_text(SIM26_SW)
    return root


def sim26_ratio(rounds: int = 5, ms: int = SIM26_MS) -> tuple[list[float], float, float]:
    """(each round's ratio, median run seconds beyond start-up, median floor
    seconds) of SIM26 through ``plcbuilder run`` against sim26_floor."""
    ratios, runs, floors = [], [], []
    with tempfile.TemporaryDirectory() as d:
        proj = _sim26_project(Path(d) / "w")
        for _ in range(rounds):
            floor = sim26_floor(ms)
            full = _cli_run_seconds(proj, ms)
            start = _cli_run_seconds(proj, 1)
            runs.append(full - start)
            floors.append(floor)
            ratios.append((full - start) / floor)
    return ratios, statistics.median(runs), statistics.median(floors)


def _compile(src: str, name: str, software: bool = False):
    kind = api.Kind.SOFTWARE if software else api.Kind.HARDWARE
    r = api.compile_source(src, f"{name}.plc", api.CompileOptions(kind=kind))
    assert r.ok, [d.message for d in r.diagnostics]
    return r.program


class _NullMachine:
    """Every PLC-facing call does nothing: what remains is the PLC core."""
    input_count = output_count = 64
    _fields = {"inputs": (0,) * 8, "outputs": (0,) * 8, "pwm": (0,) * 8, "dac": (0,) * 8,
               "adc": (0,) * 8, "axes": (0,) * 9, "velocities": (0,) * 9}

    def portset(self, pin): pass
    def portclear(self, pin): pass
    def portget(self, pin): return 0
    def gvarget(self, addr): return 0
    def gvarset(self, addr, value): pass
    def g0move(self, flags, mask, distance): pass
    def on_message(self, code): pass
    def is_plain_register(self, addr): return True
    def soft_jog(self, axis, speed): pass
    def advance(self): return ()
    def sample_fields(self): return self._fields
    def outputs_on(self): return []
    def axis_positions(self): return {}


def realtime(sim_ms: int, machine=None, backend: str = "fast") -> float:
    hw = _compile(HARDWARE, "M88")
    sws = [_compile(SOFTWARE[i % len(SOFTWARE)], f"S{i:02d}", True) for i in range(20)]
    best = float("inf")
    for _ in range(3):
        c = Controller(record_samples=False, backend=backend,
                       machine=machine() if machine else None)
        c.load([hw, *sws])
        c.start("M88")
        c.step(10)
        t0 = time.perf_counter()
        c.step(sim_ms)
        best = min(best, time.perf_counter() - t0)
        assert c.state().running == "M88" and len(c.state().software) == 20
    return sim_ms / 1000 / best


def _debug_run(mode: str, ms: int) -> float:
    """Seconds to simulate ``ms`` of the workload of realtime() with the debugger
    ``detached``, with ``none`` set, or with breakpoints ``set``."""
    hw = _compile(HARDWARE, "M88")
    sws = [_compile(SOFTWARE[i % len(SOFTWARE)], f"S{i:02d}", True) for i in range(20)]
    c = Controller(record_samples=False)
    if mode == "detached":
        c.plc.debugger = None
    c.load([hw, *sws])
    if mode == "set":                    # never halts: a hit count never reached
        never = {"mode": "eq", "n": 10 ** 9}
        c.debugger.set_breakpoints("M88.plc", [{"line": 8, "hit": never}])
        for i in range(20):
            c.debugger.set_breakpoints(f"S{i:02d}.plc", [{"line": 1, "hit": never}])
    c.start("M88")
    c.step(10)
    t0 = time.perf_counter()
    c.step(ms)
    took = time.perf_counter() - t0
    assert c.debugger.halt is None and c.state().running == "M88"
    return took


def debugger_ratios(rounds: int = 3, ms: int = 30_000) -> tuple[float, float]:
    """Median speed ratios (interleaved rounds): no breakpoint / detached, and
    breakpoints set / detached."""
    none, bps = [], []
    for _ in range(rounds):
        base = _debug_run("detached", ms)
        none.append(base / _debug_run("none", ms))
        bps.append(base / _debug_run("set", ms))
    return statistics.median(none), statistics.median(bps)


def vm_ratios(ticks: int = 200_000) -> tuple[float, float, float]:
    prog = _compile(LOOP, "L")
    assert fastvm.unsupported_reason(prog) is None

    def portget(pin):
        return 0

    def gvarset(addr, value):
        pass

    host = vm.Host(portset=portget, portclr=portget, portget=portget, gvarget=portget,
                   gvarset=gvarset, g0move=gvarset)
    makers = {
        "native": lambda: native(portget, gvarset),
        "fast": lambda: fastvm.make_runner(prog, [0] * 40, host),
        "reference": lambda: vm.run_reference(prog, [0] * 40, host),
    }
    best = {k: float("inf") for k in makers}
    for _ in range(5):                     # interleaved, so load changes hit all three alike
        for k, make in makers.items():
            step = make().__next__
            n = ticks if k != "reference" else ticks // 5
            t0 = time.perf_counter()
            for _ in range(n):
                step()
            best[k] = min(best[k], (time.perf_counter() - t0) / n)
    return best["native"] * 1e9, best["fast"] / best["native"], best["reference"] / best["native"]


_HOUR_SCRIPT = """
import sys, time, resource
from plcbuilder.api import run, RunOptions
t0 = time.perf_counter()
r = run(sys.argv[1], RunOptions(ms=3_600_000, starts=["M03:12000@1000", "M88@2000"],
                                trace=sys.argv[2]))
dt = time.perf_counter() - t0
print(dt, r.report["ended_at_ms"], resource.getrusage(resource.RUSAGE_SELF).ru_maxrss)
"""


def hour_with_trace(gz: bool = False) -> tuple[float, float, float]:
    from plcbuilder.project.new import create_project
    with tempfile.TemporaryDirectory() as d:
        proj = create_project(Path(d) / "shop").root
        (proj / "hardware" / "M88.plc").write_text(HARDWARE)   # runs for the whole hour
        trace = Path(d) / ("trace.csv.gz" if gz else "trace.csv")
        env = dict(os.environ, PYTHONPATH=str(ROOT))
        out = subprocess.run([sys.executable, "-c", _HOUR_SCRIPT, str(proj), str(trace)],
                             capture_output=True, text=True, env=env, check=True).stdout.split()
        wall, ended, rss_kb = float(out[0]), int(out[1]), int(out[2])
        assert ended == 3_600_000
        return wall, trace.stat().st_size / 1e6, rss_kb / 1024


def run() -> list[str]:
    lines = []
    rt = realtime(60_000)
    rt_core = realtime(60_000, _NullMachine)
    rt_ref = realtime(10_000, backend="reference")
    lines.append(f"real-time factor, 1 hardware + 20 software procedures, default machine: "
                 f"{rt:,.0f}x (goal >= 3000x)")
    lines.append(f"  the PLC core alone (machine stubbed): {rt_core:,.0f}x; "
                 f"with the reference interpreter: {rt_ref:,.0f}x")
    ratio, run_s, floor_s = workload_ratio()
    lines.append(f"issue 14 workload (1 hw reading an input and writing an output every tick + "
                 f"20 sw, 1,800 s simulated) through `plcbuilder run`: {run_s:.2f} s beyond "
                 f"start-up vs plain Python {floor_s:.2f} s: {ratio:.2f}x (goal <= 2.5x)")
    rs, run_s, floor_s = sim26_ratio()
    lines.append(f"issue 26.6 workload (1 hw: an input read, an output written every tick, a "
                 f"global every 256 ticks + 20 sw looping on gvarget, 7,200 s simulated) "
                 f"through `plcbuilder run`: {run_s:.2f} s beyond start-up vs plain Python "
                 f"{floor_s:.2f} s: {statistics.median(rs):.2f}x (rounds "
                 f"{', '.join(f'{r:.2f}' for r in rs)}; goal <= 1.5x)")
    fr, floor_ns = fast_loop_ratio()
    lines.append(f"  its hardware loop, fast backend vs plain Python ({floor_ns:.0f} ns/tick): "
                 f"{fr:.2f}x (goal <= 1.2x)")
    lines.append(f"  writing an output its current value every tick: "
                 f"{unchanged_write_ratio():.3f}x the same tick without the write (goal <= 1.10x)")
    none, bps = debugger_ratios()
    lines.append(f"debugger, the workload of the first line: no breakpoint set {none:.2f}x the "
                 f"speed without a debugger (goal >= 0.95x); breakpoints asked every tick "
                 f"{bps:.2f}x (goal >= 0.33x)")
    ns, fast, ref = vm_ratios()
    lines.append(f"one loop, native Python {ns:.0f} ns/tick: fast backend {fast:.2f}x native "
                 f"(goal <= 2x), reference interpreter {ref:.1f}x native (goal <= 20x)")
    for gz in (False, True):
        wall, mb, rss = hour_with_trace(gz)
        lines.append(f"one simulated hour with {'--trace .csv.gz' if gz else '--trace .csv'}: "
                     f"{wall:.1f} s wall ({3600 / wall:,.0f}x), trace {mb:.0f} MB, peak memory "
                     f"{rss:.0f} MB (goal < 200 MB)")
    return lines


if __name__ == "__main__":
    for line in run():
        print(line)
