"""What the language server answers about a document, from the same
:mod:`plcbuilder.lang.symbols` index and :mod:`plcbuilder.lang.hover` text
that the IDE uses: hover, completion, signature help, go-to-definition,
references, rename, document symbols, semantic tokens and inlay hints.

Every function takes the :class:`~plcbuilder.lsp.analysis.Analysis` and a
document's uri and returns lsprotocol types (or None).
"""

from __future__ import annotations

import functools
from pathlib import Path
from typing import Any, Callable, Optional

from lsprotocol import types as T
from pygls.uris import from_fs_path
from pygments.token import Comment, Keyword, Name, Number, Operator

from plcbuilder.lang import Span
from plcbuilder.lang import hover as lang_hover
from plcbuilder.lang import symbols as S
from plcbuilder.lang.builtins import is_reserved
from plcbuilder.lang.highlight import PlcLexer
from plcbuilder.lang.preprocess import BUILTIN_PREFIX
from plcbuilder.lsp.analysis import Analysis, builtin_path, uri_path
from plcbuilder.lsp.positions import Lines, span_range
from plcbuilder.lsp.protocol import RequestFailed

_IDENT_FIRST = set("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz_")
_IDENT = _IDENT_FIRST | set("0123456789")

_COMPLETION_KIND = {
    S.KEYWORD: T.CompletionItemKind.Keyword, S.FUNCTION: T.CompletionItemKind.Function,
    S.PREDEFINED_VARIABLE: T.CompletionItemKind.Variable, S.DEFINE: T.CompletionItemKind.Constant,
    S.PROCEDURE: T.CompletionItemKind.Function, S.VARIABLE: T.CompletionItemKind.Variable,
    S.CONSTANT: T.CompletionItemKind.EnumMember,
}

#: The semantic token legend.
TOKEN_TYPES = ["comment", "macro", "string", "keyword", "function", "variable", "enumMember",
               "number", "operator"]
TOKEN_MODIFIERS = ["declaration", "defaultLibrary", "readonly"]
LEGEND = T.SemanticTokensLegend(token_types=TOKEN_TYPES, token_modifiers=TOKEN_MODIFIERS)
_T = {n: i for i, n in enumerate(TOKEN_TYPES)}
_DECL, _LIB, _RO = 1, 2, 4


class NotPlc(Exception):
    """The document is not one the server answers about (not PLC, over the size
    limit, or a file it may not read)."""


def _answer(empty: Callable[[], Any]):
    """A feature's answer for a document it does not serve: ``empty()``."""
    def wrap(fn):
        @functools.wraps(fn)
        def feature(*args, **kwargs):
            try:
                return fn(*args, **kwargs)
            except NotPlc:
                return empty()
        return feature
    return wrap


class Snapshot:
    """One document's text, lines and symbol index, made once per question."""

    def __init__(self, analysis: Analysis, uri: str):
        self.analysis = analysis
        self.uri = uri
        self.path = uri_path(uri)
        text = analysis.usable(uri)
        if text is None:
            raise NotPlc(uri)
        self.text = text
        self.ctx = analysis.context(uri)
        self.lines = analysis.lines(uri, text)
        name = str(self.path) if self.path is not None else "<" + uri.rsplit("/", 1)[-1] + ">"
        self.name = name
        self.index = analysis.index(uri, self.text, name, self.path, self.ctx)

    def offset(self, pos: T.Position) -> int:
        return self.lines.offset(pos)

    def word(self, pos: T.Position) -> Optional[tuple[int, int, str]]:
        return self.index.word_at(self.offset(pos))

    def range_of(self, start: int, end: int) -> T.Range:
        return T.Range(self.lines.at_offset(start), self.lines.at_offset(end))

    def location(self, span: Span) -> Optional[T.Location]:
        """Where a span is, as a client location (a header: its file; the built-in
        pins.h: the file it is read from)."""
        if span.file == self.name:
            return T.Location(self.uri, self.lines.span_range(span))
        if span.file.startswith(BUILTIN_PREFIX):
            p = builtin_path(span.file)
        elif span.file.startswith("<"):
            return None
        else:
            p = Path(span.file).resolve()
        if p is None:
            return None
        uri = from_fs_path(str(p))
        text = self.analysis.read(p) or ""
        lines = Lines(text, self.analysis.encoding)
        return T.Location(uri, span_range(span, lambda n1: lines.line(n1 - 1), lines.encoding))


# ---------------------------------------------------------------- hover
@_answer(lambda: None)
def hover(an: Analysis, uri: str, pos: T.Position) -> Optional[T.Hover]:
    snap = Snapshot(an, uri)
    w = snap.word(pos)
    if w is None:
        return None
    start, end, word = w
    line_start = snap.lines.starts[snap.lines.at_offset(start).line]
    before = snap.text[line_start:start]
    result = an.results.get(uri)
    text = lang_hover.hover_text(
        word, before, software=snap.ctx.software, symbols=getattr(result, "symbols", None),
        header_defines=_header_defines(an, snap), variables=tuple(snap.index.variables),
        procedures={n: s.span for n, s in snap.index.procedures.items()})
    if text is None:
        d = snap.index.defines.get(word)
        if d is None:
            return None
        text = f"#define {word} {d.value}".rstrip()
    return T.Hover(contents=T.MarkupContent(T.MarkupKind.PlainText, text),
                   range=snap.range_of(start, end))


def _header_defines(an: Analysis, snap: Snapshot) -> dict:
    return an.header_defines(snap.ctx)


# ---------------------------------------------------------------- completion
@_answer(lambda: T.CompletionList(is_incomplete=False, items=[]))
def completion(an: Analysis, uri: str, pos: T.Position) -> T.CompletionList:
    snap = Snapshot(an, uri)
    off = snap.offset(pos)
    start = off
    while start > 0 and snap.text[start - 1] in _IDENT:
        start -= 1
    prefix = snap.text[start:off]
    items = snap.index.completions(prefix, software=snap.ctx.software)
    headers = _header_defines(an, snap)
    items = S.unique(items + [(n, S.DEFINE) for n in headers])
    out = []
    for name, kind in items:
        if prefix and not name.lower().startswith(prefix.lower()):
            continue
        detail = None
        doc = None
        if kind == S.FUNCTION:
            b = S.FUNCTIONS[name]
            detail = b.call_text
            doc = lang_hover.signature_text(name)
        elif kind == S.DEFINE:
            sym = snap.index.defines.get(name)
            value = sym.value if sym is not None else headers.get(name, ("",))[0]
            detail = f"#define {name} {value}".rstrip()
        elif kind == S.CONSTANT:
            detail = f"= {S.CONSTANTS[name]}"
        elif kind == S.PREDEFINED_VARIABLE:
            detail = "predefined variable"
        elif kind == S.PROCEDURE:
            detail = f"{name}()  procedure"
        elif kind == S.VARIABLE:
            detail = "variable of this file"
        out.append(T.CompletionItem(
            label=name, kind=_COMPLETION_KIND.get(kind), detail=detail,
            documentation=T.MarkupContent(T.MarkupKind.PlainText, doc) if doc else None,
            insert_text=call_snippet(name, S.FUNCTIONS[name].params) if kind == S.FUNCTION else None,
            insert_text_format=T.InsertTextFormat.Snippet if kind == S.FUNCTION else None))
    return T.CompletionList(is_incomplete=not prefix, items=out)


def call_snippet(name: str, params) -> str:
    """A call with one named placeholder per argument: ``gvarset(${1:addr}, ${2:value})``
    (``name()`` for a function without arguments)."""
    def esc(text: str) -> str:
        return text.replace("\\", "\\\\").replace("$", "\\$").replace("}", "\\}")
    args = ", ".join(f"${{{i}:{esc(p)}}}" for i, p in enumerate(params, 1))
    return f"{name}({args})"


@_answer(lambda: None)
def signature_help(an: Analysis, uri: str, pos: T.Position) -> Optional[T.SignatureHelp]:
    """The built-in function whose call the caret is in, and which argument."""
    snap = Snapshot(an, uri)
    toks = S.tokens_of(snap.text[:snap.offset(pos)])
    depth, commas = 0, 0
    for i in range(len(toks) - 1, -1, -1):
        k = toks[i].kind
        if k == "RPAR":
            depth += 1
        elif k == "LPAR":
            if depth == 0:
                name = toks[i - 1].value if i > 0 and toks[i - 1].kind == "NAME" else ""
                b = S.FUNCTIONS.get(name)
                if b is None:
                    return None
                params = [T.ParameterInformation(label=p) for p in b.params]
                sig = T.SignatureInformation(
                    label=b.call_text, documentation=lang_hover.signature_text(name),
                    parameters=params)
                return T.SignatureHelp(signatures=[sig], active_signature=0,
                                       active_parameter=min(commas, max(len(params) - 1, 0)))
            depth -= 1
        elif k == "COMMA" and depth == 0:
            commas += 1
        elif k in ("SEMI", "LBRACE", "RBRACE"):
            return None
    return None


# ---------------------------------------------------------------- navigation
@_answer(lambda: None)
def definition(an: Analysis, uri: str, pos: T.Position) -> Optional[T.Location]:
    snap = Snapshot(an, uri)
    w = snap.word(pos)
    if w is None:
        return None
    span = snap.index.definition(w[2])
    if span is None and w[2] in snap.index.variables:
        span = snap.index.variables[w[2]].span
    if span is None:
        hd = _header_defines(an, snap).get(w[2])
        if hd is not None:
            span = Span.point(hd[1], hd[2], 1, len(w[2]))
    return snap.location(span) if span is not None else None


@_answer(list)
def references(an: Analysis, uri: str, pos: T.Position,
               include_declaration: bool = True) -> list[T.Location]:
    snap = Snapshot(an, uri)
    w = snap.word(pos)
    if w is None:
        return []
    return _occurrences(an, snap, w[2])


def _occurrences(an: Analysis, snap: Snapshot, name: str) -> list[T.Location]:
    """Every place ``name`` is used: in this document and, for a define that a
    header makes (or any name in a header), in every file of the project."""
    out = []
    for span in snap.index.occurrences(name):
        out.append(T.Location(snap.uri, snap.lines.span_range(span)))
    d = snap.index.defines.get(name)
    shared = snap.ctx.header or (d is not None and d.span is not None and d.span.file != snap.name)
    if not shared or snap.ctx.project is None:
        return out
    for path in _project_files(snap.ctx):
        uri = from_fs_path(str(path))
        if uri == snap.uri:
            continue
        text = an.read(path)
        if text is None or name not in text:
            continue
        lines = Lines(text, an.encoding)
        for t in S.tokens_of(text, str(path)):
            if t.kind == "NAME" and t.value == name:
                out.append(T.Location(uri, lines.span_range(t.span)))
    return out


def _project_files(ctx) -> list[Path]:
    p = ctx.project
    files = [proc.path for proc in p.procedures()]
    for d in ctx.include_dirs:
        try:
            files += sorted(h for h in Path(d).glob("*.h") if h.is_file())
        except OSError:
            continue
    return files


@_answer(lambda: None)
def prepare_rename(an: Analysis, uri: str, pos: T.Position):
    snap = Snapshot(an, uri)
    w = snap.word(pos)
    if w is None or not _renamable(snap, w[2]):
        return None
    return snap.range_of(w[0], w[1])


@_answer(lambda: None)
def rename(an: Analysis, uri: str, pos: T.Position, new_name: str) -> Optional[T.WorkspaceEdit]:
    snap = Snapshot(an, uri)
    w = snap.word(pos)
    if w is None:
        return None
    old = w[2]
    if not _renamable(snap, old):
        raise RequestFailed(f"{old} is built in (a keyword, function, predefined variable or "
                            "table name) and cannot be renamed")
    if not new_name or new_name[0] not in _IDENT_FIRST or any(c not in _IDENT for c in new_name):
        raise RequestFailed(f"{new_name!r} is not a name (letters, digits and _, not starting "
                            "with a digit)")
    if is_reserved(new_name):
        raise RequestFailed(f"{new_name} is a built-in name")
    changes: dict[str, list[T.TextEdit]] = {}
    for loc in _occurrences(an, snap, old):
        changes.setdefault(loc.uri, []).append(T.TextEdit(loc.range, new_name))
    return T.WorkspaceEdit(changes=changes)


def _renamable(snap: Snapshot, name: str) -> bool:
    if is_reserved(name) or name in S.CONSTANTS or not name[:1] in _IDENT_FIRST:
        return False
    return (name in snap.index.defines or name in snap.index.procedures
            or name in snap.index.variables)


# ---------------------------------------------------------------- symbols
@_answer(list)
def document_symbols(an: Analysis, uri: str) -> list[T.DocumentSymbol]:
    snap = Snapshot(an, uri)
    out = []
    groups = ((snap.index.procedures, T.SymbolKind.Function, "procedure"),
              (snap.index.defines, T.SymbolKind.Constant, "#define"),
              (snap.index.variables, T.SymbolKind.Variable, "variable"))
    for table, kind, detail in groups:
        for name, sym in table.items():
            if sym.span is None or sym.span.file != snap.name:
                continue
            rng = snap.lines.span_range(sym.span)
            out.append(T.DocumentSymbol(name=name, kind=kind, range=rng, selection_range=rng,
                                        detail=(f"{detail} {sym.value}".rstrip()
                                                if kind == T.SymbolKind.Constant else detail)))
    out.sort(key=lambda s: (s.range.start.line, s.range.start.character))
    return out


# ---------------------------------------------------------------- colours
@_answer(lambda: T.SemanticTokens(data=[]))
def semantic_tokens(an: Analysis, uri: str) -> T.SemanticTokens:
    """The highlighter's tokens (:class:`~plcbuilder.lang.highlight.PlcLexer`,
    the IDE's colours) with what the index knows of each name, encoded as LSP
    wants (relative positions, one line a token)."""
    snap = Snapshot(an, uri)
    data: list[int] = []
    prev_line = prev_col = 0
    idx = snap.index
    for offset, tok, value in PlcLexer().get_tokens_unprocessed(snap.text):
        kind = _token_kind(tok, value, idx)
        if kind is None:
            continue
        ttype, mods = kind
        # a token may span lines (a block comment): one entry a line
        pos = offset
        for piece in value.split("\n"):
            if piece:
                start = snap.lines.at_offset(pos)
                length = snap.lines.at_offset(pos + len(piece)).character - start.character
                dl = start.line - prev_line
                dc = start.character - prev_col if dl == 0 else start.character
                data += [dl, dc, length, ttype, mods]
                prev_line, prev_col = start.line, start.character
            pos += len(piece) + 1
    return T.SemanticTokens(data=data)


def _token_kind(tok, value: str, idx) -> Optional[tuple[int, int]]:
    if tok in Comment.PreprocFile:
        return _T["string"], 0
    if tok in Comment.Preproc:
        return _T["macro"], 0
    if tok in Comment:
        return _T["comment"], 0
    if tok in Keyword:
        return _T["keyword"], 0
    if tok in Name.Builtin:
        return _T["function"], _LIB
    if tok in Name.Variable.Magic:
        return _T["variable"], _LIB
    if tok in Name.Function:
        return _T["function"], _DECL
    if tok in Name.Constant:
        if value in S.CONSTANTS:
            return _T["enumMember"], _LIB | _RO
        return _T["macro"], _DECL
    if tok in Name:
        if value in idx.defines:
            return _T["macro"], 0
        if value in idx.procedures:
            return _T["function"], 0
        return _T["variable"], 0
    if tok in Number:
        return _T["number"], 0
    if tok in Operator:
        return _T["operator"], 0
    return None


@_answer(list)
def inlay_hints(an: Analysis, uri: str, rng: T.Range) -> list[T.InlayHint]:
    """The name of every register given by number: ``gvarget(6060)`` shows
    ``GVAR_CURRENT_MOTION_CODE`` after the number."""
    snap = Snapshot(an, uri)
    toks = [t for t in snap.index.tokens]
    out = []
    first, last = rng.start.line + 1, rng.end.line + 1
    for i in range(len(toks) - 2):
        f, par, num = toks[i], toks[i + 1], toks[i + 2]
        if f.kind != "NAME" or f.value not in S.REGISTER_FUNCTIONS or par.kind != "LPAR" \
                or num.kind != "NUMBER" or not first <= num.span.line <= last:
            continue
        value = S.parse_number(num.value)
        name = lang_hover.register_name(value) if value is not None else None
        if name is None:
            continue
        end = snap.lines.position(num.span.end_line, num.span.end_col)
        out.append(T.InlayHint(position=end, label=name, kind=T.InlayHintKind.Type,
                               padding_left=True,
                               tooltip=lang_hover.register_text(value)))
    return out
