"""The pygments lexer: token types, registration, and totality (never raises, round-trips)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from pygments.lexers import get_lexer_by_name, get_lexer_for_filename
from pygments.token import Comment, Error, Keyword, Name, Number, Operator, Punctuation
from pygments.util import ClassNotFound

from plcbuilder.bytecode import abi
from plcbuilder.lang.highlight import PlcLexer

SEED_M03 = """#include pins.h
  #define SPEED 0x10 // speed
/* block
   comment */
helper ()
{
  timer=10; do{timer--;}while(timer>0);
};
main()
{
  val=eparam;
  if (val>0xffff) {val=0xffff;} else val = -1 % 3;
  portset(OUTPUT_SPINDLE); portclr(3);
  message=PLCCMD_LINE_STOP; helper();
  gvarset(GVAR_HW_PWM0, pwm01 << 2 && Param);
  exit(plc_exit_normal);
};
"""


def toks(text: str) -> list[tuple[object, str]]:
    return [(t, v) for _i, t, v in PlcLexer().get_tokens_unprocessed(text) if v.strip()]


def kind(text: str, word: str):
    found = [t for t, v in toks(text) if v == word]
    assert found, f"{word!r} not among the tokens of {text!r}"
    return found[0]


# ------------------------------------------------------------ registration

def test_found_by_name_alias_and_filename():
    assert isinstance(get_lexer_by_name("plc"), PlcLexer)
    assert isinstance(get_lexer_by_name("mycnc-plc"), PlcLexer)
    assert isinstance(get_lexer_for_filename("M03.plc"), PlcLexer)


@pytest.mark.parametrize("fname", ["pins.h", "main.c", "x.txt", "M03.bin"])
def test_claims_no_other_file(fname):
    try:
        lexer = get_lexer_for_filename(fname)
    except ClassNotFound:
        return
    assert not isinstance(lexer, PlcLexer)


def test_does_not_guess_itself_onto_other_text():
    assert PlcLexer.analyse_text("int main(void) { return 0; }") == 0.0
    assert PlcLexer.mimetypes == [] and PlcLexer.alias_filenames == []


def test_pygmentize_command(tmp_path):
    src = tmp_path / "M03.plc"
    src.write_text(SEED_M03)
    exe = Path(sys.executable).with_name("pygmentize")
    cmd = [str(exe)] if exe.exists() else [sys.executable, "-m", "pygments"]
    out = subprocess.run(cmd + ["-l", "plc", "-f", "terminal", str(src)],
                         capture_output=True, text=True, timeout=60)
    assert out.returncode == 0, out.stderr
    assert "\x1b[" in out.stdout and "portset" in out.stdout
    raw = subprocess.run(cmd + ["-l", "plc", "-f", "raw", str(src)],
                         capture_output=True, text=True, timeout=60)
    assert "Token.Name.Builtin\t'portclr'" in raw.stdout
    assert "Token.Error" not in raw.stdout


# ------------------------------------------------------------ token types

def test_comments():
    assert toks("// hello world\n") == [(Comment.Single, "// hello world")]
    assert kind("a=1; /* two\nlines */ b=2;", "/*") in Comment.Multiline
    assert all(t in Comment for t, _v in toks("/* never closed\n x=1;")), "unclosed runs to the end"


def test_preprocessor():
    t = toks('#include pins.h\n#include "my pins.h"\n#include <pins.h>\n  #define OUT_A 5 // c\n')
    assert t[:2] == [(Comment.Preproc, "#include"), (Comment.PreprocFile, "pins.h")]
    assert (Comment.PreprocFile, '"my pins.h"') in t
    assert (Comment.PreprocFile, "<pins.h>") in t
    assert (Comment.Preproc, "#define") in t and (Name.Constant, "OUT_A") in t
    assert (Number.Integer, "5") in t and (Comment.Single, "// c") in t
    assert toks("#include dir/pins.h// note") == [(Comment.Preproc, "#include"),
                                                 (Comment.PreprocFile, "dir/pins.h"),
                                                 (Comment.Single, "// note")]
    assert toks("#ifndef PINS_H\n# endif\n#\n") == [
        (Comment.Preproc, "#ifndef"), (Name.Constant, "PINS_H"), (Comment.Preproc, "# endif"),
        (Comment.Preproc, "#")]
    # a directive is one only at the start of a line
    assert kind("x = 1; #define Y 2", "#") is Error


def test_keywords_builtins_variables_constants():
    src = "if (a) b=1; else do { portset(1); } while (x); exit(99);"
    for w in ("if", "else", "do", "while"):
        assert kind(src, w) is Keyword
    for w in ("portset", "portclear", "portclr", "portget", "gvarget", "gvarset", "g0moveA", "exit"):
        assert kind(f"{w}(1);", w) is Name.Builtin
    names = ["eparam", "proc", "timer", "vexit", "message", "pwm01", "pwm04", "dac01", "dac02",
             "adc01", "adc02", "var00", "var15", "command", "parameter", "Param"]
    for w in names:
        assert kind(f"x={w};", w) in Name.Variable, w
    for w in abi.BUILTIN_NAMES:
        assert kind(f"x={w};", w) is Name.Constant, w
    assert kind("x=myvar;", "myvar") is Name
    assert kind("x=var16;", "var16") is Name
    assert kind("x=PLCCMD_LINE_STOPX;", "PLCCMD_LINE_STOPX") is Name


def test_numbers_operators_punctuation():
    t = toks("x=0x1F+10-0XaB;")
    assert (Number.Hex, "0x1F") in t and (Number.Integer, "10") in t and (Number.Hex, "0XaB") in t
    for op in ("++", "--", "<<", ">>", "<=", ">=", "==", "!=", "&&", "||", "%", "^", "~", "!"):
        assert (Operator, op) in toks(f"a {op} b"), op
    assert [v for t, v in toks("f(a,b);{}") if t is Punctuation] == ["(", ",", ")", ";", "{", "}"]
    # malformed numbers, as the compiler reports them
    for bad in ("12ab", "0x", "0xfg", "0x1_"):
        assert toks(f"x={bad};")[2] == (Error, bad)


def test_procedure_definitions_and_calls():
    src = "helper ( )\n// why\n/* not */ {\n}; main() { helper(); }"
    t = toks(src)
    assert (Name.Function, "helper") in t and (Name.Function, "main") in t
    assert [tk for tk, v in t if v == "helper"] == [Name.Function, Name], "a call is not a definition"
    assert kind("main();", "main") is Name
    assert kind("while() {", "while") is Keyword


def test_invalid_characters_only_are_errors():
    assert [v for t, v in toks(SEED_M03) if t is Error] == []
    bad = "x = 1 @ 2; y = $; z = \"s\"; \\ é"
    assert [v for t, v in toks(bad) if t is Error] == ["@", "$", '"', '"', "\\", "é"]
    assert [v for t, v in toks("// é @ $\n/* ü */") if t is Error] == []


def test_seed_examples_have_no_errors():
    seed = Path("/work/shared/seeds/000_46f074ffe3bf5576.txt")
    if not seed.exists():
        pytest.skip("seed not available")
    blocks = seed.read_text().split("```")[1::2]
    assert blocks
    for b in blocks:
        errs = [v for t, v in toks(b) if t is Error]
        assert errs == [], (b, errs)


def test_get_tokens_keeps_leading_blank_lines():
    text = "\n\nmain() { }\n"
    assert "".join(v for _t, v in PlcLexer().get_tokens(text)) == text


# ------------------------------------------------------------ totality

ALPHABET = st.sampled_from(list("abxX_019 \t\n\r#/*\"<>(){};,=+-!&|^~%@$\\.é") +
                           ["include", "define", "main", "portset", "timer", "0x", "//", "/*",
                            "*/", "if", "PLCCMD_LINE_STOP", "()"])


@settings(max_examples=300, deadline=None)
@given(st.lists(ALPHABET, max_size=60).map("".join))
def test_round_trips_plc_like_text(text):
    tokens = list(PlcLexer().get_tokens_unprocessed(text))
    assert "".join(v for _i, _t, v in tokens) == text
    pos = 0
    for i, _t, v in tokens:
        assert i == pos
        pos += len(v)


@settings(max_examples=200, deadline=None)
@given(st.text(max_size=200))
def test_round_trips_any_text(text):
    tokens = list(PlcLexer().get_tokens_unprocessed(text))
    assert "".join(v for _i, _t, v in tokens) == text
    # get_tokens normalises line endings and ends with a newline, and keeps everything else
    norm = text.replace("\r\n", "\n").replace("\r", "\n")
    if not norm.endswith("\n"):
        norm += "\n"
    assert "".join(v for _t, v in PlcLexer().get_tokens(text)) == norm


@settings(max_examples=100, deadline=None)
@given(st.text(alphabet=st.characters(min_codepoint=32, max_codepoint=126), max_size=200))
def test_errors_only_for_characters_outside_the_language(text):
    for _i, t, v in PlcLexer().get_tokens_unprocessed(text):
        if t is Error:
            assert v in "@$\"'`.?:[]\\#" or v[0].isdigit(), v


def test_large_inputs_finish():
    # no catastrophic backtracking on long runs (definitions' look-ahead, comments)
    for text in ("a()" + " " * 20000, "a() /*" + "x" * 20000, "/*" * 10000, "a()\n" * 5000,
                 SEED_M03 * 200):
        tokens = list(PlcLexer().get_tokens_unprocessed(text))
        assert "".join(v for _i, _t, v in tokens) == text
