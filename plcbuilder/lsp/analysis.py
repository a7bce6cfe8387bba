"""Checking open documents: the same compile as ``plcbuilder check`` and
Build All (the same checker, messages and codes), with the unsaved text of
every open document (a header being edited is read from the editor, not the
disk), and diagnostics sent to the file they are in.

A procedure's diagnostics may point into a header it includes: they are
published on the header too. A header is checked through the procedures
that include it (the open ones and those of its project); its diagnostics are
the union of theirs, each once. A project's unreadable ``plcbuilder.toml``
is a diagnostic on that file.
"""

from __future__ import annotations

from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Optional

from lsprotocol import types as T
from pygls.uris import from_fs_path, to_fs_path

from plcbuilder.lang import Diagnostic, Severity
from plcbuilder.lang.pipeline import CompileResult, compile_source
from plcbuilder.lang.preprocess import BUILTIN_PREFIX
from plcbuilder.lang.source import MAX_SOURCE_BYTES, normalise, read_source
from plcbuilder.lang import symbols as lang_symbols
from plcbuilder.lsp.positions import UTF16, Lines, span_range
from plcbuilder.lsp.projects import Context, Projects

SOURCE = "plcbuilder"
_SEVERITY = {Severity.ERROR: T.DiagnosticSeverity.Error,
             Severity.WARNING: T.DiagnosticSeverity.Warning,
             Severity.NOTE: T.DiagnosticSeverity.Information}


def uri_path(uri: str) -> Optional[Path]:
    """The file of a ``file:`` URI (None for another scheme)."""
    if not uri.startswith("file:"):
        return None
    p = to_fs_path(uri)
    return Path(p) if p else None


def builtin_path(name: str) -> Optional[Path]:
    """The file of a built-in header (``<builtin>/pins.h``), where there is one."""
    try:
        ref = resources.files("plcbuilder") / "resources" / "include" / name[len(BUILTIN_PREFIX):]
        return Path(str(ref)) if ref.is_file() else None
    except (OSError, TypeError, ValueError):
        return None


@dataclass
class Open:
    """An open document: its text as the editor has it."""
    uri: str
    path: Optional[Path]
    text: str
    version: int = 0


class Analysis:
    """Open documents, their compiles and the diagnostics published."""

    def __init__(self, encoding: str = UTF16):
        self.encoding = encoding
        self.projects = Projects()
        self.docs: dict[str, Open] = {}
        self._by_path: dict[Path, Open] = {}
        self.results: dict[str, CompileResult] = {}
        #: source uri (or "project:ROOT") -> {target uri: diagnostics}
        self._contrib: dict[str, dict[str, list[T.Diagnostic]]] = {}
        self._headers = lang_symbols.HeaderCache()
        self._indexes: dict[str, tuple] = {}        # uri -> (text, include dirs, index)
        self._header_defs: dict[tuple, tuple] = {}   # include dirs -> (stamp, defines)

    # ------------------------------------------------------------ documents
    def open(self, uri: str, text: str, version: int = 0) -> None:
        doc = Open(uri, uri_path(uri), normalise(text), version)
        self.docs[uri] = doc
        if doc.path is not None:
            self._by_path[_key(doc.path)] = doc

    def close(self, uri: str) -> dict[str, list[T.Diagnostic]]:
        """Forget a document; the diagnostics to publish again (its own: none)."""
        doc = self.docs.pop(uri, None)
        if doc is not None and doc.path is not None:
            self._by_path.pop(_key(doc.path), None)
        self.results.pop(uri, None)
        self._indexes.pop(uri, None)
        old = self._contrib.pop(uri, {})
        out = {t: self.merged(t) for t in old}
        out[uri] = [] if not self._owned_elsewhere(uri) else self.merged(uri)
        return out

    def text(self, uri: str) -> Optional[str]:
        doc = self.docs.get(uri)
        if doc is not None:
            return doc.text
        path = uri_path(uri)
        return self.read(path) if path is not None else None

    def read(self, path: Path) -> Optional[str]:
        """A file's text: the editor's when it is open, else the disk's."""
        doc = self._by_path.get(_key(path))
        if doc is not None:
            return doc.text
        text, _d = read_source(path, str(path))
        return text

    def context(self, uri: str) -> Context:
        return self.projects.context(uri_path(uri))

    # ------------------------------------------------------------ checking
    def check(self, uri: str) -> dict[str, list[T.Diagnostic]]:
        """Check a document (a header: through the procedures that include it);
        {uri: every diagnostic it has now} for every uri whose diagnostics changed."""
        ctx = self.context(uri)
        touched: set[str] = {uri}
        if ctx.header:
            sources = self._includers(uri, ctx)
        else:
            sources = [uri]
        for src in sources:
            touched |= self._compile_source(src)
        touched |= self._project_problem(ctx, uri)
        return {t: self.merged(t) for t in touched}

    def compile(self, uri: str, ctx: Optional[Context] = None) -> Optional[CompileResult]:
        text = self.text(uri)
        if text is None:
            return None
        ctx = ctx or self.context(uri)
        path = uri_path(uri)
        name = str(path) if path is not None else "<" + uri.rsplit("/", 1)[-1] + ">"
        result = compile_source(text, name, ctx.options, file_path=path, read_file=self._read_file)
        if uri in self.docs:
            self.results[uri] = result
        return result

    def merged(self, target: str) -> list[T.Diagnostic]:
        seen = set()
        out = []
        for contrib in self._contrib.values():
            for d in contrib.get(target, ()):
                key = (d.range.start.line, d.range.start.character, d.range.end.line,
                       d.range.end.character, d.code, d.message)
                if key not in seen:
                    seen.add(key)
                    out.append(d)
        return out

    # ------------------------------------------------------------ private
    def _owned_elsewhere(self, uri: str) -> bool:
        return any(uri in c for c in self._contrib.values())

    def _read_file(self, path: Path, name: str):
        doc = self._by_path.get(_key(path))
        if doc is not None:
            if len(doc.text) > MAX_SOURCE_BYTES:
                return read_source(path, name)
            return doc.text, []
        return read_source(path, name)

    def _compile_source(self, uri: str) -> set[str]:
        result = self.compile(uri)
        old = self._contrib.get(uri, {})
        new: dict[str, list[T.Diagnostic]] = {uri: []}
        if result is not None:
            for d in result.diagnostics:
                target = self._uri_of(d.span.file if d.span else None, result, uri)
                if target is None:
                    continue
                new.setdefault(target, []).append(self.to_lsp(d, result, target))
        self._contrib[uri] = new
        return set(old) | set(new)

    def _includers(self, uri: str, ctx: Context) -> list[str]:
        """The procedures that include the header ``uri``: open ones, then the
        project's."""
        header = uri_path(uri)
        if header is None:
            return []
        want = _key(header)
        candidates = [u for u, d in self.docs.items()
                      if d.path is not None and d.path.suffix.lower() == ".plc"]
        if ctx.project is not None:
            try:
                procs = ctx.project.procedures()
            except Exception:  # noqa: BLE001 - a folder that cannot be listed: the open ones
                procs = []
            for p in procs:
                u = from_fs_path(str(p.path))
                if u not in candidates:
                    candidates.append(u)
        out = []
        for u in candidates:
            result = self.compile(u)
            if result is None:
                continue
            if any(_key(Path(inc)) == want for inc in result.includes
                   if not inc.startswith(BUILTIN_PREFIX)):
                out.append(u)
        # a procedure that no longer includes it keeps no diagnostics on it
        for src, contrib in self._contrib.items():
            if src not in out and uri in contrib and not src.startswith("project:"):
                contrib.pop(uri, None)
        return out

    def _project_problem(self, ctx: Context, uri: str) -> set[str]:
        path = uri_path(uri)
        settings = self.projects.settings_file(path) if path is not None else None
        if settings is None:
            return set()
        key = "project:" + str(settings)
        old = self._contrib.get(key, {})
        new: dict[str, list[T.Diagnostic]] = {}
        problem = ctx.problem
        if problem is not None:
            target = from_fs_path(problem.file) if problem.file else from_fs_path(str(settings))
            line = max((problem.line or 1) - 1, 0)
            new[target] = [T.Diagnostic(
                range=T.Range(T.Position(line, 0), T.Position(line, 0)),
                message=f"{problem} (the defaults are used until it is fixed)",
                severity=T.DiagnosticSeverity.Error, code="project-settings", source=SOURCE)]
            new[uri] = [T.Diagnostic(
                range=T.Range(T.Position(0, 0), T.Position(0, 0)),
                message=f"the project's settings cannot be read: {problem}",
                severity=T.DiagnosticSeverity.Warning, code="project-settings", source=SOURCE)]
        self._contrib[key] = new
        return set(old) | set(new)

    def _uri_of(self, file: Optional[str], result: CompileResult, uri: str) -> Optional[str]:
        if file is None or file == result.path:
            return uri
        if file.startswith(BUILTIN_PREFIX):
            return None           # the built-in headers are not the user's to fix
        if file.startswith("<"):
            return uri
        return from_fs_path(str(Path(file).resolve()))

    def to_lsp(self, d: Diagnostic, result: CompileResult, target: str) -> T.Diagnostic:
        lines = self._line_source(result, target)
        message = d.message + "".join(f"\nhint: {h}" for h in d.hints)
        rng = (span_range(d.span, lines, self.encoding) if d.span is not None
               else T.Range(T.Position(0, 0), T.Position(0, 0)))
        related = []
        for r in d.related:
            t = self._uri_of(r.span.file, result, target)
            if t is not None:
                related.append(T.DiagnosticRelatedInformation(
                    T.Location(t, span_range(r.span, self._line_source(result, t), self.encoding)),
                    r.message))
        return T.Diagnostic(range=rng, message=message, severity=_SEVERITY.get(d.severity),
                            code=d.code, source=SOURCE, related_information=related or None)

    def _line_source(self, result: CompileResult, target: str):
        doc = self.docs.get(target)
        if doc is not None:
            lines = Lines(doc.text, self.encoding)
            return lambda n1: lines.line(n1 - 1)
        path = uri_path(target)
        name = result.path if path is not None and _key(path) == _key(Path(result.path)) else None

        def line(n1: int) -> Optional[str]:
            for f in ([name] if name else []) + list(result.sources.files):
                sf = result.sources.files.get(f)
                if sf is not None and sf.path is not None and path is not None \
                        and _key(sf.path) == _key(path):
                    return result.sources.line(f, n1)
            return None
        return line

    # ------------------------------------------------------------ symbols
    def index(self, uri: str, text: str, name: str, path: Optional[Path], ctx: Context):
        """The symbol index of a document's text (kept while the text is the same:
        hover, completion and the rest ask again and again between edits)."""
        hit = self._indexes.get(uri)
        if hit is not None and hit[0] is text and hit[1] == ctx.include_dirs:
            return hit[2]
        idx = lang_symbols.index(text, name, path, ctx.include_dirs, software=ctx.software)
        if uri in self.docs:
            self._indexes[uri] = (text, ctx.include_dirs, idx)
        return idx

    # ------------------------------------------------------------ header defines
    def header_defines(self, ctx: Context) -> dict[str, tuple[str, str, int]]:
        """{name: (value, file, line)} of the project's headers and the built-in
        pins.h (made again only when a header changed, on disk or in the editor)."""
        stamp = []
        for d in ctx.include_dirs:
            try:
                for h in sorted(Path(d).glob("*.h")):
                    doc = self._by_path.get(_key(h))
                    stamp.append((str(h), id(doc.text) if doc else h.stat().st_mtime_ns))
            except OSError:
                continue
        key = (ctx.include_dirs, tuple(stamp))
        hit = self._header_defs.get(ctx.include_dirs)
        if hit is not None and hit[0] == key:
            return hit[1]
        found = {n: (s.value, s.span.file, s.span.line)
                 for n, s in lang_symbols.header_defines(ctx.include_dirs, read=self._header).items()}
        self._header_defs[ctx.include_dirs] = (key, found)
        return found

    def _header(self, path: Path) -> dict:
        doc = self._by_path.get(_key(path))
        if doc is not None:
            return lang_symbols.file_defines(doc.text, str(path))
        return self._headers.read(path)


def _key(p: Path) -> Path:
    try:
        return p.resolve()
    except (OSError, RuntimeError):
        return p.absolute()
