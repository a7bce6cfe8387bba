"""Compile benchmark: checking a 300-line procedure, compiling 100 procedures,
the whole pipeline against lark's bare parse of the same text, and checking
again after one keystroke (incremental, as the IDE does while typing) at
300/1,000/3,000 lines against lark's bare parse of the same file."""

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


def keystrokes(text: str):
    """Edits a person makes in the middle of ``text``, each applied to the
    text before it: (what, new text). A character typed into a name and
    deleted again (the lines stay where they are), and Enter pressed and
    taken back (every line below moves)."""
    lines = text.split("\n")
    mid = len(lines) // 2
    at = next(i for i in range(mid, len(lines)) if lines[i].startswith("    v"))
    typed = lines[:at] + ["    v1" + lines[at][5:]] + lines[at + 1:]
    enter = lines[:at] + [lines[at], ""] + lines[at + 1:]
    while True:
        yield "type", "\n".join(typed)
        yield "type", text
        yield "enter", "\n".join(enter)
        yield "enter", text


def incremental_check(sizes=(300, 1000, 3000), reps: int = 3) -> list[str]:
    """The compile after one keystroke with the file's Incremental (what the
    IDE's diagnostics worker runs), as a ratio to lark's bare parse of the
    same file, timed side by side."""
    try:
        from plcbuilder.lang.incremental import Incremental
    except ImportError:
        return ["incremental check: not in this version"]
    lark = bare_lark()
    sw = CompileOptions(kind=Kind.SOFTWARE, code_limit=1 << 20)
    out = []
    for n in sizes:
        body = procedure(n, n)
        text = "#include pins.h\n" + body
        inc = Incremental()
        compile_source(text, f"P{n}.plc", sw, incremental=inc)
        edits = keystrokes(text)
        ratio: dict[str, list[float]] = {"type": [], "enter": []}
        bare_t = []
        for _ in range(reps * 4):
            what, new_text = next(edits)
            bare = _median(lambda: lark.parse(body), 1)
            bare_t.append(bare)
            ratio[what].append(_median(lambda: compile_source(new_text, f"P{n}.plc", sw,
                                                              incremental=inc), 1) / bare)
        out.append(f"check after a keystroke, {body.count(chr(10))} lines: typing "
                   f"{statistics.median(ratio['type']):.2f}x, Enter {statistics.median(ratio['enter']):.2f}x "
                   f"lark's bare parse (floor {statistics.median(bare_t) * 1000:.0f} ms; median of "
                   f"{reps * 2} each; goal at 3,000 lines <= 0.7x with the IDE's worker)")
    return out


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
    ] + incremental_check()
