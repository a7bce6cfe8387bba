"""The Project panel: the project's procedures and files as a tree.

    my machine
      Hardware PLC      hardware/*.plc (M03 is what M03 starts)
      Software PLC      software/*.plc (__NAME: system procedures)
      Headers           include/*.h (and the built-in pins.h when the project has none)
      Machine           the simulated machine description
      Variables         plc-variables.xml (var00..var15)
      Settings          plcbuilder.toml

New, rename, duplicate and delete procedures (and headers) from the context
menu, each with its dialog. The tree follows the folders on disk
(a QFileSystemWatcher on them, re-armed after every change).
"""

from __future__ import annotations

import os
import re
import shutil
from pathlib import Path
from typing import Optional

from PySide6.QtCore import QFileSystemWatcher, Qt, QTimer, Signal
from PySide6.QtGui import QAction, QBrush, QColor
from PySide6.QtWidgets import (QAbstractItemView, QLabel, QMenu, QStyledItemDelegate, QMessageBox, QTreeWidget,
                               QTreeWidgetItem, QVBoxLayout, QWidget)

from plcbuilder.api import Kind
from plcbuilder.ide import dialogs
from plcbuilder.ide.editor import file_key
from plcbuilder.ide.first_frame import (HARDWARE_GROUP, HEADERS_GROUP, SOFTWARE_GROUP,
                                        TARGET_LABEL, procedure_icon)
from plcbuilder.ide.icons import icon
from plcbuilder.ide.looks import set_text_colour
from plcbuilder._support.files import atomic_write
from plcbuilder.project.model import Project

ROLE_PATH = Qt.ItemDataRole.UserRole + 1
ROLE_WHAT = Qt.ItemDataRole.UserRole + 2
ROLE_DESCRIPTION = Qt.ItemDataRole.UserRole + 3
#: descriptions read per turn of the event loop
DESCRIBE_BATCH = 64

# what an item is
W_PROJECT = "project"
W_HW_FOLDER = "hardware"
W_SW_FOLDER = "software"
W_HEADERS = "headers"
W_PROCEDURE = "procedure"
W_HEADER = "header"
W_BUILTIN_HEADER = "builtin-header"
W_FILE = "file"
W_TARGET_PROC = "target-procedure"     # a procedure a target calls (init, Program_04, ...)

BUILTIN_PINS = "<builtin>/pins.h"


def procedure_template(name: str, kind: Kind) -> str:
    """The text of a new procedure."""
    if kind is Kind.SOFTWARE:
        return (f"// {name}: software procedure (ticks of 100 ms, runs beside the others)\n"
                "#include pins.h\n\n"
                "main()\n{\n"
                "    do {\n"
                "        // poll inputs, drive outputs ...\n"
                "        timer = timer + 1;\n"
                "    } while (1);\n"
                "};\n")
    return (f"// {name}: hardware procedure\n"
            "#include pins.h\n\n"
            "main()\n{\n"
            "    // ...\n"
            "    exit(99);        // plc_exit_normal\n"
            "};\n")


def target_outline(project: Project) -> list[tuple[str, str]]:
    """(procedure, when the target calls it) for a target project (docs/targets.md);
    [] for a myCNC project."""
    st = project.settings
    if st.target == "huazhong":
        return [("init", "once, at the start"),
                ("plc1", "every plc1_time ms (16 until set)"),
                ("plc2", "every plc2_time ms (32 until set)")]
    if st.target == "tgmotion":
        from plcbuilder.lang.targets import slots_per_cycle
        slot = st.cycle_time_us / slots_per_cycle(st.cycle_time_us)
        p1, p2, p3 = st.program_periods_us
        return [("Program_Ini", "once, at the start"),
                ("Program_01", f"every {p1} µs, lowest priority"),
                ("Program_02", f"every {p2} µs"),
                ("Program_03", f"every {p3} µs"),
                ("Program_04", f"every cycle ({st.cycle_time_us} µs), in the fourth slot"),
                ("Program_05", f"every slot ({slot:g} µs)")]
    return []




def header_template(name: str) -> str:
    guard = "".join(c if c.isalnum() else "_" for c in name.upper())
    return f"// {name}\n#ifndef {guard}\n#define {guard}\n\n#endif\n"


class ProjectTree(QWidget):
    """The Project dock's widget."""

    sig_open_file = Signal(str)
    """Open this file in an editor (a path, or <builtin>/NAME)."""

    sig_file_created = Signal(str)
    """A procedure or header was created (path); the main window opens it."""

    sig_file_renamed = Signal(str, str)
    """A file was renamed (old path, new path)."""

    sig_file_deleted = Signal(str)
    """A file was deleted (path)."""

    sig_start_procedure = Signal(str)
    """Start this procedure on the controller (name)."""

    sig_changed = Signal()
    """The files of the project changed on disk (listing refreshed)."""

    def __init__(self, parent=None):
        super().__init__(parent)
        self.project: Optional[Project] = None
        #: called before renaming/deleting a file: (path, action) -> proceed?
        self.before_file_change = None
        self._running: Optional[str] = None
        self._problems: dict[str, int] = {}      # file key -> 1 error, 2 warning
        # the files' descriptions (first comments) are read after the tree is
        # built, a batch per turn of the event loop; held while the window has
        # not painted yet (see describing, release_descriptions)
        self._undescribed: list[tuple[QTreeWidgetItem, Path, str]] = []
        self.descriptions_held = False
        lay = QVBoxLayout(self)
        lay.setContentsMargins(0, 0, 0, 0)
        self.tree = QTreeWidget(self)
        self.tree.setHeaderHidden(True)
        self.tree.setItemDelegate(_DescriptionDelegate(self.tree))
        self.tree.setFrameShape(QTreeWidget.Shape.NoFrame)
        self.tree.setContextMenuPolicy(Qt.ContextMenuPolicy.CustomContextMenu)
        self.tree.setSelectionMode(QAbstractItemView.SelectionMode.SingleSelection)
        self.tree.setUniformRowHeights(True)
        self.tree.setIndentation(14)
        self.tree.setAnimated(True)
        self.placeholder = QLabel("No project is open.\n\nFile › New Project… creates one "
                                  "(myCNC, Huazhong or TG Motion);\nFile › Open Project… opens "
                                  "a project folder;\nFile › Open Example Project… makes a copy "
                                  "of the example to try.", self)
        self.placeholder.setWordWrap(True)
        self.placeholder.setAlignment(Qt.AlignmentFlag.AlignTop | Qt.AlignmentFlag.AlignLeft)
        self.placeholder.setContentsMargins(10, 10, 10, 10)
        set_text_colour(self.placeholder, "#8c959f")
        lay.addWidget(self.tree)
        lay.addWidget(self.placeholder, 1)
        self.tree.hide()
        self.tree.itemActivated.connect(self._activated)
        self.tree.customContextMenuRequested.connect(self._context_menu)
        self.watcher = QFileSystemWatcher(self)
        self.watcher.directoryChanged.connect(self._schedule_refresh)
        self._refresh_timer = QTimer(self)
        self._refresh_timer.setSingleShot(True)
        self._refresh_timer.setInterval(200)
        self._refresh_timer.timeout.connect(self._refresh_from_disk)
        self._listing: tuple = ()
        self._build_actions()

    # ---------------------------------------------------------------- public
    def set_project(self, project: Optional[Project]) -> None:
        self.project = project
        self.tree.setVisible(project is not None)
        self.placeholder.setVisible(project is None)
        self._listing = ()
        self._running = None
        self._problems = {}
        self.refresh(force=True)
        self._watch()

    def refresh(self, force: bool = False) -> None:
        """Rebuild the tree from disk (keeping expansion and selection)."""
        listing = self._scan()
        if not force and listing == self._listing:
            return
        self._listing = listing
        expanded, selected = self._view_state()
        self.tree.setUpdatesEnabled(False)
        self._undescribed = []                  # their items go with the clear
        self.tree.clear()
        p = self.project
        if p is None:
            self.tree.setUpdatesEnabled(True)
            return
        root = self._item(None, p.name or p.root.name, "project", W_PROJECT, str(p.root))
        root.setToolTip(0, str(p.root))
        f = root.font(0)
        f.setBold(True)
        root.setFont(0, f)
        target = p.settings.target
        hw = self._item(root, TARGET_LABEL.get(target, HARDWARE_GROUP[0]), HARDWARE_GROUP[1],
                        W_HW_FOLDER, str(p.hardware_dir))
        hw.setToolTip(0, "hardware/: procedures run by the controller's PLC core, 1 ms ticks; "
                         "an M-code starts the procedure of its name" if target == "mycnc" else
                      f"hardware/: the {target} target's one program (docs/targets.md)")
        sw = self._item(root, *SOFTWARE_GROUP, W_SW_FOLDER, str(p.software_dir))
        sw.setToolTip(0, "software/: procedures run by the host side by side, 100 ms ticks; "
                         "__HANDLER_* ones start on events")
        sw.setHidden(target != "mycnc" and not any(pr.kind is Kind.SOFTWARE
                                                   for pr in p.procedures()))
        outline = target_outline(p)
        for proc in p.procedures():
            parent = hw if proc.kind is Kind.HARDWARE else sw
            ic = procedure_icon(proc.kind is Kind.HARDWARE, proc.system)
            it = self._item(parent, proc.name, ic, W_PROCEDURE, str(proc.path))
            it.setToolTip(0, str(proc.path))
            self._undescribed.append((it, proc.path, proc.name))
            if outline and proc.kind is Kind.HARDWARE:
                self._target_procedures(it, proc.path, outline)
        headers = self._item(root, *HEADERS_GROUP, W_HEADERS, str(p.include_dir))
        headers.setToolTip(0, "include/: searched by #include after the procedure's own folder")
        names = set()
        for h in self._headers():
            names.add(h.name)
            it = self._item(headers, h.name, "file-header", W_HEADER, str(h))
            it.setToolTip(0, str(h))
            self._undescribed.append((it, h, h.stem))
        if "pins.h" not in names:
            it = self._item(headers, "pins.h (built-in)", "file-header", W_BUILTIN_HEADER, BUILTIN_PINS)
            it.setToolTip(0, "the built-in default pin map (read-only); copy it into include/ to edit")
            it.setForeground(0, QBrush(QColor("#7d8590")))
        files = [("Machine", "machine", p.machine_path),
                 ("Variables", "variables", p.variables_path),
                 ("Settings", "settings", p.settings_path)]
        if target == "huazhong":
            files.insert(1, ("Parameters (P)", "variables", p.parameters_path))
        for label, ic, path in files:
            text = f"{label}  ·  {path.name}"
            it = self._item(root, text, ic, W_FILE, str(path))
            it.setToolTip(0, str(path) + ("" if path.exists() else "  (not there yet)"))
            if not path.exists():
                it.setForeground(0, QBrush(QColor("#9a9a9a")))
        io_dat = p.root / "IO.DAT"               # softMC input presets, when the project has one
        if io_dat.is_file():
            it = self._item(root, "Input presets  ·  IO.DAT", "variables", W_FILE, str(io_dat))
            it.setToolTip(0, f"{io_dat}: INP presets inputs 0..22, DIP is register IO_DAT_DIP")
        self._apply_decorations()
        self._restore_view_state(expanded, selected, first=not expanded)
        self.tree.setUpdatesEnabled(True)
        self._describe_later()

    def describing(self) -> bool:
        """Whether descriptions are still to be read (tests and screenshots wait)."""
        return bool(self._undescribed)

    def release_descriptions(self) -> None:
        """The window has painted: the held descriptions may be read now."""
        self.descriptions_held = False
        self._describe_later()

    def set_running(self, name: Optional[str]) -> None:
        """Mark the procedure that runs on the controller."""
        if name != self._running:
            self._running = name
            self._apply_decorations()

    def set_problem_files(self, problems: dict[str, int]) -> None:
        """{file key: 1 (error) or 2 (warning)}: files drawn as having problems."""
        if problems != self._problems:
            self._problems = dict(problems)
            self._apply_decorations()

    def find_item(self, path_or_name: str) -> Optional[QTreeWidgetItem]:
        key = file_key(path_or_name)
        for it in self._all_items():
            p = it.data(0, ROLE_PATH)
            if p and (file_key(p) == key or it.text(0) == path_or_name):
                return it
        return None

    def select_path(self, path: str) -> None:
        it = self.find_item(path)
        if it is not None:
            self.tree.setCurrentItem(it)

    # -------------------------------------------------------------- actions
    def new_procedure(self, kind: Kind = Kind.HARDWARE) -> Optional[Path]:
        """Ask for a name and create the procedure; returns its path."""
        p = self.project
        if p is None:
            return None
        res = dialogs.ProcedureNameDialog.get_name(
            self, title="New Procedure", kind=kind, existing=self._names(), allow_kind=True,
            initial=_suggest_name(kind, self._names()))
        if res is None:
            return None
        name, kind = res
        path = p.new_procedure_path(name, kind)
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            atomic_write(path, procedure_template(name, kind))
        except OSError as exc:
            QMessageBox.critical(self, "New Procedure", f"Cannot create {path}:\n{exc}")
            return None
        self.refresh()
        self.sig_file_created.emit(str(path))
        return path

    def new_header(self) -> Optional[Path]:
        p = self.project
        if p is None:
            return None
        existing = {h.name for h in self._headers()}
        name = dialogs.HeaderNameDialog.get_name(self, existing)
        if name is None:
            return None
        path = p.include_dir / name
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            atomic_write(path, header_template(name))
        except OSError as exc:
            QMessageBox.critical(self, "New Header", f"Cannot create {path}:\n{exc}")
            return None
        self.refresh()
        self.sig_file_created.emit(str(path))
        return path

    def rename(self, path: str) -> Optional[Path]:
        """Rename a procedure (or header); returns the new path."""
        old = Path(path)
        if not old.exists():
            return None
        is_header = old.suffix == ".h"
        if is_header:
            existing = {h.name for h in self._headers()} - {old.name}
            new_name = dialogs.HeaderNameDialog.get_name(self, existing, initial=old.name,
                                                         title="Rename Header")
            if new_name is None or new_name == old.name:
                return None
            new = old.with_name(new_name)
        else:
            kind = Kind.SOFTWARE if old.parent.name == "software" else Kind.HARDWARE
            res = dialogs.ProcedureNameDialog.get_name(
                self, title=f"Rename {old.stem}", kind=kind, existing=self._names() - {old.stem},
                initial=old.stem)
            if res is None or res[0] == old.stem:
                return None
            new = old.with_name(res[0] + old.suffix)
        if self.before_file_change is not None and not self.before_file_change(str(old), "rename"):
            return None
        try:
            if new.exists():
                raise OSError(f"{new.name} exists")
            os.rename(old, new)
        except OSError as exc:
            QMessageBox.critical(self, "Rename", f"Cannot rename {old.name}:\n{exc}")
            return None
        self.refresh()
        self.sig_file_renamed.emit(str(old), str(new))
        return new

    def duplicate(self, path: str) -> Optional[Path]:
        old = Path(path)
        if not old.exists() or old.suffix != ".plc":
            return None
        kind = Kind.SOFTWARE if old.parent.name == "software" else Kind.HARDWARE
        names = self._names()
        initial = old.stem + "_copy"
        i = 2
        while initial in names:
            initial = f"{old.stem}_copy{i}"
            i += 1
        res = dialogs.ProcedureNameDialog.get_name(
            self, title=f"Duplicate {old.stem}", kind=kind, existing=names, initial=initial,
            allow_kind=True)
        if res is None:
            return None
        name, kind = res
        new = self.project.new_procedure_path(name, kind)
        try:
            new.parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(old, new)
        except OSError as exc:
            QMessageBox.critical(self, "Duplicate", f"Cannot copy {old.name}:\n{exc}")
            return None
        self.refresh()
        self.sig_file_created.emit(str(new))
        return new

    def delete(self, path: str) -> bool:
        p = Path(path)
        if not p.exists():
            return False
        answer = QMessageBox.question(
            self, "Delete", f"Delete {p.name}?\n\n{p}\n\nThis cannot be undone.",
            QMessageBox.StandardButton.Yes | QMessageBox.StandardButton.No,
            QMessageBox.StandardButton.No)
        if answer != QMessageBox.StandardButton.Yes:
            return False
        if self.before_file_change is not None and not self.before_file_change(str(p), "delete"):
            return False
        try:
            p.unlink()
        except OSError as exc:
            QMessageBox.critical(self, "Delete", f"Cannot delete {p.name}:\n{exc}")
            return False
        self.refresh()
        self.sig_file_deleted.emit(str(p))
        return True

    # --------------------------------------------------------------- private
    def _build_actions(self) -> None:
        self.action_new_hw = QAction(icon("new"), "New Hardware Procedure…", self)
        self.action_new_hw.triggered.connect(lambda: self.new_procedure(Kind.HARDWARE))
        self.action_new_sw = QAction(icon("new"), "New Software Procedure…", self)
        self.action_new_sw.triggered.connect(lambda: self.new_procedure(Kind.SOFTWARE))
        self.action_new_header = QAction(icon("file-header"), "New Header…", self)
        self.action_new_header.triggered.connect(self.new_header)

    def _item(self, parent, text, ic, what, path) -> QTreeWidgetItem:
        it = QTreeWidgetItem(parent if parent is not None else self.tree)
        it.setText(0, text)
        it.setIcon(0, icon(ic))
        it.setData(0, ROLE_WHAT, what)
        it.setData(0, ROLE_PATH, path)
        return it

    def _target_procedures(self, parent: QTreeWidgetItem, path: Path,
                           outline: list[tuple[str, str]]) -> None:
        """The procedures the target calls, under its program, each with when
        it runs; one the source does not define (yet) in grey."""
        try:
            text = path.read_text(encoding="utf-8", errors="replace")
        except OSError:
            text = ""
        for name, when in outline:
            it = self._item(parent, f"{name}()", "file-plc-sys", W_TARGET_PROC, str(path))
            it.setData(0, ROLE_DESCRIPTION, when)
            defined = re.search(rf"^\s*{name}\s*\(\s*\)", text, re.M) is not None
            it.setToolTip(0, f"{name}(): {when}" + ("" if defined else
                                                      "  (not in the program yet)"))
            if not defined:
                it.setForeground(0, QBrush(QColor("#9a9a9a")))

    def _describe_later(self) -> None:
        if self._undescribed and not self.descriptions_held:
            batch = self._undescribed
            QTimer.singleShot(0, self, lambda: self._describe_some(batch))

    def _describe_some(self, batch: list) -> None:
        """Read a batch of the files' first comments, in grey beside their names
        ("spindle on, clockwise"); the rest on the next turn. A project of a
        thousand procedures opens without waiting for a thousand reads, and
        the window's first paint waits for none."""
        if batch is not self._undescribed:
            return                           # the tree was built again meanwhile
        for item, path, name in batch[:DESCRIBE_BATCH]:
            text = first_comment(path, name)
            if text:
                item.setData(0, ROLE_DESCRIPTION, text)
                item.setToolTip(0, f"{path}\n{text}")
        del batch[:DESCRIBE_BATCH]
        self._describe_later()

    def _headers(self) -> list[Path]:
        d = self.project.include_dir if self.project else None
        if d is None or not d.is_dir():
            return []
        try:
            return sorted((h for h in d.iterdir() if h.suffix == ".h" and h.is_file()),
                          key=lambda h: h.name.lower())
        except OSError:
            return []

    def _names(self) -> set[str]:
        if self.project is None:
            return set()
        try:
            return {pr.name for pr in self.project.procedures()}
        except Exception:  # noqa: BLE001 - an unreadable folder lists as empty
            return set()

    def _scan(self) -> tuple:
        p = self.project
        if p is None:
            return ()
        try:
            procs = tuple((pr.kind, pr.name) for pr in p.procedures())
        except Exception:  # noqa: BLE001
            procs = ()
        return (p.name, procs, tuple(h.name for h in self._headers()),
                p.machine_path.exists(), p.variables_path.exists(), p.settings_path.exists(),
                p.settings.target, p.settings.program_periods_us, p.settings.cycle_time_us,
                (p.root / "IO.DAT").is_file())

    def _watch(self) -> None:
        old = self.watcher.directories() + self.watcher.files()
        if old:
            self.watcher.removePaths(old)
        p = self.project
        if p is None:
            return
        dirs = [str(d) for d in (p.root, p.hardware_dir, p.software_dir, p.include_dir) if d.is_dir()]
        if dirs:
            self.watcher.addPaths(dirs)

    def _schedule_refresh(self, *_args) -> None:
        self._refresh_timer.start()

    def _refresh_from_disk(self) -> None:
        before = self._listing
        self.refresh()
        self._watch()          # folders created or replaced meanwhile
        if self._listing != before:
            self.sig_changed.emit()

    def _all_items(self):
        stack = [self.tree.topLevelItem(i) for i in range(self.tree.topLevelItemCount())]
        while stack:
            it = stack.pop()
            yield it
            stack.extend(it.child(i) for i in range(it.childCount()))

    def _view_state(self):
        collapsed = set()
        for it in self._all_items():
            if it.childCount() and not it.isExpanded():
                collapsed.add(it.data(0, ROLE_WHAT) + ":" + str(it.data(0, ROLE_PATH)))
        cur = self.tree.currentItem()
        selected = cur.data(0, ROLE_PATH) if cur is not None else None
        return collapsed, selected

    def _restore_view_state(self, collapsed, selected, first=False) -> None:
        for it in self._all_items():
            if it.childCount():
                key = it.data(0, ROLE_WHAT) + ":" + str(it.data(0, ROLE_PATH))
                it.setExpanded(key not in collapsed)
            if selected and it.data(0, ROLE_PATH) == selected:
                self.tree.setCurrentItem(it)

    def _apply_decorations(self) -> None:
        for it in self._all_items():
            if it.data(0, ROLE_WHAT) not in (W_PROCEDURE, W_HEADER):
                continue
            path = it.data(0, ROLE_PATH)
            level = self._problems.get(file_key(path))
            running = it.data(0, ROLE_WHAT) == W_PROCEDURE and it.text(0) == self._running
            font = it.font(0)
            font.setBold(running)
            it.setFont(0, font)
            if level == 1:
                it.setForeground(0, QBrush(QColor("#d1242f")))
            elif level == 2:
                it.setForeground(0, QBrush(QColor("#9a6700")))
            elif running:
                it.setForeground(0, QBrush(QColor("#1a7f37")))
            else:
                it.setData(0, Qt.ItemDataRole.ForegroundRole, None)
            tip = str(path)
            if running:
                tip += "\nrunning on the controller"
            if level == 1:
                tip += "\nhas errors"
            elif level == 2:
                tip += "\nhas warnings"
            it.setToolTip(0, tip)

    def _activated(self, item: QTreeWidgetItem, _col: int = 0) -> None:
        what = item.data(0, ROLE_WHAT)
        path = item.data(0, ROLE_PATH)
        if what in (W_PROCEDURE, W_HEADER, W_BUILTIN_HEADER, W_FILE, W_TARGET_PROC) and path:
            if what == W_FILE and not Path(path).exists():
                return
            self.sig_open_file.emit(path)

    def _context_menu(self, point) -> None:
        item = self.tree.itemAt(point)
        menu = self.context_menu_for(item)
        if menu is not None and not menu.isEmpty():
            menu.exec(self.tree.viewport().mapToGlobal(point))

    def context_menu_for(self, item: Optional[QTreeWidgetItem]) -> Optional[QMenu]:
        """The context menu of an item (built, not shown: tests use it)."""
        if self.project is None:
            return None
        menu = QMenu(self)
        what = item.data(0, ROLE_WHAT) if item is not None else W_PROJECT
        path = item.data(0, ROLE_PATH) if item is not None else None
        if what in (W_PROJECT, W_HW_FOLDER):
            menu.addAction(self.action_new_hw)
        if what in (W_PROJECT, W_SW_FOLDER):
            menu.addAction(self.action_new_sw)
        if what in (W_PROJECT, W_HEADERS):
            menu.addAction(self.action_new_header)
        if what in (W_PROCEDURE, W_HEADER, W_BUILTIN_HEADER, W_FILE, W_TARGET_PROC):
            a = menu.addAction(icon("open"), "Open")
            a.triggered.connect(lambda: self._activated(item))
        if what == W_PROCEDURE:
            is_hw = Path(path).parent.name != "software"
            a = menu.addAction(icon("start"), f"Start {item.text(0)}")
            a.setObjectName("start")
            a.triggered.connect(lambda: self.sig_start_procedure.emit(item.text(0)))
            a.setEnabled(is_hw or item.text(0).startswith("__"))
            menu.addSeparator()
            a = menu.addAction(icon("rename"), "Rename…")
            a.setObjectName("rename")
            a.triggered.connect(lambda: self.rename(path))
            a = menu.addAction(icon("duplicate"), "Duplicate…")
            a.setObjectName("duplicate")
            a.triggered.connect(lambda: self.duplicate(path))
            a = menu.addAction(icon("delete"), "Delete")
            a.setObjectName("delete")
            a.triggered.connect(lambda: self.delete(path))
        elif what == W_HEADER:
            menu.addSeparator()
            a = menu.addAction(icon("rename"), "Rename…")
            a.triggered.connect(lambda: self.rename(path))
            a = menu.addAction(icon("delete"), "Delete")
            a.triggered.connect(lambda: self.delete(path))
        if what in (W_PROJECT, W_HW_FOLDER, W_SW_FOLDER, W_HEADERS):
            menu.addSeparator()
            a = menu.addAction(icon("refresh"), "Refresh")
            a.triggered.connect(lambda: self.refresh(force=True))
        return menu


class _DescriptionDelegate(QStyledItemDelegate):
    """Draws an item's description (its file's first comment) in grey after its name."""

    def paint(self, painter, option, index) -> None:
        super().paint(painter, option, index)
        desc = index.data(ROLE_DESCRIPTION)
        if not desc:
            return
        # here, not at the top: the first use of QStyle from Python builds its
        # enums (5 ms), and the window's first paint has no descriptions yet
        from PySide6.QtWidgets import QStyle
        opt = option.__class__(option)
        self.initStyleOption(opt, index)
        style = opt.widget.style() if opt.widget else None
        if style is None:
            return
        text_rect = style.subElementRect(QStyle.SubElement.SE_ItemViewItemText, opt, opt.widget)
        fm = opt.fontMetrics
        x = text_rect.left() + fm.horizontalAdvance(opt.text) + fm.horizontalAdvance("   ")
        room = text_rect.right() - x
        if room < 30:
            return
        painter.save()
        selected = bool(opt.state & QStyle.StateFlag.State_Selected)
        painter.setPen(opt.palette.highlightedText().color() if selected else QColor("#8c959f"))
        painter.drawText(x, text_rect.top(), room, text_rect.height(),
                         int(Qt.AlignmentFlag.AlignVCenter | Qt.AlignmentFlag.AlignLeft),
                         fm.elidedText(desc, Qt.TextElideMode.ElideRight, room))
        painter.restore()


def first_comment(path: Path, name: str = "", limit: int = 48) -> str:
    """The gist of a file's leading // comment: its first sentence, without
    the file's own name in front ("// M03: spindle on, clockwise. ..." ->
    "spindle on, clockwise")."""
    try:
        if not Path(path).is_file():        # a FIFO or a device: never opened (it could block)
            return ""
        with open(path, "rb") as f:
            head = f.read(400).decode("utf-8", "replace")
    except OSError:
        return ""
    line = head.lstrip("\ufeff").split("\n", 1)[0].strip()
    if not line.startswith("//"):
        return ""
    text = line.lstrip("/").strip()
    for prefix in (Path(path).name, name):
        if prefix and text.startswith(prefix):
            text = text[len(prefix):].lstrip(" :-—–").strip()
    text = text.split(". ")[0].rstrip(".").strip()
    if len(text) > limit:
        text = text[:limit - 1].rstrip() + "…"
    return text


def _suggest_name(kind: Kind, names: set[str]) -> str:
    if kind is Kind.SOFTWARE:
        base, i = "TASK", 1
        while f"{base}{i}" in names:
            i += 1
        return f"{base}{i}"
    for n in range(10, 1000):
        cand = f"M{n:02d}"
        if cand not in names:
            return cand
    return "M999"


def dock_panel(win, key: str):
    """The Project dock's panel (docks.DOCKS): the window's tree."""
    return win.tree
