"""The preprocessor: include search, whole-token defines, the origin map."""

from pathlib import Path

from plcbuilder.api import CompileOptions, compile_bytes, compile_file, compile_source
from plcbuilder.lang.preprocess import builtin_header, preprocess_text


def test_builtin_names_need_no_include():
    r = compile_source("main(){ message=PLCCMD_LINE_STOP; exit(plc_exit_normal); };")
    assert r.ok


def test_pins_h_is_builtin_and_names_the_spec_pins():
    text = builtin_header("pins.h")
    for name in ("INPUT_HOME_X", "INPUT_HOME_Y", "INPUT_HOME_Z", "INPUT_PROBE", "INPUT_IHC",
                 "OUTPUT_SPINDLE", "OUTPUT_MIST", "OUTPUT_PLASMA"):
        assert f"#define {name} " in text
    r = preprocess_text("#include pins.h\n", "x.plc")
    assert not r.diagnostics, "the default pins.h has no define-substring pairs"


def test_search_order_procedure_folder_then_include_dirs_then_builtin(tmp_path: Path):
    (tmp_path / "proc").mkdir()
    (tmp_path / "inc").mkdir()
    (tmp_path / "inc" / "pins.h").write_text("#define OUTPUT_SPINDLE 42\n")
    src = tmp_path / "proc" / "M03.plc"
    src.write_text("#include pins.h\nmain(){ a=OUTPUT_SPINDLE; exit(a); };\n")
    r = compile_file(src, CompileOptions(include_dirs=(tmp_path / "inc",)))
    assert r.ok and r.program.code[:2] == bytes([0x03, 42])
    (tmp_path / "proc" / "pins.h").write_text("#define OUTPUT_SPINDLE 7\n")
    r = compile_file(src, CompileOptions(include_dirs=(tmp_path / "inc",)))
    assert r.ok and r.program.code[:2] == bytes([0x03, 7])
    r = compile_file(tmp_path / "proc" / "M03.plc")       # no include dir: the folder's own
    assert r.ok


def test_diagnostics_in_a_header_point_into_the_header(tmp_path: Path):
    (tmp_path / "func_plasma.h").write_text("\n\nplasma_off()\n{\n    portclear(4, 5);\n};\n")
    src = tmp_path / "M02.plc"
    src.write_text('#include "func_plasma.h"\nmain(){ plasma_off(); exit(99); };\n')
    r = compile_file(src)
    (d,) = r.errors
    assert d.span.file.endswith("func_plasma.h") and d.span.line == 5 and d.span.col == 5
    assert r.source_line(d.span.file, d.span.line).strip() == "portclear(4, 5);"


def test_header_procedures_are_compiled_only_when_called(tmp_path: Path):
    (tmp_path / "lib.h").write_text("used(){ a=1; };\nunused(){ b=2; };\n")
    src = tmp_path / "M02.plc"
    src.write_text('#include "lib.h"\nmain(){ used(); exit(a); };\n')
    r = compile_file(src)
    assert r.ok and not r.warnings
    assert [n for n, _ in r.program.procs] == ["main", "used"]


def test_macro_use_points_at_the_use():
    r = compile_source("#define BAD portset(1,2)\nmain(){\n  BAD;\n  exit(99);\n};\n", "m.plc")
    (d,) = r.errors
    assert (d.span.line, d.span.col) == (3, 3)


def test_include_cycle_is_an_error(tmp_path: Path):
    (tmp_path / "a.h").write_text('#include "b.h"\n')
    (tmp_path / "b.h").write_text('#include "a.h"\n')
    src = tmp_path / "x.plc"
    src.write_text('#include "a.h"\nmain(){ exit(99); };\n')
    r = compile_file(src)
    assert any(d.code == "include-cycle" for d in r.errors)


def test_header_included_twice_is_read_once(tmp_path: Path):
    (tmp_path / "lib.h").write_text("helper(){ a=1; };\n#define K 3\n")
    src = tmp_path / "x.plc"
    src.write_text('#include "lib.h"\n#include "lib.h"\nmain(){ helper(); exit(a+K); };\n')
    assert compile_file(src).ok


def test_recursive_defines_do_not_loop():
    r = compile_source("#define A B\n#define B A\nmain(){ x=A; exit(x); };\n")
    assert any(d.code == "never-assigned" for d in r.diagnostics)


def test_binary_huge_missing_and_latin1_files(tmp_path: Path):
    r = compile_bytes(b"\x7fELF\x00\x00\x01", "tool.plc")
    assert [d.code for d in r.diagnostics] == ["file-binary"]
    r = compile_bytes(b"main(){ exit(99); };" + b" " * (1 << 20), "big.plc")
    assert [d.code for d in r.diagnostics] == ["file-too-large"]
    r = compile_file(tmp_path / "nope.plc")
    assert [d.code for d in r.diagnostics] == ["file-not-found"]
    r = compile_bytes("// temp 20\xb0C\nmain(){ exit(99); };".encode("latin-1"), "l.plc")
    assert r.ok and [d.code for d in r.diagnostics] == ["file-encoding"]
    r = compile_file(tmp_path)
    assert [d.code for d in r.diagnostics] == ["file-unreadable"]


def test_crlf_and_bom_keep_columns():
    r = compile_bytes(b"\xef\xbb\xbfmain()\r\n{\r\n  a=1 b=2;\r\n  exit(a);\r\n};\r\n", "w.plc")
    (d,) = r.errors
    assert (d.span.line, d.span.col) == (3, 6)
