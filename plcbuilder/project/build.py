"""Build All: compile every procedure of a project, write build/ and the image.

    compile_all(project) -> [ProcedureBuild]     compile, write nothing (also ``run``'s)
    build_project(project, progress) -> BuildResult

1. Every ``hardware/*.plc`` and ``software/*.plc`` is compiled (going on past
   errors) as :meth:`Project.compile_options` says: the project's include folder
   and size limits; each procedure's diagnostics and size against its limit are
   in the result (:func:`compile_all`).
2. Each procedure that compiles is written to ``build/NAME.bin``; the binary of
   a procedure that no longer compiles (or no longer exists) is removed, so
   ``build/`` never holds a stale binary.
3. The hardware procedures' total is checked against its limit (8 KiB).
4. Only when there is no error at all is ``build/eeprom.rom`` written (a ROMFS
   image with a manifest, see plcbuilder.image); otherwise the previous image
   is kept, and the result says so.

Every file is written atomically, and only when its contents change. The same
sources give byte-identical outputs.

Incremental builds: ``build/.cache.json`` remembers, per procedure, a key (a
SHA-256 of the source, of every header it may include as the search order
resolves it, of the compile options and of the compiler itself) with the
diagnostics and the CRC of the binary. A procedure whose key is unchanged and
whose binary is still there is not recompiled; its warnings are reported again
from the cache. The outputs are the same either way.
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import zlib
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path
from typing import Callable, Optional

import plcbuilder
from plcbuilder.bytecode.program import MAX_FILE_SIZE, Kind, Program
from plcbuilder.lang import Diagnostic, Related, Severity, Span, error
from plcbuilder.image.manifest import ImageError, Limits, valid_name, write_image
from plcbuilder.lang import pipeline as _pipeline
from plcbuilder.lang.pipeline import CompileOptions, compile_file
from plcbuilder.lang.preprocess import BUILTIN_PREFIX, builtin_header
from plcbuilder.lang.source import MAX_SOURCE_BYTES
from plcbuilder._support.files import atomic_write, read_bounded
from plcbuilder.project.model import Procedure, Project

CACHE_FILE = ".cache.json"
MAX_CACHE_BYTES = 64 << 20      # a larger build/.cache.json is not ours: it is ignored
CACHE_VERSION = 1
BIN_SUFFIX = ".bin"

#: progress(done, total, name): called after each procedure is compiled (or found
#: unchanged); first with done=0 before any work.
Progress = Callable[[int, int, str], None]


# ------------------------------------------------------------------ results

@dataclass
class ProcedureBuild:
    procedure: Procedure
    diagnostics: list[Diagnostic]
    size: Optional[int]                 # code bytes, None when it did not compile
    limit: int
    binary: Optional[bytes] = field(default=None, repr=False)
    cached: bool = False                # reused from build/.cache.json
    _source_line: Optional[Callable[[str, int], Optional[str]]] = field(default=None, repr=False)

    @property
    def name(self) -> str:
        return self.procedure.name

    @property
    def kind(self) -> Kind:
        return self.procedure.kind

    @property
    def path(self) -> Path:
        return self.procedure.path

    @property
    def ok(self) -> bool:
        return self.binary is not None and not any(d.is_error for d in self.diagnostics)

    @property
    def bin_name(self) -> str:
        return self.name + BIN_SUFFIX

    def program(self) -> Optional[Program]:
        """The compiled procedure, as the controller loads it (None if it did not compile)."""
        return Program.from_bytes(self.binary) if self.ok else None

    def source_line(self, file: str, line: int) -> Optional[str]:
        """A source line for diagnostics.render_text."""
        if self._source_line is not None:
            text = self._source_line(file, line)
            if text is not None:
                return text
        return _disk_line(file, line)


@dataclass
class BuildResult:
    project: Project
    procedures: list[ProcedureBuild]
    diagnostics: list[Diagnostic]       # the project's own (hardware total, names, image)
    limits: Limits
    hw_total: int                       # code bytes of the hardware procedures that compiled
    image_path: Path
    image_written: bool = False
    image_size: Optional[int] = None
    image_message: str = ""
    compiled: int = 0                   # procedures compiled this time
    reused: int = 0                     # procedures taken from the cache

    @property
    def all_diagnostics(self) -> list[Diagnostic]:
        out = [d for p in self.procedures for d in p.diagnostics]
        return out + list(self.diagnostics)

    @property
    def error_count(self) -> int:
        return sum(1 for d in self.all_diagnostics if d.is_error)

    @property
    def warning_count(self) -> int:
        return sum(1 for d in self.all_diagnostics if d.severity == Severity.WARNING)

    @property
    def ok(self) -> bool:
        return self.error_count == 0

    def get(self, name: str) -> Optional[ProcedureBuild]:
        for p in self.procedures:
            if p.name == name:
                return p
        return None

    def source_line(self, file: str, line: int) -> Optional[str]:
        for p in self.procedures:
            text = p.source_line(file, line) if p._source_line else None
            if text is not None:
                return text
        return _disk_line(file, line)


# -------------------------------------------------------------- build all

def compile_all(project: Project, progress: Optional[Progress] = None, *,
                strict: Optional[bool] = None,
                extra_includes: tuple = (), reuse: Optional[tuple[Path, dict, dict]] = None
                ) -> list[ProcedureBuild]:
    """Compile every procedure of the project, going on past errors; writes
    nothing. A name that cannot be a procedure's, or that two files share, is an
    error of that procedure. ``reuse`` is Build All's incremental build: (the
    build folder, the cache read from it, the cache to fill); a procedure whose
    key is unchanged and whose binary is still there is taken from it."""
    procs = project.procedures()
    total = len(procs)
    out: list[ProcedureBuild] = []
    by_name: dict[str, Procedure] = {}
    if progress:
        progress(0, total, "")
    for i, proc in enumerate(procs):
        options = project.compile_options(proc.path, strict=strict, extra_includes=extra_includes)
        problem = _outside_problem(proc, project) or _name_problem(proc, by_name)
        by_name.setdefault(proc.name, proc)
        if problem is not None:
            pb = ProcedureBuild(proc, [problem], None, options.limit)
        else:
            pb = _build_one(proc, options, reuse)
        out.append(pb)
        if progress:
            progress(i + 1, total, proc.name)
    return out


def build_project(project: Project, progress: Optional[Progress] = None, *,
                  strict: Optional[bool] = None, use_cache: bool = True) -> BuildResult:
    """Build All (see the module docstring); ``strict`` None: as the project's
    settings say. Never raises for problems in the sources; an unwritable build
    folder raises OSError."""
    limits = project.limits
    build_dir = project.build_dir
    outside = _build_dir_problem(project)
    if outside is not None:          # write nothing there: compile, report, keep the image
        result = BuildResult(project, compile_all(project, progress, strict=strict), [outside],
                             limits, 0, project.image_path)
        result.compiled = sum(1 for p in result.procedures if not _is_name_problem(p))
        result.image_message = (f"{project.image_path} not written: {build_dir} is outside "
                                "the project")
        return result
    build_dir.mkdir(parents=True, exist_ok=True)
    previous = _load_cache(build_dir, any_compiler=True)   # to find stale binaries
    old_cache = _load_cache(build_dir) if use_cache else {}
    new_cache: dict[str, dict] = {}
    result = BuildResult(project, [], [], limits, 0, project.image_path)
    result.procedures = compile_all(project, progress, strict=strict,
                                    reuse=(build_dir, old_cache, new_cache))
    result.reused = sum(1 for p in result.procedures if p.cached)
    result.compiled = sum(1 for p in result.procedures
                          if not p.cached and not _is_name_problem(p))

    # binaries: write what compiled, remove what no longer does
    good = {p.bin_name: p.binary for p in result.procedures if p.ok}
    for name, data in sorted(good.items()):
        _write_if_changed(build_dir / name, data)
    stale = {e.get("bin") for e in previous.values()} | {p.bin_name for p in result.procedures}
    for name in sorted(n for n in stale if n and n not in good and _safe_bin_name(n)):
        try:
            (build_dir / name).unlink()
        except FileNotFoundError:
            pass

    hw = [(p.size, p.name) for p in result.procedures if p.ok and p.kind is Kind.HARDWARE]
    result.hw_total = sum(s for s, _ in hw)
    if result.hw_total > limits.hw_total:
        biggest = ", ".join(f"{n} {s}" for s, n in sorted(hw, key=lambda x: (-x[0], x[1]))[:5])
        result.diagnostics.append(error(
            "size-limit",
            f"hardware procedures together are {result.hw_total} bytes of code; the limit is "
            f"{limits.hw_total} ({result.hw_total}/{limits.hw_total} bytes; largest: {biggest})",
            None, "move work into software procedures, or remove procedures you do not use"))

    if result.ok:
        try:
            image = write_image([(p.name, p.kind, p.binary) for p in result.procedures], limits)
        except ImageError as exc:
            result.diagnostics.append(error("image", f"cannot make the image: {exc}", None))
        else:
            changed = _write_if_changed(project.image_path, image)
            result.image_written = True
            result.image_size = len(image)
            n = len(result.procedures)
            result.image_message = (f"{'wrote' if changed else 'up to date:'} {project.image_path} "
                                    f"({len(image)} bytes, {n} procedure{'s' * (n != 1)})")
    if not result.image_written:
        n = result.error_count
        keep = (f"the previous {project.image_path.name} is kept"
                if project.image_path.exists() else f"there is no {project.image_path.name} yet")
        result.image_message = (f"{project.image_path} not written: {n} error{'s' * (n != 1)}; "
                                f"{keep}")

    _save_cache(build_dir, new_cache)
    return result


def _real(p: Path) -> Path:
    try:
        return p.resolve()
    except (OSError, RuntimeError):     # a link loop
        return p.absolute()


def _outside_problem(proc: Procedure, project: Project) -> Optional[Diagnostic]:
    """A source file that is a link out of the project: an error, and it is not
    read (its lines would be echoed in diagnostics)."""
    real = _real(proc.path)
    if real.is_relative_to(_real(project.root)):
        return None
    return error("source-outside-project",
                 f"{proc.path} is a link to {real}, outside the project; Build All compiles "
                 "only files inside the project", None,     # no span: its lines are not shown
                 "copy the file into the project instead of linking to it")


def _build_dir_problem(project: Project) -> Optional[Diagnostic]:
    """build/ (or something in the way of it) leading out of the project."""
    build_dir = project.build_dir
    if not os.path.lexists(build_dir):
        return None
    real = _real(build_dir)
    if real.is_relative_to(_real(project.root)) and real != _real(project.root):
        return None
    return error("build-outside-project",
                 f"{build_dir} leads to {real}, outside the project; Build All writes only "
                 "inside the project", None,
                 f"remove the link {build_dir} (Build All makes the folder)")


def _name_problem(proc: Procedure, seen: dict[str, Procedure]) -> Optional[Diagnostic]:
    at = Span.point(str(proc.path), 1, 1)
    if not valid_name(proc.name):
        return error("procedure-name",
                     f"'{proc.name}' cannot be a procedure name: use letters, digits, '_' and "
                     "'-' (at most 64), as in M03 or __HANDLER_INIT", at,
                     "rename the file")
    other = seen.get(proc.name)
    if other is not None:
        return error("duplicate-procedure",
                     f"there is a {other.kind.label} procedure named {proc.name} too "
                     f"({other.path}); names must be unique in a project (they share build/ "
                     "and the image)", at, "rename one of the files")
    return None


def _is_name_problem(pb: ProcedureBuild) -> bool:
    return any(d.code in ("procedure-name", "duplicate-procedure", "source-outside-project")
               for d in pb.diagnostics)


def _build_one(proc: Procedure, options: CompileOptions,
               reuse: Optional[tuple[Path, dict, dict]]) -> ProcedureBuild:
    build_dir, old_cache, new_cache = reuse if reuse is not None else (None, {}, None)
    cache_id = f"{proc.kind.label}/{proc.name}"
    key = _cache_key(proc, options) if reuse is not None else None
    entry = old_cache.get(cache_id)
    if key is not None and entry and entry.get("key") == key:
        reused = _from_cache(proc, options, entry, build_dir)
        if reused is not None:
            new_cache[cache_id] = entry
            return reused
    try:
        r = compile_file(proc.path, options)
    except Exception as exc:  # noqa: BLE001 - one procedure must not stop Build All
        diag = error("internal", f"internal compiler error: {type(exc).__name__}: {exc}",
                     Span.point(str(proc.path), 1, 1))
        return ProcedureBuild(proc, [diag], None, options.limit)
    binary = r.program.to_bytes() if r.ok and r.program is not None else None
    pb = ProcedureBuild(proc, list(r.diagnostics), r.size if binary else None, r.limit,
                        binary, False, r.source_line)
    if key is not None:
        new_cache[cache_id] = {
            "key": key,
            "bin": pb.bin_name if binary else None,
            "crc32": zlib.crc32(binary) if binary else None,
            "size": pb.size,
            "diagnostics": [_diag_to_json(d) for d in pb.diagnostics],
        }
    return pb


def _from_cache(proc: Procedure, options: CompileOptions, entry: dict,
                build_dir: Path) -> Optional[ProcedureBuild]:
    try:
        diags = [_diag_from_json(d) for d in entry["diagnostics"]]
        binary = None
        if entry.get("bin"):
            if entry["bin"] != proc.name + BIN_SUFFIX:
                return None
            binary = read_bounded(build_dir / entry["bin"], MAX_FILE_SIZE, "compiled procedure")
            if zlib.crc32(binary) != entry["crc32"]:
                return None
        elif not any(d.is_error for d in diags):
            return None
        size = entry.get("size")
        if binary is not None and type(size) is not int:
            return None
    except (OSError, KeyError, TypeError, ValueError):
        return None
    return ProcedureBuild(proc, diags, size, options.limit, binary, True, None)


def _write_if_changed(path: Path, data: bytes) -> bool:
    """Write data atomically unless path already holds it; whether it wrote."""
    try:
        if read_bounded(path, len(data)) == data:
            return False
    except OSError:       # missing, different, or not a regular file (atomic_write says so)
        pass
    atomic_write(path, data)
    return True


def _safe_bin_name(name: str) -> bool:
    return name.endswith(BIN_SUFFIX) and "/" not in name and "\\" not in name \
        and valid_name(name[:-len(BIN_SUFFIX)])


# ------------------------------------------------------------------ cache

@lru_cache(maxsize=1)
def compiler_fingerprint() -> str:
    """A hash of the compiler (its version and its own source files), so that a
    changed compiler never reuses a cached build."""
    h = hashlib.sha256()
    h.update(f"plcbuilder {plcbuilder.__version__} compiler {_pipeline.COMPILER_VERSION}".encode())
    pkg = Path(plcbuilder.__file__).parent
    for sub in ("lang", "bytecode"):
        folder = pkg / sub
        try:
            files = sorted(p for p in folder.iterdir() if p.suffix in (".py", ".lark"))
        except OSError:
            continue
        for p in files:
            try:
                h.update(p.name.encode() + b"\0" + p.read_bytes() + b"\0")
            except OSError:
                pass
    return h.hexdigest()


_INCLUDE_RE = re.compile(r"^[ \t]*#[ \t]*include\b(.*)$", re.MULTILINE)
_MAX_DEPS = 256


def _include_targets(text: str) -> list[str]:
    """Every #include target named in text (an over-approximation: includes in
    comments or inactive #ifdef branches count too, which only costs a rebuild)."""
    out = []
    for m in _INCLUDE_RE.finditer(text):
        arg = re.sub(r"//.*|/\*.*?\*/", "", m.group(1)).strip()
        mm = re.fullmatch(r'"([^"]+)"|<([^>]+)>|([^\s"<>]+)', arg)
        if mm:
            out.append(next(g for g in mm.groups() if g))
    return out


def _cache_key(proc: Procedure, options: CompileOptions) -> Optional[str]:
    """The SHA-256 that decides whether a cached build is still good, or None
    when the sources cannot be read (then the compiler reports why)."""
    h = hashlib.sha256()

    def put(*parts) -> None:
        for part in parts:
            b = part if isinstance(part, bytes) else str(part).encode("utf-8", "surrogatepass")
            h.update(len(b).to_bytes(8, "little") + b)

    try:
        source = read_bounded(proc.path, MAX_SOURCE_BYTES)
    except OSError:
        return None
    try:
        cwd = os.getcwd()      # diagnostics name headers relative to it
    except OSError:
        cwd = ""
    put(CACHE_VERSION, compiler_fingerprint(), proc.kind.label, options.strict,
        options.limit, str(proc.path), cwd, source)
    dirs = [Path(d) for d in options.include_dirs]
    put(len(dirs), *[str(d) for d in dirs])
    # Resolve includes as the preprocessor does: the including file's folder,
    # then the include folders, then the built-in headers.
    todo = [(t, proc.path.parent) for t in _include_targets(_text(source))]
    seen: set[tuple[str, str]] = set()
    while todo:
        target, folder = todo.pop(0)
        if (target, str(folder)) in seen:
            continue
        seen.add((target, str(folder)))
        if len(seen) > _MAX_DEPS:
            return None
        put("include", target, str(folder))
        found = None
        for d in ([folder] if folder is not None else []) + dirs:
            p = d / target
            try:
                if p.is_file():
                    found = p
                    break
            except OSError:
                return None
        if found is not None:
            try:
                data = read_bounded(found, MAX_SOURCE_BYTES)
            except OSError:
                return None
            put("file", str(found), data)
            todo.extend((t, found.parent) for t in _include_targets(_text(data)))
            continue
        text = builtin_header(target)
        if text is not None:
            put("builtin", text)
            todo.extend((t, None) for t in _include_targets(text))
        else:
            put("missing")
    return h.hexdigest()


def _text(data: bytes) -> str:
    return data.decode("utf-8", "replace")


def _load_cache(build_dir: Path, any_compiler: bool = False) -> dict:
    try:
        doc = json.loads(read_bounded(build_dir / CACHE_FILE, MAX_CACHE_BYTES).decode("utf-8"))
    except (OSError, ValueError, RecursionError):
        return {}
    if not isinstance(doc, dict):
        return {}
    if not any_compiler and (doc.get("version") != CACHE_VERSION
                             or doc.get("compiler") != compiler_fingerprint()):
        return {}
    procs = doc.get("procedures")
    if not isinstance(procs, dict):
        return {}
    return {k: v for k, v in procs.items() if isinstance(v, dict)}


def _save_cache(build_dir: Path, entries: dict) -> None:
    doc = {"version": CACHE_VERSION, "compiler": compiler_fingerprint(),
           "procedures": dict(sorted(entries.items()))}
    text = json.dumps(doc, indent=1, sort_keys=True) + "\n"
    try:
        _write_if_changed(build_dir / CACHE_FILE, text.encode("utf-8"))
    except OSError:
        pass   # a cache that cannot be written only costs time next build


def _span_to_json(s: Optional[Span]):
    return None if s is None else [s.file, s.line, s.col, s.end_line, s.end_col]


def _span_from_json(v) -> Optional[Span]:
    if v is None:
        return None
    f, a, b, c, d = v
    if not isinstance(f, str) or not all(type(x) is int for x in (a, b, c, d)):
        raise ValueError("bad span")
    return Span(f, a, b, c, d)


def _diag_to_json(d: Diagnostic) -> dict:
    return {"severity": int(d.severity), "code": d.code, "message": d.message,
            "span": _span_to_json(d.span), "hints": list(d.hints),
            "related": [[_span_to_json(r.span), r.message] for r in d.related]}


def _diag_from_json(v: dict) -> Diagnostic:
    if not isinstance(v["code"], str) or not isinstance(v["message"], str):
        raise ValueError("bad diagnostic")
    return Diagnostic(Severity(v["severity"]), v["code"], v["message"], _span_from_json(v["span"]),
                      tuple(str(h) for h in v["hints"]),
                      tuple(Related(_span_from_json(s), str(m)) for s, m in v["related"]))


def _disk_line(file: str, line: int) -> Optional[str]:
    """A line of a file as diagnostics name it (a path, or a built-in header)."""
    try:
        if file.startswith(BUILTIN_PREFIX):
            text = builtin_header(file[len(BUILTIN_PREFIX):])
        else:
            text = read_bounded(file, MAX_SOURCE_BYTES).decode("utf-8", "replace")
    except (OSError, ValueError):
        return None
    if text is None:
        return None
    lines = text.replace("\r\n", "\n").replace("\r", "\n").split("\n")
    return lines[line - 1] if 1 <= line <= len(lines) else None
