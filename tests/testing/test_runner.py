"""Running scenario tests: each time selector's edge cases, each condition's
expected/actual/tick, and a parallel run equal to a serial one."""

from __future__ import annotations

import pytest

from plcbuilder.testing.runner import prepare, run_suite

from tests.testing._proj import make_project


def run_one(tmp_path, body: str, ms: int = 50, scenario: str = "start PULSE @ 0"):
    """Run one test with the expectations ``body``; returns its result."""
    text = f'[[test]]\nname = "t"\nms = {ms}\nscenario = "{scenario}"\n\n{body}'
    suite = prepare(make_project(tmp_path / "p", {"t": text}))
    assert not suite.errors, suite.errors
    (result,) = run_suite(suite, jobs=1).results
    return result


def failures(result):
    return [(f.condition, f.expected, f.actual, f.tick) for f in result.failures]


# ----------------------------------------------------------------- at_ms

@pytest.mark.parametrize("tick, ok", [(4, False), (5, True), (7, True), (8, False)])
def test_at_ms_is_the_state_at_the_end_of_that_tick(tmp_path, tick, ok):
    r = run_one(tmp_path, f"[[test.expect]]\nat_ms = {tick}\noutputs_on = [3]\n")
    assert r.passed is ok
    if not ok:
        assert failures(r) == [("outputs_on = [3]", "output 3 on", "output 3 off", tick)]
        assert r.failures[0].line == 8


# ----------------------------------------------------------------- by_ms

def test_by_ms_reports_the_first_tick_it_held(tmp_path):
    r = run_one(tmp_path, "[[test.expect]]\nby_ms = 30\noutputs_on = [3]\n")
    assert r.passed and r.expectations[0]["tick"] == 5


def test_by_ms_holds_at_its_last_tick(tmp_path):
    assert run_one(tmp_path, "[[test.expect]]\nby_ms = 5\noutputs_on = [3]\n").passed


def test_by_ms_fails_when_it_never_held_and_reports_its_last_tick(tmp_path):
    r = run_one(tmp_path, "[[test.expect]]\nby_ms = 4\noutputs_on = [3]\n")
    assert failures(r) == [("outputs_on = [3]", "output 3 on", "output 3 off", 4)]
    assert "never held by tick 4" in r.failures[0].note


# ------------------------------------------------------------- during_ms

def test_during_ms_holds_at_every_tick(tmp_path):
    assert run_one(tmp_path, "[[test.expect]]\nduring_ms = [5, 7]\noutputs_on = [3]\n").passed


@pytest.mark.parametrize("rng, bad", [("[5, 8]", 8), ("[4, 7]", 4), ("[0, 40]", 0)])
def test_during_ms_fails_at_its_first_bad_tick(tmp_path, rng, bad):
    r = run_one(tmp_path, f"[[test.expect]]\nduring_ms = {rng}\noutputs_on = [3]\n")
    assert [f[3] for f in failures(r)] == [bad]


def test_during_ms_of_one_tick(tmp_path):
    assert run_one(tmp_path, "[[test.expect]]\nduring_ms = [6, 6]\noutputs_on = [3]\n").passed


# ---------------------------------------------------------------- at_end

def test_at_end_is_when_the_run_stops(tmp_path):
    r = run_one(tmp_path, "[[test.expect]]\nat_end = true\noutputs_off = [3]\n"
                          "exit = { PULSE = \"plc_exit_normal\" }\nno_faults = true\n")
    assert r.passed and r.ended_at_ms == 8        # PULSE ends at 8; nothing else runs


def test_the_run_goes_on_while_an_expectation_waits(tmp_path):
    r = run_one(tmp_path, "[[test.expect]]\nat_ms = 30\noutputs_off = [3]\n"
                          "[[test.expect]]\nat_end = true\nfaults = 0\n")
    assert r.passed and r.ended_at_ms == 30


# ------------------------------------------------------------ conditions

def test_every_condition_holds_on_the_branch_program(tmp_path):
    body = ("[[test.expect]]\nat_end = true\npwm = { 0 = 10 }\nmessage = \"PLC_MESSAGE_USER\"\n"
            "print = { 20001 = 1 }\nexit = { BRANCH = 1 }\nvars = { \"BRANCH.b\" = 1 }\n"
            "axes = { X = [-100000, 100000] }\nno_faults = true\nproc = 0\n"
            "outputs_off = [0]\ninputs_off = [\"INPUT_ESTOP\"]\n")
    r = run_one(tmp_path, body, scenario="start BRANCH:1 @ 0")
    assert r.passed, [f.text() for f in r.failures]


def test_every_condition_reports_expected_and_actual(tmp_path):
    body = ("[[test.expect]]\nat_end = true\npwm = { 0 = 10 }\nmessage = \"PLC_MESSAGE_PLASMA_OK\"\n"
            "print = { 20001 = 1 }\nexit = { BRANCH = 1, PULSE = 99 }\n"
            "vars = { \"BRANCH.b\" = 1, \"PULSE.timer\" = 0 }\n"
            "axes = { X = [5, 6] }\nproc = \"plc_proc_spindle\"\noutputs_on = [0, 1]\n"
            "faults = 1\n")
    r = run_one(tmp_path, body, scenario="start BRANCH:2 @ 0")
    got = {f[0].split(" =")[0]: f[1:] for f in failures(r)}
    assert got["pwm"][:2] == ("pwm 0 = 10", "pwm 0 = 20")
    assert got["message"][0] == "sent: PLC_MESSAGE_PLASMA_OK (101)"
    assert "PLC_MESSAGE_USER at 0" in got["message"][1]
    assert got["print"][:2] == ("print [20001] = 1", "[20001] printed 2")
    assert got["exit"][:2] == ("BRANCH exit 1, PULSE exit plc_exit_normal (99)",
                               "BRANCH exit plc_exit_gas_fail (2) (ended at 0 ms), PULSE not started")
    assert got["vars"][:2] == ("BRANCH.b = 1, PULSE.timer = 0",
                               "BRANCH.b = 2, PULSE has not run")
    assert got["axes"][0] == "X in [5, 6]" and got["axes"][1].startswith("X = ")
    assert got["proc"][:2] == ("proc plc_proc_spindle (70)", "proc plc_proc_idle (0)")
    assert got["outputs_on"][:2] == ("outputs 0, 1 on", "outputs 0, 1 off")
    assert got["faults"][:2] == ("1 fault", "0")
    assert {f[3] for f in failures(r)} == {r.ended_at_ms}


def test_a_fault_is_reported_with_its_text(tmp_path):
    r = run_one(tmp_path, "[[test.expect]]\nat_end = true\nno_faults = true\n",
                scenario="start DIVIDE:0 @ 0")
    (f,) = r.failures
    assert f.expected == "no fault" and "division by zero" in f.actual
    assert "DIVIDE.plc:4" in f.actual


def test_vars_during_a_range_are_read_every_tick(tmp_path):
    r = run_one(tmp_path, '[[test.expect]]\nduring_ms = [0, 3]\nvars = { "PULSE.timer" = 5 }\n')
    assert failures(r) == [('vars = { "PULSE.timer" = 5 }', "PULSE.timer = 5", "PULSE.timer = 4", 0)]
    r = run_one(tmp_path / "b", '[[test.expect]]\nat_ms = 2\nvars = { "PULSE.timer" = 2 }\n')
    assert r.passed


def test_message_counts_a_reply_to_mycnc_by_its_command(tmp_path):
    reply = ("main(){ command=PLC_MESSAGE_SPINDLE_SPEED_CHANGED; parameter=5; "
             "message=PLCCMD_REPLY_TO_MYCNC; exit(99); };\n")
    text = ('[[test]]\nname = "t"\nscenario = "start R @ 0"\n[[test.expect]]\nby_ms = 3\n'
            'message = "PLC_MESSAGE_SPINDLE_SPEED_CHANGED"\n')
    suite = prepare(make_project(tmp_path / "p", {"t": text}, {"R": reply}))
    assert run_suite(suite, jobs=1).results[0].passed


def test_a_message_is_not_sent_before_its_tick(tmp_path):
    r = run_one(tmp_path, '[[test.expect]]\nby_ms = 0\nmessage = "PLC_MESSAGE_USER"\n',
                scenario="start BRANCH:1 @ 3")
    assert failures(r)[0][2] == "sent: no message" and failures(r)[0][3] == 0


# ------------------------------------------------------------- selection

def test_k_selects_by_name(tmp_path):
    text = "".join(f'[[test]]\nname = "{n}"\nscenario = "start PULSE @ 0"\n'
                   f'[[test.expect]]\nat_ms = 5\noutputs_on = [3]\n' for n in ("alpha", "beta"))
    root = make_project(tmp_path / "p", {"t": text})
    assert [t.name for t in prepare(root, "ALP").tests] == ["alpha"]
    assert [t.name for t in prepare(root, "t").tests] == ["alpha", "beta"]   # the file name


# -------------------------------------------------------------- parallel

def test_parallel_results_equal_serial_ones_in_order(tmp_path):
    blocks = []
    for i in range(8):
        ok = i % 3 != 0
        blocks.append(f'[[test]]\nname = "t{i}"\nms = {200 + i}\n'
                      f'scenario = "start BRANCH:{1 if ok else 2} @ {i}"\n'
                      f'[[test.expect]]\nby_ms = {50 + i}\npwm = {{ 0 = 10 }}\n'
                      f'[[test.expect]]\nduring_ms = [{60 + i}, {100 + i}]\n'
                      f'vars = {{ "BRANCH.b" = 1 }}\n'
                      f'[[test.expect]]\nat_end = true\nexit = {{ BRANCH = 1 }}\n')
    suite = prepare(make_project(tmp_path / "p", {"many": "\n".join(blocks)}))
    serial = run_suite(suite, jobs=1)
    parallel = run_suite(suite, jobs=2)
    assert parallel.jobs == 2 and serial.jobs == 1
    assert [r.outcome() for r in parallel.results] == [r.outcome() for r in serial.results]
    assert [r.passed for r in serial.results] == [i % 3 != 0 for i in range(8)]
    cov_s = run_suite(suite, jobs=1, coverage=True).coverage
    cov_p = run_suite(suite, jobs=2, coverage=True).coverage
    assert [c.to_dict() for c in cov_p] == [c.to_dict() for c in cov_s]


# ------------------------------------------------------- write and force lines

def test_scenario_lines_force_and_release_outputs_and_variables(tmp_path):
    """Scenario lines (SPEC §5 syntax, extended for writes and forces):
    PULSE's output 3 forced off stays off while it runs; its timer forced to 1
    holds the first loop until released (restore: the program's last store, 0)."""
    r = run_one(tmp_path, "[[test.expect]]\nduring_ms = [0, 12]\noutputs_off = [3]\n"
                          "[[test.expect]]\nat_end = true\nexit = { PULSE = 99 }\n",
                scenario="start PULSE @ 0\\nforce out 3=0 @ 0\\nforce PULSE.timer=1 @ 1\\n"
                         "release PULSE.timer restore @ 9\\nrelease all @ 13")
    assert r.passed, failures(r)


def test_a_scenario_force_of_an_unknown_variable_is_reported_at_its_line(tmp_path):
    text = ('[[test]]\nname = "t"\nms = 50\nscenario = """\nstart PULSE @ 0\n'
            'force PULSE.nope=1 @ 2\n"""\n[[test.expect]]\nat_end = true\nno_faults = true\n')
    suite = prepare(make_project(tmp_path / "p", {"t": text}))
    (err,) = suite.errors
    assert "PULSE has no variable 'nope'" in str(err) and ":6:" in str(err)
