"""Syntax errors a person can act on: the parser reports where it stopped
and which terminals it expected; this turns that into one message, naming the
usual mistakes (C types, ``for``/``switch``, ``return``, ``+=``, ``=`` in a
condition, a missing ``;`` or ``)``) before falling back to the expected tokens.
"""

from __future__ import annotations

from plcbuilder.diagnostics import Diagnostic, Span, error
from plcbuilder.lang.tokens import TERMINAL_TEXT, Tok

C_TYPES = {"int", "long", "short", "char", "unsigned", "signed", "void", "float", "double", "bool",
           "const", "static", "uint32_t", "int32_t"}


def token_span(toks: list[Tok], i: int) -> Span:
    """The span of token i; just past the last token at the end."""
    if 0 <= i < len(toks):
        return toks[i].span
    if toks:
        s = toks[-1].span
        return Span(s.file, s.end_line, s.end_col, s.end_line, s.end_col + 1)
    return Span("<input>", 1, 1, 1, 2)


def statement_start(toks: list[Tok], i: int) -> int:
    """The index of the first token of the statement token i is in."""
    j = min(i, len(toks)) - 1
    depth = 0
    while j >= 0:
        k = toks[j].kind
        if k == "RPAR":
            depth += 1
        elif k == "LPAR":
            if depth == 0:
                pass
            else:
                depth -= 1
        elif depth == 0 and k in ("SEMI", "LBRACE", "RBRACE"):
            break
        j -= 1
    return j + 1


def c_statement_header(toks: list[Tok], i: int) -> int:
    """For a C statement the language lacks (for, switch), the index of the
    ')' closing its header: errors up to there are one mistake."""
    s = statement_start(toks, i)
    if s < len(toks) and toks[s].kind == "NAME" and toks[s].value in ("for", "switch") \
            and s + 1 < len(toks) and toks[s + 1].kind == "LPAR":
        depth = 0
        for j in range(s + 1, len(toks)):
            if toks[j].kind == "LPAR":
                depth += 1
            elif toks[j].kind == "RPAR":
                depth -= 1
                if depth == 0:
                    return j
    return -1


def _prev_real(toks: list[Tok], i: int) -> int:
    j = i - 1
    while j >= 0 and toks[j].kind == "BAD":
        j -= 1
    return j


def syntax_error(toks: list[Tok], i: int, expected: set[str]) -> Diagnostic:
    """The error for an unexpected token i, when the parser ``expected`` these
    terminals: a friendly message for the usual mistakes (C habits, typos)."""
    at_end = i >= len(toks)
    tok = None if at_end else toks[i]
    span = token_span(toks, i)
    what = "the end of the file" if at_end else f"'{tok.value}'"
    p = _prev_real(toks, i)
    prev = toks[p] if p >= 0 else None
    # Friendly messages for the usual mistakes (C habits, typos).
    if prev is not None and prev.kind == "NAME" and prev.value in C_TYPES and tok is not None \
            and tok.kind == "NAME":
        return error("syntax", f"unexpected '{tok.value}' after '{prev.value}'", prev.span,
                     "variables need no declaration: write the name and assign it "
                     f"(e.g. {tok.value}=0;)", "procedures are written name() { ... }")
    if prev is not None and prev.kind == "NAME" and tok is not None and tok.kind == "NAME" \
            and expected == {"LPAR"} and i + 1 < len(toks) and toks[i + 1].kind == "LPAR":
        # a stray word before a procedure: `Z` above `main()`
        return error("syntax", f"unexpected '{prev.value}' before the procedure {tok.value}()",
                     prev.span, "delete it: outside procedures there are only "
                     "procedures, name() { ... }")
    start = statement_start(toks, i)
    first = toks[start] if start < len(toks) else None
    if first is not None and first.kind == "NAME" and first.value in ("for", "switch") \
            and start + 1 < len(toks) and toks[start + 1].kind == "LPAR":
        if first.value == "for":
            return error("syntax", "'for' loops are not part of the PLC language", first.span,
                         "write i=0; do { ...; i++; } while (i<N);")
        return error("syntax", "'switch' is not part of the PLC language", first.span,
                     "use if (...) { ... } else if (...) { ... }")
    if prev is not None and prev.kind == "NAME" and tok is not None:
        word = prev.value
        if word == "return":
            return error("syntax", "'return' is not part of the PLC language", prev.span,
                         "a procedure ends at its closing brace; use exit(code) to end the "
                         "whole PLC procedure")
        if word in ("break", "continue"):
            return error("syntax", f"'{word}' is not part of the PLC language", prev.span,
                         "leave a loop by making its condition false (e.g. set a flag)")
    nxt = toks[i + 1] if i + 1 < len(toks) else None
    if tok is not None and nxt is not None and nxt.kind == "ASSIGN" \
            and tok.kind in ("PLUS", "MINUS", "STAR", "SLASH", "PERCENT", "AMP", "PIPE",
                             "CARET", "SHL", "SHR") and tok.span.end_col == nxt.span.col:
        return error("syntax", f"compound assignment '{tok.value}=' is not supported",
                     tok.span.cover(nxt.span), f"write x = x {tok.value} value;")
    if tok is not None and tok.kind == "ASSIGN" and prev is not None \
            and prev.kind in ("PLUS", "MINUS", "STAR", "SLASH", "PERCENT", "AMP", "PIPE",
                              "CARET", "SHL", "SHR"):
        return error("syntax", f"compound assignment '{prev.value}=' is not supported",
                     prev.span.cover(tok.span), f"write x = x {prev.value} value;")
    if tok is not None and tok.kind == "ASSIGN" and "RPAR" in expected:
        return error("syntax", "'=' in a condition", tok.span,
                     "compare with '=='; assignments are statements of their own")
    if at_end and "RBRACE" in expected:
        return error("syntax", "expected '}' before the end of the file", span,
                     "a block or procedure is not closed")
    operand = tok is not None and tok.kind in ("NAME", "NUMBER", "IF", "DO", "WHILE", "LBRACE")
    if "RPAR" in expected and "SEMI" not in expected and prev is not None and operand:
        ps = prev.span
        return error("syntax", f"expected ')' after '{prev.value}'",
                     Span(ps.file, ps.end_line, ps.end_col, ps.end_line, ps.end_col + 1))
    if "SEMI" in expected and prev is not None and (at_end or operand or tok.span.line > prev.span.line
                                                     or len(expected) <= 3):
        ps = prev.span
        return error("syntax", f"expected ';' after '{prev.value}'",
                     Span(ps.file, ps.end_line, ps.end_col, ps.end_line, ps.end_col + 1))
    if {"NAME", "NUMBER", "LPAR"} <= expected and "SEMI" not in expected:
        return error("syntax", f"expected an expression before {what}", span)
    names = sorted(TERMINAL_TEXT.get(e, e) for e in expected if e != "$END")
    names = [n if n.startswith(("a ", "the ")) else f"'{n}'" for n in names]
    if not names:
        return error("syntax", f"unexpected {what}", span)
    if len(names) > 6:
        hint = "expected a statement or an expression here" if "'('" in names else ""
        return error("syntax", f"unexpected {what}", span, *([hint] if hint else []))
    return error("syntax", f"unexpected {what}; expected {', '.join(names[:-1])}"
                 + (" or " if len(names) > 1 else "") + names[-1], span)
