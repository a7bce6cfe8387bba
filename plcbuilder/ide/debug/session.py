"""The debug session: the IDE side of SPEC §6.

It owns the project's breakpoints (:class:`BreakpointStore`) and sends each
file's to the controller when they change, when the controller (re)connects
and after an upload; it attaches the breakpoint margin, markers and inline
values to every editor; and it follows the controller: halted (the lines of
every running procedure marked and scrolled to, the halting one opened, the
Call Stack and Watch filled, inline values at the ends of lines) or running.
The debug verbs (continue, pause, steps, run to line) and write/force/release
go through the :class:`~plcbuilder.ide.connection.ControllerConnection`.
"""

from __future__ import annotations

import base64
from pathlib import Path
from typing import TYPE_CHECKING, Optional

from PySide6.QtCore import QObject, QTimer, Signal
from PySide6.QtWidgets import QMenu

from plcbuilder.ide.debug.breakpoints import Breakpoint, BreakpointStore
from plcbuilder.ide.editor import file_key

if TYPE_CHECKING:
    from plcbuilder.ide.docks import PanelsView

SOURCE_SUFFIXES = (".plc", ".h")
#: The debug docks' keys (docks.DOCKS).
DOCKS = ("callstack", "breakpoints", "forces")
SAVE_DELAY_MS = 300


class DebugSession(QObject):
    """Breakpoints, the halted state and the debug verbs of the main window."""

    sig_state_changed = Signal()
    """Halted, resumed, connected or disconnected: the debug actions follow."""

    sig_message = Signal(str, int)
    """A message for the status bar (text, milliseconds; 0: until the next)."""

    def __init__(self, win):
        super().__init__(win)
        self.win = win
        self.store = BreakpointStore(self)
        self.halted: Optional[dict] = None
        self.picked: Optional[tuple[str, int, str, int]] = None   # a frame clicked
        self.forces: list[dict] = []
        self.root: Optional[Path] = None
        self._sent: dict[str, list[Breakpoint]] = {}
        self._send_due: set[str] = set()
        self._send_timer = _single_shot(self, 0, self._send_pending)
        self._save_timer = _single_shot(self, SAVE_DELAY_MS, self.save)
        #: the docks' panels, made when first shown or used (docks.DOCKS)
        self.panels: Optional["PanelsView"] = None
        self.store.sig_changed.connect(self._on_store_changed)
        win.tree.sig_file_renamed.connect(self.store.rename)
        win.tree.sig_file_deleted.connect(lambda p: self.store.clear(p))

    def wire_connection(self) -> None:
        """Follow the new editors (after the lint, whose hover it extends) and
        the controller connection (once the window has one)."""
        self.win.editor_stack.sig_editor_created.connect(self.attach)
        c = self.connection
        if c is not None and hasattr(c, "sig_halted"):
            c.sig_halted.connect(self._on_halted)
            c.sig_resumed.connect(self._on_resumed)
            c.sig_breakpoints.connect(self._on_breakpoint_answers)
            c.sig_breakpoints_refused.connect(self._on_breakpoints_refused)
            c.sig_forces_changed.connect(self._on_forces)
            c.sig_connected.connect(self._on_connected)
            c.sig_disconnected.connect(self._on_disconnected)
            c.sig_result.connect(self._on_result)

    # ================================================================ docks
    @property
    def call_stack(self):
        """The Call Stack dock's panel (made when first shown or used)."""
        return self.panels.get("callstack")

    @property
    def breakpoints_panel(self):
        """The Breakpoints dock's panel."""
        return self.panels.get("breakpoints")

    @property
    def forces_panel(self):
        """The Forces dock's panel."""
        return self.panels.get("forces")

    def make_panel(self, key: str):
        """A dock's panel, wired and brought up to date (the window's dock table makes it the
        first time it shows or is used)."""
        if key == "callstack":
            from plcbuilder.ide.debug.callstack import CallStackPanel
            panel = CallStackPanel()
            panel.sig_frame_selected.connect(self.pick_frame)
            panel.show_state(self.halted)
        elif key == "breakpoints":
            from plcbuilder.ide.debug.breakpoints_panel import BreakpointsPanel
            panel = BreakpointsPanel(self.store)
            panel.sig_open_location.connect(lambda path, line: self.win.open_file(path, line))
            panel.sig_edit.connect(lambda bp: self.edit_breakpoint(bp))
        else:
            from plcbuilder.ide.debug.forces_panel import ForcesPanel
            panel = ForcesPanel()
            panel.sig_force.connect(self.force)
            panel.sig_release.connect(self.release)
            panel.sig_release_all.connect(self.release_all)
            panel.show_forces(self.forces)
        return panel

    def _made(self, key: str):
        """A dock's panel if it was made (None: it catches up when it is)."""
        return self.panels.made.get(key) if self.panels is not None else None

    # ================================================================ state
    @property
    def connection(self):
        return self.win.connection

    def debuggable(self) -> bool:
        """The connection speaks the debugger's messages."""
        c = self.connection
        return c is not None and hasattr(c, "debug_step") and bool(getattr(c, "debugger", False))

    def connected(self) -> bool:
        return self.debuggable() and bool(getattr(self.connection, "connected", False))

    def is_halted(self) -> bool:
        return self.halted is not None

    def procedures(self) -> list[dict]:
        return list((self.halted or {}).get("procedures") or ())

    def step_procedure(self) -> Optional[str]:
        """Whose statements a step steps: the frame picked, else the procedure
        that halted, else the current editor's, else the first running."""
        if self.picked is not None:
            return self.picked[0]
        st = self.halted or {}
        from plcbuilder.ide.debug.callstack import halting_ended
        if st.get("procedure") and not halting_ended(st):
            return str(st["procedure"])
        names = [str(p.get("name")) for p in self.procedures()]
        ed = self.win.current_editor()
        if ed is not None and Path(ed.path).stem in names:
            return Path(ed.path).stem
        return names[0] if names else None

    # ============================================================ project
    def project_opened(self, root) -> None:
        """Load the project's breakpoints (the previous project's are saved first)."""
        self.save()
        self.root = Path(root)
        self.store.load_list(self.win.settings.breakpoints(self.root), self.root)

    def project_closed(self) -> None:
        self.save()
        self.root = None
        self.store.load_list([], None)

    def save(self) -> None:
        if self.root is not None:
            self.win.settings.save_breakpoints(self.root, self.store.to_list(self.root))

    # ========================================================= the editors
    def attach(self, ed) -> None:
        """A new editor: breakpoint margin and markers, hover values, and the
        halted marks when halted."""
        from plcbuilder.ide.debug.markers import EditorMarks    # Scintilla: with the editors
        marks = EditorMarks(ed)
        ed.debug_marks = marks
        ed.sig_margin_clicked.connect(lambda line, _mods, e=ed: self.toggle_breakpoint(e, line))
        ed.margin_menu_provider = self.margin_menu
        ed.sig_text_changed.connect(lambda e=ed: self._follow_edits(e))
        base = ed.hover_provider
        ed.hover_provider = lambda e, pos, base=base: self._hover(e, pos, base)
        marks.show_breakpoints(self.store.for_file(ed.path))
        if self.halted is not None:
            self._show_in(ed)

    def breakable(self, ed) -> bool:
        return ed is not None and Path(ed.path).suffix.lower() in SOURCE_SUFFIXES

    def toggle_breakpoint(self, ed=None, line: Optional[int] = None) -> Optional[Breakpoint]:
        """Add or remove a breakpoint (the current editor's caret line by default)."""
        ed = ed or self.win.current_editor()
        if not self.breakable(ed):
            return None
        if line is None:
            line = ed.cursor_line_col()[0]
        return self.store.toggle(ed.path, line)

    def margin_menu(self, ed, line: int) -> Optional[QMenu]:
        """The menu of a right-click in the breakpoint margin."""
        if not self.breakable(ed):
            return None
        menu = QMenu(ed)
        bp = self.store.at(ed.path, line)

        def add(text, name, slot, enabled=True):
            act = menu.addAction(text, slot)
            act.setObjectName(name)
            act.setEnabled(enabled)
        if bp is None:
            add("Add Breakpoint", "add", lambda: self.store.toggle(ed.path, line))
            add("Add Conditional Breakpoint…", "add_condition",
                lambda: self._add_with(ed.path, line, "condition"))
            add("Add Hit Count Breakpoint…", "add_hit", lambda: self._add_with(ed.path, line, "hit"))
            add("Add Logpoint…", "add_log", lambda: self._add_with(ed.path, line, "log"))
        else:
            add("Remove Breakpoint", "remove", lambda: self.store.remove(bp))
            add("Disable Breakpoint" if bp.enabled else "Enable Breakpoint", "enable",
                lambda: self.store.update(bp, enabled=not bp.enabled))
            add("Edit Condition…", "edit_condition", lambda: self.edit_breakpoint(bp, "condition"))
            add("Edit Hit Count…", "edit_hit", lambda: self.edit_breakpoint(bp, "hit"))
            add("Edit Log Message…", "edit_log", lambda: self.edit_breakpoint(bp, "log"))
        menu.addSeparator()
        add("Run to Line", "run_to", lambda: self.run_to(ed.path, line), self.connected())
        return menu

    def edit_breakpoint(self, bp: Breakpoint, focus: str = "condition") -> bool:
        from plcbuilder.ide.debug.breakpoint_dialog import BreakpointDialog
        dlg = BreakpointDialog(self.win, bp, lambda text: self.condition_error(text, bp.path),
                               focus)
        if dlg.exec() != BreakpointDialog.DialogCode.Accepted:
            return False
        self.store.update(bp, **dlg.values())
        return True

    def _add_with(self, path: str, line: int, focus: str) -> None:
        bp = Breakpoint(str(path), line)
        if self.edit_breakpoint(bp, focus):
            self.store.add(bp)

    def _follow_edits(self, ed) -> None:
        marks = getattr(ed, "debug_marks", None)
        if marks is None:
            return
        moved = False
        for bp, line in marks.moved_lines().values():
            if bp.line != line:
                bp.line, moved = line, True
        if moved:
            self.store.move_lines(ed.path, {})
            self._refresh_breakpoints()
            self._save_timer.start()

    def _redraw(self, path: str = "") -> None:
        key = file_key(path) if path else None
        for ed in self.win.editors():
            if key is None or file_key(ed.path) == key:
                marks = getattr(ed, "debug_marks", None)
                if marks is not None:
                    marks.show_breakpoints(self.store.for_file(ed.path))

    # ================================================ breakpoints → controller
    def _refresh_breakpoints(self) -> None:
        if self._made("breakpoints") is not None:
            self.breakpoints_panel.refresh()

    def _on_store_changed(self, path: str) -> None:
        self._redraw(path)
        self._save_timer.start()
        if path:
            self._send_due.add(Path(path).name)
        else:
            self._send_due |= {Path(p).name for p in self.store.files()} | set(self._sent)
        self._send_timer.start()

    def send_all(self) -> None:
        """Send every file's breakpoints (a new controller, a new image)."""
        self._send_due |= {Path(p).name for p in self.store.files()} | set(self._sent)
        self._send_pending()

    def _send_pending(self) -> None:
        due, self._send_due = self._send_due, set()
        if not self.connected():
            return
        for name in sorted(due):
            self._send_file(name)

    def _send_file(self, file_name: str) -> None:
        specs, sent, refused = [], [], set()
        for bp in self.store.all():
            if bp.file_name != file_name:
                continue
            spec = bp.spec()
            if bp.condition:
                code, error = self.compile_condition(bp.condition, bp.path)
                if error:
                    self.store.mark_refused(bp, f"the condition does not compile: {error}")
                    refused.add(bp.path)
                    continue
                spec["condition"] = {"text": bp.condition, "code": code}
            specs.append(spec)
            sent.append(bp)
        self._sent[file_name] = sent
        for p in refused:
            self._redraw(p)
        if refused:
            self._refresh_breakpoints()
        self.connection.set_breakpoints(file_name, specs)

    def compile_condition(self, text: str, path: str = "") -> tuple[Optional[str], Optional[str]]:
        """(the compiled condition as base64, None) or (None, the error)."""
        from plcbuilder import api
        fn = getattr(api, "compile_condition", None)
        if fn is None:
            return None, None
        # the breakpoint's file gives the condition its #include and #define lines
        where = path if path and not str(path).startswith("<") else (
            self.win.project.root if self.win.project is not None else None)
        try:
            result = fn(text, where)
        except Exception as exc:  # noqa: BLE001 - a compiler bug is a refused condition
            return None, f"{type(exc).__name__}: {exc}"
        if isinstance(result, (bytes, bytearray)):
            return base64.b64encode(bytes(result)).decode("ascii"), None
        diags = list(result) if isinstance(result, (list, tuple)) else [result]
        msgs = [getattr(d, "message", str(d)) for d in diags]
        return None, "; ".join(msgs) or "it does not compile"

    def condition_error(self, text: str, path: str = "") -> Optional[str]:
        return self.compile_condition(text, path)[1]

    def _on_breakpoint_answers(self, file_name: str, answers: list) -> None:
        for p in self.store.set_answers(self._sent.get(file_name, []), answers):
            self._redraw(p)
        self._refresh_breakpoints()

    def _on_breakpoints_refused(self, file_name: str, reason: str) -> None:
        for bp in self._sent.get(file_name, []):
            self.store.mark_refused(bp, reason)
            self._redraw(bp.path)
        self._refresh_breakpoints()

    def _on_connected(self, _address: str) -> None:
        self.store.reset_answers()
        self._sent.clear()
        self.send_all()
        self.sig_state_changed.emit()

    def _on_disconnected(self, _reason: str) -> None:
        if self.halted is not None:
            self._on_resumed(0)
        self.sig_state_changed.emit()

    def _on_result(self, verb: str, _result: dict) -> None:
        if verb in ("upload", "reset"):
            self.send_all()               # breakpoints stay on their lines after a rebuild

    # ============================================================== halted
    def _on_halted(self, state: dict) -> None:
        self.halted = state
        self.picked = None
        self.call_stack.show_state(state)
        dock = getattr(self.win, "callstack_dock", None)
        if dock is not None:                # it shares its tabs with Outline and Breakpoints
            dock.show()
            dock.raise_()
        for ed in self.win.editors():
            self._show_in(ed, scroll=True)
        from plcbuilder.ide.debug.callstack import current_procedure, halted_text
        # where it is now: the line that halted, or (the procedure that halted
        # ended since, as after Stop) the line the procedure that runs now waits at
        now = current_procedure(state) or {}
        file, line = state.get("file") or now.get("file"), state.get("line") or now.get("line")
        if file and line:
            ed = self.win.open_location(str(file), int(line))
            if ed is not None:
                self._show_in(ed, scroll=True)
        self._update_watch()
        self.sig_message.emit(halted_text(state), 0)
        self.sig_state_changed.emit()

    def _on_resumed(self, _t_ms: int) -> None:
        self.halted = None
        self.picked = None
        if self._made("callstack") is not None:
            self.call_stack.show_state(None)
        for ed in self.win.editors():
            marks = getattr(ed, "debug_marks", None)
            if marks is not None:
                marks.clear()
        self.sig_message.emit("Running", 2000)
        self.sig_state_changed.emit()

    def pick_frame(self, procedure: str, index: int, file: str, line: int) -> None:
        """A call stack frame was clicked: go to its line (marked as a caller's
        line when it is not the innermost frame)."""
        self.picked = (procedure, index, file, line) if index else (procedure, 0, file, line)
        if file and line:
            ed = self.win.open_location(file, line)
            if ed is not None:
                for e in self.win.editors():
                    self._show_in(e)
        self._update_watch(procedure)

    def _show_in(self, ed, scroll: bool = False) -> None:
        """Mark one editor for the halted state: the lines procedures are at,
        the picked caller's line, the inline values."""
        marks = getattr(ed, "debug_marks", None)
        if marks is None or self.halted is None:
            return
        # loaded when first halted, not before the window's first paint
        from plcbuilder.ide.debug.callstack import frames_of
        from plcbuilder.ide.debug.inline import inline_values
        name, stem = Path(ed.path).name, Path(ed.path).stem
        exec_lines, wait_lines, frame_lines = [], [], []
        values = None
        owner = None
        for proc in self.procedures():
            pname = str(proc.get("name"))
            if proc.get("file") and Path(str(proc["file"])).name == name and proc.get("line"):
                (wait_lines if proc.get("at_loop_end") else exec_lines).append(int(proc["line"]))
            if self.picked and self.picked[0] == pname and self.picked[1]:
                for f in frames_of(proc):
                    if f["index"] == self.picked[1] and f.get("file") and \
                            Path(str(f["file"])).name == name:
                        frame_lines.append(int(f["line"]))
            if pname == stem or (owner is None and proc.get("file")
                                 and Path(str(proc["file"])).name == name):
                values, owner = proc.get("vars") or {}, pname
        marks.show_exec(exec_lines, wait_lines, frame_lines)
        if values:
            forced = frozenset(t.split(".", 1)[1] for t in self.forced_targets()
                               if t.startswith(f"{owner}."))
            marks.show_inline(inline_values(ed.text(), values, forced=forced))
        else:
            marks.show_inline({})
        lines = exec_lines or wait_lines
        if scroll and lines:
            ed.scroll_to_line(lines[0])

    def _update_watch(self, current: Optional[str] = None) -> None:
        panels = getattr(self.win, "run_panels", None)
        if panels is None or self.halted is None:
            return
        variables = {str(p.get("name")): dict(p.get("vars") or {}) for p in self.procedures()}
        if variables:
            panels.watch.set_variables(variables, current or self.step_procedure())

    def values_for(self, ed) -> tuple[Optional[str], dict]:
        """(procedure, its variables) shown for an editor: the halted state's,
        else the watch's last poll of the editor's procedure."""
        stem, name = Path(ed.path).stem, Path(ed.path).name
        if self.halted is not None:
            for proc in self.procedures():
                if str(proc.get("name")) == stem:
                    return stem, dict(proc.get("vars") or {})
            for proc in self.procedures():
                if proc.get("file") and Path(str(proc["file"])).name == name:
                    return str(proc.get("name")), dict(proc.get("vars") or {})
            return None, {}
        panels = getattr(self.win, "run_panels", None)
        if panels is not None and getattr(self.connection, "connected", False):
            return stem, dict(panels.watch.variables.get(stem, {}))
        return None, {}

    def _hover(self, ed, pos: int, base) -> Optional[str]:
        text = base(ed, pos) if base is not None else None
        _s, _e, word = ed.word_at(pos)
        proc, values = self.values_for(ed)
        from plcbuilder.ide.debug.inline import hover_value
        live = hover_value(word, values, proc or "", halted=self.halted is not None,
                           forced=f"{proc}.{word}" in self.forced_targets()) if proc else None
        if live and text:
            return f"{live}\n{text}"
        return live or text

    # ============================================================== verbs
    def continue_(self) -> None:
        if self.connected():
            self._send_pending()          # breakpoints just changed go first
            self.connection.debug_continue()

    def pause(self) -> None:
        if self.connected():
            self.connection.debug_pause()
            self.sig_message.emit("Pausing at the end of this tick…", 3000)

    def step(self, kind: str) -> None:
        """``over``, ``into``, ``out`` (statements) or ``tick`` (1 ms)."""
        if not self.connected():
            return
        proc = None if kind == "tick" else self.step_procedure()
        self._send_pending()
        self.connection.debug_step(kind, proc)

    def step_back(self, kind: str) -> None:
        """Back one ``statement`` (of the procedure halted) or one ``tick``: the
        controller runs the session again from its recording (SPEC §7)."""
        if not self.connected():
            return
        self._send_pending()
        self.connection.debug_step_back(kind)
        self.sig_message.emit("Stepping back: running the session again…", 3000)

    def run_back(self) -> None:
        """Back to the previous breakpoint hit (SPEC §7)."""
        if not self.connected():
            return
        self._send_pending()
        self.connection.debug_run_back()
        self.sig_message.emit("Running back to the previous breakpoint hit…", 3000)

    def run_to(self, path: Optional[str] = None, line: Optional[int] = None) -> bool:
        """Run until a line is reached (the current editor's caret line by default)."""
        if not self.connected():
            return False
        if path is None:
            ed = self.win.current_editor()
            if not self.breakable(ed):
                return False
            path, line = ed.path, ed.cursor_line_col()[0]
        self._send_pending()
        self.connection.debug_run_to(Path(path).name, int(line))
        self.sig_message.emit(f"Running to {Path(path).name}:{line}…", 3000)
        return True

    # ======================================================== write / force
    def write(self, target: str, value: int) -> None:
        if self.connected():
            self.connection.write(target, value)

    def force(self, target: str, value: int) -> None:
        if self.connected():
            self.connection.force(target, value)

    def release(self, target: str, mode: str = "keep") -> None:
        if self.connected():
            self.connection.release(target, mode)

    def release_all(self, mode: str = "keep") -> None:
        if self.connected():
            self.connection.release_all(mode)

    def forced_targets(self) -> set[str]:
        return {str(f.get("target")) for f in self.forces}

    def _on_forces(self, forces: list) -> None:
        self.forces = list(forces)
        if self._made("forces") is not None:
            self.forces_panel.show_forces(self.forces)
        panels = getattr(self.win, "run_panels", None)
        if panels is not None and hasattr(panels, "set_forces"):
            panels.set_forces(self.forces)
        if self.halted is not None:
            for ed in self.win.editors():
                self._show_in(ed)


def _single_shot(parent, ms: int, slot) -> QTimer:
    t = QTimer(parent)
    t.setSingleShot(True)
    t.setInterval(ms)
    t.timeout.connect(slot)
    return t
