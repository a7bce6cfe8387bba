"""Diagnostics: the data every stage of the pipeline adds to.

A :class:`Diagnostic` is shaped like an LSP diagnostic (a span, a severity, a
code, a message) plus hints. :meth:`Diagnostic.to_dict` and
:meth:`Diagnostic.from_dict` are its one serialisation (Build All's workers and
its cache use it). The core never prints: the CLI and the IDE render
diagnostics with the helpers at the bottom of this module.

Lines and columns are 1-based; ``end_col`` is exclusive. Columns count
characters (not bytes): the IDE converts to Scintilla's byte offsets itself.
"""

from __future__ import annotations

import enum
from collections import namedtuple

from plcbuilder._support.records import dataclass

TYPE_CHECKING = False               # (typing is not imported at run time: start-up)
if TYPE_CHECKING:
    from typing import Callable, Iterable, Optional


class Severity(enum.IntEnum):
    ERROR = 1
    WARNING = 2
    NOTE = 3

    @property
    def label(self) -> str:
        return self.name.lower()


_new = tuple.__new__        # Span(...) without a Python call in between: one is made per token


class Span(namedtuple("Span", "file line col end_line end_col")):
    """Where something is: 1-based line and column, ``end_col`` exclusive.
    A named tuple: made for every token, so it must be cheap to create.
    Fields: ``file`` (str), ``line``, ``col``, ``end_line``, ``end_col`` (int)."""
    __slots__ = ()

    @classmethod
    def point(cls, file: str, line: int, col: int, length: int = 1) -> "Span":
        return cls(file, line, col, line, col + max(length, 1))

    def cover(self, other: "Span") -> "Span":
        """The smallest span from the start of self to the end of other (same file)."""
        if other[0] != self[0]:
            return self
        if (other[1], other[2]) < (self[1], self[2]):
            start_line, start_col = other[1], other[2]
        else:
            start_line, start_col = self[1], self[2]
        if (other[3], other[4]) > (self[3], self[4]):
            end_line, end_col = other[3], other[4]
        else:
            end_line, end_col = self[3], self[4]
        return _new(Span, (self[0], start_line, start_col, end_line, end_col))


@dataclass(frozen=True)
class Related:
    span: Span
    message: str


@dataclass(frozen=True)
class Diagnostic:
    severity: Severity
    code: str
    message: str
    span: Optional[Span]
    hints: tuple[str, ...] = ()
    related: tuple[Related, ...] = ()

    @property
    def is_error(self) -> bool:
        return self.severity == Severity.ERROR

    def sort_key(self):
        s = self.span
        return (s.file, s.line, s.col) if s else ("", 0, 0)

    # The one serialisation of a diagnostic (Build All's workers send it, the
    # build cache stores it): a dict of JSON values,
    #     {"severity": 1, "code": "...", "message": "...",
    #      "span": [file, line, col, end_line, end_col] or null,
    #      "hints": ["..."], "related": [[span, "message"], ...]}

    def to_dict(self) -> dict:
        """This diagnostic as a dict of JSON values (read back by :meth:`from_dict`)."""
        return {"severity": int(self.severity), "code": self.code, "message": self.message,
                "span": _span_to_list(self.span), "hints": list(self.hints),
                "related": [[_span_to_list(r.span), r.message] for r in self.related]}

    @classmethod
    def from_dict(cls, v) -> "Diagnostic":
        """The diagnostic :meth:`to_dict` made ``v`` from; ValueError when ``v``
        is not such a dict."""
        Diagnostic.check_dict(v)
        return cls(Severity(v["severity"]), v["code"], v["message"], _span_from_list(v["span"]),
                   tuple(v["hints"]),
                   tuple(Related(_span_from_list(s), m) for s, m in v["related"]))

    @staticmethod
    def check_dict(v) -> None:
        """Raise ValueError unless ``v`` is a dict as :meth:`to_dict` makes it,
        without making the objects (a cache checks what it read this way)."""
        if type(v) is not dict or v.get("severity") not in _SEVERITIES \
                or type(v.get("code")) is not str or type(v.get("message")) is not str:
            raise ValueError("bad diagnostic")
        hints, related = v.get("hints"), v.get("related")
        if type(hints) is not list or type(related) is not list:
            raise ValueError("bad diagnostic")
        for h in hints:
            if type(h) is not str:
                raise ValueError("bad diagnostic")
        _check_span(v.get("span"))
        for rel in related:
            if type(rel) is not list or len(rel) != 2 or type(rel[1]) is not str:
                raise ValueError("bad diagnostic")
            _check_span(rel[0])


_SEVERITIES = frozenset(int(s) for s in Severity)


def _span_to_list(s: Optional[Span]) -> Optional[list]:
    return None if s is None else [s.file, s.line, s.col, s.end_line, s.end_col]


def _span_from_list(v) -> Optional[Span]:
    return None if v is None else Span(*v)


def _check_span(v) -> None:
    if v is not None and (type(v) is not list or len(v) != 5 or type(v[0]) is not str
                          or type(v[1]) is not int or type(v[2]) is not int
                          or type(v[3]) is not int or type(v[4]) is not int):
        raise ValueError("bad span")


def error(code: str, message: str, span: Optional[Span], *hints: str,
          related: Iterable[Related] = ()) -> Diagnostic:
    return Diagnostic(Severity.ERROR, code, message, span, tuple(hints), tuple(related))


def warning(code: str, message: str, span: Optional[Span], *hints: str,
            related: Iterable[Related] = ()) -> Diagnostic:
    return Diagnostic(Severity.WARNING, code, message, span, tuple(hints), tuple(related))


# ---------------------------------------------------------------- rendering

#: the most of a source line a rendered diagnostic shows (around the column)
MAX_SHOWN = 160


def render_text(diag: Diagnostic, source_line: Callable[[str, int], Optional[str]] | None = None,
                colorize: Callable[[str, str], str] | None = None) -> str:
    """Render one diagnostic the way compilers do::

        file:line:col: error: text
            the source line
            ^~~~
          hint: ...

    ``source_line(file, line)`` returns the text of a line (or None);
    ``colorize(kind, text)`` may wrap pieces in terminal colours
    (kinds: "location", "error", "warning", "note", "caret", "hint", "source").
    """
    c = colorize or (lambda _kind, text: text)
    s = diag.span
    loc = f"{s.file}:{s.line}:{s.col}" if s else "plcbuilder"
    out = [f"{c('location', loc + ':')} {c(diag.severity.label, diag.severity.label + ':')} {diag.message}"]
    if s and source_line is not None:
        text = source_line(s.file, s.line)
        if text is not None:
            text = text.rstrip("\n").replace("\t", " ")
            start = max(s.col - 1, 0)
            if s.end_line == s.line:
                width = max(s.end_col - s.col, 1)
            else:
                width = max(len(text) - start, 1)
            if len(text) > MAX_SHOWN:           # a very long line: the part around the column
                lo = max(0, min(start - MAX_SHOWN // 4, len(text) - MAX_SHOWN))
                hi = lo + MAX_SHOWN
                width = max(1, min(width, hi - start))
                text = ("..." if lo else "") + text[lo:hi] + ("..." if hi < len(text) else "")
                start += (3 if lo else 0) - lo
            out.append("    " + c("source", text))
            out.append("    " + " " * start + c("caret", "^" + "~" * (width - 1)))
    for h in diag.hints:
        out.append("  " + c("hint", "hint:") + " " + h)
    for r in diag.related:
        rs = r.span
        out.append(f"  {c('note', 'note:')} {rs.file}:{rs.line}:{rs.col}: {r.message}")
    return "\n".join(out)


def summary(diags: Iterable[Diagnostic]) -> str:
    diags = list(diags)
    return summary_counts(sum(1 for d in diags if d.severity == Severity.ERROR),
                          sum(1 for d in diags if d.severity == Severity.WARNING))


def summary_counts(errors: int, warnings: int) -> str:
    """``1 error, 2 warnings``."""
    part = lambda n, word: f"{n} {word}{'' if n == 1 else 's'}"  # noqa: E731
    return f"{part(errors, 'error')}, {part(warnings, 'warning')}"
