"""The welcome page the editor stack shows when no editor is open."""

from __future__ import annotations

from pathlib import Path

from PySide6.QtCore import Qt, Signal
from PySide6.QtWidgets import (QHBoxLayout, QLabel, QListWidget, QListWidgetItem, QPushButton,
                               QVBoxLayout, QWidget)

from plcbuilder.api import Kind
from plcbuilder.ide.first_frame import APP_NAME
from plcbuilder.ide.icons import icon
from plcbuilder.ide.project_tree import TARGET_LABEL, target_outline



class WelcomePage(QWidget):
    """What the IDE is, the open project, buttons to start and the recent projects."""

    sig_open_project = Signal(str)
    """A recent project was chosen (its folder)."""

    sig_open_project_dialog = Signal()
    """"Open Project…" was pressed."""

    sig_open_example = Signal()
    """"Open Example Project…" was pressed."""

    sig_new_project = Signal()
    """New Project… was clicked."""

    sig_new_procedure = Signal()
    """"New Procedure…" was pressed."""

    def __init__(self, parent=None):
        super().__init__(parent)
        w = self
        w.setObjectName("welcome")
        outer = QVBoxLayout(w)
        outer.addStretch(1)
        box = QWidget(w)
        box.setMaximumWidth(660)          # room for the four buttons side by side
        lay = QVBoxLayout(box)
        title = QLabel(f"<span style='font-size:20pt; font-weight:600'>{APP_NAME}</span>", box)
        lay.addWidget(title)
        self.welcome_text = QLabel(box)
        self.welcome_text.setWordWrap(True)
        self.welcome_text.setTextFormat(Qt.TextFormat.RichText)
        lay.addWidget(self.welcome_text)
        row = QHBoxLayout()
        self.welcome_new_project = QPushButton(icon("project"), "New Project…", box)
        self.welcome_open = QPushButton(icon("open"), "Open Project…", box)
        self.welcome_example = QPushButton(icon("example"), "Open Example Project…", box)
        self.welcome_new = QPushButton(icon("new"), "New Procedure…", box)
        row.addWidget(self.welcome_new_project)
        row.addWidget(self.welcome_open)
        row.addWidget(self.welcome_example)
        row.addWidget(self.welcome_new)
        row.addStretch(1)
        lay.addLayout(row)
        self.welcome_recent_label = QLabel("<b>Recent projects</b>", box)
        lay.addSpacing(10)
        lay.addWidget(self.welcome_recent_label)
        self.welcome_recent = QListWidget(box)
        self.welcome_recent.setMaximumHeight(180)
        self.welcome_recent.itemActivated.connect(
            lambda it: self.sig_open_project.emit(it.data(Qt.ItemDataRole.UserRole)))
        lay.addWidget(self.welcome_recent)
        h = QHBoxLayout()
        h.addStretch(1)
        h.addWidget(box, 3)
        h.addStretch(1)
        outer.addLayout(h)
        outer.addStretch(2)
        self.welcome_new_project.clicked.connect(self.sig_new_project)
        self.welcome_open.clicked.connect(self.sig_open_project_dialog)
        self.welcome_example.clicked.connect(self.sig_open_example)
        self.welcome_new.clicked.connect(self.sig_new_procedure)

    def show_project(self, project) -> None:
        """The text for no project, or for this one."""
        if project is None:
            self.welcome_text.setText(
                "An editor, compiler and simulated controller for myCNC PLC procedures.<br><br>"
                "Create a project for myCNC, Huazhong or TG Motion (<b>New Project…</b>), "
                "open a project folder (with <tt>hardware/</tt> and <tt>software/</tt>), or "
                "start from a copy of the example project.")
            self.welcome_new.hide()
        else:
            p = project
            outline = target_outline(p)
            if outline:
                # a target's one source holds its procedures (docs/targets.md)
                names = ", ".join(f"{name}()" for name, _when in outline)
                what = f"{TARGET_LABEL.get(p.target, p.target)}: {names}."
            else:
                procs = p.procedures()                   # one listing of the folders
                hw = sum(1 for pr in procs if pr.kind is Kind.HARDWARE)
                what = f"{hw} hardware and {len(procs) - hw} software procedures."
            self.welcome_text.setText(
                f"<b>{p.name}</b> — {p.root}<br>{what}"
                "<br><br>Open a procedure from the <b>Project</b> panel, or press "
                "<b>Ctrl+B</b> to build them all.")
            self.welcome_new.show()

    def set_recent(self, recent: list) -> None:
        """The recent projects (folders), newest first."""
        self.welcome_recent.clear()
        for path in recent:
            it = QListWidgetItem(icon("project"), f"{Path(path).name}    {path}")
            it.setData(Qt.ItemDataRole.UserRole, path)
            self.welcome_recent.addItem(it)
        self.welcome_recent.setVisible(bool(recent))
        self.welcome_recent_label.setVisible(bool(recent))
