"""Every golden program compiles (or fails) exactly as its inline expectations say."""

import pytest

from tests.lang.golden_util import check_diagnostics, compile_golden, goldens, listing, read_golden

GOLDENS = goldens()


@pytest.mark.parametrize("g", GOLDENS, ids=[g.id for g in GOLDENS])
def test_diagnostics(g):
    check_diagnostics(g, compile_golden(g))


@pytest.mark.parametrize("g", [g for g in GOLDENS if not any(s == "error" for _, s, _ in g.diags)],
                         ids=lambda g: g.id)
def test_disassembly_golden(g):
    r = compile_golden(g)
    assert g.dis_path.exists(), f"{g.dis_path.name} is missing: run scripts/regen_goldens.py"
    assert listing(g, r) == g.dis_path.read_text(encoding="utf-8"), \
        f"{g.id}: the code changed; if that is intended, run scripts/regen_goldens.py"


@pytest.mark.parametrize("g", [g for g in GOLDENS if not any(s == "error" for _, s, _ in g.diags)],
                         ids=lambda g: g.id)
def test_deterministic(g):
    a = compile_golden(g).program.to_bytes()
    b = compile_golden(g).program.to_bytes()
    assert a == b


# Programs too large to store: generated here, checked the same way. Each line
# of STEPS is 20 bytes of code; at 64 KiB the assembler used to crash on a
# 16-bit CALL target instead of reporting the size.
STEPS = "    var03 = var04 * {i}; var05 = var06 * {i};\n"
LARGE = {
    # (options, lines before the call, wrap the lines in an if, expected error on main's line)
    "over_the_limit_and_64k": ("--software", 3500, False,
                               "the limit for a software procedure is 16384"),
    "beyond_16_bit_calls": ("--software --code-limit=1000000", 3500, False,
                            "code is addressed with 16 bits: a procedure is at most 65536 bytes"),
    "beyond_16_bit_jumps": ("--software --code-limit=60000", 1700, True,
                            "a jump in it spans more than 32767 bytes"),
}


def large_program(options: str, lines: int, wrapped: bool, expected: str) -> str:
    body = "".join(STEPS.format(i=100000 + i) for i in range(lines))
    if wrapped:
        body = "    if (eparam == 3) {\n" + body + "    }\n"
    error = f" // error: {expected}" if expected else ""
    return (f"// options: {options}\nmain(){error}\n{{\n{body}    helper();\n    exit(99);\n}}\n"
            "helper() { timer = 1; }\n")


@pytest.mark.parametrize("name", sorted(LARGE))
def test_large_programs_are_a_size_diagnostic(name, tmp_path):
    path = tmp_path / f"{name}.plc"
    path.write_text(large_program(*LARGE[name]), encoding="utf-8")
    g = read_golden(path)
    r = compile_golden(g)
    check_diagnostics(g, r)
    assert r.size > 32767


def test_the_largest_addressable_program_compiles(tmp_path):
    path = tmp_path / "just_fits.plc"
    path.write_text(large_program("--software --code-limit=65536", 3250, False, ""), encoding="utf-8")
    g = read_golden(path)
    r = compile_golden(g)
    check_diagnostics(g, r)
    assert 60000 < r.size <= 65536 and r.program is not None
