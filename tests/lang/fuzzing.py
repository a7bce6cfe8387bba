"""Fuzzing helpers shared by the test suite and scripts/fuzz.py."""

from __future__ import annotations

import random

from plcbuilder.api import CompileOptions, Kind, compile_bytes
from plcbuilder.bytecode.disasm import render_text
from plcbuilder.bytecode.program import Program
from plcbuilder.diagnostics import Severity
from tests.lang.golden_util import GOLDEN

SNIPPETS = ["(", ")", "{", "}", ";", "};", "=", "==", "<<", "+", "-", "!", "~", "&&", "||", "if", "else",
            "do", "while", "exit(", "gvarget(", "gvarset(6060)", "portset(", "0x", "0xfffffffff",
            "main", "main()", "#include pins.h\n", "#define A B\n", "#define B A\n", "/*", "*/", "//",
            "\n", "\x00", "\xff", "é", "@", "#", "99999999999", "x++", "x--", "timer", "pwm01",
            "adc01=", "Param", "g0moveA(1,2,3)", "(((((", ")))))", "{{{{", "}}}}"]


def seeds() -> list[bytes]:
    return [p.read_bytes() for p in sorted(GOLDEN.rglob("*.plc"))]


def mutate(data: bytes, rng: random.Random) -> bytes:
    b = bytearray(data)
    for _ in range(rng.randint(1, 4)):
        kind = rng.randrange(6)
        pos = rng.randint(0, len(b))
        if kind == 0 and b:                       # delete a range
            end = min(len(b), pos + rng.randint(1, 12))
            del b[pos:end]
        elif kind == 1:                           # insert a snippet
            b[pos:pos] = rng.choice(SNIPPETS).encode("utf-8", "surrogatepass")
        elif kind == 2 and b:                     # flip a byte
            i = rng.randrange(len(b))
            b[i] = rng.randrange(256)
        elif kind == 3 and b:                     # duplicate a range
            end = min(len(b), pos + rng.randint(1, 40))
            b[pos:pos] = b[pos:end]
        elif kind == 4:                           # random bytes
            b[pos:pos] = bytes(rng.randrange(256) for _ in range(rng.randint(1, 6)))
        elif b:                                   # swap two ranges of lines
            lines = bytes(b).split(b"\n")
            i, j = rng.randrange(len(lines)), rng.randrange(len(lines))
            lines[i], lines[j] = lines[j], lines[i]
            b = bytearray(b"\n".join(lines))
    return bytes(b)


def large_program(rng: random.Random, target_bytes: int) -> bytes:
    """A program of about target_bytes of code: long runs of statements, some
    inside ifs and loops (long jumps), calls to procedures defined after them
    (far CALL targets), in random order."""
    procs = ["helper0", "helper1", "helper2"]

    def run(n: int) -> str:
        return "".join(f"var03 = var04 * {100000 + rng.randrange(1 << 20)};\n" for _ in range(n))

    def body(budget: int, depth: int = 0) -> str:
        out = []
        while budget > 0:
            n = min(budget, rng.randint(1, 4000) // 10)
            kind = rng.randrange(6)
            if kind == 0 and depth < 3:
                out.append(f"if (eparam == {rng.randrange(9)}) {{\n{body(n, depth + 1)}}}\n")
            elif kind == 1 and depth < 3:
                out.append(f"do {{\n{body(n, depth + 1)}}} while (timer == {rng.randrange(9)});\n")
            elif kind == 2:
                out.append(f"{rng.choice(procs)}();\n")
                n = 1
            else:
                out.append(run(n))
            budget -= n
        return "".join(out)

    lines = target_bytes // 10                     # a line of run() is 10 bytes of code
    main = f"main() {{\n{body(lines * 3 // 4)}exit(99);\n}}\n"
    helpers = "".join(f"{name}() {{\n{body(lines // 12)}}}\n" for name in procs)
    return (main + helpers).encode()


def check_one(data: bytes, software: bool = False, strict: bool = False,
              code_limit: int | None = None) -> None:
    """Compile; anything but diagnostics (an exception, a bad span, an invalid
    binary) is a failure."""
    opts = CompileOptions(kind=Kind.SOFTWARE if software else Kind.HARDWARE, strict=strict,
                          code_limit=code_limit)
    r = compile_bytes(data, "fuzz.plc", opts)
    for d in r.diagnostics:
        assert isinstance(d.severity, Severity)
        assert d.message
        if d.span is not None:
            assert d.span.line >= 1 and d.span.col >= 1
            assert (d.span.end_line, d.span.end_col) >= (d.span.line, d.span.col)
    keys = [(d.code, d.message, d.span) for d in r.diagnostics]
    assert len(keys) == len(set(keys)), "a diagnostic was reported twice"
    assert len(r.errors) <= 120
    if r.program is not None:
        assert r.ok
        raw = r.program.to_bytes()
        back = Program.from_bytes(raw)
        assert back.code == r.program.code
        render_text(back)
