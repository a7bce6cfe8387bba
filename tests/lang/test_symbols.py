"""lang/symbols.py: what completion, hover and go-to-definition ask, answered
from the real tokens (also while the file does not parse)."""

from plcbuilder.lang import symbols
from plcbuilder.lang.preprocess import BUILTIN_PREFIX

SRC = ("#include pins.h\n"
       "#define LIMIT 10 // ten\n"
       "helper()\n{\n  count++;\n}\n"
       "main() { speed = eparam; helper(); gvarget(6060); message = 1100;\n"
       "  if (speed == LIMIT) { portset(OUTPUT_MIST); } exit(99); }\n")


def at(text: str, word: str, nth: int = 0) -> int:
    i = -1
    for _ in range(nth + 1):
        i = text.index(word, i + 1)
    return i + 1


def test_defines_procedures_and_variables():
    idx = symbols.index(SRC, "M03.plc")
    assert list(idx.procedures) == ["helper", "main"]
    assert list(idx.variables) == ["count", "speed"]          # eparam is predefined
    assert idx.defines["LIMIT"].value == "10"
    assert idx.defines["LIMIT"].span.line == 2
    assert idx.defines["OUTPUT_MIST"].span.file == BUILTIN_PREFIX + "pins.h"
    assert idx.includes == [BUILTIN_PREFIX + "pins.h"]


def test_definitions():
    idx = symbols.index(SRC, "M03.plc")
    assert idx.definition_at(at(SRC, "helper", 1)).line == 3
    assert idx.definition_at(at(SRC, "LIMIT", 1)).line == 2
    span = idx.definition_at(at(SRC, "OUTPUT_MIST"))
    assert span.file == BUILTIN_PREFIX + "pins.h"
    assert idx.definition("GVAR_HW_PWM0") is None          # built-in names have no definition
    assert idx.definition_at(at(SRC, "gvarget")) is None


def test_a_header_of_the_project(tmp_path):
    (tmp_path / "hardware").mkdir()
    inc = tmp_path / "include"
    inc.mkdir()
    (inc / "mine.h").write_text("#ifndef MINE_H\n#define MINE_H\n#define MINE 5\n#endif\n")
    text = "#include mine.h\nmain() { portset(MINE); exit(99); }\n"
    path = tmp_path / "hardware" / "M07.plc"
    idx = symbols.index(text, str(path), path, [inc])
    span = idx.definition("MINE")
    assert span.file.endswith("mine.h") and span.line == 3
    assert idx.defines["MINE"].value == "5"


def test_words_and_occurrences():
    idx = symbols.index(SRC, "M03.plc")
    start, end, word = idx.word_at(at(SRC, "speed"))
    assert word == "speed" and SRC[start:end] == "speed"
    assert idx.word_at(SRC.index("speed") + len("speed"))[2] == "speed"    # caret just after it
    assert idx.word_at(at(SRC, "6060") + 1)[2] == "6060"
    assert idx.word_at(SRC.index("{")) is None
    assert [s.line for s in idx.occurrences("speed")] == [7, 8]
    assert [s.line for s in idx.references_at(at(SRC, "LIMIT"))] == [2, 8]


def test_everything_survives_syntax_errors():
    text = "#define A 1\nhelper() { x = ; y++ \nmain() { z = A +; helper( ; \n"
    idx = symbols.index(text, "M1.plc")
    assert list(idx.procedures) == ["helper", "main"]
    assert list(idx.variables) == ["x", "y", "z"]
    assert idx.definition_at(at(text, "A", 1)).line == 1
    assert symbols.index("@@ \x00 /* never closed", "M1.plc").procedures == {}


def test_completions():
    idx = symbols.index(SRC, "M03.plc")
    items = dict(idx.completions("s"))
    assert items["if"] == symbols.KEYWORD and items["gvarget"] == symbols.FUNCTION
    assert items["eparam"] == symbols.PREDEFINED_VARIABLE and "Param" not in items
    assert items["LIMIT"] == symbols.DEFINE and items["OUTPUT_SPINDLE"] == symbols.DEFINE
    assert items["helper"] == symbols.PROCEDURE and items["speed"] == symbols.VARIABLE
    assert items["PLCCMD_LINE_STOP"] == symbols.CONSTANT
    assert "PLCCMD_LINE_STOP" not in dict(idx.completions(""))   # constants once something is typed
    assert "Param" in dict(idx.completions("P", software=True))
    assert "speed" not in dict(idx.completions("speed"))           # the word being typed
    names = [n for n, _ in idx.completions("s")]
    assert len(names) == len(set(names))


def test_number_contexts():
    idx = symbols.index(SRC, "M03.plc")
    assert idx.context_at(at(SRC, "6060")) == "register"
    assert idx.context_at(at(SRC, "99")) == "exit"
    assert idx.context_at(at(SRC, "1100")) == "message"
    assert symbols.number_context("  a = gvarset( ") == "register"
    assert symbols.number_context("proc = ") == "proc"
    assert symbols.number_context("portclr(") == "pin"
    assert symbols.number_context("a = ") == ""
    assert symbols.number_context("") == ""


def test_numbers():
    assert symbols.number_of("7") == 7
    assert symbols.number_of("0x1f // x") == 31
    assert symbols.number_of("((2))") == 2
    assert symbols.number_of("-1") == -1
    assert symbols.number_of("A") is None and symbols.number_of("1 + 2") is None
    assert symbols.number_of("12ab") is None


def test_header_defines_and_pin_names(tmp_path):
    (tmp_path / "a.h").write_text("#define INPUT_A 77 // x\n  #  define OUTPUT_B (92)\n")
    (tmp_path / "b.h").write_text("#define INPUT_A 79\n")
    found = symbols.header_defines([tmp_path])
    assert found["INPUT_A"].value == "77" and found["INPUT_A"].span.file == str(tmp_path / "a.h")
    assert found["OUTPUT_SPINDLE"].span.file == BUILTIN_PREFIX + "pins.h"
    ins, outs = symbols.pin_names(found)
    assert ins[77] == "INPUT_A" and outs[92] == "OUTPUT_B" and outs[0] == "OUTPUT_SPINDLE"
    ins, outs = symbols.pin_names({"INPUT_X": ("3", None), "OUTPUT_Y": 4, "OUTPUT_Z": "4",
                                   "INPUT_BAD": "FOO", "OUTPUT_HUGE": "100000"})
    assert ins == {3: "INPUT_X"} and outs == {4: "OUTPUT_Y / OUTPUT_Z"}


def test_the_same_defines_as_the_compiler():
    from plcbuilder.lang.pipeline import compile_source
    r = compile_source(SRC, "M03.plc")
    idx = symbols.index(SRC, "M03.plc")
    assert {n: v for n, (v, _s) in r.symbols.defines.items()} == \
        {n: s.value for n, s in idx.defines.items()}
    assert set(r.symbols.procedures) == set(idx.procedures)
    assert set(r.symbols.variables) == set(idx.variables)


def test_own_defines_read_only_the_directive_lines():
    text = "#include pins.h\n#define LIMIT 10 // ten\n#ifdef X\n#define Y 2\n#endif\nmain() { a = 1; }\n"
    found = symbols.own_defines(text, "M1.plc")
    assert {n: s.value for n, s in found.items()} == {"LIMIT": "10"}
    assert found["LIMIT"].span.line == 2
