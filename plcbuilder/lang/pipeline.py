"""The compile pipeline, one stage after another:

    compile_source / compile_bytes / compile_file:
        read -> preprocess -> parse -> check -> generate -> Program (+ diagnostics)

Everything a compile depends on is passed in (:class:`CompileOptions`); bad
input becomes diagnostics, never an exception.
"""

from __future__ import annotations

import os
import sys
from _thread import allocate_lock
from contextlib import contextmanager
from pathlib import Path

from plcbuilder._support import gcpause
from plcbuilder._support.records import dataclass, field
from plcbuilder.bytecode.program import Kind, Program
from plcbuilder.diagnostics import Diagnostic, Span, error
from plcbuilder.lang import ast as A
from plcbuilder.lang.checker import Checker, Symbols
from plcbuilder.lang.codegen import ADDRESS_LIMIT, JUMP_LIMIT, generate
from plcbuilder.lang.macro_notes import add_macro_notes
from plcbuilder.lang.options import COMPILER_VERSION, CompileOptions  # noqa: F401 - re-exported
from plcbuilder.lang.parser import parse_tokens
from plcbuilder.lang.preprocess import BUILTIN_PREFIX, Preprocessed, Preprocessor
from plcbuilder.lang.source import SourceSet, decode_source, read_source
from plcbuilder.lang.targets import lower as lower_target

TYPE_CHECKING = False               # (typing is not imported at run time: start-up)
if TYPE_CHECKING:
    from typing import Optional

    from plcbuilder.lang.incremental import Incremental   # (the language server's and the IDE's)

#: the most diagnostics of one code a compile reports (then one that says how many more)
MAX_SAME = 100

#: The recursion limit while compiling: the preprocessor expands a chain of
#: #defines (each naming the next) one Python frame a link, and a chain may be
#: longer than Python's default limit allows. (The checker and generator recurse
#: over the tree too, but the parser caps its depth at 256 levels.)
RECURSION_LIMIT = 4000
_limit_lock = allocate_lock()
_limit_users = 0                   # compiles running (in any thread)
_limit_saved: Optional[int] = None  # the limit to restore when the last one ends


@contextmanager
def _compiling():
    """While the block runs: the recursion limit at least RECURSION_LIMIT, and
    Python's cyclic garbage collector paused (:mod:`plcbuilder._support.gcpause`
    says why). The limit is global to the process: the first compile to start
    sets it and the last to end puts it back, so concurrent compiles do not
    undo each other."""
    global _limit_users, _limit_saved
    with _limit_lock:
        if _limit_users == 0:
            old = sys.getrecursionlimit()
            _limit_saved = old if old < RECURSION_LIMIT else None
            if _limit_saved is not None:
                sys.setrecursionlimit(RECURSION_LIMIT)
        _limit_users += 1
    gcpause.hold()
    try:
        yield
    finally:
        gcpause.release()
        with _limit_lock:
            _limit_users -= 1
            if _limit_users == 0:
                if _limit_saved is not None:
                    if sys.getrecursionlimit() == RECURSION_LIMIT:   # unless changed meanwhile
                        sys.setrecursionlimit(_limit_saved)
                    _limit_saved = None


# ====================================================================== options
# CompileOptions is in plcbuilder.lang.options (light: a project opens without
# loading the compiler) and imported above.


@dataclass
class CompileResult:
    name: str
    path: str
    kind: Kind
    program: Optional[Program]
    diagnostics: list[Diagnostic]
    sources: SourceSet
    size: Optional[int]
    limit: int
    symbols: Symbols = field(default_factory=Symbols)
    module: Optional[A.Module] = None
    includes: list[str] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        return not any(d.is_error for d in self.diagnostics)

    @property
    def errors(self) -> list[Diagnostic]:
        return [d for d in self.diagnostics if d.is_error]

    @property
    def warnings(self) -> list[Diagnostic]:
        return [d for d in self.diagnostics if not d.is_error]

    def source_line(self, file: str, line: int) -> Optional[str]:
        return self.sources.line(file, line)


# ====================================================================== pipeline
def procedure_name(path: str) -> str:
    stem = Path(path).stem
    return stem if stem and not stem.startswith("<") else "main"


def compile_source(text: str, path: str = "<input>", options: CompileOptions = CompileOptions(),
                   *, file_path: Optional[Path] = None,
                   incremental: Optional[Incremental] = None,
                   read_file=None) -> CompileResult:
    """Compile source text. ``path`` is the name diagnostics use; ``file_path``
    (when the text is a file's) locates the procedure's folder for #include.
    ``incremental``, kept by the caller for one file from compile to compile,
    makes the compile of an edited text redo only what the edit changed
    (:mod:`plcbuilder.lang.incremental`); the result is the same.
    ``read_file(path, name) -> (text or None, diagnostics)`` reads headers
    (default :func:`~plcbuilder.lang.source.read_source`; an editor passes one
    that gives the unsaved text of open headers)."""
    if file_path is None and not path.startswith("<"):
        p = Path(path)
        file_path = p if p.parent != Path("") or p.exists() else None
    if incremental is None:
        return _compile(Preprocessor(options.include_dirs, read_file or read_source,
                                     root=options.root), text, path, file_path, options)
    with incremental.lock:
        try:
            return _compile(Preprocessor(options.include_dirs, read_file or read_source,
                                         root=options.root, tokens=incremental.tokens),
                            text, path, file_path, options, incremental)
        except BaseException:
            incremental.reset()
            raise
        finally:
            incremental.done()


def compile_bytes(data: bytes, path: str, options: CompileOptions = CompileOptions(),
                  *, file_path: Optional[Path] = None) -> CompileResult:
    text, diags = decode_source(data, path)
    if text is None:
        return _failed(path, options, diags)
    r = compile_source(text, path, options, file_path=file_path)
    r.diagnostics = sorted(diags + r.diagnostics, key=lambda d: (d.sort_key(), d.severity))
    return r


def compile_file(path, options: CompileOptions = CompileOptions(), *,
                 data: Optional[bytes] = None) -> CompileResult:
    """Compile a .plc file. Never raises on bad input: it becomes diagnostics.
    ``data``: the file's bytes when the caller has read them already."""
    p = Path(path)
    name = str(path)
    text, diags = read_source(p, name) if data is None else decode_source(data, name)
    if text is None:
        return _failed(name, options, diags)
    pp = Preprocessor(options.include_dirs, root=options.root)
    pp.diags.extend(diags)
    return _compile(pp, text, name, p, options)


def _failed(path: str, options: CompileOptions, diags: list[Diagnostic]) -> CompileResult:
    return CompileResult(procedure_name(path), path, options.kind, None, diags, SourceSet(), None,
                         options.limit)


def _compile(pp: Preprocessor, text: str, path: str, file_path: Optional[Path],
             options: CompileOptions, incremental: Optional[Incremental] = None) -> CompileResult:
    with _compiling():
        return _compile_preprocessed(pp.run_text(text, path, file_path), path, file_path, options,
                                     incremental)


def _compile_preprocessed(pre: Preprocessed, path: str, file_path: Optional[Path],
                          options: CompileOptions,
                          incremental: Optional[Incremental] = None) -> CompileResult:
    name = procedure_name(path)
    diags = list(pre.diagnostics)
    if options.strict:
        for span in pre.block_comments:
            diags.append(error("strict", "/* */ comments are not accepted by the controller's "
                                         "compiler (--strict)", span, "use // comments"))
        for word, span in pre.directives:
            if word not in ("include", "define"):
                diags.append(error("strict", f"#{word} is not accepted by the controller's "
                                             "compiler (--strict)", span))
    if pre.too_large:
        # only the start of the text was read: parsing it would report its
        # cut-off end (an unclosed block, a missing main) as mistakes
        diags = add_macro_notes(diags, pre)
        diags.sort(key=lambda d: (d.sort_key(), d.severity))
        symbols = Symbols()
        symbols.defines = {n: (d.text, d.span) for n, d in pre.defines.items()}
        return CompileResult(name, path, options.kind, None, diags, pre.sources, None,
                             options.limit, symbols, A.Module([]), list(pre.includes))
    if incremental is None:
        module, parse_diags = parse_tokens(pre.tokens)
    else:
        module, parse_diags = incremental.parse(pre.tokens, path)
    diags += parse_diags
    checked, lowered = lower_target(module, options.target)    # the target's macros
    diags += lowered
    checker = Checker(checked, options.kind, options.strict, path, pre.sources.line,
                      syntax_errors=any(d.is_error for d in diags), target=options.target,
                      defines=pre.defines,
                      cache=incremental.checks if incremental is not None else None)
    check_diags, resolved, symbols = checker.run()
    diags += check_diags
    symbols.defines = {n: (d.text, d.span) for n, d in pre.defines.items()}
    program = None
    size = None
    if not any(d.is_error for d in diags):
        program, size = generate(resolved, name, options.kind, _file_namer(path, file_path),
                                 incremental.code if incremental is not None else None)
        main = resolved.procs.get("main") or next(iter(resolved.procs.values()), None)
        at = main.name_span if main else Span.point(path, 1, 1)
        if size > options.limit:
            diags.append(error(
                "size-limit",
                f"procedure {name} is {size} bytes of code; the limit for a "
                f"{options.kind.label} procedure is {options.limit} ({size}/{options.limit} bytes)",
                at, "move work into a software procedure, or split it into procedures started "
                    "one after another"))
            program = None
        elif program is None:      # within the limit, but beyond what 16-bit addresses reach
            why = (f"code is addressed with 16 bits: a procedure is at most {ADDRESS_LIMIT} bytes "
                   f"({size}/{ADDRESS_LIMIT} bytes)" if size > ADDRESS_LIMIT else
                   f"a jump in it spans more than {JUMP_LIMIT} bytes, the farthest a 16-bit "
                   "offset reaches")
            diags.append(error("size-limit", f"procedure {name} is {size} bytes of code; {why}", at,
                               "split it into procedures started one after another"))
    diags = add_macro_notes(diags, pre)
    diags.sort(key=lambda d: (d.sort_key(), d.severity))
    return CompileResult(name, path, options.kind, program, cap_repeated(diags), pre.sources, size,
                         options.limit, symbols, module, list(pre.includes))


def cap_repeated(diags: list[Diagnostic], limit: int = MAX_SAME) -> list[Diagnostic]:
    """At most ``limit`` diagnostics of one code (the first, in order), and
    then one saying how many more there are: thousands of one mistake (a
    character the language lacks, pasted all over) are not thousands of lines."""
    counts: dict[str, int] = {}
    for d in diags:
        counts[d.code] = counts.get(d.code, 0) + 1
    if all(n <= limit for n in counts.values()):
        return diags
    out, seen = [], {}
    for d in diags:
        k = seen[d.code] = seen.get(d.code, 0) + 1
        if k <= limit:
            out.append(d)
        elif k == limit + 1:
            more = counts[d.code] - limit
            out.append(Diagnostic(d.severity, "too-many-diagnostics",
                                  f"{more} more '{d.code}' {d.severity.label}"
                                  f"{'s' if more != 1 else ''} from here on, not shown", d.span))
    return out


def _file_namer(path: str, file_path: Optional[Path]):
    """Display name of a file -> the name stored in the binary's file table:
    relative to the procedure's folder, so a build does not depend on where the
    project lives."""
    base = file_path.resolve().parent if file_path is not None else None
    main_stored = file_path.name if file_path is not None else path

    def name(display: str) -> str:
        if display == path:
            return main_stored
        if display.startswith(BUILTIN_PREFIX) or base is None:
            return display
        try:
            return os.path.relpath(Path(display).resolve(), base).replace(os.sep, "/")
        except (ValueError, OSError):
            return Path(display).name
    return name
