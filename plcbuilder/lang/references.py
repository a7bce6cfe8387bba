"""Where a name is used across a project, and what renaming it changes.

A name means different things in different files: a procedure, a variable or
a ``#define`` made in a ``.plc`` file belongs to that file alone (every
procedure file is its own program), while a ``#define`` or a procedure made in
a header belongs to every file that includes the header. :func:`scope_of`
finds which files a name's meaning reaches, from the file where it was asked
about; :func:`find_references` lists its places (from the real tokens, so
comments never count); :func:`plan_rename` turns them into edits, refusing a
new name that is not an identifier, is a built-in name, or is taken.

``sources`` maps a file's path to its text (the IDE passes an open editor's
text instead of the file on disk). Lines and columns are 1-based, columns
count characters, as everywhere in the compiler.

    scope = scope_of("OUTPUT_SPINDLE", "/p/hardware/M03.plc", sources, [include])
    refs = find_references(scope, sources)
    plan = plan_rename(scope, "OUT_SPINDLE", sources)     # plan.error or plan.edits
    new_text = apply_edits(sources[path], plan.edits[path], "OUT_SPINDLE")
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Mapping, Optional, Sequence

from plcbuilder.bytecode import abi
from plcbuilder.diagnostics import Span
from plcbuilder.lang.builtins import FUNCTIONS, KEYWORDS, PREDEFINED
from plcbuilder.lang.builtin_headers import source_text
from plcbuilder.lang.preprocess import BUILTIN_PREFIX
from plcbuilder.lang.symbols import DEFINE, PROCEDURE, VARIABLE, SymbolIndex, index, tokens_of

BUILTIN = "built-in"
IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


@dataclass(frozen=True)
class Reference:
    """One place a name is written."""
    file: str
    line: int
    col: int
    end_col: int
    text: str              # the whole line, as written
    definition: bool = False


@dataclass(frozen=True)
class Scope:
    """What a name is, where it is defined and which files it reaches."""
    name: str
    kind: str                        # DEFINE, PROCEDURE, VARIABLE or BUILTIN
    definition: Optional[Span]
    files: tuple[str, ...]

    @property
    def read_only(self) -> Optional[str]:
        """Why this name cannot be renamed, or None."""
        if self.kind == BUILTIN:
            return f"{self.name} is a built-in name: it cannot be renamed"
        if self.definition is not None and self.definition.file.startswith(BUILTIN_PREFIX):
            return (f"{self.name} is defined in the built-in "
                    f"{self.definition.file[len(BUILTIN_PREFIX):]}, which cannot be edited: "
                    "copy it into the project's include folder first")
        return None


@dataclass
class RenamePlan:
    """The edits of a rename, by file (empty when ``error`` says why not)."""
    old: str
    new: str
    edits: dict[str, list[Reference]] = field(default_factory=dict)
    error: Optional[str] = None

    @property
    def count(self) -> int:
        return sum(len(v) for v in self.edits.values())


def is_builtin(name: str) -> bool:
    """A keyword, built-in function, predefined variable or name of the myCNC tables."""
    return name in KEYWORDS or name in FUNCTIONS or name in PREDEFINED or \
        name in abi.BUILTIN_NAMES


def _index(path: str, text: str, include_dirs: Sequence[Path]) -> SymbolIndex:
    file_path = Path(path) if not path.startswith("<") else None
    return index(text, path, file_path, tuple(include_dirs))


def _same_file(a: str, b: str) -> bool:
    if a == b:
        return True
    if a.startswith("<") or b.startswith("<"):
        return False
    try:
        return Path(a).resolve() == Path(b).resolve()
    except OSError:
        return False


def scope_of(name: str, origin: str, sources: Mapping[str, str],
             include_dirs: Sequence[Path] = ()) -> Optional[Scope]:
    """What ``name`` means in the file ``origin`` (one of ``sources``) and the
    files it reaches; None when ``origin`` does not know the name at all."""
    if not IDENTIFIER.fullmatch(name or "") or origin not in sources:
        return None
    idx = _index(origin, sources[origin], include_dirs)
    sym = idx.defines.get(name) or idx.procedures.get(name) or idx.variables.get(name) or \
        _header_procedure(name, idx, sources, include_dirs)
    if sym is None:
        if is_builtin(name):
            return Scope(name, BUILTIN, None, tuple(sources))
        if not idx.occurrences(name):
            return None
        return Scope(name, VARIABLE, None, (origin,))   # only read, never assigned
    where = sym.span.file if sym.span is not None else origin
    if _same_file(where, origin) and not origin.endswith(".h"):
        return Scope(name, sym.kind, sym.span, (origin,))
    # made in a header: every file that sees that definition
    files = []
    for path, text in sources.items():
        if _same_file(path, where):
            files.append(path)
            continue
        other = _index(path, text, include_dirs)
        seen = other.defines.get(name) if sym.kind == DEFINE else None
        if seen is not None and seen.span == sym.span:
            files.append(path)
        elif sym.kind == PROCEDURE and any(_same_file(h, where) for h in other.includes):
            files.append(path)
    return Scope(name, sym.kind, sym.span, tuple(files))


def _header_procedure(name: str, idx: SymbolIndex, sources: Mapping[str, str],
                      include_dirs: Sequence[Path]):
    """The procedure ``name`` of a header the file includes (myCNC profiles keep
    helper procedures in headers), or None."""
    for header in idx.includes:
        text = next((t for p, t in sources.items() if _same_file(p, header)), None)
        if text is None:
            try:
                text = source_text(header)
            except OSError:
                text = None
        if text:
            sym = _index(header, text, include_dirs).procedures.get(name)
            if sym is not None:
                return sym
    return None


def find_references(scope: Scope, sources: Mapping[str, str]) -> list[Reference]:
    """Every place the files of ``scope`` write its name, file by file in the
    order of ``scope.files``, then by line and column."""
    out: list[Reference] = []
    d = scope.definition
    for path in scope.files:
        text = sources.get(path)
        if text is None:
            continue
        lines = text.replace("\r\n", "\n").replace("\r", "\n").split("\n")
        for t in tokens_of(text, path):
            if t.kind != "NAME" or t.value != scope.name:
                continue
            line = lines[t.span.line - 1] if t.span.line <= len(lines) else ""
            is_def = d is not None and _same_file(d.file, path) and \
                (d.line, d.col) == (t.span.line, t.span.col)
            out.append(Reference(path, t.span.line, t.span.col, t.span.col + len(t.value),
                                 line, is_def))
    return out


def check_new_name(new: str, old: str = "") -> Optional[str]:
    """Why ``new`` cannot be a name, or None."""
    if not IDENTIFIER.fullmatch(new or ""):
        return f"'{new}' is not a name: use letters, digits and _, not starting with a digit"
    if new == old:
        return "the new name is the old one"
    if new in KEYWORDS:
        return f"'{new}' is a keyword"
    if is_builtin(new):
        return f"'{new}' is a built-in name"
    return None


def plan_rename(scope: Scope, new: str, sources: Mapping[str, str],
                include_dirs: Sequence[Path] = ()) -> RenamePlan:
    """The edits that rename ``scope.name`` to ``new`` in every file it reaches."""
    plan = RenamePlan(scope.name, new)
    plan.error = scope.read_only or check_new_name(new, scope.name)
    if plan.error:
        return plan
    for path in scope.files:
        text = sources.get(path)
        if text is None:
            continue
        idx = _index(path, text, include_dirs)
        taken = idx.defines.get(new) or idx.procedures.get(new) or idx.variables.get(new)
        if taken is not None or idx.occurrences(new):
            plan.error = f"'{new}' is already used in {Path(path).name}"
            return plan
    for ref in find_references(scope, sources):
        plan.edits.setdefault(ref.file, []).append(ref)
    if not plan.edits:
        plan.error = f"{scope.name} is not written anywhere that could be renamed"
    return plan


def renamed_line(ref: Reference, refs_on_line: Sequence[Reference], new: str) -> str:
    """The line of ``ref`` with every reference on it renamed (for a preview)."""
    text = ref.text
    for r in sorted(refs_on_line, key=lambda r: r.col, reverse=True):
        text = text[:r.col - 1] + new + text[r.end_col - 1:]
    return text


def apply_edits(text: str, refs: Sequence[Reference], new: str) -> str:
    """``text`` with each reference replaced by ``new`` (line ends kept)."""
    lines = text.split("\n")
    for r in sorted(refs, key=lambda r: (r.line, r.col), reverse=True):
        if not 1 <= r.line <= len(lines):
            continue
        s = lines[r.line - 1]
        lines[r.line - 1] = s[:r.col - 1] + new + s[r.end_col - 1:]
    return "\n".join(lines)
