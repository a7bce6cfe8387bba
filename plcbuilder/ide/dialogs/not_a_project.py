"""Opening a folder that is not a project: say so, and offer to make one there
(the example project in an empty folder; the missing parts in one that holds
other files)."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

from PySide6.QtWidgets import QMessageBox

from plcbuilder.project.model import Project, ProjectError, looks_like_project


def project_or_offer(parent, folder: Path) -> Optional[Path]:
    """The folder to open: itself when it is a project (or not a folder at all:
    opening says why); otherwise, after asking, the project made there. None
    when the user declines or making it failed (after saying why)."""
    if not folder.is_dir() or looks_like_project(folder):
        return folder
    empty = not any(folder.iterdir())
    what = ("It is empty. Create a new project there, with the example procedures?"
            if empty else
            "Make it a project? This adds hardware/, software/, include/pins.h, "
            "machine.toml and plcbuilder.toml, and changes nothing that is there.")
    answer = QMessageBox.question(
        parent, "Open Project",
        f"{folder} is not a PLC Builder project: it has no plcbuilder.toml and no "
        f"hardware/ or software/ folder.\n\n{what}",
        QMessageBox.StandardButton.Yes | QMessageBox.StandardButton.No,
        QMessageBox.StandardButton.Yes)
    if answer != QMessageBox.StandardButton.Yes:
        return None
    try:
        from plcbuilder.project.new import create_project, init_project
        project: Project = create_project(folder) if empty else init_project(folder)
    except ProjectError as exc:
        QMessageBox.critical(parent, "Open Project", f"Cannot create the project:\n\n{exc}")
        return None
    return project.root
