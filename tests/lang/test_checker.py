"""Checker details the golden programs do not spell out."""

from plcbuilder.api import CompileOptions, Kind, compile_source


def test_33rd_variable_lists_them_all():
    names = [f"v{i}" for i in range(33)]
    src = "main(){\n" + "".join(f"{n}={i};\n" for i, n in enumerate(names)) + \
        "exit(" + "+".join(names) + ");\n};\n"
    r = compile_source(src)
    (d,) = r.errors
    assert d.code == "too-many-variables" and d.span.line == 34
    listed = d.hints[0]
    assert all(n in listed for n in names)


def test_gvarset_as_value_hint_is_exact():
    r = compile_source("main(){ code=gvarset(6060); exit(code); };")
    (d,) = r.errors
    assert d.message == "gvarset takes 2 arguments and returns nothing; did you mean gvarget(6060)?"


def test_size_is_reported_against_the_limit():
    body = "".join(f"gvarset({7000 + i},{1000 + i});" for i in range(100))
    r = compile_source("main(){" + body + "exit(99);};", "BIG.plc")
    (d,) = r.errors
    assert d.code == "size-limit" and "/512 bytes" in d.message
    r = compile_source("main(){" + body + "exit(99);};", "BIG.plc", CompileOptions(kind=Kind.SOFTWARE))
    assert r.ok and r.size < r.limit == 16384
    r = compile_source("main(){" + body + "exit(99);};", "BIG.plc", CompileOptions(code_limit=4096))
    assert r.ok and r.limit == 4096


def test_errors_are_capped_and_each_reported_once():
    src = "main(){\n" + "a = ;\n" * 200 + "exit(99);\n};\n"
    r = compile_source(src)
    assert 20 <= len(r.errors) <= 30
    assert len({(d.message, d.span) for d in r.errors}) == len(r.errors)


def test_symbols_for_the_ide():
    r = compile_source("#define SPEED 100\nhelper(){ a=SPEED; };\nmain(){ helper(); exit(a); };")
    assert r.symbols.variables == ["a"]
    assert set(r.symbols.procedures) == {"helper", "main"}
    assert r.symbols.defines["SPEED"][0] == "100"


def test_constant_conditions_fold_away():
    a = compile_source("main(){ if (1) { portset(1); } else { portset(2); }; exit(99); };").program
    b = compile_source("main(){ portset(1); exit(99); };").program
    assert a.code == b.code


def test_unary_minus_and_0_minus_x_are_the_same_constant():
    a = compile_source("main(){ gvarset(100020, -100); exit(99); };").program
    b = compile_source("main(){ gvarset(100020, 0-100); exit(99); };").program
    assert a.code == b.code
