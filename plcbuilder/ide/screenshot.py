"""Screenshot mode: ``plcbuilder gui PROJECT --screenshot FILE [--run NAME[:EPARAM]] [--after MS]
[--trace FILE [--trace FILE]]``.

Opens the project, builds it, and — with ``--run`` — uploads the image to the
embedded controller, starts the procedure and lets exactly ``--after``
milliseconds of simulated time pass (the controller is paused and stepped,
so the picture is the same every time); then saves a PNG of the main window
and exits. Without ``--run`` it waits ``--after`` ms of wall-clock time for the
window to settle. With ``--trace`` the run panels show that trace file, and a
second one compared with it (File › Compare with Trace…).

The window uses settings of its own (a temporary file), so a screenshot
neither uses nor changes the user's layout.
"""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path
from typing import Callable, Optional

from PySide6.QtCore import QEventLoop, QTimer

from plcbuilder._support.files import read_bounded
from plcbuilder._support.numbers import WORD32, parse_int_in, to_int32
from plcbuilder.link.protocol import MAX_IMAGE

WINDOW_SIZE = (1500, 940)


def parse_run(spec: Optional[str]) -> Optional[tuple[str, int]]:
    """``NAME`` or ``NAME:EPARAM`` -> (name, eparam); raises ValueError."""
    if not spec:
        return None
    name, _, eparam = spec.partition(":")
    name = name.strip()
    if not name:
        raise ValueError(f"--run needs a procedure name, got {spec!r}")
    try:
        value = parse_int_in(eparam, *WORD32, "the eparam") if eparam.strip() else 0
    except ValueError as exc:
        raise ValueError(f"--run {spec!r}: {exc}") from None
    return name, to_int32(value)


#: simulated ms stepped at a time in screenshot mode (below the telemetry queue)
STEP_SLICE_MS = 200


def wait_until(app, cond: Callable[[], bool], timeout_s: float) -> bool:
    """Run the event loop until cond() holds (True) or the time is up (False)."""
    deadline = time.monotonic() + timeout_s
    while not cond():
        if time.monotonic() > deadline:
            return False
        app.processEvents(QEventLoop.ProcessEventsFlag.AllEvents, 30)
        time.sleep(0.005)
    return True


def settle(app, ms: int) -> None:
    loop = QEventLoop()
    QTimer.singleShot(max(0, int(ms)), loop.quit)
    loop.exec()


def _say(text: str) -> None:
    print(f"plcbuilder gui: {text}", file=sys.stderr)


def run(app, settings, project: Optional[str], out: str, run_spec: Optional[str],
        after_ms: int, start_controller: bool = True, traces: tuple = ()) -> int:
    from plcbuilder.ide.main_window import MainWindow
    from plcbuilder.ide.settings import Settings
    try:
        run_target = parse_run(run_spec)
    except ValueError as exc:
        _say(str(exc))
        return 2
    if not settings.explicit:
        tmp = tempfile.mkdtemp(prefix="plcbuilder-shot-")
        settings = Settings(str(Path(tmp) / "settings.ini"))
    win = MainWindow(settings, start_controller=start_controller)
    win.resize(*WINDOW_SIZE)
    win.show()
    try:
        if project and not win.open_project(project, offer_recovery=False):
            _say(f"cannot open the project {project}")
            return 1
        proj = win.project
        if proj is not None:
            shown = None
            if run_target is not None:
                p = proj.procedure(run_target[0])
                shown = p.path if p is not None else None
            if shown is None:
                procs = proj.procedures()
                shown = procs[0].path if procs else None
            if shown is not None and win.editor_for(shown) is None:
                win.open_file(shown)
            elif shown is not None:
                win.open_file(shown)
            done: list = []
            win.sig_build_finished.connect(done.append)
            if win.build_all():
                wait_until(app, lambda: bool(done), 60)
            # a build that failed shows its first error, as a person would look at it
            result = done[0] if done else None
            first = next((d for d in getattr(result, "all_diagnostics", []) or []
                          if d.is_error and d.span is not None), None)
            if first is not None and run_target is None:
                win.open_location(first.span.file, first.span.line, first.span.col)
        if traces and not _show_traces(win, traces):
            return 1
        if run_target is not None:
            if not _run_procedure(app, win, run_target, after_ms):
                return 1
        else:
            settle(app, after_ms)
        wait_until(app, lambda: not win.busy(), 5)
        settle(app, 250)                    # let the plots redraw (40 Hz)
        image = win.grab()
        if not image.save(str(out)):
            _say(f"cannot write {out}")
            return 1
        print(f"wrote {out} ({image.width()}x{image.height()})")
        return 0
    finally:
        win.shutdown()
        win._closing = True
        win.hide()
        win.deleteLater()


def _show_traces(win, traces: tuple) -> bool:
    """The first trace in the run panels; the second compared with it (drawn over it)."""
    from plcbuilder.api import TraceFileError
    panels = win.ensure_run_panels()
    if panels is None:
        _say("--trace needs the run panels (they are not available)")
        return False
    try:
        panels.traces.open(traces[0])
        for path in traces[1:]:
            panels.traces.compare_with(path)
    except TraceFileError as exc:
        _say(str(exc))
        return False
    from PySide6.QtCore import Qt
    for key in ("outputs", "proc", "analog"):
        panels.dock(key).show()
    outputs = panels.dock("outputs")
    outputs.raise_()
    # the plots are the picture: give their dock most of the window
    for key in ("inputs", "watch"):
        panels.dock(key).hide()
    watched = bool(len(panels.model.watched))
    if watched:
        # its variables: lanes above the pins, and curves under PWM/DAC/ADC: that
        # dock under the lanes, the bottom docks out of the way to make room
        analog = panels.dock("analog")
        win.removeDockWidget(analog)
        win.addDockWidget(Qt.DockWidgetArea.RightDockWidgetArea, analog, Qt.Orientation.Vertical)
        analog.show()
        for dock in (win.problems_dock, win.build_dock, win.tests_dock, panels.dock("log")):
            dock.hide()
    if len(traces) > 1 or watched:      # the cursors read both traces, or the variables
        panels.dock("cursors").show()
        panels.dock("cursors").raise_()
        panels.cursor_table.toggle.setChecked(True)
    # half the window (the editor keeps its least width), and the project's side
    # room for its tabs' shortened titles (squeezed, it read "ints | Outline")
    win.resizeDocks([win.project_dock, outputs], [180, int(win.width() * 0.5)],
                    Qt.Orientation.Horizontal)
    if watched:
        h = win.height()
        win.resizeDocks([outputs, panels.dock("cursors"), panels.dock("analog")],
                        [int(h * 0.34), int(h * 0.14), int(h * 0.52)], Qt.Orientation.Vertical)
    return True


def _run_procedure(app, win, target: tuple[str, int], after_ms: int) -> bool:
    c = win.connection
    if c is None:
        _say("--run needs the controller (the run side of the IDE is not available)")
        return False
    if win.project is None:             # (its controller starts with the project)
        _say("--run needs a project: plcbuilder gui PROJECT --run NAME --screenshot FILE")
        return False
    if not wait_until(app, lambda: bool(getattr(c, "connected", False)), 30):
        _say("the controller did not start")
        return False
    if win.project is None or not win.project.image_path.exists():
        _say("there is no image to upload (does the project build?)")
        return False
    results: list = []
    if hasattr(c, "sig_result"):
        c.sig_result.connect(lambda verb, res: results.append(verb))
    c.set_speed("pause")
    win.set_speed("pause")
    c.upload(read_bounded(win.project.image_path, MAX_IMAGE, "controller image"))
    name, eparam = target
    win.start_procedure(name, eparam)
    t0 = None

    def state_t():
        st = getattr(c, "last_state", None) or win._last_state
        return st.t_ms if st is not None else 0

    wait_until(app, lambda: "start" in results or not hasattr(c, "sig_result"), 10)
    t0 = state_t() or 0
    stepper = getattr(c, "step", None)
    if stepper is None and hasattr(c, "_send"):
        stepper = lambda ms: c._send("step", {"ms": ms})  # noqa: E731
    if stepper is not None and hasattr(c, "sig_result"):
        # in slices small enough that the IDE receives every tick's telemetry
        # (a paused controller keeps only the newest few hundred samples for it)
        done = 0
        while done < after_ms:
            n = min(STEP_SLICE_MS, int(after_ms) - done)
            before = results.count("step")
            stepper(n)
            wait_until(app, lambda: results.count("step") > before, 60)
            settle(app, 40)                 # a telemetry frame or two
            done += n
    elif stepper is not None:
        stepper(int(after_ms))
    else:                                   # no stepping: let it run in real time
        c.set_speed("realtime")
        settle(app, after_ms)
        c.set_speed("pause")
    debug = getattr(win, "debug", None)
    halted = lambda: debug is not None and debug.is_halted()  # noqa: E731
    ok = wait_until(app, lambda: (state_t() or 0) >= t0 + after_ms or halted(), 10)
    if halted():                        # a breakpoint: the picture shows where
        from plcbuilder.ide.debug.callstack import halted_text
        _say(f"the simulation halted before t = {t0 + after_ms} ms: {halted_text(debug.halted)}")
    elif not ok:
        _say(f"the simulation did not reach t = {t0 + after_ms} ms")
    return True
