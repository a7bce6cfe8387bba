"""Checking open documents: the same compile as ``plcbuilder check`` and
Build All (the same checker, messages and codes), with the unsaved text of
every open document (a header being edited is read from the editor, not the
disk), and diagnostics sent to the file they are in.

A procedure's diagnostics may point into a header it includes: they are
published on the header too. A header is checked through the procedures
that include it (the open ones and those of its project); its diagnostics are
the union of theirs, each once. A project's unreadable ``plcbuilder.toml``
is a diagnostic on that file.

Only PLC documents are checked and answered about: a document opened with the
language id ``plc``, a ``.plc`` file, or a ``.h`` file of a project (in a
project's folder or one of its include folders; a ``.h`` elsewhere is a C
header). A document over the source size limit (1 MiB, as ``plcbuilder
check``) is not compiled: one diagnostic says so.

A check has three steps so that the compile runs off the message loop
(:mod:`plcbuilder.lsp.checks`): :meth:`Analysis.plan` takes a snapshot of the
open documents (on the loop), :meth:`Analysis.compute` compiles it (on the
worker thread: it reads only the snapshot, the disk and its own caches), and
:meth:`Analysis.apply` keeps the outcome and says what to publish (on the
loop). Each open procedure keeps a :class:`~plcbuilder.lang.incremental.Incremental`
on the worker, so a keystroke recompiles only what it changed.

Files are read from disk only where :class:`~plcbuilder.lsp.access.Access`
allows.
"""

from __future__ import annotations

import logging
import traceback
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Optional

from lsprotocol import types as T
from pygls.uris import from_fs_path, to_fs_path

from plcbuilder.lang import Diagnostic, Severity, Span, error
from plcbuilder.lang import symbols as lang_symbols
from plcbuilder.lang.incremental import Incremental
from plcbuilder.lang.pipeline import CompileResult, compile_source, procedure_name
from plcbuilder.lang.preprocess import BUILTIN_PREFIX
from plcbuilder.lang.source import MAX_SOURCE_BYTES, SourceSet, normalise, read_source
from plcbuilder.lsp.access import Access
from plcbuilder.lsp.positions import UTF16, Lines, span_range
from plcbuilder.lsp.projects import HEADER_SUFFIXES, Context, Projects

log = logging.getLogger(__name__)

SOURCE = "plcbuilder"
PLC_LANGUAGE = "plc"
PLC_SUFFIX = ".plc"
_SEVERITY = {Severity.ERROR: T.DiagnosticSeverity.Error,
             Severity.WARNING: T.DiagnosticSeverity.Warning,
             Severity.NOTE: T.DiagnosticSeverity.Information}


def uri_path(uri: str) -> Optional[Path]:
    """The file of a ``file:`` URI (None for another scheme)."""
    if not uri.startswith("file:"):
        return None
    try:
        p = to_fs_path(uri)
    except (ValueError, TypeError):
        return None
    if not p or "\x00" in p:
        return None                    # no file has such a name
    return Path(p)


def builtin_path(name: str) -> Optional[Path]:
    """The file of a built-in header (``<builtin>/pins.h``), where there is one."""
    try:
        ref = resources.files("plcbuilder") / "resources" / "include" / name[len(BUILTIN_PREFIX):]
        return Path(str(ref)) if ref.is_file() else None
    except (OSError, TypeError, ValueError):
        return None


def oversize(text: str, name: str) -> Optional[list[Diagnostic]]:
    """The diagnostic of ``plcbuilder check`` for a text over the source size
    limit (None when it is within it)."""
    if len(text) * 4 <= MAX_SOURCE_BYTES:
        return None                              # within the limit, whatever its characters
    if len(text) <= MAX_SOURCE_BYTES and len(text.encode("utf-8")) <= MAX_SOURCE_BYTES:
        return None
    size = len(text.encode("utf-8"))
    return [error("file-too-large", f"{name} is {size} bytes; a PLC source file is at most "
                                    f"{MAX_SOURCE_BYTES} bytes", Span.point(name, 1, 1),
                  "the language server, like plcbuilder check, does not compile it")]


class Open:
    """An open document: its text as the editor has it (replaced, never changed,
    at each edit: a check's snapshot keeps the text it was given)."""

    __slots__ = ("uri", "path", "text", "version", "language_id", "_lines")

    def __init__(self, uri: str, path: Optional[Path], text: str, version: int = 0,
                 language_id: str = PLC_LANGUAGE):
        self.uri = uri
        self.path = path
        self.text = text
        self.version = version
        self.language_id = language_id
        self._lines: Optional[Lines] = None

    def lines(self, encoding: str) -> Lines:
        if self._lines is None or self._lines.encoding != encoding:
            self._lines = Lines(self.text, encoding)
        return self._lines


@dataclass
class Job:
    """What one check compiles: the documents as they were when it was asked for."""
    uri: str
    generation: int
    docs: dict                        # uri -> Open
    by_path: dict                     # resolved path -> Open


@dataclass
class Outcome:
    """What a check found, for :meth:`Analysis.apply`."""
    uri: str
    checked: bool = False             # False: not a PLC document, nothing to publish
    header: bool = False
    #: source uri -> (its CompileResult or None, {target uri: diagnostics})
    sources: dict = field(default_factory=dict)
    #: the project's settings problem: (key, {target: diagnostics}) or None
    project: Optional[tuple] = None
    versions: dict = field(default_factory=dict)


class Analysis:
    """Open documents, their compiles and the diagnostics published."""

    def __init__(self, encoding: str = UTF16, access: Optional[Access] = None):
        self.encoding = encoding
        self.access = access or Access()
        self.projects = Projects()
        self.docs: dict[str, Open] = {}
        self._by_path: dict[Path, Open] = {}
        self.results: dict[str, CompileResult] = {}
        #: source uri (or "project:ROOT") -> {target uri: diagnostics}
        self._contrib: dict[str, dict[str, list[T.Diagnostic]]] = {}
        self._headers = lang_symbols.HeaderCache()
        self._indexes: dict[str, tuple] = {}        # uri -> (text, include dirs, index)
        self._header_defs: dict[tuple, tuple] = {}   # include dirs -> (stamp, defines)
        self._incremental: dict[str, Incremental] = {}   # uri -> Incremental (used by the worker)

    # ------------------------------------------------------------ documents
    def open(self, uri: str, text: str, version: int = 0,
             language_id: Optional[str] = None) -> None:
        """A document's text (its language id: kept from before when None)."""
        old = self.docs.get(uri)
        if language_id is None:
            language_id = old.language_id if old is not None else PLC_LANGUAGE
        doc = Open(uri, uri_path(uri), normalise(text), version, language_id or PLC_LANGUAGE)
        self.docs[uri] = doc
        if doc.path is not None:
            self._by_path[_key(doc.path)] = doc
            self.access.open(doc.path)

    def change(self, uri: str, version: Optional[int], changes) -> bool:
        """Apply a didChange's edits (ranges in the client's position encoding;
        a change without a range replaces the whole text). False when the
        document is not open."""
        doc = self.docs.get(uri)
        if doc is None:
            return False
        text = doc.text
        lines: Optional[Lines] = doc.lines(self.encoding)
        for ch in changes:
            rng = getattr(ch, "range", None)
            new = normalise(ch.text) if "\r" in ch.text else ch.text
            if rng is None:
                text = new
            else:
                if lines is None:
                    lines = Lines(text, self.encoding)
                a, b = lines.offset(rng.start), lines.offset(rng.end)
                if b < a:
                    a, b = b, a
                text = text[:a] + new + text[b:]
            lines = None
        self.open(uri, text, doc.version if version is None else version, doc.language_id)
        return True

    def close(self, uri: str) -> dict[str, list[T.Diagnostic]]:
        """Forget a document; the diagnostics to publish again (its own: none)."""
        doc = self.docs.pop(uri, None)
        if doc is not None and doc.path is not None:
            self._by_path.pop(_key(doc.path), None)
            self.access.close(doc.path)
        self.results.pop(uri, None)
        self._indexes.pop(uri, None)
        self._incremental.pop(uri, None)     # (a compile using it keeps its own reference)
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
        """A file's text: the editor's when it is open, else the disk's (where
        the server may read)."""
        doc = self._by_path.get(_key(path))
        if doc is not None:
            return doc.text
        if not self.access.may_read(path):
            return None
        text, _d = read_source(path, str(path))
        return text

    def lines(self, uri: str, text: str) -> Lines:
        """The lines of ``text`` (an open document's, kept while it is the same)."""
        doc = self.docs.get(uri)
        if doc is not None and doc.text is text:
            return doc.lines(self.encoding)
        return Lines(text, self.encoding)

    def context(self, uri: str) -> Context:
        """How the file is compiled. Its project is looked for only when the file
        is inside the workspace: a file elsewhere compiles with the defaults."""
        path = uri_path(uri)
        if path is None or not self.access.in_workspace(path):
            return self.projects.context(path, find_project=False)
        ctx = self.projects.context(path)
        if ctx.project is not None:
            self.access.add_project(ctx.project.root, ctx.include_dirs)
        return ctx

    def is_plc(self, uri: str) -> bool:
        """A PLC document: opened as ``plc``, a ``.plc`` file, or a ``.h`` file of
        a project (in its folder or one of its include folders)."""
        doc = self.docs.get(uri)
        if doc is not None and (doc.language_id or "").lower() == PLC_LANGUAGE:
            return True
        path = uri_path(uri)
        if path is None:
            return False
        suffix = path.suffix.lower()
        if suffix == PLC_SUFFIX:
            return True
        if suffix in HEADER_SUFFIXES:
            if self.context(uri).project is not None:
                return True
            real = _key(path)
            return any(real.is_relative_to(d) for dirs in list(self.access.includes.values())
                       for d in dirs)
        return False

    def usable(self, uri: str) -> Optional[str]:
        """The text features answer about: a PLC document within the size limit
        (None otherwise)."""
        if not self.is_plc(uri):
            return None
        text = self.text(uri)
        if text is None or oversize(text, uri) is not None:
            return None
        return text

    # ------------------------------------------------------------ checking
    def check(self, uri: str) -> dict[str, list[T.Diagnostic]]:
        """Check a document at once (plan, compute and apply in this thread);
        {uri: every diagnostic it has now} for every uri whose diagnostics changed."""
        return self.apply(self.compute(self.plan(uri)))

    def plan(self, uri: str, generation: int = 0) -> Job:
        """(On the loop) a check of ``uri`` with the documents as they are now."""
        return Job(uri, generation, dict(self.docs), dict(self._by_path))

    def compute(self, job: Job) -> Outcome:
        """(On the worker) compile what the check needs. The open documents, the
        results and the diagnostics kept are the loop's: only apply changes them."""
        uri = job.uri
        out = Outcome(uri, versions={u: d.version for u, d in job.docs.items()})
        if not self._is_plc_in(job, uri):
            return out
        out.checked = True
        ctx = self.context(uri)
        out.header = ctx.header
        if ctx.header:
            out.sources = self._includers(job, uri, ctx)
        else:
            result = self._compile(job, uri, ctx)
            out.sources[uri] = (result, self._diagnostics(job, uri, result))
        out.project = self._project_problem(ctx, uri)
        return out

    def apply(self, outcome: Outcome) -> dict[str, list[T.Diagnostic]]:
        """(On the loop) keep a check's outcome; {uri: diagnostics} to publish."""
        uri = outcome.uri
        if not outcome.checked:
            return {}
        touched: set[str] = {uri}
        for src, (result, contrib) in outcome.sources.items():
            old = self._contrib.get(src, {})
            self._contrib[src] = contrib
            touched |= set(old) | set(contrib)
            if result is not None and src in self.docs:
                self.results[src] = result
        if outcome.header:
            # a procedure that no longer includes it keeps no diagnostics on it
            for src, contrib in self._contrib.items():
                if src not in outcome.sources and uri in contrib and not src.startswith("project:"):
                    contrib.pop(uri, None)
        if outcome.project is not None:
            key, new = outcome.project
            old = self._contrib.get(key, {})
            self._contrib[key] = new
            touched |= set(old) | set(new)
        return {t: self.merged(t) for t in touched}

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

    def _is_plc_in(self, job: Job, uri: str) -> bool:
        doc = job.docs.get(uri)
        if doc is not None and (doc.language_id or "").lower() == PLC_LANGUAGE:
            return True
        return self.is_plc(uri)

    def _compile(self, job: Job, uri: str, ctx: Context) -> Optional[CompileResult]:
        doc = job.docs.get(uri)
        path = uri_path(uri)
        name = str(path) if path is not None else "<" + uri.rsplit("/", 1)[-1] + ">"
        if doc is not None:
            text = doc.text
        elif path is not None and self.access.may_read(path):
            text, _d = read_source(path, name)
        else:
            text = None
        if text is None:
            return None
        too_big = oversize(text, name)
        if too_big is not None:
            return CompileResult(procedure_name(name), name, ctx.options.kind, None, too_big,
                                 SourceSet(), None, ctx.options.limit)
        incremental = None
        if doc is not None:
            incremental = self._incremental.get(uri)
            if incremental is None:
                incremental = self._incremental[uri] = Incremental()
        reader = self._reader(job, incremental)
        try:
            return compile_source(text, name, ctx.options, file_path=path,
                                  read_file=reader, incremental=incremental)
        except Exception as exc:  # noqa: BLE001 - a compiler bug: one diagnostic, and the log
            log.exception("compiling %s failed", name)
            detail = "".join(traceback.format_exception_only(type(exc), exc)).strip()
            return CompileResult(procedure_name(name), name, ctx.options.kind, None,
                                 [error("internal", f"internal compiler error: {detail}",
                                        Span.point(name, 1, 1))],
                                 SourceSet(), None, ctx.options.limit)

    def _reader(self, job: Job, incremental: Optional[Incremental]):
        """How a compile of ``job`` reads a header: the editor's text when it is
        open, else the disk where the server may read."""
        def read(path: Path, name: str):
            doc = job.by_path.get(_key(path))
            if doc is not None:
                return (None, too_big) if (too_big := oversize(doc.text, name)) else (doc.text, [])
            if not self.access.may_read(path):
                return None, [error("file-outside-workspace", self.access.refusal(path),
                                    Span.point(name, 1, 1))]
            if incremental is not None:
                return incremental.tokens.read(path, name)
            return read_source(path, name)
        return read

    def _diagnostics(self, job: Job, uri: str,
                     result: Optional[CompileResult]) -> dict[str, list[T.Diagnostic]]:
        new: dict[str, list[T.Diagnostic]] = {uri: []}
        if result is None:
            return new
        for d in result.diagnostics:
            target = self._uri_of(d.span.file if d.span else None, result, uri)
            if target is None:
                continue
            new.setdefault(target, []).append(self.to_lsp(d, result, target, job))
        return new

    def _includers(self, job: Job, uri: str, ctx: Context) -> dict:
        """The procedures that include the header ``uri`` (open ones, then the
        project's), each with its compile and diagnostics."""
        header = uri_path(uri)
        if header is None:
            return {}
        want = _key(header)
        candidates = [u for u, d in job.docs.items()
                      if d.path is not None and d.path.suffix.lower() == PLC_SUFFIX]
        if ctx.project is not None:
            try:
                procs = ctx.project.procedures()
            except Exception:  # noqa: BLE001 - a folder that cannot be listed: the open ones
                procs = []
            for p in procs:
                u = from_fs_path(str(p.path))
                if u not in candidates:
                    candidates.append(u)
        out = {}
        for u in candidates:
            result = self._compile(job, u, self.context(u))
            if result is None:
                continue
            if any(_key(Path(inc)) == want for inc in result.includes
                   if not inc.startswith(BUILTIN_PREFIX)):
                out[u] = (result, self._diagnostics(job, u, result))
        return out

    def _project_problem(self, ctx: Context, uri: str) -> Optional[tuple]:
        path = uri_path(uri)
        if path is None or ctx.project is None and ctx.problem is None:
            return None
        settings = self.projects.settings_file(path)
        if settings is None:
            return None
        key = "project:" + str(settings)
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
        return key, new

    def _uri_of(self, file: Optional[str], result: CompileResult, uri: str) -> Optional[str]:
        if file is None or file == result.path:
            return uri
        if file.startswith(BUILTIN_PREFIX):
            return None           # the built-in headers are not the user's to fix
        if file.startswith("<"):
            return uri
        return from_fs_path(str(Path(file).resolve()))

    def to_lsp(self, d: Diagnostic, result: CompileResult, target: str,
               job: Optional[Job] = None) -> T.Diagnostic:
        lines = self._line_source(result, target, job)
        message = d.message + "".join(f"\nhint: {h}" for h in d.hints)
        rng = (span_range(d.span, lines, self.encoding) if d.span is not None
               else T.Range(T.Position(0, 0), T.Position(0, 0)))
        related = []
        for r in d.related:
            t = self._uri_of(r.span.file, result, target)
            if t is not None:
                related.append(T.DiagnosticRelatedInformation(
                    T.Location(t, span_range(r.span, self._line_source(result, t, job),
                                             self.encoding)),
                    r.message))
        return T.Diagnostic(range=rng, message=message, severity=_SEVERITY.get(d.severity),
                            code=d.code, source=SOURCE, related_information=related or None)

    def _line_source(self, result: CompileResult, target: str, job: Optional[Job] = None):
        doc = (job.docs if job is not None else self.docs).get(target)
        if doc is not None:
            lines = doc.lines(self.encoding)
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
        hover, completion and the rest ask again and again between edits). A
        file outside the workspace is indexed without its folder (its headers
        there are not read)."""
        hit = self._indexes.get(uri)
        if hit is not None and hit[0] is text and hit[1] == ctx.include_dirs:
            return hit[2]
        if path is not None and not self.access.in_workspace(path):
            path = None
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
        if not self.access.may_read(path):
            return {}
        return self._headers.read(path)


def _key(p: Path) -> Path:
    try:
        return p.resolve()
    except (OSError, RuntimeError, ValueError):
        return p.absolute()

