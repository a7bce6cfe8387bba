"""Attacks on the files and numbers the product takes (issue 17, items 6, 7,
8, 10 and 12; issue 24, items 7, 8 and 9: trace files, JUnit names, VCD and
CSV exports), against the real command line: each case runs
``python -m plcbuilder …`` in a child, in a temporary folder, with a timeout.

    ATTACKS: list[tuple[str, callable]]   name, attack() -> {"tried", "refused",
                                          "accepted", "crashed"}

Each case is classified:

- refused: the command said no (the exit status the manual gives for it) with
  the expected message, and no harm was done;
- accepted: the hostile input went through (a device replaced, a number
  wrapped, a line of a file outside the project printed, a file written
  outside the project);
- crashed: a traceback, "internal error", a MemoryError/RecursionError, a
  signal, or no answer within the timeout (a hang).

``scripts/attack.py`` imports ATTACKS and prints the table with the others;
run alone, this prints its own table (``--verbose`` lists every case).
Nothing here writes to a real device: the special files are FIFOs made in the
temporary folder and symbolic links there (to /dev/null, which is never
written: the product refuses first, and the old one replaced the link itself);
/dev/zero is only named for reading.
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Callable, Optional

ROOT = Path(__file__).resolve().parents[1]
TIMEOUT_S = float(os.environ.get("ATTACK_TIMEOUT_S", "30"))
OK_SOURCE = "main(){ exit(99); };\n"
MOVE_Z = "main(){ g0moveA(0, 4, 1000); do { m = gvarget(6060); } while (m == 0); exit(99); };\n"
SECRET = "root:x:0:0:attack-secret-line:/root:/bin/bash\n"
CRASH_MARKS = ("Traceback (most recent call last)", "internal error", "MemoryError",
               "RecursionError", "ZeroDivisionError")
VERBOSE = False


class Outcome:
    def __init__(self, rc: Optional[int], out: str, err: str, timed_out: bool):
        self.rc, self.out, self.err, self.timed_out = rc, out, err, timed_out

    @property
    def text(self) -> str:
        return self.out + self.err

    @property
    def crashed(self) -> bool:
        return self.timed_out or (self.rc is not None and self.rc < 0) or \
            any(m in self.text for m in CRASH_MARKS)


def plcbuilder(*argv, cwd: Path, timeout: float = TIMEOUT_S, env: Optional[dict] = None
               ) -> Outcome:
    """``python -m plcbuilder ARGV`` in ``cwd`` (this checkout's package)."""
    e = dict(os.environ, PYTHONPATH=str(ROOT), QT_QPA_PLATFORM="offscreen",
             PLCBUILDER_CONTROLLER_FILE=str(cwd / "attack-runtime.json"))
    e.pop("PLCBUILDER_DEBUG", None)
    e.update(env or {})
    try:
        p = subprocess.run([sys.executable, "-m", "plcbuilder", *map(str, argv)], cwd=cwd,
                           capture_output=True, text=True, timeout=timeout, env=e,
                           stdin=subprocess.DEVNULL)
    except subprocess.TimeoutExpired as exc:
        def s(b):
            return b.decode("utf-8", "replace") if isinstance(b, bytes) else (b or "")
        return Outcome(None, s(exc.stdout), s(exc.stderr), True)
    return Outcome(p.returncode, p.stdout, p.stderr, False)


class Tally:
    """Counts cases; ``case(name, outcome, refused=…, accepted=…)``."""

    def __init__(self, attack: str):
        self.attack = attack
        self.counts = {"tried": 0, "refused": 0, "accepted": 0, "crashed": 0}

    def case(self, name: str, o: Outcome, refused: bool, accepted: bool = False) -> None:
        self.counts["tried"] += 1
        if o.crashed:
            verdict = "crashed"
        elif accepted or not refused:
            verdict = "accepted"
        else:
            verdict = "refused"
        self.counts[verdict] += 1
        if VERBOSE:
            last = (o.err.strip() or o.out.strip()).splitlines()[-1:] or [""]
            print(f"  [{self.attack}] {verdict:8} {name}: rc={o.rc}"
                  f"{' (timeout)' if o.timed_out else ''} {last[0][:160]}", file=sys.stderr)

    def result(self) -> dict:
        return dict(self.counts)


def _mkfifo(path: Path) -> bool:
    if not hasattr(os, "mkfifo"):
        return False
    os.mkfifo(path)
    return True


def _project(root: Path, sources: dict[str, str] | None = None) -> Path:
    (root / "hardware").mkdir(parents=True, exist_ok=True)
    (root / "include").mkdir(exist_ok=True)
    (root / "plcbuilder.toml").write_text('name = "attack"\n')
    for name, text in (sources or {"M03": OK_SOURCE}).items():
        (root / "hardware" / f"{name}.plc").write_text(text)
    return root


def _is_special(p: Path) -> bool:
    """Still what it was: not replaced by a regular file."""
    return os.path.lexists(p) and not (p.is_file() and not p.is_symlink())


# ------------------------------------------------------------------ item 6

def attack_special_outputs() -> dict:
    """Item 6: compile -o / Build All onto a FIFO, a link to a device, a link to
    a FIFO; the special file must stay what it was and the command exit 1."""
    t = Tally("6 special outputs")
    with tempfile.TemporaryDirectory(prefix="attack6-") as d:
        w = Path(d)
        (w / "OK.plc").write_text(OK_SOURCE)
        targets = []
        if _mkfifo(w / "fifo.bin"):
            targets.append(("FIFO", w / "fifo.bin", False))
            (w / "to-fifo.bin").symlink_to(w / "fifo.bin")
            targets.append(("link to a FIFO", w / "to-fifo.bin", True))
        if os.path.exists("/dev/null"):
            (w / "to-null.bin").symlink_to("/dev/null")
            targets.append(("link to /dev/null", w / "to-null.bin", True))
        for label, path, link in targets:
            o = plcbuilder("compile", "OK.plc", "-o", path.name, cwd=w)
            still = path.is_symlink() if link else _is_special(path)
            t.case(f"compile -o {label}", o, refused=o.rc == 1 and "not a regular file" in o.err
                   and still, accepted=not still)
        # Build All writing into build/ where a FIFO sits in the image's place
        proj = _project(w / "proj")
        (proj / "build").mkdir()
        for name in ("eeprom.rom", "M03.bin"):
            target = proj / "build" / name
            if os.path.lexists(target):
                target.unlink()
            if not _mkfifo(target):
                continue
            o = plcbuilder("build", proj, cwd=w)
            still = _is_special(target)
            t.case(f"build with build/{name} a FIFO", o,
                   refused=o.rc == 1 and "not a regular file" in o.err and still,
                   accepted=not still)
            target.unlink()
    return t.result()


# ------------------------------------------------------------------ item 7

def attack_machine_values() -> dict:
    """Item 7: axis speeds and accelerations that are zero, subnormal, huge,
    negative or not numbers; each must be refused naming the key (exit 2),
    never crash the simulation."""
    t = Tally("7 machine values")
    values = ["5e-324", "1e-320", "0.0", "-0.0", "1e-9", "-1", "1e308", "nan", "inf", "-inf"]
    with tempfile.TemporaryDirectory(prefix="attack7-") as d:
        w = Path(d)
        (w / "M03.plc").write_text(MOVE_Z)
        for key in ("accel", "rapid", "jog"):
            for v in values:
                if key == "jog" and v in ("0.0", "-0.0", "1e-9", "5e-324", "1e-320"):
                    continue          # a jog speed of (nearly) 0 is allowed: nothing divides by it
                (w / "m.toml").write_text(f"[axes.Z]\n{key} = {v}\n")
                o = plcbuilder("run", "M03.plc", "--machine", "m.toml", "--ms", "2000",
                               "--json", cwd=w)
                t.case(f"{key} = {v}", o, refused=o.rc == 2 and f"axes.Z.{key}" in o.err)
    return t.result()


# ------------------------------------------------------------------ item 8

def attack_unbounded_reads() -> dict:
    """Item 8: devices, FIFOs, links to them, 2 GiB files and deep nesting where
    the product reads a file. Each must be refused with a message naming the
    file, promptly: no traceback, no MemoryError, no hang."""
    t = Tally("8 unbounded reads")
    with tempfile.TemporaryDirectory(prefix="attack8-") as d:
        w = Path(d)
        (w / "OK.plc").write_text(OK_SOURCE)
        (w / "deep.toml").write_text("a = " + "[" * 50_000 + "\n")
        (w / "deep-table.toml").write_text("a = " + "{b = " * 50_000 + "\n")
        big = w / "big.dat"
        with open(big, "wb") as f:
            f.truncate(2 << 30)                  # sparse: costs no disk
        fifo = w / "fifo"
        has_fifo = _mkfifo(fifo)
        zero = "/dev/zero" if os.path.exists("/dev/zero") else None
        if zero:
            (w / "zero-link").symlink_to(zero)

        def refused(o: Outcome, codes=(1, 2)) -> bool:
            return o.rc in codes and not o.crashed

        hostile = [p for p in (zero, "zero-link" if zero else None,
                               "fifo" if has_fifo else None, "big.dat") if p]
        for path in hostile:
            for opt in ("--machine", "--variables", "--image"):
                o = plcbuilder("controller", opt, path, "--port", "0", cwd=w,
                               timeout=min(20, TIMEOUT_S))
                t.case(f"controller {opt} {path}", o,
                       refused=o.rc == 1 and ("regular file" in o.err or "at most" in o.err))
            o = plcbuilder("check", path, cwd=w)
            t.case(f"check {path}", o, refused=o.rc == 1 and
                   ("regular file" in o.out or "at most" in o.out))
            o = plcbuilder("disasm", path, cwd=w)
            t.case(f"disasm {path}", o, refused=refused(o, (1,)))
            o = plcbuilder("run", "OK.plc", "--scenario", path, cwd=w)
            t.case(f"run --scenario {path}", o, refused=refused(o, (2,)))
            o = plcbuilder("run", "OK.plc", "--machine", path, cwd=w)
            t.case(f"run --machine {path}", o, refused=refused(o, (2,)))
            o = plcbuilder("upload", path, cwd=w)
            t.case(f"upload {path}", o, refused=refused(o, (1,)))
            o = plcbuilder("state", "--runtime-file", path, cwd=w)
            t.case(f"state --runtime-file {path}", o, refused=refused(o, (1,)))
            # the project's settings file is the hostile file
            proj = _project(w / f"proj-{Path(path).name}")
            (proj / "plcbuilder.toml").unlink()
            (proj / "plcbuilder.toml").symlink_to(Path(path) if Path(path).is_absolute()
                                                  else w / path)
            o = plcbuilder("build", proj, cwd=w)
            t.case(f"build with plcbuilder.toml -> {path}", o, refused=o.rc == 1 and
                   "plcbuilder.toml" in o.err)
            o = plcbuilder("run", proj, cwd=w)
            t.case(f"run PROJECT with plcbuilder.toml -> {path}", o, refused=refused(o, (2,)))
        for deep in ("deep.toml", "deep-table.toml"):
            o = plcbuilder("controller", "--machine", deep, "--port", "0", cwd=w,
                           timeout=min(20, TIMEOUT_S))
            t.case(f"controller --machine {deep}", o, refused=o.rc == 1 and "nested" in o.err)
            o = plcbuilder("run", "OK.plc", "--machine", deep, cwd=w)
            t.case(f"run --machine {deep}", o, refused=o.rc == 2 and "nested" in o.err)
            proj = _project(w / f"proj-{deep}")
            (proj / "plcbuilder.toml").write_text((w / deep).read_text())
            o = plcbuilder("build", proj, cwd=w)
            t.case(f"build with {deep} settings", o, refused=o.rc == 1 and "nested" in o.err)
        proj = _project(w / "proj-cache")
        (proj / "build").mkdir()
        (proj / "build" / ".cache.json").write_text("[" * 200_000)
        o = plcbuilder("build", proj, cwd=w)
        t.case("build with a deeply nested build/.cache.json", o, refused=o.rc == 0)
    return t.result()


# ----------------------------------------------------------------- item 10

def attack_numbers() -> dict:
    """Item 10: numbers out of range on every command that takes one; each must
    be bad usage (exit 2, the message names the option and its range), never
    wrap or go through (to the simulation or to the controller)."""
    t = Tally("10 numbers")
    huge = "99999999999999999999999"
    cases = [
        ["run", "OK.plc", "--eparam", "4294967297"],
        ["run", "OK.plc", "--eparam", "-2147483649"],
        ["run", "OK.plc", "--eparam", huge],
        ["run", "OK.plc", "--adc", "0=99999999999"],
        ["run", "OK.plc", "--adc", "9=1"],
        ["run", "OK.plc", "--adc", f"{huge}=1"],
        ["run", "OK.plc", "--input", "300=1"],
        ["run", "OK.plc", "--input", f"{huge}=1"],
        ["run", "OK.plc", "--start", "OK:4294967296@0"],
        ["run", "OK.plc", "--start", f"OK@{huge}"],
        ["run", "OK.plc", "--ms", huge],
        ["run", "OK.plc", "--gvarget-latency", huge],
        ["start", "M03", "--eparam", "4294967297"],
        ["start", huge],
        ["input", "999=1"],
        ["input", f"{huge}=1"],
        ["input", "--adc", "0=99999999999"],
        ["input", "--adc", "8=1"],
        ["state", "--timeout", "nan"],
        ["state", "--timeout", "inf"],
        ["state", "--timeout", "-1"],
        ["controller", "--port", "70000"],
        ["controller", "--parent", huge],
        ["controller", "--gvarget-latency", huge],
        ["gui", "--after", huge, "--no-controller"],
    ]
    with tempfile.TemporaryDirectory(prefix="attack10-") as d:
        w = Path(d)
        (w / "OK.plc").write_text(OK_SOURCE)
        (w / "scenario.txt").write_text("adc 0=99999999999 @ 0\n")
        cases.append(["run", "OK.plc", "--scenario", "scenario.txt"])
        for argv in cases:
            o = plcbuilder(*argv, cwd=w, timeout=min(20, TIMEOUT_S))
            t.case(" ".join(argv), o, refused=o.rc == 2)      # bad usage, before any work
        # and the one that used to run: eparam 4294967297 became 1
        (w / "E.plc").write_text("main(){ v = eparam; exit(99); };\n")
        o = plcbuilder("run", "E.plc", "--eparam", "4294967297", "--json", cwd=w)
        t.case("run --eparam 4294967297 (value seen)", o, refused=o.rc == 2,
               accepted=o.rc == 0)
    return t.result()


# ----------------------------------------------------------------- item 12

def attack_outside_files() -> dict:
    """Item 12: includes and links that reach out of the project. Each must be
    an error (exit 1) that prints no line of the outside file, and Build All
    must write nothing outside the project."""
    t = Tally("12 outside files")
    with tempfile.TemporaryDirectory(prefix="attack12-") as d:
        w = Path(d)
        out = w / "elsewhere"
        out.mkdir()
        secret = out / "passwd"
        secret.write_text(SECRET)

        def leaked(o: Outcome) -> bool:
            return "attack-secret-line" in o.text

        includes = {
            "absolute path": f'#include "{secret}"',
            "relative ../": '#include "../../elsewhere/passwd"',
            "angle brackets": f"#include <{secret}>",
        }
        for label, line in includes.items():
            proj = _project(w / f"p-{label.replace(' ', '-').replace('/', '')}",
                            {"M03": f"{line}\nmain(){{ exit(99); }};\n"})
            for argv in (["check", proj / "hardware" / "M03.plc"], ["build", proj]):
                o = plcbuilder(*argv, cwd=w)
                t.case(f"{argv[0]}: #include {label}", o,
                       refused=o.rc == 1 and "resolves to" in o.text, accepted=leaked(o))
        # a header in include/ that is a link out of the project
        proj = _project(w / "p-linked-header", {"M03": "#include pins.h\nmain(){ exit(99); };\n"})
        (proj / "include" / "pins.h").symlink_to(secret)
        o = plcbuilder("build", proj, cwd=w)
        t.case("build: include/pins.h links out", o, refused=o.rc == 1 and "resolves to" in o.out,
               accepted=leaked(o))
        # include/ itself a link out of the project
        proj = _project(w / "p-linked-include", {"M03": "#include passwd\nmain(){ exit(99); };\n"})
        (proj / "include").rmdir()
        (proj / "include").symlink_to(out, target_is_directory=True)
        o = plcbuilder("build", proj, cwd=w)
        t.case("build: include/ links out", o, refused=o.rc == 1 and "resolves to" in o.out,
               accepted=leaked(o))
        # a procedure that is a link out of the project
        proj = _project(w / "p-linked-source")
        (proj / "hardware" / "M04.plc").symlink_to(secret)
        o = plcbuilder("build", proj, cwd=w)
        t.case("build: hardware/M04.plc links out", o,
               refused=o.rc == 1 and "outside the project" in o.out, accepted=leaked(o))
        o = plcbuilder("run", proj, cwd=w)
        t.case("run PROJECT: hardware/M04.plc links out", o,
               refused=o.rc == 1 and "outside the project" in o.text, accepted=leaked(o))
        # build/ a link out of the project
        proj = _project(w / "p-linked-build")
        target = w / "written-here"
        target.mkdir()
        (proj / "build").symlink_to(target, target_is_directory=True)
        o = plcbuilder("build", proj, cwd=w)
        t.case("build: build/ links out", o, refused=o.rc == 1 and "outside the project" in o.out,
               accepted=any(target.iterdir()))
        # allowed when named: --include DIR (the folder, so it is read: not PLC code)
        proj = _project(w / "p-allowed", {"M03": "#include passwd\nmain(){ exit(99); };\n"})
        o = plcbuilder("check", proj / "hardware" / "M03.plc", "--include", out, cwd=w)
        allowed = o.rc == 1 and "resolves to" not in o.text
        t.case("check --include DIR (the user names it: allowed)", o, refused=allowed,
               accepted=not allowed)
    return t.result()


# ------------------------------------------------------- issue 24 items 7-9

def _trace_zip(path: Path, head, events="[]", bins=None, raw_head: Optional[str] = None,
               members: Optional[dict] = None) -> Path:
    """A .plctrace: trace.json (``head`` as JSON, or ``raw_head`` as written),
    the signals' members and events.json."""
    import json
    import struct
    import zipfile
    if bins is None:
        bins = [struct.pack("<2q", 0, 5) + struct.pack("<2q", 0, 1)]
    with zipfile.ZipFile(path, "w") as z:
        z.writestr("trace.json", raw_head if raw_head is not None else json.dumps(head))
        for i, b in enumerate(bins):
            z.writestr(f"signals/{i}.bin", b)
        z.writestr("events.json", events)
        for name, data in (members or {}).items():
            z.writestr(name, data)
    return path


def _hostile_traces(w: Path) -> list[tuple[str, Path]]:
    """Trace files a hostile or broken tool could hand over: each number out of
    range or of the wrong type (NaN, Infinity, 1e400, 2^64, a text, true,
    null, a fraction), nesting 200,000 and 33 deep, names and kinds that are
    not names and kinds, events with wrong fields, sizes that do not add up."""
    import json
    import struct
    good = {"format": "plcbuilder-trace", "version": 1, "t_start": 0, "t_end": 9,
            "tick_ms": 1, "strings": [""], "meta": {},
            "signals": [{"name": "out 1", "kind": "bit", "changes": 2}]}
    text = json.dumps(good)
    out: list[tuple[str, Path]] = []
    n = 0

    def add(name: str, **kw) -> None:
        nonlocal n
        n += 1
        out.append((name, _trace_zip(w / f"t{n}.plctrace", kw.pop("head", good), **kw)))

    bad_numbers = ["Infinity", "-Infinity", "NaN", "1e400", "-1e400", "-1", str(1 << 63),
                   str(1 << 64), '"5"', "true", "null", "[]", "{}", "1.5", "1" * 5000]
    for field in ("t_start", "t_end", "version"):
        for v in bad_numbers:
            add(f"{field} = {v[:12]}", raw_head=text.replace(f'"{field}": {good[field]}',
                                                             f'"{field}": {v}'))
    for v in bad_numbers + ["-5"]:
        add(f"changes = {v[:12]}", raw_head=text.replace('"changes": 2', f'"changes": {v}'))
    add("t_end before t_start", head=dict(good, t_start=9, t_end=0))
    for name in (7, "", "a\x00b", "x" * 300, None, ["out 1"]):
        add(f"signal name {str(name)[:12]!r}",
            head=dict(good, signals=[{"name": name, "kind": "bit", "changes": 2}]))
    for kind in ("float", None, ["bit"], 1):
        add(f"signal kind {kind!r}",
            head=dict(good, signals=[{"name": "out 1", "kind": kind, "changes": 2}]))
    add("a name twice", head=dict(good, signals=good["signals"] * 2),
        bins=[struct.pack("<2q", 0, 5) + struct.pack("<2q", 0, 1)] * 2)
    add("signals not a list", head=dict(good, signals={"a": 1}))
    add("strings not texts", head=dict(good, strings=[1, {}]))
    add("meta a list", head=dict(good, meta=[1]))
    for trig in (5, {"spec": "x"}, {"t_ms": 5}, {"spec": "x", "t_ms": "5"},
                 {"spec": "x", "t_ms": -1}, {"spec": 5, "t_ms": 5},
                 {"spec": "x", "t_ms": 5, "pre_ms": "a"}):
        add(f"meta.trigger {str(trig)[:30]}", head=dict(good, meta={"trigger": trig}))
    add("trigger t_ms Infinity",
        raw_head=text.replace('"meta": {}', '"meta": {"trigger": {"spec": "x", "t_ms": '
                                            'Infinity}}'))
    for depth in (200_000, 33):
        deep = "[" * depth + "]" * depth
        add(f"trace.json nested {depth}",
            raw_head=text.replace('"meta": {}', f'"meta": {{"x": {deep}}}'))
        add(f"events.json nested {depth}", events=f'[{{"t_ms": 1, "type": "halted", '
                                                  f'"state": {{"x": {deep}}}}}]')
        add(f"events.json bare nesting {depth}", events=deep)
    for ev in ('[{"t_ms": Infinity, "type": "note", "text": "x"}]',
               '[{"t_ms": 1e400, "type": "note", "text": "x"}]',
               '[{"t_ms": NaN, "type": "note", "text": "x"}]',
               '[{"t_ms": "7", "type": "note", "text": "x"}]',
               '[{"type": "note", "text": "x"}]', '[{"t_ms": 1}]',
               '[{"t_ms": 1, "type": "message", "message": "x"}]',
               '[{"t_ms": 1, "type": "print", "register": 1e400}]',
               '[{"t_ms": 1, "type": "print", "register": %d}]' % (1 << 64),
               '[{"t_ms": 1, "type": "fault", "line": []}]',
               '[{"t_ms": 1, "t_ms": 2, "type": "note"}]', '{"t_ms": 1}', "[5]", "null",
               '[{"t_ms": 1, "type": "halted", "state": {"a": [NaN]}}]'):
        add(f"events {ev[:40]}", events=ev)
    add("bit value 7", bins=[struct.pack("<2q", 0, 5) + struct.pack("<2q", 0, 7)])
    add("negative time", bins=[struct.pack("<2q", -5, 5) + struct.pack("<2q", 0, 1)])
    add("time 2^63-1", bins=[struct.pack("<2q", 0, (1 << 63) - 1) + struct.pack("<2q", 0, 1)])
    add("times decreasing", bins=[struct.pack("<2q", 5, 0) + struct.pack("<2q", 0, 1)])
    add("member short", bins=[b"\0" * 30])
    add("member missing", bins=[])
    add("trace.json not UTF-8", raw_head="\udcff".encode("utf-8", "surrogateescape")
        .decode("latin-1"))
    n += 1
    (w / f"t{n}.plctrace").write_text("not a zip")
    out.append(("not a ZIP", w / f"t{n}.plctrace"))
    return out


def attack_trace_files() -> dict:
    """Issue 24 item 7: hostile trace files through every command that reads
    one (info, export to VCD, to CSV per tick, to one-bit lanes, compare on the
    triggers). Each must be refused (exit 2) naming the file, never "internal
    error" (OverflowError, RecursionError) nor accepted."""
    t = Tally("24.7 trace files")
    with tempfile.TemporaryDirectory(prefix="attack24-7-") as d:
        w = Path(d)
        for name, path in _hostile_traces(w):
            for argv in (["trace", "info", path, "--json"],
                         ["trace", "export", path, w / "x.vcd"],
                         ["trace", "export", path, w / "x.csv", "--per-tick"],
                         ["trace", "export", path, w / "x.vcd", "--split-bits"],
                         ["trace", "compare", path, path, "--align", "trigger"]):
                o = plcbuilder(*argv, cwd=w, timeout=min(30, TIMEOUT_S))
                t.case(f"{argv[1]} {name}", o, refused=o.rc == 2 and str(path) in o.err,
                       accepted=o.rc in (0, 1))
    return t.result()


def attack_junit_names() -> dict:
    """Issue 24 item 8: tests named with every kind of character XML 1.0 cannot
    hold (controls, U+FFFE, U+FFFF) in names, with and without a test file that
    cannot be read beside them. ``refused`` counts reports that are well-formed
    XML holding the tests (the defence held), ``accepted`` reports that are not
    (not well-formed, or the tests missing)."""
    import xml.etree.ElementTree as ET
    t = Tally("24.8 JUnit names")
    chars = [0, 1, 7, 8, 0x0B, 0x0C, 0x0E, 0x1B, 0x1F, 0x7F, 0xFFFE, 0xFFFF]
    with tempfile.TemporaryDirectory(prefix="attack24-8-") as d:
        w = Path(d)
        for c in chars:
            esc = f"\\u{c:04x}"
            for broken in (False, True):
                proj = _project(w / f"p{c:x}{int(broken)}", {"M03": OK_SOURCE})
                (proj / "tests").mkdir()
                (proj / "tests" / "a.toml").write_text(
                    f'[[test]]\nname = "ok {esc} end"\nms = 20\nscenario = "start M03 @ 0"\n'
                    f'[[test.expect]]\nat_end = true\nexit = {{ M03 = 99 }}\n'
                    f'[[test]]\nname = "fails {esc}"\nms = 20\nscenario = "start M03 @ 0"\n'
                    f'[[test.expect]]\nat_end = true\nexit = {{ M03 = 1 }}\n')
                if broken:                      # and a file that cannot be read
                    (proj / "tests" / "b.toml").write_text(f'[[test]]\nname = "{esc}\n')
                report = w / f"j{c:x}{int(broken)}.xml"
                o = plcbuilder("test", proj, "--junit", report, cwd=w)
                try:
                    names = [e.get("name") for e in ET.parse(report).iter("testcase")]
                    right = any(n.startswith("ok ") for n in names)
                except (ET.ParseError, OSError):
                    right = False
                t.case(f"test name with U+{c:04X}{' and a broken file' if broken else ''}", o,
                       refused=right and o.rc == (2 if broken else 1), accepted=not right)
    return t.result()


def attack_exports() -> dict:
    """Issue 24 item 9: 64-bit values through VCD (read back with vcdvcd, every
    value whole), and signal names a spreadsheet would run as a formula through
    CSV (each must start with a quote inside double quotes). ``refused``
    counts exports that came out right."""
    import csv
    import io
    t = Tally("24.9 VCD and CSV exports")
    sys.path.insert(0, str(ROOT))
    from plcbuilder import api
    from tests.vcd_reader import VCDVCD
    extremes = [-(1 << 63), (1 << 63) - 1, -1, 0, 1, (1 << 31), -(1 << 31) - 1, 1 << 40]
    names = ["=1+2", "+SUM(A1)", "-2+3", "@cmd", "\tx", "=HYPERLINK(\"http://x\",\"y\")",
             "\uff1dcmd", "a,b", 'say "hi"']
    with tempfile.TemporaryDirectory(prefix="attack24-9-") as d:
        w = Path(d)
        for i, v in enumerate(extremes):
            tr = api.Trace(0, 3, {"axis X": ("int", [(0, 0), (1, v)])}, [""], [], {})
            src = w / f"v{i}.plctrace"
            api.save_trace(tr, src)
            out = w / f"v{i}.vcd"
            o = plcbuilder("trace", "export", src, out, cwd=w)
            try:
                var = VCDVCD(str(out))["axes.X"]
                bits = var.tv[-1][1].zfill(int(var.size))
                got = int(bits, 2) - ((1 << len(bits)) if v < 0 and bits[0] == "1" else 0)
                right = got == v
            except Exception:  # noqa: BLE001 - anything that does not read back is wrong
                right = False
            t.case(f"VCD value {v}", o, refused=right and o.rc == 0, accepted=not right)
        for i, name in enumerate(names):
            tr = api.Trace(0, 2, {name: ("int", [(0, -5)]), "running": ("text", [(0, 1)])},
                           ["", name], [], {})
            src = w / f"n{i}.plctrace"
            try:
                api.save_trace(tr, src)
            except Exception:  # noqa: BLE001
                continue
            for flag in ([], ["--per-tick"]):
                out = w / f"n{i}{len(flag)}.csv"
                o = plcbuilder("trace", "export", src, out, *flag, cwd=w)
                if o.rc == 2 and "control characters" in o.err:
                    t.case(f"CSV name {name!r} {flag} (refused on load)", o, refused=True)
                    continue
                try:
                    text = out.read_bytes().decode("utf-8")
                    cells = [c for row in csv.reader(io.StringIO(text)) for c in row]
                    formula = ("=", "+", "-", "@", "\t", "\r", "\uff1d", "\uff0b", "\uff0d",
                               "\uff20")
                    right = all(not c.startswith(formula) or c.lstrip("-").isdigit()
                                for c in cells) and (name in cells or "'" + name in cells)
                except Exception:  # noqa: BLE001
                    right = False
                t.case(f"CSV name {name!r} {flag}", o, refused=right and o.rc == 0,
                       accepted=not right)
    return t.result()


ATTACKS: list[tuple[str, Callable[[], dict]]] = [
    ("6 atomic_write on special files", attack_special_outputs),
    ("7 machine values", attack_machine_values),
    ("8 unbounded reads", attack_unbounded_reads),
    ("10 numbers out of range", attack_numbers),
    ("12 files outside the project", attack_outside_files),
    ("24.7 hostile trace files", attack_trace_files),
    ("24.8 JUnit names XML cannot hold", attack_junit_names),
    ("24.9 VCD widths and CSV formulas", attack_exports),
]


def print_table(rows: list[tuple[str, dict]]) -> None:
    w = max(len(n) for n, _ in rows)
    print(f"{'attack'.ljust(w)}  {'tried':>6} {'refused':>8} {'accepted':>9} {'crashed':>8}")
    for name, r in rows:
        print(f"{name.ljust(w)}  {r['tried']:>6} {r['refused']:>8} {r['accepted']:>9} "
              f"{r['crashed']:>8}")


def main(argv: list[str]) -> int:
    global VERBOSE
    VERBOSE = "--verbose" in argv or "-v" in argv
    wanted = [a for a in argv if not a.startswith("-")]
    rows = []
    for name, fn in ATTACKS:
        if wanted and not any(w in name for w in wanted):
            continue
        rows.append((name, fn()))
    print_table(rows)
    return 1 if any(r["accepted"] or r["crashed"] for _, r in rows) else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
