"""Diagnostics while you type: the worker, the problem store and the symbol caches.

Every procedure of the project is checked in the background
(:class:`~plcbuilder.ide.diagnostics_worker.DiagnosticsWorker`); the results
feed the problem store (:class:`~plcbuilder.ide.problems.ProblemStore`), the
Problems panel, the editors' squiggles, completion, hover and go-to-definition.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Optional

from PySide6.QtCore import QObject, QTimer, Signal

from plcbuilder import api
from plcbuilder.api import Kind, Severity
from plcbuilder.ide.diagnostics_worker import DiagnosticsWorker
from plcbuilder.ide.editor import file_key
from plcbuilder.ide.problems import ProblemsPanel, ProblemStore
from plcbuilder.project.model import ProjectError


if TYPE_CHECKING:
    from plcbuilder.ide.editor import CodeEditor


class Lint(QObject):
    """Checks the procedures and keeps what the checks found."""

    sig_diagnostics_updated = Signal(str)
    """New diagnostics of a procedure arrived (its file key)."""

    sig_problem_counts = Signal(int, int)
    """The problems changed (errors, warnings)."""

    sig_problem_files = Signal(dict)
    """The files with problems (file key -> 1 for errors, 2 for warnings only)."""

    sig_header_defines = Signal(dict)
    """The defines of the project's headers were read again (name -> (value, file, line))."""

    sig_current_size = Signal()
    """A compile of the current editor's procedure gave its code size."""

    sig_message = Signal(str, int)
    """A message for the status bar (text, milliseconds to show it)."""

    def __init__(self, parent, editors, problems: ProblemsPanel,
                 debounce_ms: Optional[int] = None):
        super().__init__(parent)
        self.editors = editors                         # the EditorStack
        self.problems = problems
        self.project = None
        self.store = ProblemStore()
        self.results: dict[str, object] = {}          # file key -> latest CompileResult
        self.sizes: dict[str, tuple] = {}             # file key -> (size, limit)
        self.header_defines: dict = {}
        self._header_scan = None                       # completion.HeaderDefines, when asked
        self._held = False                             # until the window's first paint
        self._defines_due: list = []                   # editors made meanwhile
        self.worker = DiagnosticsWorker(self, **({"debounce_ms": debounce_ms}
                                                 if debounce_ms is not None else {}))
        self.worker.sig_result.connect(self._on_compile_result)
        self._problems_timer = QTimer(self)
        self._problems_timer.setSingleShot(True)
        self._problems_timer.setInterval(25)
        self._problems_timer.timeout.connect(self.refresh_problems)

    # ================================================================ public
    def busy(self) -> bool:
        """Diagnostics still on their way."""
        return self.worker.pending() or self._problems_timer.isActive()

    def clear(self, *, sizes: bool = True) -> None:
        """Forget every result (another project, or none)."""
        self.store.clear()
        self.results.clear()
        if sizes:
            self.sizes.clear()

    def defer_ms(self, ed: CodeEditor) -> Optional[int]:
        """How long after the last keystroke a large file is compiled: one
        second a megabyte (a compile of it would hold up typing), None
        (the debounce) for the others."""
        n = ed.length()
        return None if n < LARGE_TEXT else 1000 + n // 1000

    def attach(self, ed: CodeEditor) -> None:
        """A new editor: completion, hover and diagnostics for it."""
        ed.completion_provider = self.complete
        ed.hover_provider = self.hover
        ed.signature_provider = _signature
        ed.sig_text_changed.connect(lambda e=ed: self._on_text_changed(e))
        if self._held:
            # the defines it colours come after the window's first paint (with
            # the headers'): finding them loads the compiler's symbols
            self._defines_due.append(ed)
        else:
            self.apply_defines(ed)
        ed.set_diagnostics(self.store.for_file(ed.path))
        if ed.kind is not None and not ed.builtin:
            # a large file is checked once it is open and typing has paused
            self.schedule_compile(ed, immediate=ed.length() < LARGE_TEXT)

    def hold(self, held: bool) -> None:
        """Until the window's first paint: nothing compiles in the background
        and the editors made meanwhile get their defines coloured after it."""
        self._held = bool(held)
        self.worker.hold(held)
        if not held:
            due, self._defines_due = self._defines_due, []
            for ed in due:
                if ed in self.editors.editors():
                    self.apply_defines(ed)

    def options_for(self, path: str) -> api.CompileOptions:
        if self.project is None:
            return api.CompileOptions(kind=api.kind_of(path))
        return self.project.compile_options(path)

    def size_of(self, path: str) -> tuple:
        """The code size of a procedure from its last compile (None if unknown), and its limit."""
        size, limit = self.sizes.get(file_key(path), (None, None))
        if limit is None:
            limit = self.options_for(path).limit
        return size, limit

    def schedule_compile(self, ed: CodeEditor, immediate: bool = False) -> None:
        if ed.kind is None or ed.builtin:
            return
        key = file_key(ed.path)
        if immediate:
            self.worker.submit(key, ed.path, ed.text(), self.options_for(ed.path))
        else:
            self.worker.schedule(key, lambda e=ed: (e.path, e.text(), self.options_for(e.path)),
                                 self.defer_ms(ed))

    def relint_from_disk(self, path: str) -> None:
        if path.endswith(".plc") and Path(path).exists():
            self.worker.submit(file_key(path), path, None, self.options_for(path))

    def relint_open_procedures(self) -> None:
        for ed in self.editors.editors():
            if ed.kind is not None and not ed.builtin:
                self.schedule_compile(ed, immediate=True)

    def lint_project(self) -> None:
        """Check every procedure of the project in the background (Problems);
        first forget the problems of files that are gone."""
        self.forget_missing()
        if self.project is None:
            return
        try:
            procs = self.project.procedures()
        except ProjectError:
            return
        for proc in procs:
            if self.editors.editor_for(proc.path) is None:
                self.relint_from_disk(str(proc.path))
        self.relint_open_procedures()           # a header they include may be gone

    def on_changes_discarded(self, path: str) -> None:
        """An editor closed without saving: check the file on disk instead
        (or, when it is gone, forget its problems)."""
        self.worker.cancel(file_key(path))
        self.relint_from_disk(path)
        self.forget_missing()

    def forget_missing(self) -> None:
        """Drop the problems of files deleted from disk (no editor holds them):
        a procedure's own, and those Build All reported in them."""
        changed = False
        for src in self.store.sources():
            if src.startswith("proc:"):
                key = src[5:]
                if not Path(key).exists() and self.editors.editor_for(key) is None:
                    self.store.remove(src)
                    self.results.pop(key, None)
                    self.sizes.pop(key, None)
                    changed = True
        kept = [d for d in self.store.for_source("project")
                if d.span is None or not d.span.file or Path(d.span.file).exists()
                or self.editors.editor_for(d.span.file) is not None]
        if len(kept) != len(self.store.for_source("project")):
            self.store.set("project", kept)
            changed = True
        if changed:
            self.refresh_problems()

    def on_file_saved(self, path: str) -> None:
        if path.endswith(".h"):
            # a header changed: every procedure may include it
            self.refresh_header_defines()
            self.relint_open_procedures()
            self.lint_project()

    def on_file_renamed(self, old: str, new: str) -> None:
        """A file was renamed (its editor, if any, already follows)."""
        self.store.remove(f"proc:{file_key(old)}")
        self.results.pop(file_key(old), None)
        ed = self.editors.editor_for(new)
        if ed is not None:
            self.worker.cancel(file_key(old))
            self.schedule_compile(ed, immediate=True)
        else:
            self.relint_from_disk(new)
        self.refresh_problems()

    def on_file_deleted(self, path: str) -> None:
        self.store.remove(f"proc:{file_key(path)}")
        self.results.pop(file_key(path), None)
        self.refresh_problems()

    def apply_build_result(self, result) -> None:
        """Build All's diagnostics replace those of the procedures not being edited."""
        modified = {file_key(e.path) for e in self.editors.modified_editors()}
        for pb in result.procedures:
            key = file_key(pb.path)
            if key in modified:
                continue                        # the editor's live diagnostics stay
            self.store.set(f"proc:{key}", pb.diagnostics)
            self.sizes[key] = (pb.size, pb.limit)
        live = {f"proc:{file_key(pb.path)}" for pb in result.procedures}
        for src in self.store.sources():
            if src.startswith("proc:") and src not in live and \
                    self.editors.editor_for(src[5:]) is None:
                self.store.remove(src)          # procedures that are gone
        self.store.set("project", result.diagnostics)
        self.refresh_problems()

    def apply_defines(self, ed: CodeEditor) -> None:
        from plcbuilder.ide import completion  # (loaded when first used)
        result = self.results.get(file_key(ed.path))
        names = set(self.header_defines)
        if result is not None and getattr(result, "symbols", None) is not None:
            names |= set(result.symbols.defines or {})
        names |= set(completion.scan_defines(ed.text()) if ed.length() < LARGE_TEXT else ())
        ed.highlighter.set_defines(names)

    def refresh_problems(self) -> None:
        self.problems.set_problems(self.store.all())
        for ed in self.editors.editors():
            ed.set_diagnostics(self.store.for_file(ed.path))
        marks: dict[str, int] = {}
        for d in self.store.all():
            if d.span is None:
                continue
            k = file_key(d.span.file)
            level = 1 if d.severity == Severity.ERROR else 2
            marks[k] = min(marks.get(k, 3), level)
        self.sig_problem_files.emit(marks)
        self.sig_problem_counts.emit(*self.store.counts())

    def refresh_header_defines(self) -> None:
        from plcbuilder.ide import completion  # (loaded when first used)
        dirs = self.project.include_dirs() if self.project is not None else ()
        if self._header_scan is None:
            self._header_scan = completion.HeaderDefines()
        self.header_defines = self._header_scan.defines(dirs)
        self.sig_header_defines.emit(self.header_defines)

    # ------------------------------------------------ completion, hover, goto
    def complete(self, ed: CodeEditor, prefix: str) -> list:
        from plcbuilder.ide import completion  # (loaded when first used)
        result = self.results.get(file_key(ed.path))
        return completion.completions(prefix, kind=ed.kind or Kind.HARDWARE, text=_near_caret(ed),
                                      symbols=getattr(result, "symbols", None),
                                      defines=self.header_defines)

    def hover(self, ed: CodeEditor, pos: int) -> Optional[str]:
        from plcbuilder.ide import completion, hover  # (loaded when first used)
        start, end, word = ed.word_at(pos)
        if not word:
            return None
        line0 = ed.lineFromPosition(start)
        before = ed.byte_range_text(ed.positionFromLine(line0), start)
        result = self.results.get(file_key(ed.path))
        text = _near_caret(ed, pos)
        return hover.hover_text(word, before, kind=ed.kind or Kind.HARDWARE,
                                symbols=getattr(result, "symbols", None),
                                header_defines=self.header_defines,
                                variables=tuple(completion.scan_variables(text)))

    def goto_definition(self, word: str) -> bool:
        from plcbuilder.ide import completion  # (loaded when first used)
        if not word:
            return False
        ed = self.editors.current_editor()
        dirs = self.project.include_dirs() if self.project is not None else ()
        where = completion.definition(word, ed.text() if ed is not None else "",
                                      ed.path if ed is not None else None, dirs, self.header_defines)
        if where is not None:
            self.editors.open_location(*where)
            return True
        self.sig_message.emit(f"No definition of {word} in the project "
                              "(built-in names have none)", 4000)
        return False

    # ============================================================== private
    def _on_text_changed(self, ed: CodeEditor) -> None:
        if ed.kind is not None:
            self.schedule_compile(ed)
        # headers: the procedures that include them are checked when they are saved

    def _on_compile_result(self, key: str, result) -> None:
        if self.project is not None or self.editors.editors():    # not after Close Project
            self.results[key] = result
            self.sizes[key] = (result.size, result.limit)
            self.store.set(f"proc:{key}", result.diagnostics)
            self._problems_timer.start()           # many results in a row: one refresh
            ed = self.editors.editor_for(result.path) if not result.path.startswith("<") else None
            if ed is not None:
                self.apply_defines(ed)
            if ed is not None and ed is self.editors.current_editor():
                self.sig_current_size.emit()
            self.sig_diagnostics_updated.emit(key)


#: characters from which a file is large: what completion and hover read of it
#: is the lines around the caret (the last compile gives the rest), and its
#: compile waits until typing pauses
LARGE_TEXT = 200_000
#: lines either side of the caret that completion and hover read in a large file
NEAR_LINES = 400


def _near_caret(ed: CodeEditor, pos: Optional[int] = None) -> str:
    """The editor's text, or for a large file the lines around ``pos`` (the
    caret), its own line left out when ``pos`` is None (completion: what is
    typed there changes at every key, the rest does not, so the index of the
    rest is reused): indexing 3 MB at every keystroke would freeze typing."""
    if ed.length() < LARGE_TEXT:
        return ed.text()
    line = ed.lineFromPosition(ed.currentPos() if pos is None else pos)
    first = max(0, line - NEAR_LINES)
    last = min(ed.lineCount() - 1, line + NEAR_LINES)
    if pos is not None:
        return ed.byte_range_text(ed.positionFromLine(first), ed.lineEndPosition(last))
    before = ed.byte_range_text(ed.positionFromLine(first), ed.positionFromLine(line))
    after = ed.byte_range_text(ed.lineEndPosition(line), ed.lineEndPosition(last))
    return before + after


def _signature(name: str):
    """The call tip of a built-in function (completion.py, and the compiler's
    symbols it reads, load when a tip is first asked for: not with the first
    editor, which the window's first paint shows)."""
    from plcbuilder.ide import completion
    return completion.signature(name)
