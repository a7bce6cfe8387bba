"""The breakpoints of a project: what the user set, kept across sessions.

A :class:`Breakpoint` is where the user put it (a file and a 1-based line,
which follows edits), whether it is enabled, and its condition, hit count or
log message; the controller's answer (``verified``, the line it moved to, a
reason) is kept beside it. :class:`BreakpointStore` holds them by file and says
when a file's breakpoints change (``sig_changed``): the editors redraw their
markers, the Breakpoints panel its list, and the debug session sends that
file's breakpoints to the controller.

They are saved per project in the IDE's settings (:meth:`Settings.breakpoints`)
with paths relative to the project, so a project folder that moves keeps them.
"""

from __future__ import annotations

import os
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Iterable, Optional

from PySide6.QtCore import QObject, Signal

from plcbuilder.ide.editor import file_key

#: Hit count modes: halt on the Nth hit, from the Nth hit on, on every Nth hit.
HIT_MODES = {"eq": "= N", "ge": "≥ N", "every": "every N"}


@dataclass
class Breakpoint:
    """One line breakpoint (or logpoint) as the user set it."""
    path: str                       # the file (absolute; a built-in header's <builtin> name)
    line: int                       # 1-based, where the user put it
    enabled: bool = True
    condition: Optional[str] = None
    hit: Optional[dict] = None      # {"mode": "eq" | "ge" | "every", "n": int}
    log: Optional[str] = None       # a logpoint's message ({name} placeholders)
    # the controller's answer (not saved)
    id: Optional[int] = field(default=None, compare=False)
    verified: Optional[bool] = field(default=None, compare=False)   # None: not sent yet
    actual_line: Optional[int] = field(default=None, compare=False)
    reason: Optional[str] = field(default=None, compare=False)

    @property
    def file_name(self) -> str:
        """The file as the compiler's line table names it (``M80.plc``, ``pins.h``)."""
        return Path(self.path).name

    @property
    def kind(self) -> str:
        """``logpoint``, ``conditional`` or ``breakpoint`` (what the marker shows)."""
        if self.log:
            return "logpoint"
        if self.condition or self.hit:
            return "conditional"
        return "breakpoint"

    def describe(self) -> str:
        """A short text of what it does besides halting: condition, hit count, log."""
        parts = []
        if self.condition:
            parts.append(f"when {self.condition}")
        if self.hit:
            mode = self.hit.get("mode", "eq")
            n = self.hit.get("n", 1)
            parts.append({"eq": f"on hit {n}", "ge": f"from hit {n}",
                          "every": f"every {n} hits"}.get(mode, f"hit {n}"))
        if self.log:
            parts.append(f"log “{self.log}”")
        return ", ".join(parts)

    def spec(self) -> dict:
        """The contract's breakpoint spec (the condition as text; the session
        adds its compiled code)."""
        return {"file": self.file_name, "line": self.line, "enabled": self.enabled,
                "condition": self.condition or None, "hit": dict(self.hit) if self.hit else None,
                "log": self.log or None}


class BreakpointStore(QObject):
    """Every breakpoint of the open project, by file."""

    sig_changed = Signal(str)
    """The breakpoints of a file changed (its path; ``""``: all files, a new project)."""

    def __init__(self, parent: Optional[QObject] = None):
        super().__init__(parent)
        self._by_file: dict[str, list[Breakpoint]] = {}

    # ----------------------------------------------------------------- reading
    def all(self) -> list[Breakpoint]:
        """Every breakpoint, by file then line."""
        out = []
        for key in sorted(self._by_file):
            out.extend(sorted(self._by_file[key], key=lambda b: b.line))
        return out

    def for_file(self, path) -> list[Breakpoint]:
        return sorted(self._by_file.get(file_key(path), []), key=lambda b: b.line)

    def files(self) -> list[str]:
        """The paths that have breakpoints."""
        return [bps[0].path for bps in self._by_file.values() if bps]

    def at(self, path, line: int) -> Optional[Breakpoint]:
        for bp in self._by_file.get(file_key(path), []):
            if bp.line == line:
                return bp
        return None

    def __len__(self) -> int:
        return sum(len(v) for v in self._by_file.values())

    # ---------------------------------------------------------------- changing
    def toggle(self, path, line: int) -> Optional[Breakpoint]:
        """Add a breakpoint at the line, or remove the one there; returns the new one."""
        bp = self.at(path, line)
        if bp is not None:
            self.remove(bp)
            return None
        return self.add(Breakpoint(str(path), int(line)))

    def add(self, bp: Breakpoint) -> Breakpoint:
        old = self.at(bp.path, bp.line)
        lst = self._by_file.setdefault(file_key(bp.path), [])
        if old is not None:
            lst.remove(old)
        lst.append(bp)
        self.sig_changed.emit(bp.path)
        return bp

    def remove(self, bp: Breakpoint) -> None:
        lst = self._by_file.get(file_key(bp.path), [])
        if bp in lst:
            lst.remove(bp)
            if not lst:
                self._by_file.pop(file_key(bp.path), None)
            self.sig_changed.emit(bp.path)

    def clear(self, path=None) -> None:
        """Remove the breakpoints of one file, or all of them."""
        if path is None:
            paths = self.files()
            self._by_file.clear()
            for p in paths:
                self.sig_changed.emit(p)
            return
        if self._by_file.pop(file_key(path), None) is not None:
            self.sig_changed.emit(str(path))

    def update(self, bp: Breakpoint, **changes) -> Breakpoint:
        """Change what a breakpoint does (enabled, condition, hit, log): a
        change the controller has not answered yet is unverified again."""
        for k, v in changes.items():
            setattr(bp, k, v)
        bp.verified, bp.reason = None, None
        self.sig_changed.emit(bp.path)
        return bp

    def set_all_enabled(self, on: bool) -> None:
        for path in self.files():
            for bp in self._by_file.get(file_key(path), []):
                bp.enabled = on
            self.sig_changed.emit(path)

    def move_lines(self, path, lines: dict[int, int]) -> bool:
        """Edits moved breakpoints: ``{old line: new line}``. Two that land on
        one line become one. Returns whether anything moved (no signal: the
        editor's markers already show it; the session resends on save)."""
        lst = self._by_file.get(file_key(path), [])
        moved = False
        seen: dict[int, Breakpoint] = {}
        for bp in list(lst):
            new = lines.get(bp.line, bp.line)
            if new != bp.line:
                bp.line, moved = new, True
            if bp.line in seen:
                lst.remove(bp)
                moved = True
            else:
                seen[bp.line] = bp
        return moved

    def rename(self, old, new) -> None:
        """A file was renamed in the project: its breakpoints follow."""
        lst = self._by_file.pop(file_key(old), None)
        if lst:
            for bp in lst:
                bp.path = str(new)
            self._by_file[file_key(new)] = lst
            self.sig_changed.emit(str(old))
            self.sig_changed.emit(str(new))

    def set_answers(self, bps: list[Breakpoint], answers: list) -> set[str]:
        """The controller's answer to a file's ``set_breakpoints``, one per
        breakpoint sent (in order): id, verified, the line it moved to and
        why not. No signal (nothing to send again): returns the paths whose
        marks to redraw."""
        paths = set()
        for bp, a in zip(bps, answers):
            if not isinstance(a, dict):
                continue
            bp.id = a.get("id")
            bp.verified = bool(a.get("verified"))
            line = a.get("line")
            bp.actual_line = line if type(line) is int else None
            bp.reason = a.get("reason") if isinstance(a.get("reason"), str) else None
            paths.add(bp.path)
        return paths

    def mark_refused(self, bp: Breakpoint, reason: str) -> None:
        """The IDE could not send it (a condition that does not compile)."""
        bp.verified, bp.reason, bp.id = False, reason, None

    def reset_answers(self) -> None:
        """The controller is new (restarted, another one): nothing is verified."""
        for bp in self.all():
            bp.id, bp.verified, bp.actual_line, bp.reason = None, None, None, None
        self.sig_changed.emit("")

    # ------------------------------------------------------------ persistence
    def to_list(self, root) -> list[dict]:
        """What is saved: each breakpoint as a dict, the path relative to root."""
        out = []
        for bp in self.all():
            d = {k: v for k, v in asdict(bp).items()
                 if k in ("path", "line", "enabled", "condition", "hit", "log")}
            d["path"] = _relative(bp.path, root)
            out.append(d)
        return out

    def load_list(self, items: Iterable, root) -> int:
        """Replace every breakpoint with saved ones (bad entries are skipped);
        returns how many were loaded."""
        self._by_file.clear()
        n = 0
        for d in items or ():
            bp = _from_dict(d, root)
            if bp is None:
                continue
            self._by_file.setdefault(file_key(bp.path), []).append(bp)
            n += 1
        self.sig_changed.emit("")
        return n


def _relative(path: str, root) -> str:
    if root is None or path.startswith("<"):
        return path
    try:
        rel = os.path.relpath(path, root)
    except ValueError:
        return path
    return path if rel.startswith("..") else rel.replace(os.sep, "/")


def _from_dict(d, root) -> Optional[Breakpoint]:
    if not isinstance(d, dict):
        return None
    path, line = d.get("path"), d.get("line")
    if not isinstance(path, str) or not path or type(line) is not int or line < 1:
        return None
    if root is not None and not path.startswith("<") and not os.path.isabs(path):
        path = str(Path(root) / path)
    hit = d.get("hit")
    if not (isinstance(hit, dict) and hit.get("mode") in HIT_MODES
            and type(hit.get("n")) is int and hit["n"] >= 1):
        hit = None
    cond, log = d.get("condition"), d.get("log")
    return Breakpoint(path, line, enabled=d.get("enabled", True) is not False,
                      condition=cond if isinstance(cond, str) and cond.strip() else None,
                      hit=hit, log=log if isinstance(log, str) and log else None)
