"""History memory (issue 11, SPEC §7): an hour at real time of 1 hardware and
20 software procedures, every change kept, must stay under 50 MB.

    python scripts/bench.py history            # the hour (about a minute)
    python scripts/bench_history.py 600000     # another span, in ms

The workload: a hardware procedure that switches an output every 10 ms and
sets PWM 0 every 50 ms, and 20 software procedures that each toggle their own
output and write a DAC every 100..2000 ms. The figure is the peak resident memory of a
process that runs it with the history, minus the same run without it (the
floor: the simulator itself), each in a fresh process, and the history's own
estimate of its size.
"""

from __future__ import annotations

import subprocess
import sys
import time

sys.path.insert(0, str(__import__('pathlib').Path(__file__).resolve().parent.parent))
from plcbuilder import api  # noqa: E402
from plcbuilder.controller.history import History  # noqa: E402
from plcbuilder.controller.scenario import Action, Scenario  # noqa: E402
from plcbuilder.controller.session import run_session  # noqa: E402

HOUR_MS = 3_600_000

HW = ("main(){ timer=0; do{ timer++; if (timer % 10 == 0) { if (gvarget(0x400 + 40)) "
      "{ portclear(40); } else { portset(40); }; }; if (timer % 50 == 0) { gvarset(7278, timer % 1000); };"
      " }while(1); };\n")


def _sw(n: int) -> str:
    period = 1 + n % 20
    return (f"main(){{ timer=0; do{{ timer++; if (timer % {period} == 0) {{ if (gvarget(0x400 + {n})) "
            f"{{ portclear({n}); }} else {{ portset({n}); }}; gvarset(7270 + {n % 8}, timer); }}; "
            f"}}while(1); }};\n")


def _controller():
    programs = []
    r = api.compile_source(HW, "M90.plc")
    assert r.ok, r.diagnostics
    programs.append(r.program)
    for n in range(20):
        r = api.compile_source(_sw(n), f"SW{n:02d}.plc",
                               api.CompileOptions(kind=api.Kind.SOFTWARE))
        assert r.ok, r.diagnostics
        programs.append(r.program)
    c = api.Controller(api.default_machine(), record_samples=False)
    c.load(programs)
    return c


def _peak_rss() -> int:
    """This process's peak resident memory in bytes (Linux: VmHWM)."""
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) * 1024
    return 0


def measure(ms: int, with_history: bool) -> tuple[float, int, int, int]:
    """In this process: (seconds, peak RSS bytes, history bytes, changes)."""
    c = _controller()
    t0 = time.perf_counter()
    h = History(c.machine) if with_history else None
    run_session(c, Scenario([Action(0, "start", "M90", 0)]), ms, history=h)
    secs = time.perf_counter() - t0
    if h is None:
        return secs, _peak_rss(), 0, 0
    return secs, _peak_rss(), h.nbytes(), sum(len(s) for s in h.signals.values())


def _in_child(ms: int, with_history: bool) -> tuple[float, int, int, int]:
    out = subprocess.run([sys.executable, __file__, "--child", str(ms), str(int(with_history))],
                         capture_output=True, text=True, check=True).stdout
    a, b, c, d = out.split()
    return float(a), int(b), int(c), int(d)


def run(ms: int = HOUR_MS) -> list[str]:
    floor = _in_child(ms, False)
    got = _in_child(ms, True)
    mb = 1024 * 1024
    extra = (got[1] - floor[1]) / mb
    return [f"history of {ms / 1000:.0f} s (1 hardware + 20 software procedures, {got[3]:,} "
            f"changes): peak RSS {got[1] / mb:.1f} MB with it, {floor[1] / mb:.1f} MB without "
            f"(floor) -> the history costs {extra:.1f} MB (goal < 50 MB); its own estimate "
            f"{got[2] / mb:.1f} MB; run {got[0]:.1f} s vs {floor[0]:.1f} s without "
            f"({got[0] / max(floor[0], 1e-9):.2f}x)"]


if __name__ == "__main__":
    if len(sys.argv) > 1 and sys.argv[1] == "--child":
        print(*measure(int(sys.argv[2]), sys.argv[3] == "1"))
    else:
        for line in run(int(sys.argv[1]) if len(sys.argv) > 1 else HOUR_MS):
            print(line)
