"""Errors a macro caused say where the macro came from, as gcc and clang do
("expanded from pins.h:28"), and the header with the define is flagged
(issue 13, defect 6)."""

from pathlib import Path

from plcbuilder.api import CompileOptions, compile_file
from plcbuilder.diagnostics import Severity, render_text

PINS = "".join(f"// line {n}\n" for n in range(1, 28)) + "#define OUTPUT_SPINDLE 0 +\n"
M03 = """#include pins.h
main()
{
  portset(OUTPUT_SPINDLE);
  a = OUTPUT_SPINDLE;
  portclear(OUTPUT_SPINDLE);
  exit(99);
};
"""


def _project(tmp_path: Path) -> Path:
    (tmp_path / "include").mkdir()
    (tmp_path / "hardware").mkdir()
    (tmp_path / "include" / "pins.h").write_text(PINS)
    (tmp_path / "hardware" / "M03.plc").write_text(M03)
    return tmp_path / "hardware" / "M03.plc"


def test_the_errors_name_the_define_and_the_header_is_flagged(tmp_path):
    src = _project(tmp_path)
    r = compile_file(src, CompileOptions(include_dirs=(tmp_path / "include",)))
    errors = [d for d in r.diagnostics if d.severity == Severity.ERROR]
    assert [d.span.line for d in errors] == [4, 5, 6]
    pins = str(tmp_path / "include" / "pins.h")
    for d in errors:
        assert d.span.file == str(src)
        (note,) = d.related
        assert note.span.file == pins and note.span.line == 28
        assert note.message == "expanded from OUTPUT_SPINDLE: #define OUTPUT_SPINDLE 0 +"
    in_header = [d for d in r.diagnostics if d.span and d.span.file == pins]
    # one note per message the define caused, however many uses
    assert {d.severity for d in in_header} == {Severity.NOTE}
    assert all(d.span.line == 28 and d.code == "macro-error" for d in in_header)
    assert len(in_header) == len({d.message for d in errors})
    text = render_text(errors[0], r.source_line)
    assert f"note: {pins}:28:9: expanded from OUTPUT_SPINDLE" in text


def test_errors_a_macro_did_not_cause_have_no_note(tmp_path):
    src = tmp_path / "M05.plc"
    src.write_text("#define LAMP 5\nmain()\n{\n  portset(LAMP);\n  a = ;\n  exit(99);\n};\n")
    r = compile_file(src)
    (d,) = r.diagnostics
    assert d.span.line == 5 and d.related == ()
