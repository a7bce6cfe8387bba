"""File › Open Trace…, Save Trace…, Export Trace…, Export Plot Image… and
Compare with Trace…: the dialogs around the run panels' TraceTools."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

from PySide6.QtWidgets import QFileDialog, QMessageBox

from plcbuilder import api

TRACE_FILTER = "PLC Builder traces (*.plctrace);;All files (*)"
EXPORT_FILTER = ("VCD for GTKWave and PulseView (*.vcd);;CSV, one row per change (*.csv);;"
                 "CSV, one row per tick (*.csv)")
IMAGE_FILTER = "PNG image (*.png);;SVG drawing (*.svg)"


def _tools(win):
    panels = win.ensure_run_panels()
    if panels is None:
        QMessageBox.warning(win, "Traces", "The run panels are not available.")
        return None
    return panels.traces


def _folder(win) -> str:
    project = getattr(win, "project", None)
    return str(project.root) if project is not None else str(Path.home())


def _failed(win, title: str, exc: Exception) -> None:
    QMessageBox.warning(win, title, str(exc))


def open_trace(win, path: Optional[str] = None) -> bool:
    tools = _tools(win)
    if tools is None:
        return False
    if path is None:
        path, _ = QFileDialog.getOpenFileName(win, "Open Trace", _folder(win), TRACE_FILTER)
        if not path:
            return False
    try:
        tools.open(path)
    except api.TraceFileError as exc:
        _failed(win, "Open Trace", exc)
        return False
    for key in ("outputs", "proc"):
        tools.panels.dock(key).show()
    tools.panels.dock("outputs").raise_()
    return True


def save_trace(win, path: Optional[str] = None) -> bool:
    tools = _tools(win)
    if tools is None:
        return False
    if path is None:
        path, _ = QFileDialog.getSaveFileName(win, "Save Trace", _folder(win), TRACE_FILTER)
        if not path:
            return False
        if not Path(path).suffix:
            path += ".plctrace"
    try:
        tools.save(path)
    except api.TraceFileError as exc:
        _failed(win, "Save Trace", exc)
        return False
    win.statusBar().showMessage(f"Saved {path}", 5000)
    return True


def export_trace(win, path: Optional[str] = None, per_tick: bool = False) -> bool:
    tools = _tools(win)
    if tools is None:
        return False
    if path is None:
        path, chosen = QFileDialog.getSaveFileName(win, "Export Trace", _folder(win),
                                                   EXPORT_FILTER)
        if not path:
            return False
        per_tick = "per tick" in chosen
        if not Path(path).suffix:
            path += ".vcd" if "VCD" in chosen else ".csv"
    try:
        tools.export(path, per_tick=per_tick)
    except api.ExportError as exc:
        _failed(win, "Export Trace", exc)
        return False
    win.statusBar().showMessage(f"Exported {path}", 5000)
    return True


def export_plot(win, path: Optional[str] = None) -> bool:
    tools = _tools(win)
    if tools is None:
        return False
    if path is None:
        path, chosen = QFileDialog.getSaveFileName(win, "Export Plot Image", _folder(win),
                                                   IMAGE_FILTER)
        if not path:
            return False
        if not Path(path).suffix:
            path += ".svg" if "SVG" in chosen else ".png"
    try:
        tools.export_image(path)
    except api.ExportError as exc:
        _failed(win, "Export Plot Image", exc)
        return False
    win.statusBar().showMessage(f"Exported {path}", 5000)
    return True


def compare_trace(win, path: Optional[str] = None):
    tools = _tools(win)
    if tools is None:
        return None
    if path is None:
        path, _ = QFileDialog.getOpenFileName(win, "Compare with Trace", _folder(win),
                                              TRACE_FILTER)
        if not path:
            return None
    try:
        diff = tools.compare_with(path)
    except api.TraceFileError as exc:
        _failed(win, "Compare with Trace", exc)
        return None
    QMessageBox.information(win, "Compare with Trace", diff.text())
    return diff
