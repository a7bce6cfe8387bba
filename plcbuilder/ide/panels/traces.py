"""Traces in the IDE: the session's whole history, the trigger bar, trace files.

:class:`TraceTools` belongs to the run panels. It keeps every change the live
controller sends in a :class:`~plcbuilder.api.History` (the whole session, as
changes), arms triggers on it from the :class:`TriggerBar` (single, normal or
auto mode, or "trigger now") and shows each capture in the same panels when
it completes, with a line at the trigger. It opens, saves, exports (CSV, VCD,
PNG/SVG of a plot) and compares trace files; what it saves or exports is the
trace on show, or else the whole session.
"""

from __future__ import annotations

from pathlib import Path
from typing import Optional

from PySide6 import QtCore, QtWidgets
import pyqtgraph as pg  # noqa: I001 - after PySide6 (it takes the loaded binding)

from plcbuilder import api
from plcbuilder.ide.docks import on_screen
from plcbuilder.ide.elided_label import ElidedLabel
from plcbuilder.ide.looks import set_text_colour
from plcbuilder.ide.panels import style
from plcbuilder.ide.panels.model import PINS
from plcbuilder.ide.panels.plots.overlay import comparison_of, step_samples
from plcbuilder.trace.samples import events_of, trigger_bits, variables_of

Qt = QtCore.Qt
Signal = QtCore.Signal

MODES = (("Single", "single"), ("Normal", "normal"), ("Auto", "auto"))


class TriggerBar(QtWidgets.QWidget):
    """Trigger spec, pre/post, mode, Arm, Now and the trigger's state."""

    sig_arm = Signal(str, int, int, str)
    """Arm: spec, pre ms, post ms, mode."""
    sig_disarm = Signal()
    """Stop waiting for the trigger."""
    sig_now = Signal()
    """Trigger now."""
    sig_session = Signal()
    """Show the whole session so far."""

    #: below this many pixels for the spec, the bar flows onto two rows
    SPEC_ROOM = 180

    def __init__(self, parent=None):
        super().__init__(parent)
        outer = QtWidgets.QVBoxLayout(self)
        outer.setContentsMargins(4, 0, 4, 2)
        outer.setSpacing(2)
        self._rows = (QtWidgets.QHBoxLayout(), QtWidgets.QHBoxLayout())
        for row in self._rows:
            row.setSpacing(4)
            outer.addLayout(row)
        self.label = QtWidgets.QLabel("Trigger")
        self.spec = QtWidgets.QLineEdit()
        self.spec.setPlaceholderText("out 7 rise")
        self.spec.setToolTip("What starts a capture: 'out 7 rise', 'in 3 fall', 'adc 0 up 1200', "
                             "'proc = 33', 'message', 'print = 20001', 'M80.var03 bit 2 rise' "
                             "(see the manual, Traces)")
        self.spec.setMinimumWidth(60)
        self.spec.returnPressed.connect(lambda: self.arm.setChecked(True))
        self.pre = self._ms("pre", 100, "Time kept before the trigger")
        self.post = self._ms("post", 500, "Time kept after the trigger")
        self.mode = QtWidgets.QComboBox()
        for text, mode in MODES:
            self.mode.addItem(text, mode)
        self.mode.setToolTip("Single: one capture; Normal: re-arm after each; Auto: also "
                             "capture when no trigger came for pre + post")
        self.arm = style.small_button("Arm", "Wait for the trigger (Enter in the spec too)",
                                      True)
        self.arm.toggled.connect(self._armed)
        self.now = style.small_button("Now", "Trigger now: capture around this moment")
        self.now.clicked.connect(self.sig_now)
        self.session = style.small_button("Session", "Show the whole session so far, from "
                                          "t = 0, in the panels (zoom and pan over all of it; "
                                          "Back to Live returns)")
        self.session.clicked.connect(self.sig_session)
        # what the trigger does: "…" where the dock is too narrow, whole in the tooltip
        self.state = ElidedLabel(min_chars=4)
        self.state.setTextFormat(Qt.TextFormat.PlainText)
        self.state.setSizePolicy(QtWidgets.QSizePolicy.Policy.Ignored,
                                 QtWidgets.QSizePolicy.Policy.Preferred)
        self.two_rows: Optional[bool] = None
        self._flow(False)
        # the bar never widens its dock: it takes the width there is, on two rows
        # when one would squeeze the spec and the boxes
        self.setSizePolicy(QtWidgets.QSizePolicy.Policy.Ignored,
                           QtWidgets.QSizePolicy.Policy.Fixed)
        self.setMinimumWidth(0)

    def _one_row_width(self) -> int:
        """The width every control needs on one row, with room for the spec."""
        fixed = (self.label, self.pre, self.post, self.mode, self.arm, self.now, self.session)
        spacing = self._rows[0].spacing() * (len(fixed) + 1)
        margins = self.layout().contentsMargins()
        return (sum(w.sizeHint().width() for w in fixed) + spacing + self.SPEC_ROOM
                + margins.left() + margins.right())

    def _flow(self, two_rows: bool) -> None:
        """One row: everything side by side; two: the spec's row, then times and state."""
        if two_rows == self.two_rows:
            return
        self.two_rows = two_rows
        first, second = self._rows
        for row in self._rows:
            while row.count():
                row.takeAt(0)
        first.addWidget(self.label)
        first.addWidget(self.spec, 2)
        if two_rows:
            for w in (self.mode, self.arm, self.now):
                first.addWidget(w)
            for w in (self.pre, self.post, self.session):
                second.addWidget(w)
            second.addWidget(self.state, 3)
        else:
            for w in (self.pre, self.post, self.mode, self.arm, self.now, self.session):
                first.addWidget(w)
            first.addWidget(self.state, 3)
        self.updateGeometry()

    def resizeEvent(self, event) -> None:  # noqa: N802 - Qt's name
        self._flow(event.size().width() < self._one_row_width())
        super().resizeEvent(event)

    @staticmethod
    def _ms(prefix: str, value: int, tip: str) -> QtWidgets.QSpinBox:
        box = QtWidgets.QSpinBox()
        box.setRange(0, 3_600_000)
        box.setSingleStep(50)
        box.setValue(value)
        box.setPrefix(f"{prefix} ")
        box.setSuffix(" ms")
        box.setToolTip(tip)
        box.setMaximumWidth(box.fontMetrics().horizontalAdvance(f"{prefix} 99999 ms") + 36)
        return box

    def _armed(self, on: bool) -> None:
        if on:
            self.sig_arm.emit(self.spec.text(), self.pre.value(), self.post.value(),
                              self.mode.currentData())
        else:
            self.sig_disarm.emit()

    def set_state(self, text: str, error: bool = False, armed: Optional[bool] = None) -> None:
        set_text_colour(self.state, "#c62828" if error else "#505050")
        self.state.setText(text)
        if armed is not None and armed != self.arm.isChecked():
            self.arm.blockSignals(True)
            self.arm.setChecked(armed)
            self.arm.blockSignals(False)


class TraceTools(QtCore.QObject):
    """The session history, triggers and trace files of the run panels."""

    sig_note = Signal(str)
    """Something to tell the user (a capture made, a file written, a comparison)."""

    def __init__(self, panels, parent=None):
        super().__init__(parent)
        self.panels = panels
        self.session = self._new_history()
        self.capturer: Optional[api.Capturer] = None
        self.shown: Optional[api.Trace] = None       # a trace on show instead of live data
        self.captures = 0
        self._armed_text = "not armed"       # what the bar says while it waits
        #: the variables this trigger had the controller record (``watch``)
        self.watching: list[str] = []
        #: the bit the last trigger armed watches of a variable (its lane live)
        self.live_bits: dict[str, int] = {}
        self.bar = TriggerBar()
        self.bar.sig_arm.connect(self.arm)
        self.bar.sig_disarm.connect(self.disarm)
        self.bar.sig_now.connect(self.trigger_now)
        self.bar.sig_session.connect(self.show_session)
        self.bar.set_state("not armed")
        refused = getattr(panels.connection, "sig_refused", None)
        if refused is not None:
            refused.connect(self._refused)
        # the trigger's spec, times and mode belong to the project: remembered
        # as they change, each project's own brought back when it opens
        self._restoring = False
        self.restore_trigger()
        bar = self.bar
        bar.spec.textChanged.connect(self._remember_trigger)
        bar.pre.valueChanged.connect(self._remember_trigger)
        bar.post.valueChanged.connect(self._remember_trigger)
        bar.mode.currentIndexChanged.connect(self._remember_trigger)

    @staticmethod
    def _new_history() -> api.History:
        return api.History(input_count=PINS, output_count=PINS, axes=api.abi.AXES)

    # ------------------------------------------------- the project's trigger
    #: the bar's fields as a project remembers them: (settings key, default)
    TRIGGER_KEYS = (("trigger", ""), ("trigger_pre", 100), ("trigger_post", 500),
                    ("trigger_mode", "single"))

    def _project_settings(self):
        """(the open project's root, the window's Settings), or (None, None)."""
        parent = getattr(self.panels, "parent", None)
        win = parent() if callable(parent) else None
        project, settings = getattr(win, "project", None), getattr(win, "settings", None)
        if project is None or settings is None or not hasattr(settings, "project_value"):
            return None, None
        return project.root, settings

    def restore_trigger(self) -> None:
        """The open project's trigger spec, pre, post and mode, as it left them
        (a project never seen, or none open: an empty spec and the defaults)."""
        root, settings = self._project_settings()
        saved = {}
        for key, default in self.TRIGGER_KEYS:
            saved[key] = settings.project_value(root, key, default) if root else default
        bar = self.bar
        self._restoring = True
        try:
            bar.spec.setText(str(saved["trigger"] or ""))
            for box, key, default in ((bar.pre, "trigger_pre", 100),
                                      (bar.post, "trigger_post", 500)):
                try:
                    box.setValue(int(saved[key]))
                except (TypeError, ValueError):
                    box.setValue(default)
            at = bar.mode.findData(str(saved["trigger_mode"]))
            bar.mode.setCurrentIndex(at if at >= 0 else 0)
        finally:
            self._restoring = False

    def _remember_trigger(self, *_args) -> None:
        if self._restoring:
            return
        root, settings = self._project_settings()
        if root is None:
            return
        bar = self.bar
        for key, value in (("trigger", bar.spec.text()), ("trigger_pre", bar.pre.value()),
                           ("trigger_post", bar.post.value()),
                           ("trigger_mode", bar.mode.currentData())):
            settings.set_project_value(root, key, value)

    def project_changed(self) -> None:
        """Another project (or none): its trigger no longer waits, and the bar
        shows the new project's own trigger (not the last project's)."""
        self.disarm()
        self.restore_trigger()

    # ------------------------------------------------------------ live data
    def feed(self, samples: list, events: list = ()) -> None:
        """Live telemetry (the panels pass on what the controller sends)."""
        s = self.session
        if samples and s.t_start is not None and samples[0].t_ms < s.t_end:
            self.session = s = self._new_history()      # the controller started over
            if self.capturer is not None:
                self.capturer = api.Capturer(s, self.capturer.trigger, self.capturer.pre,
                                             self.capturer.post, self.capturer.mode)
        s.feed_samples(samples, events)
        if self.capturer is not None:
            for cap in self.capturer.update():
                self._captured(cap)

    # -------------------------------------------------------------- trigger
    def arm(self, spec: str, pre: int, post: int, mode: str) -> bool:
        """Wait for ``spec``; a spec that cannot be read says why and stays disarmed."""
        try:
            trig = api.parse_trigger(spec)
            self.capturer = api.Capturer(self.session, trig, pre, post, mode)
        except api.TriggerError as exc:
            self.capturer = None
            self.bar.set_state(str(exc), error=True, armed=False)
            return False
        names = api.watched_variables(trig)
        self.live_bits = {trig.signal: trig.bit} if names and trig.bit is not None else {}
        if self.panels.recorded is None:
            self.panels.model.set_watch_bits(self.live_bits)
            self.panels.wake()
        if names:
            # the telemetry has no variables: the controller records this one each
            # tick and sends its changes ("watch" events), which the session keeps
            conn = self.panels.connection
            if not hasattr(conn, "watch_variables") or not getattr(conn, "connected", False):
                self.capturer = None
                self._watch([])
                self.bar.set_state(f"a trigger on {names[0]} needs the controller to record "
                                   f"it: not connected to a controller that can", error=True,
                                   armed=False)
                return False
            self._watch(names)
            self._armed_text = (f"armed: waiting for {spec} ({mode}; the controller records "
                                f"{', '.join(names)} each tick)")
            self.bar.set_state(self._armed_text, armed=True)
            return True
        self._watch([])
        self._armed_text = f"armed: waiting for {spec} ({mode})"
        self.bar.set_state(self._armed_text, armed=True)
        return True

    def disarm(self) -> None:
        self.capturer = None
        self._watch([])
        self.bar.set_state("not armed", armed=False)
        self._armed_text = "not armed"

    def shown_over(self) -> None:
        """The panels went back to live: "captured at t = …" is over (issue
        23.8); the bar says whether it still waits for its trigger."""
        self.shown = None
        self.bar.set_state(self._armed_text if self.capturer is not None else "not armed",
                           armed=self.capturer is not None)

    def _watch(self, names: list[str]) -> None:
        """Have the controller record ``names`` each tick (none: stop), when that changes."""
        if names == self.watching:
            return
        self.watching = list(names)
        conn = self.panels.connection
        if hasattr(conn, "watch_variables") and getattr(conn, "connected", False):
            conn.watch_variables(self.watching)

    def _refused(self, verb: str, reason: str) -> None:
        """The controller refused to record the trigger's variable: say why, disarmed."""
        if verb != "watch" or not self.watching:
            return
        self.capturer = None
        self.watching = []
        self.bar.set_state(f"cannot trigger on it: {reason}", error=True, armed=False)

    def trigger_now(self) -> None:
        if self.capturer is None:
            self.capturer = api.Capturer(self.session, _trigger_or_default(self.bar.spec.text()),
                                         self.bar.pre.value(), self.bar.post.value(), "single")
        self.capturer.trigger_now()
        self.bar.set_state("triggered now: capturing…", armed=True)
        for cap in self.capturer.update():
            self._captured(cap)

    def _captured(self, cap: api.Trace) -> None:
        self.captures += 1
        t = cap.meta["trigger"]["t_ms"]
        mode = self.capturer.mode if self.capturer is not None else "single"
        if self.capturer is not None and self.capturer.done:
            self.capturer = None
            self._watch([])
        armed = self.capturer is not None
        self.bar.set_state(f"captured at t = {t / 1000:.3f} s"
                           + (f" (capture {self.captures}, re-armed)" if armed else ""),
                           armed=armed)
        self.show(cap, f"capture at {t / 1000:.3f} s ({mode})")
        self.sig_note.emit(f"trigger {cap.meta['trigger']['spec']}: captured "
                           f"{cap.t_start}..{cap.t_end} ms")

    # ---------------------------------------------------------------- show
    def show(self, trace: api.Trace, title: str, marker_label: Optional[str] = None,
             bits: Optional[dict] = None) -> None:
        """Show a trace in the run panels instead of the live data, its watched
        variables too (the bit its trigger watched, or ``bits``, as a lane)."""
        samples = step_samples(trace)
        marker = (trace.meta.get("trigger") or {}).get("t_ms")
        self.shown = trace
        self.panels.show_recorded(title, samples, events_of(trace), marker,
                                  text=f"showing {title}", marker_label=marker_label,
                                  variables=variables_of(trace),
                                  bits=trigger_bits(trace) if bits is None else bits)

    def show_session(self) -> api.Trace:
        """Show the whole session so far in the run panels (every change since
        the controller started, not only the seconds the live view keeps)."""
        tr = self.session_trace()
        self.show(tr, f"the whole session, {tr.t_start / 1000:.3f}..{tr.t_end / 1000:.3f} s")
        panels = self.panels
        t0, t1 = tr.t_start * 1e-3, max(tr.t_end * 1e-3, tr.t_start * 1e-3 + 0.01)
        panels.show_span(t0, t1)
        return tr

    def current(self) -> api.Trace:
        """The trace on show, or the whole session so far."""
        if self.shown is not None and self.panels.recorded is not None:
            return self.shown
        return self.session_trace()

    def session_trace(self) -> api.Trace:
        """The session's history as a trace, without the pins and channels that
        never changed from 0 (a watched variable stays, 0 or not)."""
        tr = self.session.snapshot(meta={"source": "PLC Builder IDE session"})
        keep = {"proc", "message", "running", *variables_of(tr)}
        for name in list(tr.signals):
            kind, changes = tr.signals[name]
            if name not in keep and \
                    all(v == 0 for _t, v in changes) and len(changes) <= 1:
                del tr.signals[name]
        return tr

    # --------------------------------------------------------------- files
    def open(self, path) -> api.Trace:
        """Open a trace file and show it; raises api.TraceFileError."""
        trace = api.load_trace(path)
        self.show(trace, f"trace {Path(path).name}")
        self.bar.set_state(self._armed_text if self.capturer is not None else "not armed",
                           armed=self.capturer is not None)
        self.sig_note.emit(f"opened {path}: {trace.t_start}..{trace.t_end} ms, "
                           f"{len(trace.signals)} signals")
        return trace

    def save(self, path) -> None:
        """Save what is on show (or the session); raises api.TraceFileError."""
        api.save_trace(self.current(), path)
        self.sig_note.emit(f"saved {path}")

    def export(self, path, **chosen: bool) -> str:
        """Export as CSV or VCD (by suffix), the way ``chosen`` picks
        (``split_bits=True``: a VCD's numbers as one-bit lanes, for PulseView;
        ``per_tick=True``); raises api.ExportError."""
        fmt = api.export_trace(self.current(), path, **chosen)
        self.sig_note.emit(f"exported {path} ({fmt})")
        return fmt

    def export_image(self, path, panel=None) -> None:
        """The plots of one panel (default: the first visible) as PNG or SVG."""
        path = Path(path)
        if panel is None:
            shown = [p for p in self.panels.time_panels if on_screen(p)]
            panel = shown[0] if shown else self.panels.lanes
        scene = panel._time_plots[0].scene()
        suffix = path.suffix.lower()
        if suffix not in (".svg", ".png"):
            raise api.ExportError(f"{path}: export a plot as .png or .svg")
        if not path.parent.is_dir():
            raise api.ExportError(f"{path}: cannot write: no such folder {path.parent}")
        tmp = path.with_name(f".{path.name}.tmp{path.suffix}")
        try:
            if suffix == ".png":
                import pyqtgraph.exporters  # noqa: F401 - pg.exporters (when first asked for)
                pg.exporters.ImageExporter(scene).export(str(tmp))
            else:
                _svg(scene, tmp, panel)
            tmp.replace(path)
        except OSError as exc:
            tmp.unlink(missing_ok=True)
            raise api.ExportError(f"{path}: cannot write: {exc.strerror or exc}") from None
        self.sig_note.emit(f"exported {path}")

    def base_name(self) -> str:
        """What a comparison compares with: the trace on show, or the session."""
        shown = self.shown is not None and self.panels.recorded is not None
        return self.panels.recorded if shown else "the session"

    def compare_with(self, path, align: str = "none",
                     offset_ms: int = 0) -> "api.trace_compare.Difference":
        """Compare what is on show (or the session) with a trace file, the
        file's trace lined up first (``align``: none, start or trigger, then
        ``offset_ms``): the panels show the first with the second drawn over it
        (dashed) where it lines up, and a line at the first difference; raises
        api.TraceFileError, api.CompareError."""
        base = self.current()
        base_name = self.base_name()
        other = api.load_trace(path)
        diff = api.compare_traces(base, other, align, offset_ms)
        name = Path(path).name
        meta = dict(base.meta)
        label = "first difference"
        if diff.t_ms is not None:
            meta["trigger"] = {"spec": f"first difference from {name}", "t_ms": diff.t_ms,
                               "pre_ms": 0, "post_ms": 0, "mode": "compare"}
        elif diff.shift_ms and api.trace_compare.trigger_ms(base) is not None:
            label = "trigger"                   # lined up on it, the same: show where
        else:
            meta.pop("trigger", None)
        shown_trace = api.Trace(base.t_start, base.t_end, base.signals, base.strings,
                                base.events, meta)
        where = (f"first difference at {diff.t_ms / 1000:.3f} s" if diff.t_ms is not None
                 else "no difference" if diff.same else "no tick in common")
        drawn = name
        if diff.shift_ms or align != "none":
            how = {"none": "", "start": "starts together, ",
                   "trigger": "triggers together, "}[align]
            drawn = f"{name} (moved {diff.shift_ms / 1000:+.3f} s)"
            where = f"{how}{name} moved {diff.shift_ms / 1000:+.3f} s; {where}"
        self.show(shown_trace, base_name, marker_label=label, bits=trigger_bits(base))
        self.panels.compare(comparison_of(api.trace_compare.shifted(other, diff.shift_ms),
                                          drawn, base_name, where))
        self.sig_note.emit(f"comparing {base_name} with {name}: {where}; "
                           + diff.text().replace("\n", "; "))
        return diff


def _svg(scene, path: Path, panel) -> None:
    """The scene drawn into an SVG file by Qt's own SVG generator (pyqtgraph's
    SVG exporter cannot read the paths this Qt writes)."""
    from PySide6.QtCore import QRectF, QSize
    from PySide6.QtGui import QPainter
    from PySide6.QtSvg import QSvgGenerator
    rect = scene.sceneRect()
    gen = QSvgGenerator()
    gen.setFileName(str(path))
    gen.setSize(QSize(int(rect.width()), int(rect.height())))
    gen.setViewBox(QRectF(0, 0, rect.width(), rect.height()))
    gen.setTitle("PLC Builder plot")
    painter = QPainter(gen)
    try:
        scene.render(painter, QRectF(0, 0, rect.width(), rect.height()), rect)
    finally:
        painter.end()
    if not path.is_file():
        raise OSError(f"the SVG generator wrote nothing to {path}")


def _trigger_or_default(spec: str):
    """The bar's trigger, or "in 0 edge" when it has none that can be read (a
    manual trigger needs one only to name the capture)."""
    try:
        return api.parse_trigger(spec.strip() or "in 0 edge")
    except api.TriggerError:
        return api.parse_trigger("in 0 edge")
