"""One table of the language's own words: every stage that knows a word reads
it from lang/builtins.py, so the checker, the tokenizer, the highlighter,
completion and hover agree."""

from pygments.token import Keyword, Name

from plcbuilder.bytecode import abi
from plcbuilder.bytecode.program import Kind
from plcbuilder.lang import builtins, symbols
from plcbuilder.lang.highlight import PlcLexer
from plcbuilder.lang.pipeline import CompileOptions, compile_source
from plcbuilder.lang.tokens import TERMINAL_TEXT, Tokenizer


def colour(word: str):
    toks = [(t, v) for t, v in PlcLexer().get_tokens(f"a = {word};\n") if v == word]
    return toks[0][0]


def completed(software: bool) -> dict[str, str]:
    return dict(symbols.index("").completions("x", software=software))


def test_every_builtin_function_compiles_is_highlighted_completed_and_described():
    for name, b in builtins.FUNCTIONS.items():
        args = ", ".join("1" for _ in b.params)
        call = f"a = {name}({args});" if b.returns else f"{name}({args});"
        r = compile_source(f"main() {{ {call} exit(a); }}", "M1.plc")
        assert not [d for d in r.errors if name in d.message], (name, r.errors)
        assert colour(name) is Name.Builtin, name
        assert completed(False)[name] == symbols.FUNCTION
        assert b.signature.endswith(f"{name}({', '.join(b.params)})")
        assert b.doc and b.arity == len(b.params)


def test_a_wrong_number_of_arguments_is_an_error_for_every_function():
    for name, b in builtins.FUNCTIONS.items():
        args = ", ".join("1" for _ in range(b.arity + 1))
        r = compile_source(f"main() {{ {name}({args}); exit(99); }}", "M1.plc")
        assert r.errors, name


def test_every_predefined_variable_is_known_to_the_checker_highlighter_and_completion():
    for name, v in builtins.PREDEFINED.items():
        kind = Kind.SOFTWARE if v.software_only else Kind.HARDWARE
        stmt = f"a = {name};" if v.read_only else f"{name} = 1; a = {name};"
        r = compile_source(f"main() {{ {stmt} exit(a); }}", "M1.plc", CompileOptions(kind=kind))
        assert r.ok, (name, [d.message for d in r.errors])
        assert name not in r.symbols.variables          # not a variable of the file
        assert colour(name) is Name.Variable.Magic, name
        assert completed(v.software_only)[name] == symbols.PREDEFINED_VARIABLE
        assert (v.slot is None) != (v.register is None) and v.doc
    assert "Param" not in completed(False)


def test_software_only_variables_are_user_variables_in_hardware_procedures():
    for name, v in builtins.PREDEFINED.items():
        if v.software_only:
            r = compile_source(f"main() {{ {name} = 1; exit({name}); }}", "M1.plc")
            assert name in r.symbols.variables


def test_slots_and_registers_come_from_the_abi():
    assert builtins.slot_names(False) == abi.SLOT_NAMES
    assert builtins.slot_names(True) == {**abi.SLOT_NAMES, **abi.SOFTWARE_SLOT_NAMES}
    assert builtins.REGISTERS == abi.MAPPED_VARIABLES
    assert {n for n, v in builtins.PREDEFINED.items() if v.read_only} == abi.READ_ONLY_VARIABLES


def test_keywords_are_tokens_highlighted_and_completed():
    for word, terminal in builtins.KEYWORDS.items():
        toks = [t for _d, line, _h, _r in Tokenizer(word, "k", [], []).lines() for t in line]
        assert [(t.kind, t.value) for t in toks] == [(terminal, word)]
        assert TERMINAL_TEXT[terminal] == word
        assert colour(word) is Keyword
        assert completed(False)[word] == symbols.KEYWORD


def test_builtin_names_cannot_be_procedures():
    for name in list(builtins.FUNCTIONS) + list(builtins.PREDEFINED)[:3] + ["PLCCMD_LINE_STOP"]:
        r = compile_source(f"{name}() {{ }}\nmain() {{ exit(99); }}", "M1.plc")
        assert any(d.code == "reserved-name" for d in r.errors), name
        assert builtins.is_reserved(name)
    assert not builtins.is_reserved("speed")
