"""Breakpoint conditions: an expression of the PLC language compiled into a
small procedure whose exit code is its value (SPEC §6). The
debugger binds its variables by name to the procedure that reaches the
breakpoint. The IDE, ``plcbuilder run --break`` (through the api) and the
debug adapter compile conditions (and the expressions they evaluate) here.

A condition is one line of at most :data:`MAX_CONDITION_CHARS` characters whose
brackets match and nest at most :data:`MAX_CONDITION_DEPTH` deep: checked by a
scan of the text before the compiler sees it, so no text, however hostile, takes
the compiler's error recovery long (a debugger checks conditions while the user
waits). Messages speak of the text the user wrote: the ``exit(...);`` the
condition is wrapped in never shows."""

from __future__ import annotations

import re
from pathlib import Path

from plcbuilder._support.files import read_bounded
from plcbuilder.lang import Diagnostic, Span, error
from plcbuilder.lang.pipeline import CompileOptions, compile_source
from plcbuilder.lang.source import MAX_SOURCE_BYTES
from plcbuilder.project.model import Project, ProjectError, kind_of

__all__ = ["CONDITION_FILE", "MAX_CONDITION_CHARS", "MAX_CONDITION_DEPTH", "compile_condition"]

CONDITION_FILE = "<condition>"
#: The longest condition (characters); the controller's link takes no longer text.
MAX_CONDITION_CHARS = 1000
#: How deep a condition's brackets may nest.
MAX_CONDITION_DEPTH = 16
_CLOSE = {")": "(", "]": "["}


def compile_condition(text: str, context=None) -> "bytes | list[Diagnostic]":
    """A breakpoint's condition (an expression of the PLC language) compiled
    into a small procedure whose exit code is its value: the Program's bytes,
    which the debugger binds by name to the variables of the procedure that
    reaches the breakpoint. ``context``: the source file (or project folder)
    whose ``#include`` and ``#define`` lines the condition may use. When it
    does not compile (or is longer, or nests deeper, than a condition may): its
    error diagnostics, pointing into the condition's text (file
    ``<condition>``, line 1)."""
    if not isinstance(text, str) or not text.strip():
        return [error("condition", "a condition needs an expression",
                      Span.point(CONDITION_FILE, 1, 1))]
    if "\n" in text or "\r" in text:
        return [error("condition", "a condition is one line", Span.point(CONDITION_FILE, 1, 1))]
    problem = _shape_problem(text)
    if problem is not None:
        return [problem]
    head: list[str] = []
    path = Path(context) if context is not None else None
    options = CompileOptions()
    if path is not None and path.is_file():
        try:
            project = Project.find_for(path)
            options = (project.compile_options(path) if project is not None
                       else CompileOptions(kind=kind_of(path)))
            lines = read_bounded(path, MAX_SOURCE_BYTES, "source").decode("utf-8", "replace")
        except (ProjectError, OSError):
            lines = ""
        head = [ln for ln in lines.splitlines() if ln.lstrip().startswith(("#include", "#define"))]
    elif path is not None and path.is_dir():
        try:
            options = Project.open(path).compile_options(path / "hardware" / "_.plc")
        except (ProjectError, OSError):
            pass
    # the text on a line of its own: a message about what the wrapper adds (its
    # ')' and ';') is a message about the end of the condition
    src = "\n".join([*head, "main()", "{", "  exit(", text, "  );", "}"]) + "\n"
    where = str(path.with_name("__condition__.plc")) if path is not None and path.is_file() \
        else "<condition>"
    r = compile_source(src, where, options)
    at = len(head) + 4
    errors = []
    for d in r.diagnostics:
        if not d.is_error:
            continue
        s = d.span
        message = d.message
        if s is not None and s.line == at:
            span = Span(CONDITION_FILE, 1, s.col, 1,
                        max(s.col + 1, s.end_col if s.end_line == at else len(text) + 1))
            message = _outside_brackets(message, text, s.col)
        elif s is not None and s.line > at:
            span = Span.point(CONDITION_FILE, 1, len(text.rstrip()) + 1)
            message = _at_the_end(message)
        elif s is not None and s.line == at - 1:        # the wrapper's "exit(": the start
            first = len(text) - len(text.lstrip()) + 1
            span = Span.point(CONDITION_FILE, 1, first)
            message = _outside_brackets(message, text, first)
        else:
            span = Span.point(CONDITION_FILE, 1, 1)
        errors.append(Diagnostic(d.severity, d.code, message, span, d.hints))
    if errors or r.program is None:
        return errors or [error("condition", "the condition does not compile",
                                Span.point(CONDITION_FILE, 1, 1))]
    return r.program.to_bytes()


def _shape_problem(text: str) -> "Diagnostic | None":
    """The text's length, its brackets (each closed, in order, at most
    MAX_CONDITION_DEPTH deep) and its block comments (closed), checked in one
    pass: the first problem, or None."""
    if len(text) > MAX_CONDITION_CHARS:
        return error("condition-too-long", f"a condition is at most {MAX_CONDITION_CHARS} "
                     f"characters; this one has {len(text):,}",
                     Span(CONDITION_FILE, 1, 1, 1, MAX_CONDITION_CHARS + 1),
                     "name a part of it with a variable in the procedure")
    opened: list[tuple[str, int]] = []
    i, n = 0, len(text)
    while i < n:
        ch = text[i]
        if text.startswith("//", i):
            break
        if text.startswith("/*", i):
            end = text.find("*/", i + 2)
            if end < 0:
                return error("condition", "the comment '/*' is not closed",
                             Span(CONDITION_FILE, 1, i + 1, 1, i + 3))
            i = end + 2
            continue
        if ch in ";{}" or (ch == "," and not opened) or (ch == "#" and not text[:i].strip()):
            what = {";": "';' ends a statement", "{": "'{' starts a block",
                    "}": "'}' ends a block", ",": "',' separates arguments",
                    "#": "'#' starts a directive (#define, #include)"}[ch]
            return error("condition", f"{what}: a condition is one expression",
                         Span(CONDITION_FILE, 1, i + 1, 1, i + 2),
                         "a condition may use the #define lines of its procedure's file")
        if ch in "([":
            opened.append((ch, i))
            if len(opened) > MAX_CONDITION_DEPTH:
                return error("condition-too-deep", f"a condition's brackets nest at most "
                             f"{MAX_CONDITION_DEPTH} deep",
                             Span(CONDITION_FILE, 1, i + 1, 1, i + 2),
                             "split it into simpler parts")
        elif ch in _CLOSE:
            if not opened or opened[-1][0] != _CLOSE[ch]:
                return error("condition", f"'{ch}' has no '{_CLOSE[ch]}' before it to close"
                             + (f" (the '{opened[-1][0]}' at column {opened[-1][1] + 1} is "
                                "still open)" if opened else ""),
                             Span(CONDITION_FILE, 1, i + 1, 1, i + 2))
            opened.pop()
        i += 1
    if opened:
        ch, k = opened[-1]
        want = ")" if ch == "(" else "]"
        return error("condition", f"the '{ch}' at column {k + 1} is not closed: a '{want}' is "
                     "missing", Span(CONDITION_FILE, 1, k + 1, 1, k + 2))
    return None


_TOKEN = re.compile(r"\s*(\w+|\S{1,2})")


def _outside_brackets(message: str, text: str, col: int) -> str:
    """A message about the condition's own text: a ')' it expects outside every
    bracket of the text is the wrapper's (the expression went on where it could
    not), said as the token that was unexpected."""
    depth = 0
    for ch in text[:max(col - 1, 0)]:
        depth += 1 if ch in "([" else -1 if ch in ")]" else 0
    if depth > 0 or "expected ')'" not in message:
        return message
    m = _TOKEN.match(text, max(col - 1, 0))
    token = m.group(1) if m else text[col - 1:col]
    message = message.replace("expected ')' or ','", f"unexpected '{token}'")
    message = message.replace("expected ')'", f"unexpected '{token}'")
    if not text[:max(col - 1, 0)].strip():
        message = message.replace("after '('", "at the start of the condition")
    return message


def _at_the_end(message: str) -> str:
    """A message about the wrapper's closing ')' or ';' said of the condition's end."""
    for wrapper in ("')'", "';'"):
        message = (message.replace(f"before {wrapper}", "at the end of the condition")
                   .replace(f"unexpected {wrapper}", "the condition ends too early"))
    return message
