"""The test file format (SPEC §8): ``tests/*.toml`` in a project, each with one
or more ``[[test]]`` tables.

    load_file(path) -> [TestCase]              parse one file (TestFileError on a mistake)
    load_dir(folder) -> ([TestCase], [TestFileError])
    Expectation, Condition                     what a test expects, and when

A test has a ``name``, a time limit ``ms`` (default 10000), an optional
``machine`` file (relative to the project), a ``scenario`` (the lines of a
scenario file: start, input, adc, stop, event, bind, write, force, release), an
optional ``gcode`` (a G-code program the job runs from 0 ms, SPEC §10) and one or more
``[[test.expect]]`` tables. An expectation has exactly one time selector
(``at_ms``, ``by_ms``, ``during_ms``, ``at_end``) and one or more conditions.

Every mistake is a :class:`TestFileError` with the file, the line (from the
TOML parser's position, or the line of the key) and the reason; an unknown key
names the known ones. Names that need the built project (procedures, their
variables, pins.h names, axes) are checked by :func:`resolve` once it is built.
"""

from __future__ import annotations

import re
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Optional

from plcbuilder._support.files import read_bounded
from plcbuilder._support.toml_errors import TomlLocator, decode_error
from plcbuilder._support.toml_errors import loads as toml_loads
from plcbuilder.controller import names as abi
from plcbuilder.controller.scenario import MAX_TIME_MS, Scenario, ScenarioError

MAX_TEST_FILE_BYTES = 1 << 20
DEFAULT_MS = 10_000
TESTS_DIR = "tests"

SELECTORS = ("at_ms", "by_ms", "during_ms", "at_end")
CONDITIONS = ("outputs_on", "outputs_off", "inputs_on", "inputs_off", "pwm", "dac", "adc",
              "proc", "message", "print", "exit", "vars", "axes", "no_faults", "faults")
TEST_KEYS = ("name", "ms", "machine", "scenario", "gcode", "expect")


class TestFileError(Exception):
    """A test file that cannot be used: ``str()`` reads ``FILE:LINE: reason``."""

    __test__ = False                     # not a pytest class

    def __init__(self, message: str, file, line: Optional[int] = None):
        self.message, self.file, self.line = message, str(file), line
        where = f"{self.file}:{line}" if line else self.file
        super().__init__(f"{where}: {message}")

    def to_dict(self) -> dict:
        return {"file": self.file, "line": self.line, "message": self.message}


@dataclass
class Condition:
    """One condition of an expectation: ``key = value`` as written, at ``line``.
    ``value`` is normalised by :func:`_condition` (numbers for names where the
    name is known without the project; the rest by :func:`resolve`)."""
    key: str
    value: Any
    line: Optional[int]
    text: str                            # as the report shows it: outputs_on = [0]


@dataclass
class Expectation:
    selector: str                        # one of SELECTORS
    lo: int = 0                          # the ticks it looks at (at: lo == hi; by: 0..hi)
    hi: int = 0
    conditions: list[Condition] = field(default_factory=list)
    line: Optional[int] = None

    @property
    def when(self) -> str:
        if self.selector == "at_ms":
            return f"at_ms = {self.hi}"
        if self.selector == "by_ms":
            return f"by_ms = {self.hi}"
        if self.selector == "during_ms":
            return f"during_ms = [{self.lo}, {self.hi}]"
        return "at_end"

    @property
    def needs_vars(self) -> bool:
        return any(c.key == "vars" for c in self.conditions)


@dataclass
class TestCase:
    __test__ = False                     # not a pytest class

    name: str
    file: str
    line: Optional[int]
    ms: int = DEFAULT_MS
    machine: Optional[str] = None
    machine_line: Optional[int] = None
    scenario: Scenario = field(default_factory=Scenario)
    scenario_lines: list = field(default_factory=list)   # the line of each action
    expectations: list[Expectation] = field(default_factory=list)

    @property
    def where(self) -> str:
        return f"{self.file}:{self.line}" if self.line else self.file


# ------------------------------------------------------------------ values

def render(value) -> str:
    """A value as TOML writes it (for messages)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(value, list):
        return "[" + ", ".join(render(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{ " + ", ".join(f"{_key(k)} = {render(v)}" for k, v in value.items()) + " }"
    return str(value)


def _key(k: str) -> str:
    return k if re.fullmatch(r"[A-Za-z0-9_-]+", k) else render(k)


def _is_int(v) -> bool:
    return isinstance(v, int) and not isinstance(v, bool)


def _type_word(v) -> str:
    return {bool: "true or false", int: "a whole number", float: "a number", str: "a string",
            list: "a list", dict: "a table"}.get(type(v), type(v).__name__)


def name_or_number(table: dict[str, int], v, what: str) -> int:
    """A code given as a name of ``table`` or a whole number."""
    if _is_int(v):
        return v
    if isinstance(v, str):
        if v in table:
            return table[v]
        close = [n for n in table if v.lower() in n.lower() or n.lower() in v.lower()][:5]
        hint = f" (did you mean {', '.join(close)}?)" if close else ""
        raise ValueError(f"unknown {what} {v!r}{hint}")
    raise ValueError(f"a {what} is a name or a whole number, not {_type_word(v)}")


MESSAGES, EXITS, PROCS = abi.MESSAGES, abi.EXITS, abi.PROCS


# ----------------------------------------------------------------- parsing

class _File:
    """One file being read: its text, the locator, and error helpers."""

    def __init__(self, path: Path, text: str):
        self.path, self.text = path, text
        self.loc = TomlLocator(text)

    def line(self, *path) -> Optional[int]:
        return self.loc.line_of(tuple(path))

    def error(self, message: str, *path) -> TestFileError:
        return TestFileError(message, self.path, self.line(*path) if path else None)


def load_file(path) -> list[TestCase]:
    """The tests of one file; raises :class:`TestFileError` for the first mistake."""
    path = Path(path)
    try:
        data = read_bounded(path, MAX_TEST_FILE_BYTES, "test file")
    except OSError as exc:
        raise TestFileError(f"cannot read: {exc.strerror or exc}", path) from None
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise TestFileError("not UTF-8 text", path, data[:exc.start].count(b"\n") + 1) from None
    return parse(text, path)


def parse(text: str, path="<tests>") -> list[TestCase]:
    """The tests in the text of a test file (see :func:`load_file`)."""
    f = _File(Path(path), text)
    try:
        doc = toml_loads(text)
    except tomllib.TOMLDecodeError as exc:
        msg, line = decode_error(exc, text)
        raise TestFileError(f"not valid TOML: {msg}", path, line) from None
    for key in doc:
        if key != "test":
            raise f.error(f"unknown key {key!r} (a test file holds [[test]] tables)", key)
    tests = doc.get("test")
    if tests is None:
        raise TestFileError("no [[test]] table (a test file holds one or more [[test]] "
                            "tables)", path, 1)
    if not isinstance(tests, list) or not all(isinstance(t, dict) for t in tests):
        raise f.error("test must be an array of tables: write [[test]]", "test")
    out = []
    expect_base = 0                      # [[test.expect]] headers count across tests
    for i, t in enumerate(tests):
        out.append(_test(f, i, t, expect_base))
        exp = t.get("expect")
        expect_base += len(exp) if isinstance(exp, list) else 0
    return out


def _test(f: _File, i: int, t: dict, expect_base: int) -> TestCase:
    at = ("test", i)
    for key in t:
        if key not in TEST_KEYS:
            raise f.error(f"unknown key {key!r} in [[test]] (known: {', '.join(TEST_KEYS)})",
                          *at, key)
    name = t.get("name")
    if not isinstance(name, str) or not name.strip():
        if name is None:
            raise f.error("a test needs a name (name = \"...\")", *at)
        raise f.error(f"name must be a non-empty string, is {_type_word(name)}", *at, "name")
    tc = TestCase(name=name.strip(), file=str(f.path), line=f.line(*at))
    ms = t.get("ms", DEFAULT_MS)
    if not _is_int(ms) or not 1 <= ms <= MAX_TIME_MS:
        raise f.error(f"ms must be a whole number from 1 to {MAX_TIME_MS}, is {render(ms)}",
                      *at, "ms")
    tc.ms = ms
    machine = t.get("machine")
    if machine is not None:
        if not isinstance(machine, str) or not machine.strip():
            raise f.error("machine must name a file (relative to the project)", *at, "machine")
        tc.machine, tc.machine_line = machine, f.line(*at, "machine")
    scenario = t.get("scenario", "")
    if not isinstance(scenario, str):
        raise f.error(f"scenario must be a string of scenario lines, is {_type_word(scenario)}",
                      *at, "scenario")
    _scenario(f, tc, scenario, at)
    gcode = t.get("gcode")
    if gcode is not None:
        _gcode(f, tc, gcode, at)
    expect = t.get("expect")
    if expect is None or expect == []:
        raise f.error(f"test {tc.name!r} expects nothing: add a [[test.expect]] table", *at)
    if not isinstance(expect, list) or not all(isinstance(e, dict) for e in expect):
        raise f.error("expect must be an array of tables: write [[test.expect]]", *at, "expect")
    for j, e in enumerate(expect):
        tc.expectations.append(_expectation(f, tc, e, ("test", "expect", expect_base + j)))
    return tc


def _scenario(f: _File, tc: TestCase, text: str, at: tuple) -> None:
    if not text.strip():
        return
    key_line = f.line(*at, "scenario")
    first = key_line or 1
    if key_line is not None:             # a multi-line string starting after its quotes
        src = f.loc.lines[key_line - 1] if key_line - 1 < len(f.loc.lines) else ""
        m = re.search(r"=\s*(\"\"\"|''')\s*$", src)
        if m:
            first = key_line + 1
    try:
        sc = Scenario.parse(text, str(f.path), first)
    except ScenarioError as exc:
        line = first + exc.line - 1 if exc.line else key_line
        raise TestFileError(f"scenario: {exc.message}", f.path, line) from None
    lines = [first + k for k, raw in enumerate(text.splitlines())
             if raw.split("#", 1)[0].strip()]
    tc.scenario = sc
    tc.scenario_lines = lines[:len(sc.actions)]


def _gcode(f: _File, tc: TestCase, text, at: tuple) -> None:
    """``gcode = "..."``: the job runs the G-code program from 0 ms. It is
    padded with blank lines so that its line numbers are the test file's: an
    error, the job's line and its M-codes' lines name lines of the .toml."""
    from plcbuilder.controller.gcode import GcodeError, parse
    from plcbuilder.controller.scenario import Action
    if not isinstance(text, str) or not text.strip():
        raise f.error("gcode must be a string holding a G-code program", *at, "gcode")
    key_line = f.line(*at, "gcode") or 1
    first = key_line
    src = f.loc.lines[key_line - 1] if key_line - 1 < len(f.loc.lines) else ""
    if re.search(r"=\s*(\"\"\"|''')\s*$", src):
        first = key_line + 1
    padded = "\n" * (first - 1) + text
    try:
        parse(padded, str(f.path), functions="MSTB")    # the words; the target's at run time
    except GcodeError as exc:
        raise TestFileError(f"gcode: {exc.message}", f.path, exc.line) from None
    tc.scenario.actions.insert(0, Action(0, "gcode", str(f.path), 1, text=padded))
    tc.scenario_lines.insert(0, key_line)


def _expectation(f: _File, tc: TestCase, e: dict, at: tuple) -> Expectation:
    line = f.line(*at)
    known = SELECTORS + CONDITIONS
    for key in e:
        if key not in known:
            raise f.error(f"unknown key {key!r} in [[test.expect]] (time selectors: "
                          f"{', '.join(SELECTORS)}; conditions: {', '.join(CONDITIONS)})",
                          *at, key)
    sel = [k for k in SELECTORS if k in e]
    if len(sel) != 1:
        if not sel:
            raise TestFileError("an expectation needs one time selector (at_ms, by_ms, "
                                "during_ms or at_end)", f.path, line)
        raise f.error(f"an expectation has exactly one time selector, this one has "
                      f"{len(sel)}: {', '.join(sel)}", *at, sel[1])
    s = sel[0]
    v = e[s]
    last = tc.ms - 1

    def tick(x, what: str) -> int:
        if not _is_int(x) or x < 0:
            raise f.error(f"{what} must be a whole number of ms from 0, is {render(x)}", *at, s)
        if x > last:
            raise f.error(f"{what} = {x} is after the test's last tick ({last}: ms = {tc.ms} "
                          f"runs ticks 0..{last})", *at, s)
        return x

    ex = Expectation(s, line=line)
    if s == "at_ms":
        ex.lo = ex.hi = tick(v, "at_ms")
    elif s == "by_ms":
        ex.lo, ex.hi = 0, tick(v, "by_ms")
    elif s == "during_ms":
        if not isinstance(v, list) or len(v) != 2:
            raise f.error(f"during_ms is [FROM, TO] (two ticks), is {render(v)}", *at, s)
        ex.lo, ex.hi = tick(v[0], "during_ms's first tick"), tick(v[1], "during_ms's last tick")
        if ex.lo > ex.hi:
            raise f.error(f"during_ms = {render(v)} ends before it begins", *at, s)
    else:
        if v is not True:
            raise f.error(f"at_end must be true, is {render(v)}", *at, s)
        ex.lo = ex.hi = last
    for key in CONDITIONS:
        if key in e:
            cline = f.line(*at, key) or line
            try:
                value = _condition(key, e[key])
            except ValueError as exc:
                raise TestFileError(f"{key}: {exc}", f.path, cline) from None
            ex.conditions.append(Condition(key, value, cline, f"{key} = {render(e[key])}"))
    if not ex.conditions:
        raise TestFileError(f"an expectation ({ex.when}) needs one or more conditions "
                            f"({', '.join(CONDITIONS)})", f.path, line)
    return ex


def _int_key(k: str, what: str, lo: int, hi: int) -> int:
    try:
        n = int(k, 0)
    except ValueError:
        raise ValueError(f"{k!r} is not a {what} number") from None
    if not lo <= n <= hi:
        raise ValueError(f"{what} {n} does not exist ({lo}..{hi})")
    return n


def _int_value(v, what: str) -> int:
    if not _is_int(v):
        raise ValueError(f"the value of {what} must be a whole number, is {_type_word(v)}")
    return v


def _condition(key: str, v):
    """The value of a condition, checked and normalised (pin names stay names
    until :func:`resolve`)."""
    if key in ("outputs_on", "outputs_off", "inputs_on", "inputs_off"):
        items = v if isinstance(v, list) else [v]
        for p in items:
            if not (_is_int(p) and 0 <= p <= 255) and not isinstance(p, str):
                raise ValueError(f"a pin is a number 0..255 or a pins.h name, not {render(p)}")
        return list(items)
    if key in ("pwm", "dac", "adc"):
        if not isinstance(v, dict) or not v:
            raise ValueError(f"{key} is a table of channel = value ({key} = {{ 0 = 100 }})")
        return {_int_key(k, f"{key} channel", 0, 7): _int_value(x, f"{key} {k}")
                for k, x in v.items()}
    if key == "proc":
        return name_or_number(PROCS, v, "proc state")
    if key == "message":
        items = v if isinstance(v, list) else [v]
        if not items:
            raise ValueError("message names one or more messages")
        return [name_or_number(MESSAGES, m, "message") for m in items]
    if key == "print":
        if not isinstance(v, dict) or not v:
            raise ValueError("print is a table of register = value (print = { 20001 = 5 })")
        return {_int_key(k, "print register", abi.PRINT_FIRST, abi.PRINT_LAST):
                _int_value(x, f"print {k}") for k, x in v.items()}
    if key == "exit":
        if not isinstance(v, dict) or not v:
            raise ValueError("exit is a table of procedure = exit code (exit = { M03 = 99 })")
        return {k: name_or_number(EXITS, x, "exit code") for k, x in v.items()}
    if key == "vars":
        if not isinstance(v, dict) or not v:
            raise ValueError('vars is a table of "PROCEDURE.variable" = value')
        out = {}
        for k, x in v.items():
            proc, dot, var = k.partition(".")
            if not dot or not proc or not var:
                raise ValueError(f'a variable is named "PROCEDURE.variable", not {k!r}')
            out[(proc, var)] = _int_value(x, k)
        return out
    if key == "axes":
        if not isinstance(v, dict) or not v:
            raise ValueError("axes is a table of axis = [low, high] in 0.01 mm")
        out = {}
        for k, x in v.items():
            if k.upper() not in abi.AXES:
                raise ValueError(f"unknown axis {k!r} (one of {', '.join(abi.AXES)})")
            if _is_int(x):
                x = [x, x]
            if not (isinstance(x, list) and len(x) == 2 and all(_is_int(y) for y in x)):
                raise ValueError(f"axis {k} takes [low, high] (0.01 mm, inclusive) or one "
                                 f"position, not {render(x)}")
            if x[0] > x[1]:
                raise ValueError(f"axis {k}: the range {render(x)} is empty (low > high)")
            out[k.upper()] = (x[0], x[1])
        return out
    if key == "no_faults":
        if v is not True:
            raise ValueError(f"no_faults must be true, is {render(v)}")
        return True
    if key == "faults":
        if not _is_int(v) or v < 0:
            raise ValueError(f"faults is the number of faults expected (0 or more), "
                             f"is {render(v)}")
        return v
    raise ValueError(f"unknown condition {key!r}")  # pragma: no cover


# ---------------------------------------------------------------- folders

def test_files(folder) -> list[Path]:
    """``folder/*.toml``, sorted by name."""
    folder = Path(folder)
    try:
        return sorted(p for p in folder.iterdir() if p.suffix == ".toml"
                      and not p.name.startswith(".") and p.is_file())
    except (FileNotFoundError, NotADirectoryError):
        return []


test_files.__test__ = False              # not a pytest function


def load_dir(folder) -> tuple[list[TestCase], list[TestFileError]]:
    """Every test of ``folder/*.toml`` in file order, and the files' errors (one
    per file: the first mistake). Test names must be unique in the project."""
    tests: list[TestCase] = []
    errors: list[TestFileError] = []
    seen: dict[str, TestCase] = {}
    for p in test_files(folder):
        try:
            found = load_file(p)
        except TestFileError as exc:
            errors.append(exc)
            continue
        for t in found:
            if t.name in seen:
                errors.append(TestFileError(f"a second test named {t.name!r} (the first is at "
                                            f"{seen[t.name].where})", t.file, t.line))
                continue
            seen[t.name] = t
            tests.append(t)
    return tests, errors


# --------------------------------------------------------------- resolving

@dataclass
class Names:
    """What the built project offers to name: procedures and their variables,
    pins.h's names, the machine's axes and pin counts."""
    variables: dict[str, set]             # procedure -> its variable names
    pins: dict[str, int]                  # pins.h: NAME -> number
    axes: set = field(default_factory=lambda: set(abi.AXES))
    inputs: int = 256
    outputs: int = 256


_DEFINE = re.compile(r"^\s*#\s*define\s+([A-Za-z_][A-Za-z0-9_]*)\s+(0[xX][0-9a-fA-F]+|\d+)\b",
                     re.M)


def pin_names(text: str) -> dict[str, int]:
    """The ``#define NAME NUMBER`` lines of a pins.h."""
    return {m.group(1): int(m.group(2), 0) for m in _DEFINE.finditer(text)}


def resolve(tc: TestCase, names: Names, machine_names: Optional[Names] = None) -> None:
    """Check the names a test uses against the built project (procedures in the
    scenario, exit and vars; pins.h names; axes the machine has), and turn pin
    names into numbers. Raises :class:`TestFileError` at the line of the name."""
    n = machine_names or names
    procs = names.variables

    def unknown_proc(name: str) -> str:
        shown = ", ".join(sorted(procs)[:20]) or "none"
        return f"no procedure named {name!r} in the project (procedures: {shown})"

    for a, line in zip(tc.scenario.actions, tc.scenario_lines):
        if a.kind in ("start", "bind") and a.name not in procs:
            raise TestFileError(f"scenario: {unknown_proc(a.name)}", tc.file, line)
        if (a.kind == "input" or a.kind == "bind" and a.source == "in") \
                and not 0 <= a.a < n.inputs:
            raise TestFileError(f"scenario: no input {a.a} (the machine has inputs "
                                f"0..{n.inputs - 1})", tc.file, line)
        if a.kind in ("write", "force", "release") and "." in a.name:
            proc, var = a.name.split(".", 1)
            if proc not in procs:
                raise TestFileError(f"scenario: {unknown_proc(proc)}", tc.file, line)
            if var not in procs[proc] and var not in ("command", "parameter"):
                raise TestFileError(f"scenario: {proc} has no variable {var!r} (its variables: "
                                    f"{', '.join(sorted(procs[proc]))})", tc.file, line)
    for ex in tc.expectations:
        for c in ex.conditions:
            def fail(msg: str, c=c):
                return TestFileError(f"{c.key}: {msg}", tc.file, c.line)
            if c.key in ("outputs_on", "outputs_off", "inputs_on", "inputs_off"):
                kind = "output" if c.key.startswith("outputs") else "input"
                count = n.outputs if kind == "output" else n.inputs
                pins = []
                for p in c.value:
                    if isinstance(p, str):
                        if p not in names.pins:
                            like = sorted(k for k in names.pins
                                          if k.startswith(kind.upper() + "_"))
                            raise fail(f"unknown {kind} name {p!r} (pins.h names "
                                       f"{', '.join(like) or 'none'})")
                        p = names.pins[p]
                    if not 0 <= p < count:
                        raise fail(f"no {kind} {p} (the machine has {kind}s 0..{count - 1})")
                    pins.append(p)
                c.value = pins
            elif c.key == "exit":
                for proc in c.value:
                    if proc not in procs:
                        raise fail(unknown_proc(proc))
            elif c.key == "vars":
                for proc, var in c.value:
                    if proc not in procs:
                        raise fail(unknown_proc(proc))
                    if var not in procs[proc]:
                        shown = ", ".join(sorted(procs[proc]))
                        raise fail(f"{proc} has no variable {var!r} (its variables: {shown})")
            elif c.key == "axes":
                for axis in c.value:
                    if axis not in n.axes:
                        raise fail(f"the machine has no axis {axis} (its axes: "
                                   f"{', '.join(sorted(n.axes, key=abi.AXES.index)) or 'none'})")
