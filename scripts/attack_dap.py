#!/usr/bin/env python3
"""Attacks on the debug adapter and Build All (issue 24, items 2 and 5),
against the real ``plcbuilder dap`` and ``plcbuilder build`` in children, in
temporary folders.

    ATTACKS: list[tuple[str, callable]]   name, attack() -> {"tried", "refused",
                                          "accepted", "crashed"}

- **24.2 hostile conditions**: breakpoint conditions and expressions to
  evaluate that stalled the compiler (runs of '(' and ')', nesting at and over
  the limit, text over the length limit, unclosed comments, statements, floods
  of errors), each followed by a cheap request (``threads``). Refused: the
  breakpoint is unverified / the evaluate fails, and the cheap request is
  answered within ``CHEAP_S``. Accepted: a hostile condition was set, or the
  cheap request waited longer. Crashed: the adapter died or did not answer.
- **24.5 launch into folders that are not projects**: an empty folder, one
  with other files, a missing one, a file, the current folder. Refused: the
  launch fails and nothing is written. Accepted: it built or wrote anything.
- **24.5 build of folders that are not projects**: the same folders given to
  ``plcbuilder build``; refused: exit status 1, a message, nothing written.
- **24.5 relaunches**: five launches in one session; refused when one
  controller runs after each (Linux's /proc counts the adapter's children);
  accepted when more stay running.

Nothing here touches a folder outside its temporary one (the original attack
wrote /build and /etc/build; these attacks use folders of the same kinds made
for the purpose). Run alone, it prints its own table (``--verbose`` lists
every case).
"""

from __future__ import annotations

import json
import os
import queue
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Optional

ROOT = Path(__file__).resolve().parents[1]
CHEAP_S = float(os.environ.get("ATTACK_DAP_CHEAP_S", "1.0"))
TIMEOUT_S = float(os.environ.get("ATTACK_TIMEOUT_S", "60"))
VERBOSE = False

M03 = "main()\n{\n  count = 0;\n  do {\n    count = count + 1;\n  } while (count < 5);\n  exit(99);\n}\n"

HOSTILE = {
    "800 (": "(" * 800, "1,600 (": "(" * 1600, "3,200 (": "(" * 3200,
    "100,000 (": "(" * 100_000, "3,200 )": ")" * 3200,
    "17 deep": "(" * 17 + "1" + ")" * 17, "1,001 characters": "1+" * 500 + "1",
    "16 deep, empty, repeated": "+".join(["(" * 16 + ")" * 16] * 30),
    "16 deep, errors, repeated": "+".join(["(" * 16 + "1 1" + ")" * 16] * 27),
    "unclosed comment": "count /* " + "(" * 900, "statements": "count = 1; " * 90,
    "block": "{" * 500, "directive": "#include \"/etc/passwd\"",
    "error flood": "1 " * 499, "unary flood": "!" * 999 + "1", "minus flood": "-" * 999 + "1",
    "nope(": "nope(", "mixed": "([" * 400, "close first": ")(" * 500,
}


def _counts() -> dict:
    return {"tried": 0, "refused": 0, "accepted": 0, "crashed": 0}


def _tally(counts: dict, attack: str, name: str, verdict: str, note: str = "") -> None:
    counts["tried"] += 1
    counts[verdict] += 1
    if VERBOSE:
        print(f"  [{attack}] {verdict:8} {name}: {note[:150]}", file=sys.stderr)


class Adapter:
    """``plcbuilder dap`` in a child; requests in, messages out (a reader thread)."""

    def __init__(self, cwd: Path, command: Optional[list] = None):
        env = dict(os.environ, PYTHONPATH=str(ROOT))
        self.proc = subprocess.Popen(command or [sys.executable, "-m", "plcbuilder", "dap"],
                                     cwd=cwd,
                                     stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                     stderr=subprocess.DEVNULL, env=env)
        self.got: "queue.Queue[dict]" = queue.Queue()
        self.seen: list[dict] = []
        self.seq = 0
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self) -> None:
        out = self.proc.stdout
        while True:
            length = None
            while True:
                line = out.readline()
                if not line:
                    return
                if line in (b"\r\n", b"\n"):
                    break
                name, _, value = line.decode("ascii", "replace").partition(":")
                if name.strip().lower() == "content-length":
                    length = int(value)
            self.got.put(json.loads(out.read(length)))

    def send(self, command: str, arguments: Optional[dict] = None) -> int:
        self.seq += 1
        body = json.dumps({"seq": self.seq, "type": "request", "command": command,
                           "arguments": arguments or {}}).encode()
        self.proc.stdin.write(b"Content-Length: %d\r\n\r\n" % len(body) + body)
        self.proc.stdin.flush()
        return self.seq

    def wait(self, pred, timeout: float = TIMEOUT_S) -> Optional[dict]:
        for m in self.seen:
            if pred(m):
                self.seen.remove(m)
                return m
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            try:
                m = self.got.get(timeout=max(0.01, end - time.monotonic()))
            except queue.Empty:
                break
            if pred(m):
                return m
            self.seen.append(m)
        return None

    def request(self, command: str, arguments: Optional[dict] = None,
                timeout: float = TIMEOUT_S) -> Optional[dict]:
        seq = self.send(command, arguments)
        return self.wait(lambda m: m.get("type") == "response" and m.get("request_seq") == seq,
                         timeout)

    def close(self) -> None:
        try:
            self.request("disconnect", {}, timeout=10)
            self.proc.stdin.close()
            self.proc.wait(10)
        except (OSError, ValueError, subprocess.TimeoutExpired):
            self.proc.kill()
            self.proc.wait(5)


def _project(root: Path) -> Path:
    (root / "hardware").mkdir(parents=True)
    (root / "plcbuilder.toml").write_text('name = "attack"\n')
    (root / "hardware" / "M03.plc").write_text(M03)
    return root


def _launch(dap: Adapter, project: Path, procedure: str = "M03") -> bool:
    if dap.request("initialize", {"adapterID": "plcbuilder"}) is None:
        return False
    r = dap.request("launch", {"project": str(project), "procedure": procedure})
    return bool(r and r.get("success"))


# ------------------------------------------------------------------ 24.2

def hostile_conditions() -> dict:
    counts = _counts()
    with tempfile.TemporaryDirectory() as tmp:
        project = _project(Path(tmp) / "proj")
        dap = Adapter(project)
        try:
            if not _launch(dap, project):
                _tally(counts, "24.2", "launch", "crashed", "the launch failed")
                return counts
            path = str(project / "hardware" / "M03.plc")
            for name, text in HOSTILE.items():
                for kind in ("condition", "evaluate"):
                    t0 = time.monotonic()
                    if kind == "condition":
                        r = dap.request("setBreakpoints", {"source": {"path": path},
                                                           "breakpoints": [{"line": 5,
                                                                            "condition": text}]})
                        took = time.monotonic() - t0
                        bps = (r or {}).get("body", {}).get("breakpoints", [{}])
                        got_through = bool(bps and bps[0].get("verified"))
                        note = (bps[0].get("message", "") if bps else "")
                    else:
                        r = dap.request("evaluate", {"expression": text, "context": "repl"})
                        took = time.monotonic() - t0
                        got_through = bool(r and r.get("success"))
                        note = (r or {}).get("message", "")
                    t1 = time.monotonic()
                    cheap = dap.request("threads", {}, timeout=TIMEOUT_S)
                    cheap_s = time.monotonic() - t1
                    case = f"{kind} {name} ({took:.3f} s, then threads {cheap_s:.3f} s)"
                    if r is None or cheap is None or dap.proc.poll() is not None:
                        _tally(counts, "24.2", case, "crashed", "no answer")
                    elif got_through or cheap_s > CHEAP_S or took > CHEAP_S:
                        _tally(counts, "24.2", case, "accepted", note)
                    else:
                        _tally(counts, "24.2", case, "refused", note)
        finally:
            dap.close()
    return counts


# ------------------------------------------------------------------ 24.5

def _strays(base: Path) -> dict[str, tuple[Path, Path]]:
    """name -> (the folder given, the folder whose contents must stay as they are)."""
    empty = base / "empty"
    empty.mkdir()
    etc = base / "etc"
    etc.mkdir()
    (etc / "passwd").write_text("root:x:0:0:attack:/root:/bin/sh\n")
    (etc / "hosts").write_text("127.0.0.1 localhost\n")
    a_file = base / "file.txt"
    a_file.write_text("x\n")
    nested = base / "etc" / "ssh"
    nested.mkdir()
    return {"an empty folder": (empty, empty), "a folder of other files": (etc, etc),
            "a folder inside it": (nested, etc), "a missing folder": (base / "nowhere", base),
            "a file": (a_file, base), "dot-dot": (nested / "..", etc)}


def _snapshot(root: Path) -> list[str]:
    return sorted(str(p.relative_to(root)) for p in root.rglob("*"))


def launch_into_non_projects() -> dict:
    counts = _counts()
    with tempfile.TemporaryDirectory() as tmp:
        base = Path(tmp)
        for name, (given, watched) in _strays(base).items():
            for how in ("project", "cwd", "program"):
                before = _snapshot(base)
                cwd = given if how == "cwd" and given.is_dir() else base
                dap = Adapter(cwd)
                try:
                    dap.request("initialize", {"adapterID": "plcbuilder"})
                    args = ({"project": str(given)} if how == "project" else
                            {} if how == "cwd" else {"program": str(given / "hardware" / "M03.plc")})
                    r = dap.request("launch", args)
                finally:
                    dap.close()
                wrote = _snapshot(base) != before
                case = f"{name} as {how}"
                if r is None:
                    _tally(counts, "24.5", case, "crashed", "no answer")
                elif r.get("success") or wrote:
                    _tally(counts, "24.5", case, "accepted",
                           "wrote " + ", ".join(sorted(set(_snapshot(base)) - set(before))))
                else:
                    _tally(counts, "24.5", case, "refused", r.get("message", ""))
    return counts


def build_non_projects() -> dict:
    counts = _counts()
    with tempfile.TemporaryDirectory() as tmp:
        base = Path(tmp)
        for name, (given, _watched) in _strays(base).items():
            before = _snapshot(base)
            env = dict(os.environ, PYTHONPATH=str(ROOT))
            try:
                p = subprocess.run([sys.executable, "-m", "plcbuilder", "build", str(given)],
                                   cwd=base, capture_output=True, text=True, timeout=TIMEOUT_S,
                                   env=env, stdin=subprocess.DEVNULL)
            except subprocess.TimeoutExpired:
                _tally(counts, "24.5", name, "crashed", "no answer")
                continue
            wrote = _snapshot(base) != before
            text = p.stdout + p.stderr
            if p.returncode < 0 or "Traceback" in text or "internal error" in text:
                _tally(counts, "24.5", name, "crashed", text)
            elif p.returncode == 0 or wrote or "error" not in text:
                _tally(counts, "24.5", name, "accepted", text)
            else:
                _tally(counts, "24.5", name, "refused", text.strip())
    return counts


def _children(pid: int) -> int:
    n = 0
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            if int(stat.read_text().rsplit(")", 1)[1].split()[1]) == pid:
                n += 1
        except (OSError, ValueError, IndexError):
            continue
    return n


def relaunches() -> dict:
    counts = _counts()
    if not Path("/proc/self/stat").exists():
        return counts                       # needs Linux's /proc to count the controllers
    with tempfile.TemporaryDirectory() as tmp:
        project = _project(Path(tmp) / "proj")
        dap = Adapter(project)
        try:
            dap.request("initialize", {"adapterID": "plcbuilder"})
            for k in range(5):
                r = dap.request("launch", {"project": str(project), "procedure": "M03"})
                dap.request("configurationDone", {})
                running = _children(dap.proc.pid)
                case = f"launch {k + 1}: {running} controller(s) running"
                if r is None or not r.get("success"):
                    _tally(counts, "24.5", case, "crashed", str(r))
                elif running > 1:
                    _tally(counts, "24.5", case, "accepted")
                else:
                    _tally(counts, "24.5", case, "refused")
        finally:
            dap.close()
    return counts


ATTACKS = [
    ("24.2 hostile conditions (dap)", hostile_conditions),
    ("24.5 launch into non-projects (dap)", launch_into_non_projects),
    ("24.5 build of non-projects", build_non_projects),
    ("24.5 relaunches (dap)", relaunches),
]


def main(argv: list[str]) -> int:
    global VERBOSE
    VERBOSE = "--verbose" in argv or "-v" in argv
    wanted = [a for a in argv if not a.startswith("-")]
    rows = [(n, f()) for n, f in ATTACKS if not wanted or any(w in n for w in wanted)]
    w = max(len(n) for n, _ in rows)
    print(f"{'attack'.ljust(w)}  {'tried':>6} {'refused':>8} {'accepted':>9} {'crashed':>8}")
    for name, r in rows:
        print(f"{name.ljust(w)}  {r['tried']:>6} {r['refused']:>8} {r['accepted']:>9} "
              f"{r['crashed']:>8}")
    return 1 if any(r["accepted"] or r["crashed"] for _, r in rows) else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
