"""The window's navigation, build-insight, register and help features, wired in.

:func:`install` makes, for a :class:`~plcbuilder.ide.main_window.MainWindow`:

* Back / Forward (:mod:`.navigation`), Quick Open (:mod:`.dialogs.quick_open`),
  Find in Files and Find References (:mod:`.panels.find_in_files`,
  :mod:`.panels.results`), Rename Symbol (:mod:`.dialogs.rename`, planned by
  :mod:`plcbuilder.lang.references`), the Outline (:mod:`.panels.outline`);
* the Disassembly dock (:mod:`.panels.disasm_view`) and the code bytes in the
  editor margin (:mod:`.code_bytes`), both from the last check of the
  current procedure; Build, Upload and Start in the Build menu and the toolbar;
* the Registers dock (:mod:`.panels.register_browser`);
* the manual, the shortcuts list and What Is This? (:mod:`.help`);

with their actions (named in :class:`~plcbuilder.ide.actions.Act`), menus
and docks. :class:`Workbench` holds them and answers the actions.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Optional

from PySide6.QtCore import QObject
from PySide6.QtWidgets import QMenu, QMessageBox

from plcbuilder._support.files import atomic_write, read_bounded
from plcbuilder.ide import actions as acts, code_bytes
from plcbuilder.ide.actions import Act
from plcbuilder.ide.editor import file_key
from plcbuilder.ide.navigation import NavigationHistory
from plcbuilder.ide.panels.outline import OutlinePanel

if TYPE_CHECKING:
    from plcbuilder.ide.help import HelpWindow, ShortcutsDialog
    from plcbuilder.lang import references

MAX_SOURCE = 4 << 20
#: The settings key that remembers View → Code Bytes in Margin.
CODE_BYTES_KEY = "view/code_bytes"
#: folders of a project whose files Quick Open does not list
SKIP_DIRS = {"build", ".git", "__pycache__", ".plcbuilder"}
QUICK_OPEN_SUFFIXES = (".plc", ".h", ".toml", ".xml", ".md", ".txt")
MAX_QUICK_OPEN = 5000


class Workbench(QObject):
    """The features of the module docstring, for one window."""

    def __init__(self, win):
        super().__init__(win)
        self.win = win
        self.nav = NavigationHistory(win.editor_stack, self)
        self.help_window: Optional[HelpWindow] = None
        self.show_bytes = False
        # its docks (docks.DOCKS): the Outline is in the first frame; the
        # others get their panel when first shown or used (``panels``, set by
        # the window from its dock table)
        self.outline = OutlinePanel(win)
        self._root: Optional[Path] = None
        self.panels = None

    # ============================================================ the docks
    @property
    def references(self):
        """The References dock's panel (made when first shown or used)."""
        return self.panels.get("references")

    @property
    def find_panel(self):
        """The Find in Files dock's panel."""
        return self.panels.get("find")

    @property
    def disasm(self):
        """The Disassembly dock's view."""
        return self.panels.get("disasm")

    @property
    def registers(self):
        """The Registers dock's browser."""
        return self.panels.get("registers")

    def _make_panel(self, key: str):
        """A dock's panel, wired and brought up to date (the window's dock table makes it the
        first time it shows or is used)."""
        win = self.win
        if key == "references":
            from plcbuilder.ide.panels.results import ResultsPanel
            panel = ResultsPanel(win, "Shift+F12 on a name lists where it is used")
        elif key == "find":
            from plcbuilder.ide.panels.find_in_files import FindInFilesPanel
            panel = FindInFilesPanel(win)
            panel.sources_provider = self.project_sources
        elif key == "disasm":
            from plcbuilder.ide.panels.disasm_view import DisasmView
            panel = DisasmView(win)
            panel.source_line = self._source_line
        else:
            from plcbuilder.ide.panels.register_browser import RegisterBrowser
            panel = RegisterBrowser(win)
            panel.sig_insert.connect(self.insert_name)
            if win.connection is not None:
                panel.set_connection(win.connection)
        if key != "registers":
            panel.sig_open_location.connect(self.jump)
        if key in ("references", "find") and self._root is not None:
            panel.tree.root = self._root
        return panel

    def _panel_made(self, key: str) -> None:
        """The disassembly, once in its dock, shows the current procedure (and
        again each time it shows)."""
        if key == "disasm":
            self.win.disasm_dock.visibilityChanged.connect(
                lambda on: on and self.refresh_build_views())
            self.refresh_build_views()

    def dock_panel(self, key: str):
        """The panel of one of its docks (docks.DOCKS)."""
        return self.outline if key == "outline" else self._make_panel(key)

    # ============================================================ files
    def project_files(self) -> list[Path]:
        """The project's procedures and headers (headers of its include folders too)."""
        p = self.win.project
        if p is None:
            return []
        out: list[Path] = [pr.path for pr in p.procedures()]
        seen = {file_key(x) for x in out}
        folders = [p.root / "hardware", p.root / "software", *p.include_dirs()]
        for folder in folders:
            try:
                headers = sorted(folder.glob("*.h"))
            except OSError:
                continue
            for h in headers:
                if h.is_file() and file_key(h) not in seen:
                    seen.add(file_key(h))
                    out.append(h)
        return out

    def project_sources(self) -> dict[str, str]:
        """{path: text} of the project's sources and headers; an open editor's
        text (unsaved changes included) stands in for its file."""
        out: dict[str, str] = {}
        for path in self.project_files():
            ed = self.win.editor_for(path)
            if ed is not None:
                out[str(path)] = ed.text()
                continue
            try:
                out[str(path)] = read_bounded(path, MAX_SOURCE).decode("utf-8", "replace")
            except OSError:
                continue
        for ed in self.win.editors():               # open files outside the lists above
            if ed.path not in out and not ed.builtin and ed.path.endswith((".plc", ".h")):
                out[ed.path] = ed.text()
        return out

    def _source_line(self, path: str, line: int) -> Optional[str]:
        ed = self.win.editor_for(path)
        if ed is not None:
            return ed.line_text(line - 1)
        from plcbuilder.lang.builtin_headers import source_text
        try:
            text = source_text(path, MAX_SOURCE)
        except OSError:
            return None
        lines = (text or "").split("\n")
        return lines[line - 1] if 1 <= line <= len(lines) else None

    # ======================================================= navigation
    def jump(self, file: str, line: int, col: int = 1) -> None:
        """Open a place (remembering where the caret was, for Back)."""
        self.nav.record()
        self.win.open_location(file, line, col)

    def quick_open(self, text: str = "") -> Optional[str]:
        p = self.win.project
        if p is None:
            return None
        files = []
        for f in sorted(self._all_files(p.root)):
            files.append((str(f), f.relative_to(p.root).as_posix()))
        from plcbuilder.ide.dialogs.quick_open import QuickOpenDialog
        path = QuickOpenDialog.get_file(self.win, files, text)
        if path:
            self.nav.record()
            self.win.open_file(path)
        return path

    def _all_files(self, root: Path) -> list[Path]:
        out = []
        stack = [root]
        while stack and len(out) < MAX_QUICK_OPEN:
            folder = stack.pop()
            try:
                entries = list(folder.iterdir())
            except OSError:
                continue
            for e in entries:
                if e.name.startswith(".") or e.name in SKIP_DIRS:
                    continue
                if e.is_dir():
                    stack.append(e)
                elif e.suffix.lower() in QUICK_OPEN_SUFFIXES:
                    out.append(e)
        return out

    def find_in_files(self) -> None:
        ed = self.win.current_editor()
        sel = ed.selected_text() if ed is not None else ""
        self.win.find_dock.show()
        self.win.find_dock.raise_()
        self.find_panel.focus_pattern(sel if sel and "\n" not in sel else "")

    def _scope_at_caret(self, verb: str):
        ed = self.win.current_editor()
        if ed is None:
            return None, None
        word = ed.word_under_caret()
        if not word or word[0].isdigit():
            self.win.statusBar().showMessage(f"{verb}: put the caret on a name", 4000)
            return None, None
        sources = self.project_sources()
        origin = ed.path
        if origin not in sources:
            sources[origin] = ed.text()
        dirs = self.win.project.include_dirs() if self.win.project is not None else ()
        from plcbuilder.lang import references
        scope = references.scope_of(word, origin, sources, dirs)
        if scope is None:
            self.win.statusBar().showMessage(f"{verb}: {word} is not a name of this file", 4000)
        return scope, sources

    def find_references(self) -> int:
        """Shift+F12: list where the name at the caret is used (in the References dock)."""
        scope, sources = self._scope_at_caret("Find References")
        if scope is None:
            return 0
        from plcbuilder.ide.panels.results import Hit
        from plcbuilder.lang import references
        refs = references.find_references(scope, sources)
        hits = [Hit(r.file, r.line, r.col, r.end_col, r.text,
                    "definition" if r.definition else "") for r in refs]
        files = len({r.file for r in refs})
        what = "built-in name" if scope.kind == references.BUILTIN else scope.kind
        summary = (f"{scope.name} ({what}): {len(refs)} reference{'s' * (len(refs) != 1)} "
                   f"in {files} file{'s' * (files != 1)}")
        n = self.references.show_hits(summary, hits)
        self.win.references_dock.show()
        self.win.references_dock.raise_()
        return n

    def rename_symbol(self) -> bool:
        """F2: rename the name at the caret everywhere it reaches, after a preview."""
        scope, sources = self._scope_at_caret("Rename")
        if scope is None:
            return False
        if scope.read_only:
            QMessageBox.information(self.win, "Rename", scope.read_only)
            return False
        dirs = self.win.project.include_dirs() if self.win.project is not None else ()
        from plcbuilder.ide.dialogs.rename import RenameDialog
        from plcbuilder.lang import references
        plan = RenameDialog.get_plan(
            self.win, scope, lambda new: references.plan_rename(scope, new, sources, dirs),
            self.win.project.root if self.win.project else None)
        if plan is None:
            return False
        return self.apply_rename(plan, sources)

    def apply_rename(self, plan: references.RenamePlan, sources: dict[str, str]) -> bool:
        """Write a rename: open editors change as one undoable step each (and are
        saved when they had no other unsaved change); other files are rewritten
        atomically, unless they changed on disk since the preview."""
        from plcbuilder.lang import references
        es = self.win.editor_stack
        changed, skipped, unsaved = [], [], []
        for path, refs in plan.edits.items():
            ed = self.win.editor_for(path)
            if ed is not None:
                was_modified = es.is_modified(ed)
                _rename_in_editor(ed, refs, plan.new)
                if not was_modified:
                    es.save_editor(ed)
                else:
                    unsaved.append(Path(path).name)
                changed.append(path)
                continue
            try:
                now = read_bounded(path, MAX_SOURCE).decode("utf-8", "replace")
            except OSError:
                skipped.append(Path(path).name)
                continue
            if now != sources.get(path):
                skipped.append(Path(path).name)
                continue
            try:
                atomic_write(path, references.apply_edits(now, refs, plan.new).encode("utf-8"))
            except OSError:
                skipped.append(Path(path).name)
                continue
            changed.append(path)
        self.references.show_hits(f"{plan.old} was renamed to {plan.new}: Shift+F12 on it "
                                  "lists its places again", [])
        lint = self.win.lint
        if any(p.endswith(".h") for p in changed):
            lint.refresh_header_defines()
        lint.relint_open_procedures()
        lint.lint_project()
        self.win.tree.refresh()
        msg = f"Renamed {plan.old} to {plan.new}: {plan.count} changes in {len(changed)} files"
        if unsaved:
            msg += f"; not saved (they had other changes): {', '.join(unsaved)}"
        self.win.statusBar().showMessage(msg, 8000)
        if skipped:
            QMessageBox.warning(self.win, "Rename",
                                "These files changed on disk (or could not be written) since "
                                f"the preview and were left as they are:\n\n{', '.join(skipped)}")
        return not skipped

    # ========================================================= build insight
    def refresh_build_views(self, key: Optional[str] = None) -> None:
        """The current procedure was checked again (or another editor came up):
        the disassembly and the byte margin follow."""
        ed = self.win.current_editor()
        disasm = self.panels.made.get("disasm")   # (not made yet: it catches up when it is)
        if ed is None:
            if disasm is not None:
                disasm.clear_view("No procedure open")
            return
        if key is not None and key != file_key(ed.path):
            return
        result = self.win.lint.results.get(file_key(ed.path))
        if ed.kind is None or result is None:
            if disasm is not None:
                disasm.clear_view(f"{Path(ed.path).name} is not a procedure: open a .plc file"
                                  if ed.kind is None else "Checking…")
            code_bytes.show_margin(ed, None)
            return
        if disasm is not None and not self.win.disasm_dock.isHidden():
            disasm.show_result(ed.path, result)
            disasm.follow(ed.path, ed.cursor_line_col()[0])
        if self.show_bytes:
            counts = code_bytes.bytes_by_line(code_bytes.instructions_of(result), ed.path)
            code_bytes.show_margin(ed, code_bytes.lines_of_file(counts, ed.path))
        else:
            code_bytes.show_margin(ed, None)

    def set_show_bytes(self, on: bool) -> None:
        self.show_bytes = bool(on)
        self.win.settings.qs.setValue(CODE_BYTES_KEY, self.show_bytes)
        for ed in self.win.editors():
            if ed is not self.win.current_editor():
                code_bytes.show_margin(ed, None)
        self.refresh_build_views()

    def show_disassembly(self) -> None:
        self.win.disasm_dock.show()
        self.win.disasm_dock.raise_()
        self.refresh_build_views()

    # ============================================================ registers
    def insert_name(self, name: str) -> None:
        ed = self.win.current_editor()
        if ed is None or ed.readOnly():
            self.win.statusBar().showMessage("Open a file to insert a name into", 3000)
            return
        ed.replaceSel(name)
        ed.take_focus()

    # ================================================================= help
    def show_manual(self, chapter: str = "ide", anchor: str = "") -> HelpWindow:
        if self.help_window is None:
            from plcbuilder.ide.help import HelpWindow
            self.help_window = HelpWindow(self.win)
        self.help_window.show()
        self.help_window.raise_()
        self.help_window.activateWindow()
        if chapter:
            self.help_window.open_named(chapter, anchor)
        return self.help_window

    def show_shortcuts(self) -> ShortcutsDialog:
        from plcbuilder.ide.help import ShortcutsDialog
        dlg = ShortcutsDialog(self.win, self.win._actions.values())
        dlg.show()
        return dlg

    def what_is_this(self) -> Optional[str]:
        """Shift+F1: what the name or number at the caret is (the hover text, in
        a popup); a name of the ABI is also selected in the Registers dock."""
        ed = self.win.current_editor()
        if ed is None:
            return None
        pos = ed.currentPos()
        s, e, word = ed.word_at(pos)
        if not word and pos > 0:
            s, e, word = ed.word_at(pos - 1)
        text = ed.hover_text_at(s) if word else None
        if not text:
            text = f"{word}: nothing is known about this name" if word else \
                "Put the caret on a name or a number"
        ed.callTipShow(s if word else pos, text)
        if word and self._select_register(ed, s, word):
            self.win.registers_dock.show()
            self.win.registers_dock.raise_()
        return text

    def _select_register(self, ed, start: int, word: str) -> bool:
        """Select ``word`` in the Registers dock: a name of the myCNC tables, or
        a number where it means one (``gvarget(6060)``, ``exit(99)``)."""
        if not word[0].isdigit():
            return self.registers.select_name(word)
        from plcbuilder.lang import symbols as lang_symbols    # (not needed to start up)
        value = lang_symbols.number_of(word)
        line0 = ed.lineFromPosition(start)
        context = lang_symbols.number_context(ed.byte_range_text(ed.positionFromLine(line0),
                                                                  start))
        kind = {"register": "register", "exit": "exit code", "message": "message",
                "proc": "proc state"}.get(context)
        return value is not None and kind is not None and self.registers.select_number(value, kind)

    # ============================================================ signals
    def on_project_opened(self, root: str) -> None:
        """Another project: the history and the old project's results go."""
        self.nav.clear()
        self._root = Path(root)
        for key in ("references", "find"):
            panel = self.panels.made.get(key)
            if panel is not None:
                panel.tree.root = self._root
                panel.tree.clear()
        if "references" in self.panels.made:
            self.references.summary.setText("Shift+F12 on a name lists where it is used")
        if "find" in self.panels.made:
            self.find_panel.summary.setText("")

    def on_current_changed(self, ed) -> None:
        self.outline.set_editor(ed)
        self.refresh_build_views()

    def on_cursor_moved(self, line: int, _col: int) -> None:
        ed = self.win.current_editor()
        if ed is not None and not self.win.disasm_dock.isHidden():
            self.disasm.follow(ed.path, line)       # (shown: made)

    def on_editor_created(self, ed) -> None:
        # Alt+Left/Right are Back/Forward, whatever Scintilla would make of them
        alt = 4 << 16
        for key in (300 + 2, 300 + 3):          # SCK_LEFT, SCK_RIGHT
            ed.clearCmdKey(key | alt)


def _rename_in_editor(ed, refs, new: str) -> None:
    """Replace each reference in the editor's text, as one undoable step."""
    ed.beginUndoAction()
    try:
        for r in sorted(refs, key=lambda r: (r.line, r.col), reverse=True):
            start = ed.position_of(r.line, r.col)
            end = ed.position_of(r.line, r.end_col)
            ed.setTargetRange(start, end)
            ed.replaceTarget(len(new.encode("utf-8")), new)
    finally:
        ed.endUndoAction()


# ===================================================================== install
def dock_panel(win, key: str):
    """The panel of a workbench dock (Outline, Find in Files, References,
    Disassembly, Registers: docks.DOCKS)."""
    return win.workbench.dock_panel(key)


def dock_panel_made(win, key: str) -> None:
    """A workbench dock's panel is in its dock (docks.DOCKS)."""
    win.workbench._panel_made(key)


def install(win) -> Workbench:
    """The features' actions, menus and signals for ``win`` (its
    :class:`Workbench` made, and its docks by the window's table)."""
    wb = win.workbench
    _actions(win, wb)
    _menus(win)
    es = win.editor_stack
    es.sig_current_changed.connect(wb.on_current_changed)
    es.sig_cursor_moved.connect(wb.on_cursor_moved)
    es.sig_editor_created.connect(wb.on_editor_created)
    win.lint.sig_diagnostics_updated.connect(wb.refresh_build_views)
    win.tree.sig_file_deleted.connect(wb.nav.forget_file)
    win.sig_project_opened.connect(wb.on_project_opened)
    wb.outline.sig_goto.connect(lambda line, col: wb.jump(win.current_editor().path, line, col)
                                if win.current_editor() is not None else None)
    wb.nav.sig_changed.connect(lambda b, f: (win.action(Act.BACK).setEnabled(b),
                                             win.action(Act.FORWARD).setEnabled(f)))
    win.action(Act.BACK).setEnabled(False)
    win.action(Act.FORWARD).setEnabled(False)
    return wb


def _actions(win, wb: Workbench) -> None:
    a = win._actions

    def A(*args, **kw):
        return acts.add_action(win, a, *args, **kw)

    A(Act.BACK, "Go &Back", wb.nav.back, "Alt+Left", None,
      "Back to where the caret was before the last jump")
    A(Act.FORWARD, "Go &Forward", wb.nav.forward, "Alt+Right", None,
      "Forward again, after Go Back")
    A(Act.QUICK_OPEN, "&Quick Open…", wb.quick_open, "Ctrl+P", "open",
      "Open a project file by typing part of its name")
    A(Act.FIND_IN_FILES, "Find in &Files…", wb.find_in_files, "Ctrl+Shift+F", "find",
      "Search every source and header of the project")
    A(Act.FIND_REFERENCES, "Find &References", wb.find_references, "Shift+F12", None,
      "List every place the name under the caret is used", editor_scope=True)
    A(Act.RENAME_SYMBOL, "Re&name Symbol…", wb.rename_symbol, "F2", "rename",
      "Rename the name under the caret everywhere it is used, after a preview",
      editor_scope=True)
    A(Act.SHOW_DISASSEMBLY, "Show &Disassembly", wb.show_disassembly, "Ctrl+Shift+D", None,
      "The code of the current procedure, with its source lines")
    act = A(Act.CODE_BYTES, "Code &Bytes in Margin", None, None, None,
            "Show the code bytes of each source line beside it", checkable=True)
    act.toggled.connect(wb.set_show_bytes)
    act.setChecked(str(win.settings.qs.value(CODE_BYTES_KEY, False)).lower() == "true")
    A(Act.REGISTERS, "&Registers", lambda: (win.registers_dock.show(),
                                            win.registers_dock.raise_(),
                                            wb.registers.search.setFocus()), None, None,
      "Every register, message, exit code and proc value, searchable")
    A(Act.MANUAL, "PLC Builder &Manual", wb.show_manual, "F1", "info",
      "Open the manual")
    A(Act.SHORTCUTS, "&Keyboard Shortcuts", wb.show_shortcuts, None, None,
      "Every action that has a key")
    A(Act.WHAT_IS_THIS, "&What Is This?", wb.what_is_this, "Shift+F1", None,
      "What the name or number under the caret is", editor_scope=True)
    win.editor_stack.context_actions = list(win.editor_stack.context_actions) + \
        [None, a[Act.FIND_REFERENCES], a[Act.RENAME_SYMBOL], a[Act.WHAT_IS_THIS]]


def _menu(win, title: str) -> Optional[QMenu]:
    for act in win.menuBar().actions():
        if act.menu() is not None and act.text().replace("&", "") == title:
            return act.menu()
    return None


def _menus(win) -> None:
    a = win.action
    edit = _menu(win, "Edit")
    if edit is not None:
        edit.addAction(a(Act.FIND_REFERENCES))
        edit.addAction(a(Act.RENAME_SYMBOL))
        edit.addSeparator()
        edit.addAction(a(Act.FIND_IN_FILES))
    view = _menu(win, "View")
    go = QMenu("&Go", win)
    for name in (Act.BACK, Act.FORWARD, None, Act.QUICK_OPEN, Act.GOTO_LINE,
                 Act.GOTO_DEFINITION, Act.FIND_REFERENCES):
        go.addAction(a(name)) if name else go.addSeparator()
    if view is not None:
        win.menuBar().insertMenu(view.menuAction(), go)
    else:
        win.menuBar().addMenu(go)
    build = _menu(win, "Build")
    if build is not None:
        build.addAction(a(Act.BUILD_UPLOAD_START))
        build.addSeparator()
        build.addAction(a(Act.SHOW_DISASSEMBLY))
        build.addAction(a(Act.CODE_BYTES))
    run = _menu(win, "Run")
    if run is not None:
        run.addSeparator()
        run.addAction(a(Act.REGISTERS))
    help_menu = _menu(win, "Help")
    if help_menu is not None:
        about = help_menu.actions()[0] if help_menu.actions() else None
        for name in (Act.MANUAL, Act.SHORTCUTS, Act.WHAT_IS_THIS):
            help_menu.insertAction(about, a(name))
        help_menu.insertSeparator(about)
    acts.fill_view_menu(win)
    win.view_menu.addSeparator()
    win.view_menu.addAction(a(Act.CODE_BYTES))
    tb = getattr(win, "toolbar", None)
    if tb is not None:
        tb.insertAction(a(Act.START), a(Act.BUILD_UPLOAD_START))
