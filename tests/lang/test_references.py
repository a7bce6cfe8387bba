"""lang/references.py and SymbolIndex.outline: where a name reaches across a
project's files, its references (from real tokens: comments never count),
and the edits of a rename with the names it refuses."""

from pathlib import Path

import pytest

from plcbuilder.lang import references as R
from plcbuilder.lang import symbols

PINS = ("// my pins: SPINDLE is output 0\n"
        "#define SPINDLE 0\n"
        "#define LAMP 7\n"
        "blink()\n{\n  portset(LAMP);\n}\n")
M03 = ("#include pins.h\n"
       "// SPINDLE on\n"
       "main()\n{\n  speed = eparam;\n  pwm01 = speed;\n  portset(SPINDLE);\n"
       "  blink();\n  exit(99);\n};\n")
M05 = ("#include pins.h\n"
       "main()\n{\n  speed = 0; portclear(SPINDLE); portclear(SPINDLE);\n  exit(99);\n};\n")
LONE = ("#define SPINDLE 5\n"          # a define of its own: not the header's
        "main()\n{\n  portset(SPINDLE);\n  exit(99);\n};\n")


@pytest.fixture
def proj(tmp_path):
    inc = tmp_path / "include"
    hw = tmp_path / "hardware"
    inc.mkdir()
    hw.mkdir()
    files = {inc / "pins.h": PINS, hw / "M03.plc": M03, hw / "M05.plc": M05,
             hw / "LONE.plc": LONE}
    for p, t in files.items():
        p.write_text(t)
    sources = {str(p): t for p, t in files.items()}
    return tmp_path, sources, [inc]


def names(paths):
    return sorted(Path(p).name for p in paths)


def test_a_header_define_reaches_the_files_that_include_it(proj):
    root, sources, dirs = proj
    scope = R.scope_of("SPINDLE", str(root / "hardware/M03.plc"), sources, dirs)
    assert scope.kind == symbols.DEFINE
    assert Path(scope.definition.file).name == "pins.h" and scope.definition.line == 2
    assert names(scope.files) == ["M03.plc", "M05.plc", "pins.h"]     # not LONE.plc
    refs = R.find_references(scope, sources)
    assert [(Path(r.file).name, r.line, r.col) for r in refs if r.file.endswith(".plc")] == \
        [("M03.plc", 7, 11), ("M05.plc", 4, 24), ("M05.plc", 4, 44)]
    (definition,) = [r for r in refs if r.definition]
    assert Path(definition.file).name == "pins.h" and definition.line == 2
    assert all(r.line != 1 for r in refs if r.file.endswith("pins.h"))   # not the comment


def test_asking_from_the_header_gives_the_same_scope(proj):
    root, sources, dirs = proj
    scope = R.scope_of("SPINDLE", str(root / "include/pins.h"), sources, dirs)
    assert names(scope.files) == ["M03.plc", "M05.plc", "pins.h"]


def test_a_define_of_a_procedure_file_is_its_own(proj):
    root, sources, dirs = proj
    scope = R.scope_of("SPINDLE", str(root / "hardware/LONE.plc"), sources, dirs)
    assert names(scope.files) == ["LONE.plc"]
    assert [r.line for r in R.find_references(scope, sources)] == [1, 4]


def test_a_variable_belongs_to_its_file(proj):
    root, sources, dirs = proj
    scope = R.scope_of("speed", str(root / "hardware/M03.plc"), sources, dirs)
    assert scope.kind == symbols.VARIABLE and names(scope.files) == ["M03.plc"]
    assert [r.line for r in R.find_references(scope, sources)] == [5, 6]


def test_a_header_procedure_reaches_the_includers(proj):
    root, sources, dirs = proj
    scope = R.scope_of("blink", str(root / "hardware/M03.plc"), sources, dirs)
    assert scope.kind == symbols.PROCEDURE
    assert "M03.plc" in names(scope.files) and "pins.h" in names(scope.files)


def test_builtin_names_are_found_everywhere_but_not_renamed(proj):
    root, sources, dirs = proj
    scope = R.scope_of("pwm01", str(root / "hardware/M03.plc"), sources, dirs)
    assert scope.kind == R.BUILTIN and scope.read_only
    plan = R.plan_rename(scope, "pwm09", sources, dirs)
    assert plan.error and not plan.edits
    assert R.scope_of("nothing_here", str(root / "hardware/M03.plc"), sources, dirs) is None


def test_the_builtin_header_cannot_be_renamed_in(tmp_path):
    p = tmp_path / "M03.plc"
    src = "#include pins.h\nmain() { portset(OUTPUT_SPINDLE); exit(99); };\n"
    scope = R.scope_of("OUTPUT_SPINDLE", str(p), {str(p): src})
    assert "built-in pins.h" in scope.read_only


def test_rename_plan_and_edits(proj):
    root, sources, dirs = proj
    scope = R.scope_of("SPINDLE", str(root / "hardware/M05.plc"), sources, dirs)
    plan = R.plan_rename(scope, "MOTOR", sources, dirs)
    assert plan.error is None and plan.count == 4 and len(plan.edits) == 3
    m05 = str(root / "hardware/M05.plc")
    new = R.apply_edits(sources[m05], plan.edits[m05], "MOTOR")
    assert "portclear(MOTOR); portclear(MOTOR);" in new and "SPINDLE" not in new
    pins = str(root / "include/pins.h")
    new_pins = R.apply_edits(sources[pins], plan.edits[pins], "MOTOR")
    assert new_pins.startswith("// my pins: SPINDLE is output 0\n#define MOTOR 0\n")
    ref = plan.edits[m05][0]
    assert R.renamed_line(ref, plan.edits[m05], "MOTOR").strip() == \
        "speed = 0; portclear(MOTOR); portclear(MOTOR);"


def test_rename_refuses_bad_and_taken_names(proj):
    root, sources, dirs = proj
    scope = R.scope_of("SPINDLE", str(root / "hardware/M03.plc"), sources, dirs)
    for bad, why in (("2x", "not a name"), ("while", "keyword"), ("portset", "built-in"),
                     ("PLCCMD_LINE_STOP", "built-in"), ("LAMP", "already used"),
                     ("speed", "already used"), ("SPINDLE", "old one")):
        plan = R.plan_rename(scope, bad, sources, dirs)
        assert plan.error and why in plan.error, (bad, plan.error)
        assert not plan.edits


def test_crlf_files_keep_their_line_ends():
    text = "main()\r\n{\r\n  a = 1; a++;\r\n}\r\n"
    scope = R.Scope("a", symbols.VARIABLE, None, ("X.plc",))
    refs = R.find_references(scope, {"X.plc": text})
    assert [(r.line, r.col) for r in refs] == [(3, 3), (3, 10)]
    assert R.apply_edits(text, refs, "count") == "main()\r\n{\r\n  count = 1; count++;\r\n}\r\n"


# ------------------------------------------------------------------ outline
def test_outline_lists_what_the_file_defines_in_order():
    src = ("#include pins.h\n#define LIMIT 10 // ten\n"
           "helper()\n{\n  count++;\n}\n\n"
           "main()\n{\n  if (x) {\n    y = 1;\n  }\n  helper();\n  exit(99);\n};\n")
    idx = symbols.index(src, "M03.plc")
    items = idx.outline()
    assert [(i.name, i.kind, i.line) for i in items] == [
        ("LIMIT", symbols.DEFINE, 2), ("helper", symbols.PROCEDURE, 3),
        ("count", symbols.VARIABLE, 5), ("main", symbols.PROCEDURE, 8),
        ("y", symbols.VARIABLE, 11)]
    assert items[0].detail == "10"                        # the value, no comment
    assert [i.end_line for i in items if i.kind == symbols.PROCEDURE] == [6, 15]
    assert idx.enclosing(12).name == "main" and idx.enclosing(4).name == "helper"
    assert idx.enclosing(7) is None
    assert all(i.name != "OUTPUT_SPINDLE" for i in items)  # the header's are not its own


def test_outline_of_an_unclosed_procedure_runs_to_the_end():
    idx = symbols.index("main()\n{\n  a = 1;\n", "X.plc")
    (main,) = [i for i in idx.outline() if i.kind == symbols.PROCEDURE]
    assert main.end_line == 4
