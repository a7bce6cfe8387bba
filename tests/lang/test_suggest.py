"""Issue 23, "Did you mean?": a misspelled name gets the nearest name in scope
as a hint, in the diagnostic itself (so check, the IDE and the language server
all show it), and no hint when nothing is near or the name is short."""

from plcbuilder.lang.pipeline import compile_source
from plcbuilder.lang.suggest import did_you_mean, distance, max_distance


def hints(text: str, code: str) -> list:
    r = compile_source(text, "M03.plc")
    return [list(d.hints) for d in r.diagnostics if d.code == code]


def test_distance():
    assert distance("timer", "timer", 2) == 0
    assert distance("timr", "timer", 2) == 1
    assert distance("tiemr", "timer", 2) == 1          # two letters swapped: one edit
    assert distance("OUTPUT_SPINDLEX", "OUTPUT_SPINDLE", 3) == 1
    assert distance("abcdef", "uvwxyz", 2) == 3        # past the limit: limit + 1
    assert [max_distance(n) for n in ("a1", "pwm1", "timer", "counter", "OUTPUT_SPINDLEX")] == \
        [0, 1, 1, 2, 3]


def test_the_nearest_name_wins():
    assert did_you_mean("OUTPUT_SPINDLEX", ["OUTPUT_SPINDLE", "OUTPUT_COOLANT", "INPUT_SPINDLE"]) \
        == "OUTPUT_SPINDLE"
    assert did_you_mean("Timer", ["timer", "times"]) == "timer"      # a change of case first
    assert did_you_mean("a1", ["a2", "b1"]) is None                  # short: on purpose
    assert did_you_mean("zork", ["timer", "pwm01"]) is None
    assert did_you_mean("timer", ["timer"]) is None                  # not itself


def test_a_misspelled_define_or_pin_gets_a_hint():
    text = "#include pins.h\nmain(){ portset(OUTPUT_SPINDLEX); exit(99); };"
    assert hints(text, "never-assigned") == [["did you mean OUTPUT_SPINDLE?"]]
    text = "#define LIMIT 100\nmain(){ x = LIMMIT; gvarset(7, x); exit(99); };"
    assert hints(text, "never-assigned") == [["did you mean LIMIT?"]]


def test_a_misspelled_predefined_variable_gets_a_hint():
    assert hints("main(){ timr = 5; exit(99); };", "never-read") == [["did you mean timer?"]]
    assert hints("main(){ x = timr; gvarset(7, x); exit(99); };", "never-assigned") == \
        [["did you mean timer?"]]
    assert hints("main(){ x = plc_exit_normall; gvarset(7, x); exit(99); };",
                 "never-assigned") == [["did you mean plc_exit_normal?"]]


def test_a_misspelled_function_or_procedure_gets_a_hint():
    text = "step(){ x=1; };\nmain(){ portsett(1); stpe(); step(); gvarset(7, x); exit(99); };"
    assert hints(text, "undefined-procedure") == [["did you mean portset()?"],
                                                  ["did you mean step()?"]]


def test_no_hint_where_nothing_is_near():
    text = "main(){ x = zork; gvarset(7, x); exit(99); };"
    assert hints(text, "never-assigned") == \
        [["variables start at 0; assign it first, or use a #define for a constant"]]
    # a user's own short names differ by a letter on purpose: no suggestion
    text = "main(){ a1 = 1; a2 = b2; gvarset(7, a1 + a2); exit(99); };"
    assert all("did you mean" not in h for hs in hints(text, "never-assigned") for h in hs)
    assert hints("main(){ cnt2 = 1; exit(99); };", "never-read") == [[]]


def test_check_prints_the_hint(tmp_path):
    import subprocess
    import sys
    src = tmp_path / "M03.plc"
    src.write_text("#include pins.h\nmain()\n{\n  portset(OUTPUT_SPINDLEX);\n  exit(99);\n};\n")
    r = subprocess.run([sys.executable, "-m", "plcbuilder", "check", str(src)],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr
    assert f"{src}:4:11: warning: 'OUTPUT_SPINDLEX' is read but never assigned (it is always 0)" \
        in r.stdout
    assert "  hint: did you mean OUTPUT_SPINDLE?" in r.stdout
