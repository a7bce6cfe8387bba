"""The compiler against a project's target (lang/targets.py, SPEC §9)."""

from __future__ import annotations

import pytest

from plcbuilder.api import CompileOptions, compile_source

HZ = "init() { }\nplc1() { }\nplc2() { }\n"
TGM = "".join(f"{n}() {{ exit(1); }}\n" for n in ("Program_Ini", "Program_01", "Program_02",
                                                   "Program_03", "Program_04", "Program_05"))


def diags(text: str, target: str, code=None):
    r = compile_source(text, "plc.plc", CompileOptions(target=target))
    return [d for d in r.diagnostics if code is None or d.code == code], r


def test_huazhong_needs_init_plc1_plc2_in_one_source():
    """one source with `init()`, `plc1()` and `plc2()`"""
    found, r = diags("init() { }\nplc1() { }\n", "huazhong", "target-procedure")
    assert len(found) == 1 and "no plc2() procedure" in found[0].message and not r.ok
    found, r = diags(HZ, "huazhong")
    assert r.ok and found == []          # no main() needed, no "never called" warning


def test_tgmotion_names_are_case_sensitive():
    """procedures `Program_Ini`, `Program_01` … `Program_05`, all required"""
    found, r = diags(TGM.replace("Program_03", "program_03"), "tgmotion", "target-procedure")
    assert len(found) == 1 and "'program_03' must be spelled Program_03" in found[0].message
    assert found[0].span.line == 4
    found, _ = diags(TGM.replace("Program_Ini() { exit(1); }\n", ""), "tgmotion",
                     "target-procedure")
    assert [d.message.split(":")[0] for d in found] == ["no Program_Ini() procedure"]
    assert diags(TGM, "tgmotion")[1].ok


def test_tgmotion_status_without_exit_is_a_warning():
    """each returns its status with `exit(1)` (0 from `Program_Ini` aborts the
    start with an error)."""
    found, r = diags(TGM.replace("Program_Ini() { exit(1); }", "Program_Ini() { }"), "tgmotion",
                     "no-status")
    assert r.ok and len(found) == 1 and "aborts the PLC's start" in found[0].message


@pytest.mark.parametrize("text,what,names", [
    ("main() { X[0] = 1; exit(99); }", "register banks", "huazhong"),
    ("main() { a = 1; a |= 2; exit(99); }", "compound assignment '|='", "huazhong and tgmotion"),
    ("main() { a = 1; a -= 2; exit(99); }", "compound assignment '-='", "huazhong and tgmotion"),
])
def test_target_syntax_refused_on_mycnc_with_a_hint(text, what, names):
    """target-only syntax (`X[n]`, compound assignment) refused on `mycnc` with a
    hint naming the target that has it (issue 15)"""
    found, r = diags(text, "mycnc", "target-syntax")
    assert not r.ok and len(found) == 1 and what in found[0].message
    assert found[0].hints[0].startswith(f"this is {names} syntax")


def test_banks_are_not_tgmotion_syntax():
    found, r = diags(TGM.replace("Program_04() { exit(1); }", "Program_04() { Y[0] = 1; exit(1); }"),
                     "tgmotion", "target-syntax")
    assert not r.ok and 'set target = "huazhong"' in found[0].hints[0]


def test_else_is_in_the_base_language():
    """Huazhong programs also use `|=`, `&=`, `^=`, `+=`, `-=` and `else`, which
    this target accepts."""
    assert diags("main() { if (a) b = 1; else b = 2; exit(99); }", "mycnc")[1].ok
    ops = "init() { a = 1; a |= 2; a &= 3; a ^= 4; a += 5; a -= 6; R[a] += 1; if (a) b = a; else b = 0; }"
    assert diags(ops + "\nplc1() { }\nplc2() { }", "huazhong")[1].ok


@pytest.mark.parametrize("bank,n", [("X", 128), ("Y", 128), ("R", 768), ("G", 256), ("F", 256),
                                    ("P", 100), ("B", 100)])
def test_constant_index_out_of_range_is_a_compile_error(bank, n):
    """an index out of range is a compile error when constant, a runtime fault otherwise."""
    ok = HZ.replace("plc1() { }", f"plc1() {{ a = {bank}[{n - 1}]; }}")
    assert diags(ok, "huazhong")[1].ok
    bad = HZ.replace("plc1() { }", f"plc1() {{ a = {bank}[{n}]; }}")
    found, r = diags(bad, "huazhong", "index-range")
    assert not r.ok and f"{bank}[{n}] is out of range" in found[0].message
    neg = HZ.replace("plc1() { }", f"plc1() {{ {bank}[0 - 1] = 1; }}")
    assert diags(neg, "huazhong", "index-range")[0]


def test_bank_misuse_and_periods():
    """variables `plc1_time` and `plc2_time` set their periods in ms"""
    found, _ = diags(HZ.replace("plc1() { }", "plc1() { a = X; }"), "huazhong", "bank-name")
    assert "X[n]" in found[0].message
    found, _ = diags(HZ.replace("plc1() { }", "plc1() { Q[0] = 1; }"), "huazhong", "no-bank")
    assert "no register bank 'Q'" in found[0].message
    found, r = diags(HZ.replace("plc1() { }", "plc1() {\n  plc1_time = 0;\n}"), "huazhong",
                     "period")
    assert not r.ok and found[0].span.line == 3 and "at least 1" in found[0].message
    found, _ = diags(HZ.replace("plc1() { }", "plc1() { X[0] = 1; }"), "huazhong", "read-bank")
    assert found and "lost" in found[0].message


def test_constant_index_is_one_register_computed_index_goes_through_the_latches():
    """Encoding: bytecode/targets.py (constant index: base + n; else the latches)."""
    from plcbuilder.bytecode import targets as T
    from plcbuilder.bytecode.disasm import instructions
    _, r = diags(HZ.replace("plc1() { }", "plc1() { Y[3] = X[i]; }"), "huazhong")
    consts = [i.arg for i in instructions(r.program) if i.arg is not None and i.arg > 100000]
    assert consts == [T.BANKS["Y"].base + 3, T.INDEX_LATCH, T.BANKS["X"].load]


def test_a_constant_wider_than_the_element_is_a_warning():
    """A write truncates to the element's width"""
    found, r = diags(HZ.replace("plc1() { }", "plc1() { Y[0] = 0x1ff; G[0] = 0xffff; }"),
                     "huazhong", "element-width")
    assert r.ok and len(found) == 1 and "stores 255 (0xff), not 511" in found[0].message


def test_highlighter_knows_the_target_tokens():
    from pygments.token import Error
    from plcbuilder.lang.highlight import PlcLexer
    toks = list(PlcLexer().get_tokens("Y[0] |= 0x80; a -= 1;"))
    assert not any(t is Error for t, _ in toks)
    assert ("|=" in [v for _, v in toks]) and ("[" in [v for _, v in toks])
