"""A small project for the scenario-test tests: procedures with known timing."""

from __future__ import annotations

from pathlib import Path

#: output 3 is on exactly in ticks 5, 6 and 7 (a loop of N iterations takes N ticks)
PULSE = """main()
{
  timer=5;
  do{timer--;}while(timer>0);
  portset(3);
  timer=3;
  do{timer--;}while(timer>0);
  portclear(3);
  exit(99);
};
"""

#: eparam 1 takes the first branch, anything else the second
BRANCH = """main()
{
  a=eparam;
  if (a==1)
  {
    pwm01=10;
    b=1;
  };
  if (a!=1)
  {
    pwm01=20;
    b=2;
  };
  message=PLC_MESSAGE_USER;
  gvarset(20001,a);
  exit(a);
};
"""

DIVIDE = """main()
{
  a=eparam;
  b=10/a;
  exit(99);
};
"""


#: a test that passes: PULSE's output 3 is on in ticks 5..7, and it ends with 99
PASSING = """\
[[test]]
name = "pulse on in ticks 5..7"
ms = 40
scenario = "start PULSE @ 0"
[[test.expect]]
during_ms = [5, 7]
outputs_on = [3]
[[test.expect]]
at_end = true
exit = { PULSE = 99 }
"""

#: a test that fails at line 10: BRANCH with eparam 2 sets PWM 0 to 20, not 10
FAILING = """\
[[test]]
name = "branch two"
ms = 40
scenario = "start BRANCH:2 @ 0"
[[test.expect]]
at_end = true
exit = { BRANCH = 2 }
[[test.expect]]
at_ms = 1
pwm = { 0 = 10 }
"""


def make_project(root: Path, tests: dict[str, str] | None = None,
                 procs: dict[str, str] | None = None) -> Path:
    """A project folder: hardware procedures (PULSE, BRANCH, DIVIDE by default),
    an include/ folder, and tests/NAME.toml for each of ``tests``."""
    (root / "hardware").mkdir(parents=True, exist_ok=True)
    (root / "include").mkdir(exist_ok=True)
    procs = procs if procs is not None else {"PULSE": PULSE, "BRANCH": BRANCH,
                                             "DIVIDE": DIVIDE}
    for name, text in procs.items():
        (root / "hardware" / f"{name}.plc").write_text(text, encoding="utf-8")
    if tests:
        (root / "tests").mkdir(exist_ok=True)
        for name, text in tests.items():
            (root / "tests" / f"{name}.toml").write_text(text, encoding="utf-8")
    return root

#: fails at tick 8: PULSE's output 3 is on in ticks 5..7 only; the run is 1000 ms long
LONG_FAILING = """\
[[test]]
name = "pulse too long"
ms = 1000
scenario = "start PULSE @ 0"
[[test.expect]]
during_ms = [5, 8]
outputs_on = [3]
"""
