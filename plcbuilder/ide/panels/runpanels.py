"""RunPanels: the docks that show a running controller, and their one redraw timer.

Data path: ``connection.sig_samples`` -> :class:`RunModel` (numpy ring buffers,
no widgets) -> one QTimer (at most 40 Hz) -> ``refresh()`` of the visible panels
only, which hand pyqtgraph views of the buffers cut to the visible time window.

The timer runs only while there is something to redraw: samples, events, a
view change or a dock shown start it, and it stops after a tick that found
nothing to do (or, when only a put-off move is left, sleeps until it is due).
A dock that is not on screen, hidden or behind another tab, does not redraw
(it catches up when shown); when only time advanced, the plots move instead
of redrawing, and only while something runs. The watch polls the
controller's variables only while something runs and the watch is on screen.
"""

from __future__ import annotations

import html

import time
from typing import Mapping, Optional

from PySide6 import QtCore, QtWidgets
import pyqtgraph as pg  # noqa: I001 - after PySide6 (it takes the loaded binding)

from plcbuilder.api import abi
from plcbuilder.link.client import ControllerStatus
from plcbuilder.api import events as ev
from plcbuilder.ide.link_reasons import CLOSED_BY_IDE
from plcbuilder.ide.docks import RUN_DOCKS, on_screen
from plcbuilder.ide.panels.cursors import CursorTable, Cursors
from plcbuilder.ide.elided_label import ElidedLabel
from plcbuilder.ide.panels.inputs import InputsPanel
from plcbuilder.ide.panels.log import LogPanel
from plcbuilder.ide.panels.model import RunModel
from plcbuilder.ide.panels.plots import AnalogPanel, AxesPanel, LanesPanel, ProcPanel, TimeBase
from plcbuilder.ide.panels.registers import RegistersPanel, bit_names
from plcbuilder.ide.panels.traces import TraceTools
from plcbuilder.ide.panels.watch import WatchPanel
from plcbuilder.lang import symbols as lang_symbols

Qt = QtCore.Qt
Signal = QtCore.Signal

__all__ = ["RunPanels", "pin_names_from_defines", "default_pin_names"]

FPS = 40                       # redraws a second (at most)
VARIABLES_INTERVAL_MS = 250    # watch polls while something runs
BUSY_GRACE = 0.5               # seconds the plots keep moving after the last run ended
MARKER_COLOUR = "#b3261e"      # the failing tick of a recorded test run


#: Pin names from defines (INPUT_* / OUTPUT_*): a name -> value text, (text, span) or int.
pin_names_from_defines = lang_symbols.pin_names


def pin_names_from_header(text: str) -> tuple[dict[int, str], dict[int, str]]:
    """Pin names from the text of a pins.h."""
    return lang_symbols.pin_names(lang_symbols.file_defines(text, "pins.h"))


def default_pin_names() -> tuple[dict[int, str], dict[int, str]]:
    """The names of the built-in pins.h (the default machine's wiring)."""
    return lang_symbols.pin_names(lang_symbols.header_defines(()))


class RunPanels(QtCore.QObject):
    """The run docks: proc, outputs, analog, axes, inputs, watch, log."""

    sig_open_location = Signal(str, int)
    """A fault was clicked in the log: its source file and line (1-based). The
    file is the one the compiler recorded, or ``NAME.plc`` of the procedure."""

    sig_recorded = Signal(object)
    """The panels show a recorded test run (its name), or the live controller
    again (None)."""

    sig_comparison = Signal(object)
    """A second trace is drawn over the one on show (its name), or no more (None)."""

    sig_live = Signal()
    """The panels redrew with the controller's telemetry for the first time
    (once; :attr:`live` says whether they have)."""

    DOCKS = RUN_DOCKS

    def __init__(self, main_window: Optional[QtWidgets.QWidget], connection,
                 capacity: int = 30000, fps: int = FPS,
                 docks: Optional[Mapping[str, QtWidgets.QDockWidget]] = None,
                 lazy: bool = False):
        """``docks``: empty docks to fill (by key), made before the window
        showed; by default the panels make their own. ``lazy``: a dock's panel
        is made when it is first asked for (:meth:`panel`, or its attribute:
        ``.lanes``), not now: the window makes those of the docks on screen
        (docks.DockTable.release), and the others when their dock shows.
        The log is made at once either way (it keeps every message)."""
        super().__init__(main_window)
        self.connection = connection
        self.model = RunModel(capacity)
        self.live_capacity = int(capacity)
        self.timebase = TimeBase(parent=self)
        self.target = "mycnc"
        self._pin_names: tuple[dict, dict] = default_pin_names()
        self._made: dict[str, QtWidgets.QWidget] = {}   # the panels made, by dock key
        self._status = "No controller"      # what the proc panel's status says
        self._registers_report: dict = {}   # the last register report (not myCNC)
        self._span: Optional[tuple[float, float]] = None  # a recorded run's span on show
        self.traces = TraceTools(self)
        self.traces.sig_note.connect(lambda text: self.log.add_note(text, "link"))
        self.cursors = Cursors(self)
        self.banners: list[ElidedLabel] = []        # "showing test run …" beside
        self.banner_links: list[QtWidgets.QLabel] = []   # "Back to Live"
        self.compare_links: list[QtWidgets.QLabel] = []  # "Clear Comparison"
        self._docks: dict[str, QtWidgets.QDockWidget] = {}
        for key, title, object_name in self.DOCKS:
            dock = docks.get(key) if docks else None
            if dock is None:
                dock = QtWidgets.QDockWidget(title, main_window)
                dock.setObjectName(object_name)
            dock.setAllowedAreas(Qt.DockWidgetArea.AllDockWidgetAreas)
            dock.visibilityChanged.connect(self._on_visibility)
            self._docks[key] = dock
        #: each panel's dock (a panel stays in its dock: on_screen need not look for it)
        self._dock_of: dict[int, QtWidgets.QDockWidget] = {}
        self.forces: list = []
        self._stopped = True          # until the timers exist
        self._state = ControllerStatus()
        self._missed = 0
        self._running: Optional[str] = None
        self._final_poll = 0          # polls still due after something ended
        self._busy_until = 0.0        # monotonic time the plots may move until
        self.ticks = 0                # redraw timer ticks (tests count them)
        self.live = False             # redrawn with telemetry (sig_live)
        self._inputs_shown = None     # the inputs and ADC values the inputs panel shows
        self.recorded: Optional[str] = None   # the test run shown instead of live telemetry
        self.failing_ms: Optional[int] = None
        self.held = 0                 # live samples not shown while a recorded run is
        self._markers: list = []      # (panel, plot, InfiniteLine) at the failing tick
        self._marker_label: Optional[str] = None
        #: a second trace drawn over the one on show (plots/overlay.py)
        self.comparison = None
        self._banner_text = ""
        self._banner_shown = ""       # the banner's text as shown ("": hidden)
        self._connected_to: Optional[str] = None   # the controller's address (None: none)
        self._variables: Optional[tuple] = None    # the last variables polled, for the watch

        c = connection
        c.sig_samples.connect(self._on_samples)
        c.sig_events.connect(self._on_events)
        c.sig_state.connect(self._on_state)
        c.sig_connected.connect(self._on_connected)
        c.sig_disconnected.connect(self._on_disconnected)
        c.sig_error.connect(lambda text: self.log.add_note(text, "error"))
        if hasattr(c, "sig_note"):
            c.sig_note.connect(lambda text: self.log.add_note(text, "link"))
        if hasattr(c, "sig_variables"):
            c.sig_variables.connect(self._on_variables)
        if hasattr(c, "sig_target_report"):
            c.sig_target_report.connect(self._on_registers)
        self.panel("log")                   # it keeps every message, shown or not
        if getattr(c, "connected", False):
            self._on_connected(getattr(c, "address", ""))

        self.frame_ms = max(1, 1000 // max(1, fps))
        self.timer = QtCore.QTimer(self)
        self.timer.setTimerType(Qt.TimerType.PreciseTimer)
        self.timer.setInterval(self.frame_ms)
        self.timer.timeout.connect(self.tick)
        self.var_timer = QtCore.QTimer(self)
        self.var_timer.setInterval(VARIABLES_INTERVAL_MS)
        self.var_timer.timeout.connect(self._poll_variables)
        self._stopped = False
        if not lazy:
            for key, _title, _name in self.DOCKS:
                self.panel(key)
        self.wake()

    # ------------------------------------------------------------- the panels
    #: the time panels' dock keys, in the order :attr:`time_panels` lists them
    TIME_KEYS = ("proc", "outputs", "analog", "axes")

    def panel(self, key: str) -> QtWidgets.QWidget:
        """The panel of run dock ``key``, made now (and put in its dock) if it
        was not: it catches up with what the others show (the samples, a
        recorded run or comparison on show, the cursors, pin names, forces)."""
        made = self._made.get(key)
        if made is None:
            made = self._made[key] = self._make(key)
            self._dock_of[id(made)] = self._docks[key]
            self._docks[key].setWidget(made)
            if key in self.TIME_KEYS:
                self._catch_up(made)
            if not self._stopped:
                # drawn on the next turn (before what was queued after it), not
                # a frame later
                QtCore.QTimer.singleShot(0, self, self.tick)
        return made

    @property
    def made(self) -> dict:
        """The panels made so far, by dock key."""
        return dict(self._made)

    proc = property(lambda self: self.panel("proc"))
    lanes = property(lambda self: self.panel("outputs"))
    analog = property(lambda self: self.panel("analog"))
    axes = property(lambda self: self.panel("axes"))
    inputs = property(lambda self: self.panel("inputs"))
    watch = property(lambda self: self.panel("watch"))
    log = property(lambda self: self.panel("log"))
    cursor_table = property(lambda self: self.panel("cursors"))

    @property
    def registers(self) -> RegistersPanel:
        """A target's registers, under the watch (hidden on myCNC: docs/targets.md)."""
        return self.watch.registers

    @property
    def time_panels(self) -> tuple:
        """The time panels made so far (proc, outputs, analog, axes)."""
        return tuple(self._made[k] for k in self.TIME_KEYS if k in self._made)

    def _make(self, key: str) -> QtWidgets.QWidget:
        if key in self.TIME_KEYS:
            return self._make_time_panel(key)
        c = self.connection
        force = hasattr(c, "force")          # the debugger's write/force/release
        debugger = bool(getattr(c, "debugger", False)) and self._connected_to is not None
        if key == "inputs":
            inputs = InputsPanel(self.model, names=self._pin_names[0],
                                 bank="X" if self.target == "huazhong" else None)
            inputs.sig_set_input.connect(lambda pin, v: self.connection.set_input(pin, v))
            inputs.sig_set_input.connect(self.wake)
            inputs.sig_set_adc.connect(lambda ch, v: self.connection.set_adc(ch, v))
            if force:
                inputs.sig_force.connect(lambda t, v: c.force(t, v))
                inputs.sig_force.connect(self.wake)
                inputs.sig_release.connect(lambda t, m: c.release(t, m))
            inputs.set_enabled(self._connected_to is not None)
            inputs.force_by_hand = debugger
            inputs.set_forces(self.forces)
            self._inputs_shown = None
            return inputs
        if key == "watch":
            watch = WatchPanel()
            watch.registers = RegistersPanel()
            watch.add_section(watch.registers)
            if self.target != "mycnc":
                watch.registers.set_report(self._registers_report)
            if force:
                watch.sig_write.connect(lambda t, v: c.write(t, v))
                watch.sig_force.connect(lambda t, v: c.force(t, v))
                watch.sig_release.connect(lambda t, m: c.release(t, m))
            watch.editable = debugger
            watch.set_forces(self.forces)
            if self._variables is not None:
                watch.set_variables(*self._variables)
            return watch
        if key == "log":
            log = LogPanel()
            log.sig_open_location.connect(self.sig_open_location)
            return log
        if key == "cursors":
            table = CursorTable(self, self.cursors)
            self.sig_comparison.connect(table.set_compared)
            if self.comparison is not None:
                table.set_compared(self.comparison.name)
            return table
        raise KeyError(key)

    def _make_time_panel(self, key: str):
        kind = {"proc": ProcPanel, "outputs": LanesPanel, "analog": AnalogPanel,
                "axes": AxesPanel}[key]
        panel = kind(self.model, self.timebase, self.clear)
        panel.sig_dirty.connect(self.wake)
        if key == "outputs":
            panel.layout().insertWidget(1, self.traces.bar)
            names = self._pin_names
            if self.target == "huazhong":
                names = self._bank_names(*names)
            panel.set_pin_names(*names)
            panel.set_forces(self.forces)
            if bool(getattr(self.connection, "debugger", False)) and self._connected_to:
                panel.force_menu = self._lane_force_menu
        # a long test name must never widen the dock (and the window), nor
        # vanish in a narrow one: the link keeps its room, the text elides
        back = QtWidgets.QLabel("<a href='live'>Back to Live</a>")
        back.linkActivated.connect(lambda _link: self.back_to_live())
        back.setVisible(self.recorded is not None)
        clear_compare = QtWidgets.QLabel("<a href='clear'>Clear Comparison</a>")
        clear_compare.setToolTip("Stop drawing the compared trace over this one")
        clear_compare.linkActivated.connect(lambda _link: self.clear_comparison())
        clear_compare.setVisible(self.comparison is not None)
        label = ElidedLabel(min_chars=8)
        label.hide()
        # (rows of their own under the plot's buttons: what is on show, then the links)
        panel.toolbar.banner_row.addWidget(label, 1)
        panel.toolbar.shown_row.addWidget(back)
        panel.toolbar.shown_row.addWidget(clear_compare)
        panel.toolbar.shown_row.addStretch(1)
        self.banner_links.append(back)
        self.compare_links.append(clear_compare)
        self.banners.append(label)
        if self._banner_shown:
            self._show_banner(label)
        panel._epoch = self.model.epoch
        panel.model_cleared()
        panel._view_dirty = True
        if key == "proc":
            panel.set_status(self._status)
            if self.model.messages:
                panel.add_messages(self.model.messages)
        return panel

    def _catch_up(self, panel) -> None:
        """A time panel made now, in its dock, shows what the others show: a
        comparison, a recorded run's span and marker, the cursors."""
        if self.comparison is not None:
            panel.set_comparison(self.comparison)
        if self.recorded is not None and self.failing_ms is not None:
            self._add_markers(panel)
            self._place_markers()
        if self.recorded is not None and self._span is not None:
            panel.show_span(*self._span)
        if self.cursors.enabled:
            self.cursors.add_panel(panel)

    # ------------------------------------------------------------------- API
    def docks(self) -> list[QtWidgets.QDockWidget]:
        """The docks, for the main window to place (each has an objectName)."""
        return list(self._docks.values())

    def dock(self, key: str) -> QtWidgets.QDockWidget:
        """One dock by key: proc, outputs, analog, axes, inputs, watch, log."""
        return self._docks[key]

    def feed(self, samples: list, events: list) -> None:
        """Telemetry that came before the panels were made (the window keeps
        it for them): shown as if it had just come."""
        if events:
            self._on_events(list(events))
        if samples:
            self._on_samples(list(samples))

    def set_pin_names(self, inputs: Mapping[int, str], outputs: Mapping[int, str]) -> None:
        """Names for the lanes and toggles (from the project's pins.h); on the
        Huazhong target each is first the bank bit it is (X0.0, Y0.7)."""
        inputs, outputs = dict(inputs), dict(outputs)
        self._pin_names = (inputs, outputs)
        lanes, toggles = self._made.get("outputs"), self._made.get("inputs")
        if lanes is not None:
            lanes.set_pin_names(*(self._bank_names(inputs, outputs)
                                  if self.target == "huazhong" else (inputs, outputs)))
        if toggles is not None:
            # the toggles say the bank bit where the pin number would be (not both)
            toggles.set_pin_names(inputs, "X" if self.target == "huazhong" else None)

    @staticmethod
    def _bank_names(inputs: dict, outputs: dict) -> tuple[dict, dict]:
        """Huazhong: each pin first the bank bit it is (X0.0, Y0.7)."""
        return (bit_names(max(64, max(inputs, default=0) + 1), "X", inputs),
                bit_names(max(64, max(outputs, default=0) + 1), "Y", outputs))

    def set_forces(self, forces: list) -> None:
        """What is forced: the watch, the inputs and the lanes mark it."""
        forces = list(forces or [])
        self.forces = forces
        for key in ("watch", "inputs", "outputs"):
            if key in self._made:
                self._made[key].set_forces(forces)
        self.wake()

    def _lane_force_menu(self, menu: QtWidgets.QMenu, lane: tuple) -> None:
        kind, pin = lane
        t = f"{'out' if kind == 'outputs' else 'in'} {pin}"
        c = self.connection
        for text, slot in ((f"Force {t} On (1)", lambda: c.force(t, 1)),
                           (f"Force {t} Off (0)", lambda: c.force(t, 0))):
            menu.addAction(text, slot)
        for mode, text in (("keep", "keep the value"), ("restore", "restore the program's")):
            act = menu.addAction(f"Release {t} ({text})", lambda m=mode: c.release(t, m))
            act.setEnabled(lane in self.lanes.forced)
    def set_target(self, target: str) -> None:
        """The open project's target (docs/targets.md): the lanes' names, and
        the registers under the watch (shown once the controller reports them)."""
        self.target = target or "mycnc"
        if self.target == "mycnc":
            self._registers_report = {}
            if "watch" in self._made:
                self.registers.set_report({})
        self.set_pin_names(*self._pin_names)

    def project_changed(self) -> None:
        """Another project (or none): a recorded test run or a trace of the last
        one is no longer shown, and its trigger no longer waits (issue 23.8, 9)."""
        self.back_to_live()
        self.traces.project_changed()         # disarmed, the project's own trigger shown

    def clear(self) -> None:
        """Forget the recorded samples and messages (the log keeps its rows);
        while a recorded test run is shown, go back to live."""
        if self.recorded is not None:
            self.back_to_live()
            return
        self.model.clear()
        self._cleared()

    def show_recorded(self, name: str, samples: list, events: list,
                      failing_ms: Optional[int] = None, text: Optional[str] = None,
                      marker_label: Optional[str] = None, variables: Optional[dict] = None,
                      bits: Optional[dict] = None) -> None:
        """Show a recorded test run (or a trace: ``text`` says what it is)
        instead of the live telemetry (which is not shown until
        :meth:`back_to_live`): its samples and events, the Proc and Outputs
        docks raised, not following, the failing tick (or the trigger) in view
        with a line at it (labelled ``marker_label``). ``variables``: its
        watched variables' changes (``{name: [(t_ms, value), …]}``), ``bits``
        the bit its trigger watched of one (``{name: bit}``). A comparison on
        show ends."""
        self.clear_comparison()
        self.recorded, self.failing_ms, self.held = name, failing_ms, 0
        self.model.resize(max(self.live_capacity, 2 * len(samples) + 16))
        self.model.add_samples(samples)
        self.model.set_watched(variables or {}, bits)
        self._cleared()
        rows = self.model.add_events(events)
        if rows and "proc" in self._made:
            self.proc.add_messages(rows)
        if text is None:
            at = f", failing at t = {failing_ms} ms" if failing_ms is not None else ""
            text = f"showing test run '{name}' (recorded){at}"
        self.log.show_recorded(text, events)
        self._set_banner(text)
        for link in self.banner_links:
            link.show()
        self._remove_markers()
        self._marker_label = marker_label
        if failing_ms is not None:
            for panel in self.time_panels:
                self._add_markers(panel)
        self._span = None
        for key in ("proc", "outputs"):
            self._docks[key].show()
            self._docks[key].raise_()
            self.panel(key)
        t = self.model.time.view()
        first = float(t[0]) if len(t) else 0.0
        t1 = max(self.model.t_end, (failing_ms or 0) * 1e-3)
        t0 = max(first, t1 - self.timebase.window) if self.timebase.window > 0 else first
        if t1 - t0 < 0.01:
            t1 = t0 + 0.01
        self.show_span(t0, t1)
        self._place_markers()
        self.sig_recorded.emit(name)
        self.wake()

    def show_span(self, t0: float, t1: float) -> None:
        """Every time panel shows ``t0..t1`` (seconds; those made later too,
        while a recorded run is on show)."""
        self._span = (t0, t1)
        for panel in self.time_panels:
            panel.show_span(t0, t1)

    def _add_markers(self, panel) -> None:
        """A line at the failing tick (or the trigger) in each plot of ``panel``."""
        pen = pg.mkPen(MARKER_COLOUR, width=1.5, style=Qt.PenStyle.DashLine)
        label = self._marker_label
        opts = {"label": label, "labelOpts": {"position": 0.5, "color": MARKER_COLOUR}} \
            if label else {}
        for plot in panel._time_plots:
            line = pg.InfiniteLine(angle=90, movable=False, pen=pen, **opts)
            line.setZValue(20)
            plot.addItem(line, ignoreBounds=True)
            self._markers.append((panel, plot, line))

    def back_to_live(self) -> None:
        """Stop showing a recorded test run: the plots start over with the
        live telemetry, following it."""
        if self.recorded is None:
            return
        self.clear_comparison()
        self.recorded, self.failing_ms, self._span = None, None, None
        self._banner_shown = ""
        for label in self.banners + self.banner_links:
            label.hide()
        self._remove_markers()
        self.model.resize(self.live_capacity)
        self.model.set_watch_bits(self.traces.live_bits)
        self._cleared()
        self.timebase.set_follow(True)
        self.log.back_to_live("back to the live controller")
        self.traces.shown_over()
        self.sig_recorded.emit(None)

    def compare(self, comparison) -> None:
        """Draw a second trace (plots/overlay.py ``Comparison``) over the one on
        show, in every time panel, until :meth:`clear_comparison` (or Back to
        Live, or another trace shown)."""
        self.comparison = comparison
        for panel in self.time_panels:
            panel.set_comparison(comparison)
        for link in self.compare_links:
            link.show()
        # the key above the plots says which line is which trace: the bar says
        # first what the comparison found (kept where the dock is narrow), the
        # whole sentence (how they were lined up) in its tooltip
        found = comparison.where.rpartition("; ")[2]
        self._set_banner(f"{found}: {comparison.name} (dashed)",
                         f"comparing {comparison.base} (solid) with {comparison.name} "
                         f"(dashed): {comparison.where}")
        self.sig_comparison.emit(comparison.name)
        self.wake()

    def clear_comparison(self) -> None:
        """Stop drawing the compared trace (the trace on show stays)."""
        if self.comparison is None:
            return
        base = self.comparison.base
        self.comparison = None
        for panel in self.time_panels:
            panel.set_comparison(None)
        for link in self.compare_links:
            link.hide()
        if self.recorded is not None:
            self._set_banner(f"showing {base}")
        self.sig_comparison.emit(None)
        self.wake()

    def _set_banner(self, text: str, whole: Optional[str] = None) -> None:
        """What is on show, above the plots (``whole``: the longer sentence
        for its tooltip, default ``text``)."""
        self._banner_text = whole or text
        self._banner_shown = text
        for label in self.banners:
            self._show_banner(label)

    def _show_banner(self, label: ElidedLabel) -> None:
        label.setText(f"<span style='color:{MARKER_COLOUR}'>"
                      f"{html.escape(self._banner_shown, quote=False)}</span>")
        label.setToolTip(f"{self._banner_text}; the live telemetry is not shown until "
                         f"Back to Live (or Clear)")
        label.show()

    def wake(self, *args) -> None:
        """Something may need a redraw: run the redraw timer (it stops itself).
        A timer waiting longer for a put-off move comes back at once."""
        if self._stopped:
            return
        if not self.live and len(self.model):
            self.timer.start(0)             # the first telemetry: at once, not a frame later
        elif not self.timer.isActive() or self.timer.remainingTime() > self.frame_ms:
            self.timer.start(self.frame_ms)

    def busy(self) -> bool:
        """Something runs on the controller (or ended a moment ago)."""
        if self._running or self._state.software or self.model.running:
            self._busy_until = time.monotonic() + BUSY_GRACE
            return True
        return time.monotonic() < self._busy_until

    def tick(self) -> None:
        """One redraw: flush queued rows, refresh the visible panels; stop the
        timer when nothing was left to do."""
        self.ticks += 1
        moving = self.busy()
        work = False
        due: Optional[float] = None         # a put-off time-only move: due in (s)
        for panel in self.time_panels:
            if self._shown(panel):
                work |= panel.refresh(moving=moving)
                d = panel.move_due()
                if d is not None:
                    due = d if due is None else min(due, d)
        if self._markers:
            self._place_markers()
        made = self._made
        if self.cursors.enabled:
            self.cursors.place()
            if work and "cursors" in made and self._shown(made["cursors"]):
                made["cursors"].refresh()
        if "proc" in made:
            made["proc"].flush()
        made["log"].flush()
        inputs = made.get("inputs")
        if inputs is not None and self._shown(inputs):
            s = self.model.last_sample
            key = (s.inputs, s.adc) if s is not None else None
            pending = bool(getattr(inputs, "_pending", None))
            if key != self._inputs_shown or pending:
                self._inputs_shown = key
                inputs.refresh()
        else:
            pending = False
        if not self.live and len(self.model):
            self.live = True
            self.sig_live.emit()
        if self._stopped:
            return
        # what arrives next (samples, events, a view change) wakes the timer
        # again; after a redraw or a move nothing else needs a frame, except a
        # clicked input whose new state is on its way
        if pending:
            if self.timer.interval() != self.frame_ms or not self.timer.isActive():
                self.timer.start(self.frame_ms)
        elif due is not None:
            # only a move is left: come back when it is due, not every frame
            self.timer.start(max(1, int(due * 1000 + 0.999)))
        else:
            self.timer.stop()

    def shutdown(self) -> None:
        self._stopped = True
        self.timer.stop()
        self.var_timer.stop()

    # --------------------------------------------------------------- private
    def _shown_key(self, key: str) -> bool:
        """The panel of dock ``key`` is made and can be seen."""
        w = self._made.get(key)
        return w is not None and self._shown(w)

    def _shown(self, w: QtWidgets.QWidget) -> bool:
        """``w`` can be seen (docks.on_screen: a dock tabbed away is "visible"
        to Qt), for a panel of these docks without looking for its dock."""
        dock = self._dock_of.get(id(w))
        if dock is None or dock.widget() is not w:
            return on_screen(w)
        if not w.isVisible():
            return False
        if dock.isFloating():
            return True
        g = dock.geometry()
        return g.right() >= 0 and g.bottom() >= 0

    def _place_markers(self) -> None:
        for panel, _plot, line in self._markers:
            line.setPos(self.failing_ms * 1e-3 - panel.offset)

    def _remove_markers(self) -> None:
        for _panel, plot, line in self._markers:
            plot.removeItem(line)
        self._markers = []

    def _cleared(self) -> None:
        for p in self.time_panels:
            p._epoch = self.model.epoch
            p.model_cleared()
            p._view_dirty = True
        self.wake()

    def _on_visibility(self, visible: bool) -> None:
        if visible:
            self.wake()
            if self._shown_key("watch") and not self._stopped:
                self._poll_variables()
                if self._final_poll > 0 or self.busy():
                    self.var_timer.start()

    def _on_samples(self, samples: list) -> None:
        self.traces.feed(samples)           # the whole session, recorded or not
        if self.recorded is not None:       # a recorded run is shown: live waits
            self.held += len(samples)
            return
        epoch = self.model.epoch
        self.model.add_samples(samples)
        if self.model.epoch != epoch:
            self._cleared()
        elif self.timer.isActive() and not self._news():
            return          # only time advanced: the move the timer waits for shows it
        self.wake()

    def _news(self) -> bool:
        """Whether the samples just added change what a panel on screen shows
        (a value, not only the time), so the redraw timer must come sooner
        than the move it waits for."""
        if self.cursors.enabled:
            return True
        for panel in self.time_panels:
            if self._shown(panel) and (panel._view_dirty or panel.data_changed()):
                return True
        if self._shown_key("inputs"):
            s = self.model.last_sample
            if s is not None and (s.inputs, s.adc) != self._inputs_shown:
                return True
        return False

    def _on_events(self, events: list) -> None:
        self.traces.feed([], events)
        rows = self.model.add_events(events) if self.recorded is None else []
        if rows and "proc" in self._made:
            self.proc.add_messages(rows)
        self.log.add_events(events)
        if any(isinstance(e, (ev.Ended, ev.Fault)) for e in events):
            self._final_poll = 2
            self._poll_variables()
            self.var_timer.start()
        self.wake()

    def _on_state(self, st: ControllerStatus, missed: int = 0) -> None:
        self._state = st
        self._running = st.running
        if (st.running or st.software) and not self.var_timer.isActive() and \
                not self._stopped and self._shown_key("watch"):
            self.var_timer.start()
        parts = []
        if self._running:
            parts.append(f"<b>Running {self._running}</b>")
        else:
            parts.append("Idle")
        job = getattr(st, "job", None)
        if job:                         # the G-code job: its file, line and state
            from pathlib import Path
            text = (f"G-code {Path(str(job.get('file', ''))).name} line "
                    f"{job.get('line', 0)}/{job.get('lines', 0)} {job.get('state', '')}")
            last = job.get("last_call")
            if isinstance(last, dict) and last.get("code"):     # the procedure it called last
                code = last.get("exit_code")
                text += (f", line {last.get('line')} {last.get('code')} → "
                         f"{last.get('procedure') or 'no procedure'} "
                         + ("running" if code is None and last.get("procedure")
                            else "" if code is None else f"exit {code}")).rstrip()
            parts.append(text)
        soft = st.software
        if soft:
            parts.append("software: " + ", ".join(map(str, soft[:4]))
                         + (" …" if len(soft) > 4 else ""))
        proc = st.proc
        name = st.proc_name or abi.proc_name(proc)
        parts.append(f"proc {name} ({proc})" if name else f"proc {proc}")
        # (no time here: the status bar shows it, in a label of fixed size; a
        # text that changed five times a second laid the whole window out again)
        speed = st.speed
        if isinstance(speed, dict) and speed.get("mode"):
            mode = speed["mode"]
            if mode == "factor":
                mode = f"{speed.get('factor', 0):g}×"
            parts.append(mode)
        # (at any speed: the IDE gets every change unless the controller had
        # to drop some, and then says so; "plots thinned" at Max was not so)
        if missed > self._missed:
            parts.append(f"<span style='color:#b35c00'>telemetry behind: "
                         f"{missed - self._missed} samples dropped</span>")
        self._missed = missed
        self._set_status("  ·  ".join(parts))

    def _set_status(self, text: str) -> None:
        self._status = text
        if "proc" in self._made:
            self.proc.set_status(text)

    def _on_connected(self, address: str) -> None:
        self._connected_to = address
        made = self._made
        debugger = bool(getattr(self.connection, "debugger", False))
        if "inputs" in made:
            made["inputs"].set_enabled(True)
            made["inputs"].force_by_hand = debugger
        if "watch" in made:
            made["watch"].editable = debugger
        if "outputs" in made:
            made["outputs"].force_menu = self._lane_force_menu if debugger else None
        self._set_status(f"Connected to {address}")     # not "Disconnected" any more
        self.log.add_note(f"connected to the controller at {address}", "link")

    def _on_disconnected(self, reason: str) -> None:
        self._connected_to = None
        if "inputs" in self._made:
            self._made["inputs"].set_enabled(False)
        if reason == CLOSED_BY_IDE:          # another project, quitting: not an error
            self._set_status("No controller")
            self.log.add_note("disconnected from the controller (the IDE closed it)", "link")
            return
        self._set_status(f"<span style='color:#c62828'>Disconnected</span>: {reason}")
        self.log.add_note(f"controller disconnected: {reason}", "error")

    def _poll_variables(self) -> None:
        busy = bool(self._running) or bool(self._state.software)
        if not busy and self._final_poll <= 0:
            self.var_timer.stop()           # nothing runs: nothing to poll
            return
        if not getattr(self.connection, "connected", False):
            return
        if not self._shown_key("watch"):
            self.var_timer.stop()           # until the watch shows (the final polls wait too)
            return
        if not busy:
            self._final_poll -= 1
        if hasattr(self.connection, "request_variables"):
            self.connection.request_variables()

    def _on_registers(self, report: dict) -> None:
        if self.target != "mycnc":
            self._registers_report = report
            if "watch" in self._made:
                self.registers.set_report(report)

    def _on_variables(self, variables: dict) -> None:
        self._variables = (variables, self._running)
        if "watch" in self._made:
            self.watch.set_variables(variables, self._running)
