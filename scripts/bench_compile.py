"""Compile benchmark: checking a 300-line procedure, compiling 100 procedures,
and the whole pipeline against lark's bare parse of the same text."""

from __future__ import annotations

import random
import statistics
import tempfile
import time
from pathlib import Path

from lark import Lark

from plcbuilder.api import CompileOptions, Kind, compile_file, compile_source
from plcbuilder.lang.parser import grammar_text


def bare_lark() -> Lark:
    """lark with its own lexer and no transformer, on the same grammar: the
    baseline the whole pipeline is measured against."""
    return Lark(grammar_text(), parser="lalr")


def procedure(lines: int, seed: int) -> str:
    """A realistic procedure of about ``lines`` lines: helpers, loops, I/O, registers."""
    rng = random.Random(seed)
    out = []
    n = 0
    proc = 0
    while n < lines - 8:
        proc += 1
        out.append(f"step{proc}()")
        out.append("{")
        for _ in range(rng.randint(6, 14)):
            k = rng.randrange(8)
            v = f"v{rng.randrange(20)}"
            if k == 0:
                out.append(f"    {v}=gvarget({rng.choice([6060, 7180, 5021, 17023])});")
            elif k == 1:
                out.append(f"    if ({v}>{rng.randrange(100)}) {{ portset({rng.randrange(16)}); }};")
            elif k == 2:
                out.append("    timer=10; do { timer--; } while (timer>0);")
            elif k == 3:
                out.append(f"    gvarset(8635,(4<<8)|{v});")
            elif k == 4:
                out.append(f"    {v}={v}+(eparam&0xff)*{rng.randrange(1, 9)};")
            elif k == 5:
                out.append(f"    if ({v}==0) {{ message=PLCCMD_LINE_STOP; }} else {{ {v}--; }};")
            elif k == 6:
                out.append(f"    sens=portget({rng.randrange(16)});")
            else:
                out.append(f"    gvarset(20000,{v});")
        out.append("};")
        out.append("")
        n = len(out)
    out.append("main()")
    out.append("{")
    out.extend(f"    step{i}();" for i in range(1, proc + 1))
    out.append("    exit(99);")
    out.append("};")
    return "\n".join(out) + "\n"


def _median(fn, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return statistics.median(times)


def run() -> list[str]:
    sw = CompileOptions(kind=Kind.SOFTWARE)
    text = procedure(300, 1)
    nlines = text.count("\n")
    t0 = time.perf_counter()
    compile_source(text, "P300.plc", sw)               # start-up: builds the parser once
    startup = time.perf_counter() - t0
    check = _median(lambda: compile_source(text, "P300.plc", sw), 15)

    with tempfile.TemporaryDirectory() as d:
        paths = []
        for i in range(100):
            p = Path(d) / f"M{100 + i}.plc"
            p.write_text("#include pins.h\n" + procedure(40, 100 + i))
            paths.append(p)
        many = _median(lambda: [compile_file(p, sw) for p in paths], 3)

    # side by side: the two alternate, so a busy moment hits both alike
    lark = bare_lark()
    bare_t, pipe_t = [], []
    for _ in range(15):
        bare_t.append(_median(lambda: lark.parse(text), 1))
        pipe_t.append(_median(lambda: compile_source(text, "P300.plc", sw), 1))
    bare = statistics.median(bare_t)
    pipeline = statistics.median(pipe_t)
    return [
        f"start-up (first compile, builds the parser): {startup * 1000:.0f} ms",
        f"check a {nlines}-line procedure: {check * 1000:.1f} ms   (goal <= 50 ms)",
        f"compile 100 procedures from disk: {many:.3f} s   (goal <= 1 s)",
        f"lark's bare parse of the same {nlines} lines: {bare * 1000:.1f} ms",
        f"whole pipeline / bare lark parse: {pipeline / bare:.2f}x   (goal <= 1.5x)",
    ]
