"""The preprocessor.

It runs first and hands the parser a flat list of tokens (made by
:mod:`plcbuilder.lang.tokens`), each carrying the :class:`Span` it came from
(its own file, line and column, headers included). That list *is* the origin map: every later diagnostic points at the
right place. Macro uses carry the span of the use and the name of the define.

- ``#include pins.h`` / ``"pins.h"`` / ``<pins.h>``: searched in the
  procedure's folder, then each include folder, then the built-in headers.
  A header is read once per compilation, however often it is included.
  A header must lie (links resolved) inside the project (``root``; outside a
  project, the procedure's folder) or inside an include folder named outside
  it (``--include DIR``, the project's ``[build] include``): anything else, such
  as ``#include "/etc/passwd"`` or a link out of the project, is an error that
  says where it resolved and how to allow it, and the file is not read.
- ``#define NAME tokens…`` (object-like), substituted by whole token,
  rescanned, never recursively. ``#undef``, ``#ifdef``, ``#ifndef``, ``#else``
  and ``#endif`` work as in C (header guards).
- Every pair of define names where one contains the other gets a warning: the
  controller's own preprocessor substitutes substrings and rejects such pairs.
"""

from __future__ import annotations

import bisect
import os
import re
from pathlib import Path

from plcbuilder._support.records import dataclass, field, replace
from plcbuilder.diagnostics import Diagnostic, Related, Span, error, warning
from plcbuilder.lang.builtin_headers import (BUILTIN_PREFIX, builtin_header,  # noqa: F401
                                             builtin_header_names)
from plcbuilder.lang.builtins import KEYWORDS
from plcbuilder.lang.source import SourceFile, SourceSet, normalise, read_source
from plcbuilder.lang.tokens import Tok, Tokenizer

TYPE_CHECKING = False               # (typing is not imported at run time: start-up)
if TYPE_CHECKING:
    from typing import Optional, Sequence

MAX_INCLUDE_DEPTH = 32
MAX_TOKENS = 200_000
MAX_EXPANSION = 1_000_000


@dataclass
class Define:
    name: str
    tokens: list[Tok]
    span: Span
    text: str                 # the replacement as written

    @property
    def value(self) -> Optional[int]:
        """The numeric value when the replacement is one number (or minus one)."""
        t = self.tokens
        if len(t) == 1 and t[0].kind == "NUMBER":
            return t[0].number
        return None


@dataclass
class Preprocessed:
    tokens: list[Tok]
    diagnostics: list[Diagnostic]
    sources: SourceSet
    defines: dict[str, Define]
    includes: list[str]                        # display names of headers read, in order
    block_comments: list[Span] = field(default_factory=list)   # for --strict
    directives: list[tuple[str, Span]] = field(default_factory=list)   # for --strict
    #: the input was refused as too large (a "too-large" error): ``tokens`` is
    #: only its start, not to be parsed
    too_large: bool = False


class TokenCache:
    """The tokens of every file a preprocessor read, kept for the next run over
    the same files (an open file checked at every pause in typing): a header
    is tokenized once, not at every keystroke, and a file whose text changed
    is tokenized again only from the line where the change starts to the first
    line after it where the old tokens go on unchanged (moved by the lines the
    edit added or removed). ``read`` reads a file again only when its size or
    time stamps changed. Files not used since the last :meth:`sweep` are
    dropped there."""

    def __init__(self):
        self._tokenized: dict[str, _Tokenized] = {}
        self._files: dict[str, tuple] = {}
        self._used: set = set()

    def lines(self, f: SourceFile) -> tuple:
        """(the tokenizer's lines of f, its diagnostics, its block comments, and
        per line how many of each came up to it, or None when there are none)."""
        self._used.add(f.name)
        old = self._tokenized.get(f.name)
        if old is None or old.text != f.text:
            old = self._tokenized[f.name] = _Tokenized.of(f) if old is None else old.edited(f)
        return old.lines, old.diags, old.comments, old.counts if old.diags or old.comments else None

    def read(self, path: Path, name: str) -> tuple[Optional[str], list[Diagnostic]]:
        """:func:`read_source`, again only when the file's size or modification time changed."""
        try:
            st = path.stat()
            stamp = (name, st.st_mtime_ns, st.st_ctime_ns, st.st_size, st.st_ino)
        except OSError:
            return read_source(path, name)
        key = str(path)
        self._used.add(key)
        got = self._files.get(key)
        if got is None or got[0] != stamp:
            got = self._files[key] = (stamp, read_source(path, name))
        text, diags = got[1]
        return text, list(diags)

    def sweep(self) -> None:
        self._tokenized = {k: v for k, v in self._tokenized.items() if k in self._used}
        self._files = {k: v for k, v in self._files.items() if k in self._used}
        self._used = set()


@dataclass
class _Tokenized:
    """One file's text and its tokenizer lines, with where each line starts."""
    name: str
    text: str
    lines: list          # Tokenizer.lines() items
    starts: list[int]    # the offset each line starts at
    numbers: list[int]   # the line number each starts on
    counts: list[tuple[int, int]]   # (diagnostics, block comments) up to and with each line
    diags: list[Diagnostic]
    comments: list[Span]

    @classmethod
    def of(cls, f: SourceFile) -> "_Tokenized":
        t = cls(f.name, f.text, [], [], [], [], [], [])
        t._tokenize(f.text, 0, 1, None)
        return t

    def _tokenize(self, text: str, start: int, number: int, stop) -> Optional[tuple[int, int]]:
        """Tokenize from a line start until ``stop(offset, number)`` says the
        line starting there is where to stop; returns that (offset, number)."""
        tk = Tokenizer(text, self.name, self.diags, self.comments)
        lines, starts, numbers, counts = self.lines, self.starts, self.numbers, self.counts
        diags, comments = self.diags, self.comments
        at = (start, number)
        for line in tk.lines(start, number):
            lines.append(line)
            starts.append(at[0])
            numbers.append(at[1])
            counts.append((len(diags), len(comments)))
            at = tk.next_line
            if at is not None and stop is not None and stop(*at):
                return at
        return None

    def edited(self, f: SourceFile) -> "_Tokenized":
        """The tokenization of f's text, an edit of this one's."""
        old, new = self.text, f.text
        p = _common_prefix(old, new)
        s = _common_suffix(old, new, min(len(old), len(new)) - p)
        k = max(bisect.bisect_right(self.starts, p) - 1, 0)       # the line the edit starts in
        t = _Tokenized(self.name, new, self.lines[:k], self.starts[:k], self.numbers[:k],
                       self.counts[:k], [], [])
        nd, nc = self.counts[k - 1] if k else (0, 0)
        t.diags, t.comments = self.diags[:nd], self.comments[:nc]
        grow = len(new) - len(old)
        old_starts = self.starts

        def stop(offset: int, number: int) -> bool:
            if offset < len(new) - s:
                return False
            j = bisect.bisect_left(old_starts, offset - grow)
            return j < len(old_starts) and old_starts[j] == offset - grow
        at = t._tokenize(new, self.starts[k] if self.starts else 0, self.numbers[k] if self.numbers else 1,
                         stop)
        if at is None:
            return t
        j = bisect.bisect_left(old_starts, at[0] - grow)
        moved = at[1] - self.numbers[j]
        nd0, nc0 = self.counts[j - 1] if j else (0, 0)
        dd, dc = len(t.diags) - nd0, len(t.comments) - nc0
        t.lines += self.lines[j:] if not moved else [_moved_line(x, moved) for x in self.lines[j:]]
        t.starts += [x + grow for x in self.starts[j:]]
        t.numbers += [x + moved for x in self.numbers[j:]]
        t.counts += [(a + dd, b + dc) for a, b in self.counts[j:]]
        t.diags += [_moved_diag(d, moved) for d in self.diags[nd0:]]
        t.comments += [_moved_span(c, moved) for c in self.comments[nc0:]]
        return t


def _common_prefix(a: str, b: str) -> int:
    lo, hi = 0, min(len(a), len(b))
    while lo < hi:                       # a[:lo] == b[:lo]; find the longest
        mid = (lo + hi + 1) // 2
        if a[lo:mid] == b[lo:mid]:
            lo = mid
        else:
            hi = mid - 1
    return lo


def _common_suffix(a: str, b: str, limit: int) -> int:
    lo, hi = 0, limit
    la, lb = len(a), len(b)
    while lo < hi:
        mid = (lo + hi + 1) // 2
        if a[la - mid:la - lo] == b[lb - mid:lb - lo]:
            lo = mid
        else:
            hi = mid - 1
    return lo


def _moved_span(s: Optional[Span], lines: int) -> Optional[Span]:
    return s if s is None or not lines else Span(s[0], s[1] + lines, s[2], s[3] + lines, s[4])


def _moved_diag(d: Diagnostic, lines: int) -> Diagnostic:
    return d if not lines else replace(d, span=_moved_span(d.span, lines))


def _moved_line(line: tuple, lines: int) -> tuple:
    is_dir, toks, hash_span, raw = line
    new = tuple.__new__          # (a Span without the named tuple's Python __new__,
    make = object.__new__        # a Tok without a call of its __init__: every token below an Enter)
    out = []
    for t in toks:
        s = t.span
        u = make(Tok)
        u.kind, u.value, u.number, u.macro, u.synthetic = t.kind, t.value, t.number, None, False
        u.span = new(Span, (s[0], s[1] + lines, s[2], s[3] + lines, s[4]))
        out.append(u)
    return is_dir, out, _moved_span(hash_span, lines), raw


class Preprocessor:
    def __init__(self, include_dirs: Sequence[Path] = (), read_file=read_source,
                 root: Optional[Path] = None, tokens: Optional[TokenCache] = None):
        self.include_dirs = [Path(p) for p in include_dirs]
        self.tokens = tokens
        self.read_file = tokens.read if tokens is not None and read_file is read_source else read_file
        self.root = Path(root) if root is not None else None
        self.allowed: list[Path] = []         # where headers may be (set by run_text)
        self.diags: list[Diagnostic] = []
        self.sources = SourceSet()
        self.defines: dict[str, Define] = {}
        self.all_defines: list[Define] = []
        self.includes: list[str] = []
        self.seen_files: set[str] = set()
        self.block_comments: list[Span] = []
        self.directives: list[tuple[str, Span]] = []
        self.out: list[Tok] = []
        self.expanded = 0
        self.too_many = False

    # ------------------------------------------------------------ entry
    def run_text(self, text: str, name: str, path: Optional[Path]) -> Preprocessed:
        f = SourceFile(name, path, normalise(text))
        self.allowed = _allowed_folders(self.root or (path.parent if path else None),
                                        self.include_dirs)
        self.sources.add(f)
        self.seen_files.add(self._key(f))
        self._file(f, [f.name], path.parent if path else None)
        self._substring_warnings()
        return Preprocessed(self.out, self.diags, self.sources, self.defines, self.includes,
                            self.block_comments, self.directives, self.too_many)

    @staticmethod
    def _key(f: SourceFile) -> str:
        return str(f.path.resolve()) if f.path else f.name

    # ------------------------------------------------------------ files
    def _file(self, f: SourceFile, stack: list[str], folder: Optional[Path]) -> None:
        cond: list[list] = []   # [active, seen_else, parent_active, span]
        for is_dir, toks, hash_span, raw in self._lines(f):
            if self.too_many:
                return          # the rest is not read: one error, not a cascade
            active = all(c[0] for c in cond)
            if is_dir:
                self._directive(toks, hash_span, raw, f, stack, folder, cond, active)
                continue
            if active and toks:
                self._emit(toks)
        if self.too_many:
            return
        for c in cond:
            self.diags.append(error("unterminated-conditional", "#if without #endif", c[3]))

    def _lines(self, f: SourceFile):
        """The tokenizer's lines of f; its diagnostics and block comments are
        added as each line comes, from the token cache when there is one."""
        if self.tokens is None:
            tk = Tokenizer(f.text, f.name, self.diags, self.block_comments, MAX_TOKENS + 1)
            last = None
            for last in tk.lines():
                yield last
            if tk.truncated and not self.too_many:
                self.too_many = True
                at = last[1][-1].span if last is not None and last[1] else Span.point(f.name, 1, 1)
                self.diags.append(error("too-large", f"{f.name} has more than {MAX_TOKENS} tokens",
                                        at))
            return
        lines, diags, comments, counts = self.tokens.lines(f)
        if counts is None:
            yield from lines
            return
        nd = nc = 0
        for line, (d, c) in zip(lines, counts):
            self.diags.extend(diags[nd:d])
            self.block_comments.extend(comments[nc:c])
            nd, nc = d, c
            yield line

    def _directive(self, toks, hash_span, raw, f, stack, folder, cond, active) -> None:
        if not toks:
            return  # a lone '#' is a null directive
        head = toks[0]
        word = head.value
        span = hash_span.cover(head.span)
        self.directives.append((word, span))
        if word in ("ifdef", "ifndef"):
            if len(toks) < 2 or toks[1].kind != "NAME":
                self.diags.append(error("bad-directive", f"#{word} needs a name", span))
                cond.append([False, False, active, span])
                return
            defined = toks[1].value in self.defines
            cond.append([defined if word == "ifdef" else not defined, False, active, span])
            return
        if word == "else":
            if not cond or cond[-1][1]:
                self.diags.append(error("bad-directive", "#else without #ifdef/#ifndef", span))
                return
            cond[-1][0] = not cond[-1][0]
            cond[-1][1] = True
            return
        if word == "endif":
            if not cond:
                self.diags.append(error("bad-directive", "#endif without #ifdef/#ifndef", span))
                return
            cond.pop()
            return
        if not active:
            return
        if word == "include":
            self._include(raw, span, f, stack, folder)
        elif word == "define":
            self._define(toks, raw, span)
        elif word == "undef":
            if len(toks) >= 2 and toks[1].kind == "NAME":
                self.defines.pop(toks[1].value, None)
            else:
                self.diags.append(error("bad-directive", "#undef needs a name", span))
        else:
            self.diags.append(error("bad-directive", f"unknown directive #{word}", span,
                                    "directives are #include and #define (and #ifdef/#ifndef/"
                                    "#else/#endif, #undef)"))

    def _include(self, raw: str, span: Span, f: SourceFile, stack, folder) -> None:
        arg = re.sub(r"//.*|/\*.*?\*/", "", raw).strip()[len("include"):].strip()
        m = re.fullmatch(r'"([^"]+)"|<([^>]+)>|([^\s"<>]+)', arg)
        if not m:
            self.diags.append(error("bad-include", "#include needs a file name", span,
                                    "write #include pins.h, #include \"pins.h\" or #include <pins.h>"))
            return
        target = next(g for g in m.groups() if g)
        if len(stack) > MAX_INCLUDE_DEPTH:
            self.diags.append(error("include-depth", f"includes nest deeper than {MAX_INCLUDE_DEPTH}",
                                    span))
            return
        found = self._find(target, folder, span)
        if found is False:                 # outside where includes may go: reported
            return
        if found is None:
            where = [str(folder) if folder else "the procedure's folder"]
            where += [str(d) for d in self.include_dirs] + ["the built-in headers"]
            self.diags.append(error("include-not-found", f"cannot find header '{target}'", span,
                                    "searched " + ", ".join(where)))
            return
        hf, hfolder = found
        key = self._key(hf)
        if hf.name in stack or key in {self._key(self.sources.files[s]) for s in stack
                                       if s in self.sources.files}:
            self.diags.append(error("include-cycle",
                                    f"'{hf.name}' includes itself: " + " -> ".join(stack + [hf.name]),
                                    span))
            return
        if key in self.seen_files:
            return
        self.seen_files.add(key)
        self.sources.add(hf)
        self.includes.append(hf.name)
        self._file(hf, stack + [hf.name], hfolder)

    def _find(self, target: str, folder: Optional[Path], span: Span):
        target_path = Path(target)
        candidates = ([folder] if folder else []) + self.include_dirs
        for d in candidates:
            p = d / target_path
            if p.is_file():
                if not self._allowed(target, p, span):
                    return False
                text, diags = self.read_file(p, self._display(p))
                self.diags.extend(diags)
                if text is None:
                    return None
                return SourceFile(self._display(p), p, text), p.parent
        text = builtin_header(target)
        if text is not None:
            return SourceFile(BUILTIN_PREFIX + target, None, text), None
        return None

    def _allowed(self, target: str, p: Path, span: Span) -> bool:
        """Whether header ``p`` lies inside a folder includes may reach; if not,
        an error saying where it resolved and how to allow it."""
        try:
            real = p.resolve()
        except (OSError, RuntimeError):       # a link loop
            real = p.absolute()
        if any(real.is_relative_to(a) for a in self.allowed):
            return True
        inside = (f"the project ({self.root})" if self.root is not None else
                  "the procedure's folder" + (f" ({self.allowed[0]})" if self.allowed else ""))
        self.diags.append(error(
            "include-outside", f"'{target}' resolves to {real}, outside {inside}; "
            "includes stay inside the project, its include folders and the built-in headers",
            span, f"to allow it, name its folder: --include {real.parent} (or, in a project, "
                  f"add it to include = [...] under [build] in plcbuilder.toml)"))
        return False

    def _display(self, p: Path) -> str:
        try:
            return str(p.resolve().relative_to(Path.cwd().resolve()))
        except (ValueError, OSError):
            return str(p)

    def _define(self, toks: list[Tok], raw: str, span: Span) -> None:
        if len(toks) < 2 or toks[1].kind != "NAME" and toks[1].kind not in KEYWORDS.values():
            self.diags.append(error("bad-define", "#define needs a name", span))
            return
        name_tok = toks[1]
        name = name_tok.value
        body = toks[2:]
        # function-like: NAME immediately followed by '('
        if body and body[0].kind == "LPAR" and body[0].span.col == name_tok.span.end_col \
                and body[0].span.line == name_tok.span.line:
            self.diags.append(error("bad-define", f"function-like macro {name}(...) is not supported",
                                    name_tok.span, "only object-like defines: #define NAME value"))
            return
        text = raw.split(name, 1)[1] if name in raw else ""
        text = re.sub(r"//.*|/\*.*?\*/", "", text).strip()
        d = Define(name, body, name_tok.span, text)
        old = self.defines.get(name)
        if old is not None and [t.value for t in old.tokens] != [t.value for t in body]:
            self.diags.append(warning("define-redefined", f"'{name}' redefined", name_tok.span,
                                      related=[Related(old.span, "previous definition")]))
        self.defines[name] = d
        self.all_defines.append(d)

    # ------------------------------------------------------------ expansion
    def _emit(self, toks: list[Tok]) -> None:
        if self.too_many:
            return
        out = self.out
        defines = self.defines
        if not defines:
            out += toks         # (nothing to expand: a run of tokens costs no loop here)
        else:
            for t in toks:
                if t.kind == "NAME" and t.value in defines:
                    self._expand(t, t.span, frozenset())
                else:
                    out.append(t)
        if len(out) > MAX_TOKENS:
            self.too_many = True
            self.diags.append(error("too-large", f"more than {MAX_TOKENS} tokens after preprocessing",
                                    out[-1].span))

    def _expand(self, t: Tok, use_span: Span, hidden: frozenset) -> None:
        d = self.defines[t.value]
        hidden = hidden | {t.value}
        self.expanded += len(d.tokens)
        if self.expanded > MAX_EXPANSION:
            if not self.too_many:
                self.too_many = True
                self.diags.append(error("too-large", "define expansion is too large", use_span))
            return
        for r in d.tokens:
            if r.kind == "NAME" and r.value in self.defines and r.value not in hidden:
                self._expand(r, use_span, hidden)
            else:
                self.out.append(Tok(r.kind, r.value, use_span, r.number, t.macro or t.value))

    # ------------------------------------------------------------ checks
    def _substring_warnings(self) -> None:
        seen: dict[str, Define] = {}
        for d in self.all_defines:
            seen.setdefault(d.name, d)
        names = sorted(seen, key=len)
        for i, short in enumerate(names):
            for long in names[i + 1:]:
                if len(long) > len(short) and short in long:
                    ds, dl = seen[short], seen[long]
                    self.diags.append(warning(
                        "define-substring",
                        f"define '{long}' contains define '{short}'; the controller's preprocessor "
                        "substitutes substrings and rejects this pair (\"syntax error, unexpected ID\")",
                        dl.span,
                        f"rename '{long}' so it does not contain '{short}' "
                        f"(e.g. put the extra word first)",
                        related=[Related(ds.span, f"'{short}' is defined here")]))


def _allowed_folders(root: Optional[Path], include_dirs: Sequence[Path]) -> list[Path]:
    """The folders headers may lie in (links resolved): ``root`` (the project, or
    the procedure's folder), and each include folder named outside it (one inside
    it is part of the project: what it holds must be inside the project too)."""
    def real(p: Path) -> Path:
        try:
            return p.resolve()
        except (OSError, RuntimeError):
            return p.absolute()
    out: list[Path] = []
    base = Path(os.path.abspath(root)) if root is not None else None
    if base is not None:
        out.append(real(base))
    for d in include_dirs:
        lexical = Path(os.path.abspath(d))
        if base is None or not lexical.is_relative_to(base):
            out.append(real(lexical))
    return out


def preprocess_text(text: str, name: str = "<input>", path: Optional[Path] = None,
                    include_dirs: Sequence[Path] = ()) -> Preprocessed:
    return Preprocessor(include_dirs).run_text(text, name, path)
