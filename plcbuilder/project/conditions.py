"""Breakpoint conditions: an expression of the PLC language compiled into a
small procedure whose exit code is its value (SPEC §6). The
debugger binds its variables by name to the procedure that reaches the
breakpoint. The IDE, ``plcbuilder run --break`` (through the api) and the
debug adapter compile conditions here."""

from __future__ import annotations

from pathlib import Path

from plcbuilder._support.files import read_bounded
from plcbuilder.lang import Diagnostic, Span, error
from plcbuilder.lang.pipeline import CompileOptions, compile_source
from plcbuilder.lang.source import MAX_SOURCE_BYTES
from plcbuilder.project.model import Project, ProjectError, kind_of

__all__ = ["CONDITION_FILE", "MAX_CONDITION", "compile_condition"]

CONDITION_FILE = "<condition>"
#: the longest condition (or evaluated expression) compiled: a compile takes
#: time in proportion to the text, and a condition is an expression of a line
MAX_CONDITION = 2000


def compile_condition(text: str, context=None) -> "bytes | list[Diagnostic]":
    """A breakpoint's condition (an expression of the PLC language) compiled
    into a small procedure whose exit code is its value: the Program's bytes,
    which the debugger binds by name to the variables of the procedure that
    reaches the breakpoint. ``context``: the source file (or project folder)
    whose ``#include`` and ``#define`` lines the condition may use. When it
    does not compile: its error diagnostics, pointing into the condition's text
    (file ``<condition>``, line 1)."""
    if not isinstance(text, str) or not text.strip():
        return [error("condition", "a condition needs an expression",
                      Span.point(CONDITION_FILE, 1, 1))]
    if "\n" in text or "\r" in text:
        return [error("condition", "a condition is one line", Span.point(CONDITION_FILE, 1, 1))]
    if len(text) > MAX_CONDITION:
        return [error("condition", f"a condition is at most {MAX_CONDITION} characters "
                                   f"(this one has {len(text)})", Span.point(CONDITION_FILE, 1, 1),
                      "name the value in the procedure and test that")]
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
    prefix = "  exit("
    src = "\n".join([*head, "main()", "{", f"{prefix}{text});", "}"]) + "\n"
    where = str(path.with_name("__condition__.plc")) if path is not None and path.is_file() \
        else "<condition>"
    r = compile_source(src, where, options)
    at = len(head) + 3
    errors = []
    for d in r.diagnostics:
        if not d.is_error:
            continue
        s = d.span
        span = (Span(CONDITION_FILE, 1, max(1, s.col - len(prefix)), 1,
                     max(2, s.end_col - len(prefix))) if s is not None and s.line == at
                else Span.point(CONDITION_FILE, 1, 1))
        errors.append(Diagnostic(d.severity, d.code, d.message, span, d.hints))
    if errors or r.program is None:
        return errors or [error("condition", "the condition does not compile",
                                Span.point(CONDITION_FILE, 1, 1))]
    return r.program.to_bytes()
