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


def check_one(data: bytes, software: bool = False, strict: bool = False) -> None:
    """Compile; anything but diagnostics (an exception, a bad span, an invalid
    binary) is a failure."""
    opts = CompileOptions(kind=Kind.SOFTWARE if software else Kind.HARDWARE, strict=strict)
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
