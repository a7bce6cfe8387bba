"""Completion candidates, call tips and hover help (pure functions)."""

from plcbuilder import api
from plcbuilder.bytecode.program import Kind
from plcbuilder.ide import completion, hover
from plcbuilder.ide.editor import (KIND_CONSTANT, KIND_DEFINE, KIND_FUNCTION, KIND_PREDEFINED,
                                   KIND_PROCEDURE, KIND_VARIABLE)

SRC = ("#include pins.h\n#define LIMIT 10\n"
       "helper() { count++; }\n"
       "main() { speed = eparam; helper(); exit(99); }\n")


def names(items, kind=None):
    return {n for n, k in items if kind is None or k == kind}


def test_completions_cover_every_source():
    r = api.compile_source(SRC, "/p/hardware/M03.plc")
    items = completion.completions("s", kind=Kind.HARDWARE, text=SRC, symbols=r.symbols,
                                   defines={"INPUT_PROBE": ("3", "pins.h", 12)})
    assert {"gvarget", "gvarset", "portset", "portclr", "g0moveA", "exit"} <= names(items, KIND_FUNCTION)
    assert {"eparam", "timer", "var00", "pwm01", "adc01"} <= names(items, KIND_PREDEFINED)
    assert "Param" not in names(items)
    assert {"LIMIT", "OUTPUT_SPINDLE", "INPUT_PROBE"} <= names(items, KIND_DEFINE)
    assert {"speed", "count"} <= names(items, KIND_VARIABLE)
    assert "helper" in names(items, KIND_PROCEDURE)
    assert {"GVAR_CURRENT_MOTION_CODE", "PLCCMD_LINE_STOP", "plc_exit_normal"} <= names(items, KIND_CONSTANT)
    assert len(names(items)) == len(items)            # no duplicates


def test_software_procedures_have_param():
    assert "Param" in names(completion.completions("P", kind=Kind.SOFTWARE))


def test_variables_found_while_the_file_does_not_compile():
    text = "main() { total = ; count++; x == 1; }"
    assert completion.scan_variables(text) == ["total", "count"]
    assert completion.scan_procedures("helper()\n{\n}\nmain() {}\n") == ["helper", "main"]
    assert completion.scan_defines("#define A 1 // one\n  # define B (2)\n") == {"A": "1", "B": "(2)"}


def test_header_defines_follow_the_files(tmp_path):
    inc = tmp_path / "include"
    inc.mkdir()
    (inc / "mine.h").write_text("#define MY_PIN 7 // mine\n")
    scan = completion.HeaderDefines()
    d = scan.defines([inc])
    assert d["MY_PIN"] == ("7", str(inc / "mine.h"), 1)
    assert d["OUTPUT_SPINDLE"][1] == "<builtin>/pins.h"     # the built-in pins.h too
    (inc / "mine.h").write_text("\n#define MY_PIN 8\n")
    import os
    os.utime(inc / "mine.h", (1, 1))
    assert scan.defines([inc])["MY_PIN"] == ("8", str(inc / "mine.h"), 2)


def test_signature():
    assert completion.signature("gvarset").startswith("gvarset(addr, value)")
    assert "returns a value" in completion.signature("portget")
    assert completion.signature("nothing") is None


def test_hover_registers_by_number_and_name():
    t = hover.hover_text("6060", "  a = gvarget(")
    assert "GVAR_CURRENT_MOTION_CODE" in t and "0x4d" in t and "0 while" in t
    t = hover.hover_text("GVAR_CURRENT_MOTION_CODE")
    assert "6060" in t and "0x4d" in t
    assert "GVAR_HW_INPUTS0" in hover.hover_text("7180", "gvarget(")
    assert "plain global register" in hover.hover_text("1234", "gvarset(")
    assert "print" in hover.hover_text("20005", "gvarset(")


def test_hover_numbers_in_context():
    assert hover.hover_text("99", "exit(") == "exit code 99: plc_exit_normal — Normal exit"
    assert "PLCCMD_REPLY_TO_MYCNC" in hover.hover_text("1100", "message=")
    assert "plc_proc_probing" in hover.hover_text("33", "proc = ")
    assert hover.hover_text("0x4d", "if (a == ") == "77 (0x4d)"
    assert hover.hover_text("3", "a = ") is None


def test_hover_names():
    r = api.compile_source(SRC, "/p/hardware/M03.plc")
    t = hover.hover_text("LIMIT", symbols=r.symbols)
    assert t.startswith("#define LIMIT 10") and "M03.plc:2" in t
    t = hover.hover_text("OUTPUT_SPINDLE", symbols=r.symbols)
    assert "pins.h" in t and "output pin 0" in t
    assert "signature" not in hover.hover_text("gvarget")
    assert hover.hover_text("gvarget").startswith("gvarget(addr) — built-in function, returns a value")
    assert "plc-variables.xml" in hover.hover_text("var03")
    assert "PWM0" in hover.hover_text("pwm01")
    assert "procedure of this file" in hover.hover_text("helper", symbols=r.symbols)
    assert "variable of this file" in hover.hover_text("speed", symbols=r.symbols)
    assert hover.hover_text("if") is None
    assert hover.hover_text("Param") is None
    assert "parameter" in hover.hover_text("Param", kind=Kind.SOFTWARE)
    assert "Normal exit" in hover.hover_text("plc_exit_normal")
    t = hover.hover_text("MY", header_defines={"MY": ("6060", "/x/my.h", 4)})
    assert "my.h:4" in t and "GVAR_CURRENT_MOTION_CODE" in t
