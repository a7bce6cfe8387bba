"""File › Open Trace…, Save Trace…, Export Trace…, Export Plot Image… and
Compare with Trace…: the dialogs around the run panels' TraceTools."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

from PySide6.QtWidgets import QFileDialog, QMessageBox

from plcbuilder import api

TRACE_FILTER = "PLC Builder traces (*.plctrace);;All files (*)"
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


def _ask(win, title: str, filters: str, save: bool = False, suffix=None, name: str = ""):
    """A file from a dialog: (path, chosen filter), or (None, "") when cancelled.
    ``suffix(chosen)`` names the suffix a saved name without one gets. It starts
    in the folder a trace was last saved or opened in (else the project's),
    proposing ``name`` for a file to save; the folder chosen is remembered."""
    ask = QFileDialog.getSaveFileName if save else QFileDialog.getOpenFileName
    folder = win.settings.last_folder("traces", _folder(win))
    start = folder / name if save and name else folder
    path, chosen = ask(win, title, str(start), filters)
    if not path:
        return None, ""
    if suffix is not None and not Path(path).suffix:
        path += suffix(chosen)
    win.settings.set_last_folder("traces", Path(path).parent)
    return path, chosen


def proposed_name(win, suffix: str) -> str:
    """A name for what Save or Export writes: the project, then what is on
    show (``capture-1.010s``, a trace file's own name, a test run's), else the
    session to its end (``session-12.345s``)."""
    import re
    panels = win.run_panels
    project = getattr(win, "project", None)
    what = ""
    if panels is not None and panels.recorded is not None:
        shown = panels.recorded
        m = re.match(r"capture at ([\d.]+) s", shown)
        if m:
            what = f"capture-{m.group(1)}s"
        elif shown.startswith("trace "):
            what = Path(shown[len("trace "):]).stem
        elif shown.startswith("the whole session"):
            what = "session"
        else:
            what = shown
    elif panels is not None:
        end = panels.traces.session.t_end
        what = f"session-{end / 1000:.3f}s" if end is not None else "session"
    stem = "-".join(x for x in ((project.name if project is not None else ""), what) if x)
    stem = re.sub(r"[^\w.\-]+", "-", stem).strip("-.") or "trace"
    return stem + suffix


def open_trace(win, path: Optional[str] = None) -> bool:
    tools = _tools(win)
    if tools is None:
        return False
    if path is None:
        path, _ = _ask(win, "Open Trace", TRACE_FILTER)
        if path is None:
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


def _write_file(win, title: str, filters: str, suffix_of, path: Optional[str], write,
                error: type, done: str) -> bool:
    """Ask for a file (unless given one) and ``write(tools, path, chosen filter)``;
    an ``error`` says so in a message box, success in the status bar."""
    tools = _tools(win)
    if tools is None:
        return False
    chosen = ""
    if path is None:
        first = filters.split(";;")[0]
        path, chosen = _ask(win, title, filters, True, suffix_of,
                            proposed_name(win, suffix_of(first)))
        if path is None:
            return False
    try:
        write(tools, path, chosen)
    except error as exc:
        _failed(win, title, exc)
        return False
    win.statusBar().showMessage(f"{done} {path}", 5000)
    return True


def save_trace(win, path: Optional[str] = None) -> bool:
    return _write_file(win, "Save Trace", TRACE_FILTER, lambda _c: ".plctrace", path,
                       lambda tools, p, _c: tools.save(p), api.TraceFileError, "Saved")


def export_filter() -> str:
    """The Export Trace dialog's filters: one a way of exporting (api.trace_exporters)."""
    return ";;".join(w.ide_filter for w in api.trace_exporters())


def _way(chosen_filter: str):
    return next(w for w in api.trace_exporters() if w.ide_filter == chosen_filter)


def export_trace(win, path: Optional[str] = None, **chosen: bool) -> bool:
    """File › Export Trace…: each way of api.trace_exporters a filter of the
    dialog (VCD for GTKWave, one-bit lanes for PulseView and sigrok, CSV per
    change or per tick); given a ``path``, no dialog, the way ``chosen`` picks."""
    def write(tools, p, c):
        if c:
            way = _way(c)
            return tools.export(p, **({way.option: True} if way.option else {}))
        return tools.export(p, **chosen)

    return _write_file(win, "Export Trace", export_filter(),
                       lambda c: "." + _way(c).fmt, path, write, api.ExportError, "Exported")


def export_plot(win, path: Optional[str] = None) -> bool:
    return _write_file(win, "Export Plot Image", IMAGE_FILTER,
                       lambda c: ".svg" if "SVG" in c else ".png", path,
                       lambda tools, p, _c: tools.export_image(p), api.ExportError, "Exported")


def compare_trace(win, path: Optional[str] = None, align: Optional[str] = None,
                  offset_ms: int = 0):
    """File › Compare with Trace…: the trace on show (or the session) with a
    trace file, lined up as the dialog says (``align``: none, start or
    trigger, then ``offset_ms``); given a ``path``, no dialog (``align``
    default none). The panels draw the file's trace moved so, dashed."""
    tools = _tools(win)
    if tools is None:
        return None
    if path is None:
        from plcbuilder.ide.dialogs.compare_trace import CompareDialog
        folder = win.settings.last_folder("traces", _folder(win))
        got = CompareDialog.get(win, tools.current(), tools.base_name(), str(folder))
        if got is None:
            return None
        path, align, offset_ms = got
        win.settings.set_last_folder("traces", Path(path).resolve().parent)
    try:
        diff = tools.compare_with(path, align or "none", offset_ms)
    except (api.TraceFileError, api.CompareError) as exc:
        _failed(win, "Compare with Trace", exc)
        return None
    QMessageBox.information(win, "Compare with Trace",
                            f"{diff.text()}\n\n{Path(path).name} is drawn dashed over the "
                            f"trace on show{' (moved as above)' if diff.shift_ms else ''}; "
                            f"File › Clear Comparison (or Back to Live) removes it.")
    return diff


def clear_comparison(win) -> bool:
    """File › Clear Comparison: the compared trace is no longer drawn."""
    panels = win.run_panels
    if panels is None or panels.comparison is None:
        return False
    panels.clear_comparison()
    return True


# ------------------------------------------------------- record and replay

RECORDING_FILTER = "Session recordings (*.txt *.scenario);;All files (*)"


def save_recording(win, path: Optional[str] = None) -> bool:
    """Run › Save Session Recording…: ask the controller for the session's
    recording and write it (a scenario file) when it comes."""
    conn = getattr(win, "connection", None)
    if conn is None or not getattr(conn, "connected", False):
        QMessageBox.warning(win, "Save Session Recording", "Not connected to a controller.")
        return False
    if path is None:
        folder = win.settings.last_folder("recordings", _folder(win))
        path, _ = QFileDialog.getSaveFileName(win, "Save Session Recording",
                                              str(folder / proposed_name(win, ".txt")),
                                              RECORDING_FILTER)
        if not path:
            return False
        win.settings.set_last_folder("recordings", Path(path).parent)

    def got(verb: str, result: dict) -> None:
        if verb != "recording":
            return
        conn.sig_result.disconnect(got)
        try:
            api.atomic_write(path, str(result.get("text", "")))
        except OSError as exc:
            QMessageBox.warning(win, "Save Session Recording",
                                f"{path}: cannot write: {exc.strerror or exc}")
            return
        win.statusBar().showMessage(f"Saved the session recording ({result.get('actions', 0)} "
                                    f"actions, to {result.get('t_ms', 0)} ms) to {path}", 6000)
        win.sig_recording_saved.emit(path)

    conn.sig_result.connect(got)
    conn.request_recording()
    return True


def replay_session(win, path: Optional[str] = None, *, wait: bool = False) -> bool:
    """Run › Replay Session…: run a recording on the project's image, headless
    (in a thread), and show the replay's trace in the run panels."""
    project = getattr(win, "project", None)
    if project is None:
        QMessageBox.warning(win, "Replay Session", "Open a project first.")
        return False
    tools = _tools(win)
    if tools is None:
        return False
    if path is None:
        path, _ = QFileDialog.getOpenFileName(
            win, "Replay Session", str(win.settings.last_folder("recordings", project.root)),
            RECORDING_FILTER)
        if not path:
            return False
        win.settings.set_last_folder("recordings", Path(path).parent)
    import tempfile
    import threading
    from PySide6.QtCore import QObject, Signal

    class _Done(QObject):
        sig = Signal(object)

    done = _Done(win)
    out = Path(tempfile.mkdtemp(prefix="plcbuilder-replay-")) / "replay.plctrace"

    def work() -> None:
        try:
            ms = _recorded_end(path)
            r = api.run(project.root, api.RunOptions(scenario=Path(path), ms=ms, history=out))
            done.sig.emit(r if r.ok else RuntimeError("the project does not compile"))
        except Exception as exc:  # noqa: BLE001 - shown to the user
            done.sig.emit(exc)

    def finished(r) -> None:
        if isinstance(r, Exception):
            QMessageBox.warning(win, "Replay Session", f"{path}: {r}")
            return
        trace = api.load_trace(out)
        tools.show(trace, f"replay of {Path(path).name}")
        for note in r.report.get("notes", []):
            if note.get("level") == "warning":
                tools.panels.log.add_note(note["text"], "error", shown=True)
        win.statusBar().showMessage(f"Replayed {Path(path).name}: {trace.t_start}..{trace.t_end} ms",
                                    6000)
        win.sig_replayed.emit(trace)

    done.sig.connect(finished)
    win.statusBar().showMessage(f"Replaying {Path(path).name}…")
    t = threading.Thread(target=work, name="plcbuilder-replay", daemon=True)
    t.start()
    if wait:
        t.join()
    return True


def _recorded_end(path) -> Optional[int]:
    """The ``recorded to t = N ms`` of a recording's header (None: run as usual)."""
    import re
    text = Path(path).read_text(encoding="utf-8", errors="replace")[:4096]
    m = re.search(r"recorded to t = (\d+) ms", text)
    return int(m.group(1)) + 1 if m else None
