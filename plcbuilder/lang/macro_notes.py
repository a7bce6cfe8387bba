"""Errors a macro caused say so, as gcc and clang do: an error at (or right
after) tokens a ``#define`` expanded to gets a note pointing at the define
("expanded from OUTPUT_SPINDLE, include/pins.h:28"), and the define itself gets
a note in its header, so the file to fix is marked too.

The preprocessor gives every expanded token the span of the use and the name
of the define it came from (:attr:`Tok.macro`); nothing else is needed.
"""

from __future__ import annotations

from plcbuilder._support.records import replace
from plcbuilder.diagnostics import Diagnostic, Related, Severity
from plcbuilder.lang.preprocess import Define, Preprocessed
from plcbuilder.lang.tokens import Tok

TYPE_CHECKING = False               # (typing is not imported at run time: start-up)
if TYPE_CHECKING:
    from typing import Optional

#: codes of errors that describe the token before the one they point at
#: ("expected an expression before ')'")
_LOOKS_BACK = frozenset(("syntax",))


def add_macro_notes(diags: list[Diagnostic], pre: Preprocessed) -> list[Diagnostic]:
    """``diags`` with a note on every error a macro expansion caused, and one
    note per such define at the define (each once)."""
    toks = pre.tokens
    if not any(t.macro for t in toks):
        return diags
    starts: dict[tuple, list[int]] = {}
    for i, t in enumerate(toks):
        s = t.span
        starts.setdefault((s[0], s[1], s[2]), []).append(i)
    out: list[Diagnostic] = []
    at_defines: dict[tuple, Diagnostic] = {}
    for d in diags:
        define = None
        if d.severity == Severity.ERROR and d.span is not None:
            define = _cause(d, toks, starts.get((d.span[0], d.span[1], d.span[2])), pre)
        if define is None:
            out.append(d)
            continue
        out.append(replace(d, related=d.related + (
            Related(define.span, f"expanded from {define.name}: "
                                 f"#define {define.name} {define.text}".rstrip()),)))
        note = Diagnostic(Severity.NOTE, "macro-error",
                          f"{define.name} (#define {define.name} {define.text}) gives an error "
                          f"where it is used: {d.message}", define.span)
        at_defines.setdefault((define.name, d.message), note)
    return out + list(at_defines.values())


def _cause(d: Diagnostic, toks: list[Tok], at: Optional[list[int]],
           pre: Preprocessed) -> Optional[Define]:
    """The define whose expansion the error is in (or, for a syntax error
    about what came before, right after)."""
    if at is None:
        return None
    for i in at:
        if toks[i].macro:
            return pre.defines.get(toks[i].macro)
    first = at[0]
    if d.code in _LOOKS_BACK and first > 0 and toks[first - 1].macro:
        return pre.defines.get(toks[first - 1].macro)
    return None
