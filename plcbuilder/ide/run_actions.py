"""The run side's actions: Build All, Upload, Start, Stop, the speed, Reset,
and the controller connection the IDE talks to.

Upload may need a build first; that sequence is a small state machine
(:class:`Step`): Upload starts a build in the step ``BUILD_THEN_UPLOAD`` and the
finished build uploads the image only from that step, and only when it succeeded.
"Build, Upload and Start" is the step ``BUILD_UPLOAD_START``: after a
successful build it uploads, then starts (the link runs requests in order).

Start warns first when it would run something other than what the editors
show (:mod:`plcbuilder.ide.image_state`: unsaved, unbuilt or not uploaded)
and offers "Build, Upload and Start". When a controller connects with nothing
loaded and the project has a ``build/eeprom.rom``, that image is uploaded.
"""

from __future__ import annotations

import enum
from pathlib import Path
from typing import Optional

from PySide6.QtCore import QObject, Signal
from PySide6.QtGui import QAction, QActionGroup
from PySide6.QtWidgets import QComboBox, QMessageBox

from plcbuilder._support.files import read_bounded
from plcbuilder.api import Kind, ProjectError
from plcbuilder.ide import dialogs
from plcbuilder.ide.build_runner import BuildRunner

#: simulation speeds: (label, connection mode)
SPEEDS = (("1×", "realtime"), ("10×", "10"), ("Max", "max"), ("Pause", "pause"))


#: where the embedded controller keeps a target's state (Huazhong's B registers)
STATE_FILE = "controller-state.json"


class Step(enum.Enum):
    """Where the build → upload sequence is."""
    IDLE = "idle"                            # no build running
    BUILD = "build"                          # Build All alone
    BUILD_THEN_UPLOAD = "build then upload"  # Upload asked for a build first
    BUILD_UPLOAD_START = "build, upload and start"


class _DropDownCombo(QComboBox):
    """A combo box whose list drops down below it: the style's own popup is
    laid over the box around the current item, and in a toolbar at the top of
    the screen its first items were above the screen's edge. The style sheet
    that says so is set when the list first opens (one parsed at start-up
    made the window's first paint wait)."""

    def showPopup(self) -> None:  # noqa: N802 - Qt override
        if not self.styleSheet():
            self.setStyleSheet("QComboBox { combobox-popup: 0; }")
        super().showPopup()


class RunActions(QObject):
    """Build All, Upload, Start, Stop, the speed and the controller connection."""

    sig_message = Signal(str, int)
    """A message for the status bar (text, milliseconds to show it; 0: until the next)."""

    sig_build_started = Signal()
    """Build All started (the Build Output panel shows)."""

    sig_build_ended = Signal()
    """Build All ended, whatever its result (before sig_build_result and sig_build_finished)."""

    sig_build_result = Signal(object)
    """Build All gave a BuildResult (not an exception): the problems follow it."""

    sig_build_finished = Signal(object)
    #: the controller's G-code job changed state (its state, "" when none is open)
    sig_job_state = Signal(str)
    """Build All finished (the BuildResult, or the exception it raised)."""

    def __init__(self, parent, editors, build_panel, prefs, *, connection=None,
                 start_controller: bool = True):
        """``build_panel``: the Build Output panel, or a function that gives it
        (the window makes it when first needed)."""
        super().__init__(parent)
        self.editors = editors                  # the EditorStack
        self._build_panel = build_panel
        self.prefs = prefs
        self.project = None
        self.connection = connection
        self.start_controller = start_controller
        self.step = Step.IDLE
        self.last_eparam = 0
        self.job_state = ""                     # the G-code job's state ("" when none is open)
        self.last_start = ""
        self.pending_start: Optional[tuple[str, int]] = None   # after BUILD_UPLOAD_START
        self.pending_gcode: Optional[tuple[str, str]] = None   # (text, path), likewise
        self._image_check_due = False
        self.build_runner = BuildRunner(self)
        self.build_runner.sig_progress.connect(self._on_build_progress)
        self.build_runner.sig_finished.connect(self._on_build_finished)
        self.speed_group = QActionGroup(self)
        self.speed_actions: dict[str, QAction] = {}
        for label, mode in SPEEDS:
            act = QAction(f"Speed {label}", self)
            act.setCheckable(True)
            act.setActionGroup(self.speed_group)
            act.triggered.connect(lambda _c=False, m=mode: self.set_speed(m))
            self.speed_actions[mode] = act
        self.speed_actions["realtime"].setChecked(True)
        self.speed_combo: Optional[QComboBox] = None
        #: the window's Settings: each project's last start, eparam and speed
        self.settings = None

    def project_opened(self) -> None:
        """The project's own last start, eparam and speed (remembered per
        project: another project's are not carried over)."""
        p, st = self.project, self.settings
        if p is None or st is None:
            self.last_eparam, self.last_start = 0, ""
            return
        try:
            self.last_eparam = int(st.project_value(p.root, "eparam", 0))
        except (TypeError, ValueError):
            self.last_eparam = 0
        self.last_start = str(st.project_value(p.root, "start", "") or "")
        speed = str(st.project_value(p.root, "speed", "realtime") or "realtime")
        if speed not in dict((m, m) for _l, m in SPEEDS) or speed == "pause":
            speed = "realtime"
        current = self.speed_combo.currentData() if self.speed_combo is not None else None
        if speed != current:
            self.set_speed(speed)

    def _remember(self, **values) -> None:
        if self.project is not None and self.settings is not None:
            for key, value in values.items():
                self.settings.set_project_value(self.project.root, key, value)

    def make_speed_combo(self, parent) -> QComboBox:
        """The speed box of the toolbar."""
        self.speed_combo = _DropDownCombo(parent)
        self.speed_combo.setToolTip("Simulation speed: real time, 10× real time, as fast as "
                                    "possible, or paused")
        for label, mode in SPEEDS:
            self.speed_combo.addItem(label, mode)
        self.speed_combo.currentIndexChanged.connect(
            lambda i: self.set_speed(self.speed_combo.itemData(i)))
        return self.speed_combo

    # ================================================================ build
    def build_all(self) -> bool:
        """Build All (saving first when the preference says so)."""
        return self._build(Step.BUILD)

    def upload(self) -> bool:
        """Upload build/eeprom.rom (building first when the preference says so)."""
        if self.project is None:
            return False
        if self.connection is None:
            self.sig_message.emit("No controller to upload to", 4000)
            return False
        stale = self.editors.modified_editors() or not self.project.image_path.exists()
        if self.prefs.build_before_upload or stale:
            return self._build(Step.BUILD_THEN_UPLOAD)
        return self.upload_image()

    def upload_image(self) -> bool:
        """Upload the image Build All wrote."""
        if self.project is None or self.connection is None:
            return False
        try:
            from plcbuilder.link.protocol import MAX_IMAGE
            data = read_bounded(self.project.image_path, MAX_IMAGE, "controller image")
        except OSError as exc:
            QMessageBox.warning(self.parent(), "Upload",
                                f"Cannot read {self.project.image_path}:\n\n"
                                f"{exc.strerror or exc}\n\nBuild the project first.")
            return False
        try:
            target = self.project.target_settings()
        except ProjectError as exc:
            QMessageBox.warning(self.parent(), "Upload", str(exc))
            return False
        if target["name"] == "mycnc":
            target = None
        else:
            target = {k: list(v) if isinstance(v, tuple) else v for k, v in target.items()}
        self.connection.upload(data, target)
        self.sig_message.emit(f"Uploading {self.project.image_path.name} "
                              f"({len(data)} bytes)…", 5000)
        return True

    def building(self) -> bool:
        return self.build_runner.running()

    def ensure_saved(self, what: str) -> bool:
        """Before ``what`` (Build All, Run Tests) reads the project's files:
        every editor's text is on disk. Saved without asking when the
        preference says so, else asked (Save All or Cancel); False: not saved,
        nothing may run (never silently on files the editors do not show)."""
        modified = self.editors.modified_editors()
        if not modified:
            return True
        if not self.prefs.save_before_build:
            names = ", ".join(Path(ed.path).name for ed in modified[:6]) + \
                (" …" if len(modified) > 6 else "")
            answer = QMessageBox.question(
                self.parent(), what,
                f"{len(modified)} file{'s' * (len(modified) != 1)} ha"
                f"{'ve' if len(modified) != 1 else 's'} unsaved changes ({names}).\n\n"
                f"{what} reads the files on disk: save them first?",
                QMessageBox.StandardButton.Save | QMessageBox.StandardButton.Cancel,
                QMessageBox.StandardButton.Save)
            if answer != QMessageBox.StandardButton.Save:
                return False
        return self.editors.save_all()

    # ================================================================== run
    def start_procedure(self, name: Optional[str] = None, eparam: Optional[int] = None) -> bool:
        """Start a procedure on the controller (asking which, when not given)."""
        if self.connection is None or self.project is None:
            self.sig_message.emit("No controller to start a procedure on", 4000)
            return False
        if name is None:
            procs = [(p.name, p.kind) for p in self.project.procedures()
                     if p.kind is Kind.HARDWARE or p.system]
            initial = self.last_start
            ed = self.editors.current_editor()
            if ed is not None and ed.kind is Kind.HARDWARE:
                initial = Path(ed.path).stem
            res = dialogs.StartDialog.get_start(self.parent(), procs, initial, self.last_eparam)
            if res is None:
                return False
            name, eparam = res
        eparam = self.last_eparam if eparam is None else int(eparam)
        self.last_start, self.last_eparam = name, eparam
        self._remember(start=name, eparam=eparam)
        reasons = self.stale_reasons()
        if reasons:
            answer = self.ask_stale_start(name, reasons)
            if answer is None:
                return False
            if answer == "build":
                return self.build_upload_start(name, eparam)
        self.connection.start(name, eparam)
        self.sig_message.emit(f"Start {name} (eparam {eparam})", 4000)
        return True

    def stale_reasons(self, exclude: Optional[str] = None) -> list[str]:
        """Why Start would not run what the editors show (empty: it would, or
        no controller is connected to tell). ``exclude``: a file whose editor's
        text is sent as it is (a G-code program), not a reason."""
        if self.project is None or not self.connected():
            return []
        from plcbuilder.ide.image_state import stale_reasons
        unsaved = [ed.path for ed in self.editors.modified_editors()
                   if exclude is None or Path(ed.path).resolve() != Path(exclude).resolve()]
        st = getattr(self.connection, "last_state", None)
        loaded = getattr(self.connection, "uploaded_crc", None) or getattr(st, "image_crc32", None)
        return stale_reasons(self.project, unsaved, loaded)

    def ask_stale_start(self, name: str, reasons: list[str]) -> Optional[str]:
        """Ask before starting old code: ``"build"`` (Build, Upload and Start),
        ``"start"`` (start anyway) or None (cancel)."""
        box = QMessageBox(QMessageBox.Icon.Warning, "Start",
                          "The controller would not run what the editors show:\n\n"
                          + "\n".join(f"  • {r}" for r in reasons)
                          + f"\n\nBuild All, upload the image and start {name}?",
                          parent=self.parent())
        build = box.addButton("Build, Upload and Start", QMessageBox.ButtonRole.AcceptRole)
        anyway = box.addButton("Start Anyway", QMessageBox.ButtonRole.DestructiveRole)
        box.addButton(QMessageBox.StandardButton.Cancel)
        box.setDefaultButton(build)
        box.setObjectName("staleStartBox")
        self.stale_box = box
        box.exec()
        clicked = box.clickedButton()
        self.stale_box = None
        return "build" if clicked is build else "start" if clicked is anyway else None

    def build_upload_start(self, name: Optional[str] = None,
                           eparam: Optional[int] = None) -> bool:
        """Build All, upload the image, then start a procedure (the current
        editor's, or the last one started)."""
        if self.connection is None or self.project is None:
            self.sig_message.emit("No controller to start a procedure on", 4000)
            return False
        if name is None:
            ed = self.editors.current_editor()
            name = Path(ed.path).stem if ed is not None and ed.kind is not None \
                else self.last_start
            if not name:
                return self.start_procedure()
        eparam = self.last_eparam if eparam is None else int(eparam)
        self.last_start, self.last_eparam = name, eparam
        self._remember(start=name, eparam=eparam)
        self.pending_start = (name, eparam)
        if not self._build(Step.BUILD_UPLOAD_START):
            self.pending_start = None
            return False
        return True

    def start_current(self) -> None:
        """Start the current editor's procedure with the last eparam."""
        ed = self.editors.current_editor()
        if ed is not None and ed.kind is not None:
            self.start_procedure(Path(ed.path).stem, self.last_eparam)
        else:
            self.start_procedure()

    # ------------------------------------------------------------ G-code jobs
    #: the file dialog's filter for G-code programs
    GCODE_FILTER = "G-code programs (*.nc *.ngc *.gcode *.tap *.cnc *.txt);;All files (*)"
    GCODE_SUFFIXES = (".nc", ".ngc", ".gcode", ".tap", ".cnc")

    def run_gcode(self, path: Optional[str] = None) -> bool:
        """Run a G-code program as a job on the controller (docs/controller.md,
        "G-code jobs"): asks for the file when not given (the current editor's
        when it holds one is offered). An open editor's text is what runs, saved
        or not; when the controller would not run the procedures the editors
        show, it asks first, as Start does. The controller checks the program
        whole; a line it cannot run comes back as an error naming it."""
        if self.connection is None:
            self.sig_message.emit("No controller to run a G-code program on", 4000)
            return False
        if path is None:
            from PySide6.QtWidgets import QFileDialog
            start = str(self.project.root) if self.project is not None else ""
            ed = self.editors.current_editor()
            if ed is not None and Path(ed.path).suffix.lower() in self.GCODE_SUFFIXES:
                start = str(ed.path)
            path, _ = QFileDialog.getOpenFileName(self.parent(), "Run G-code Program", start,
                                                  self.GCODE_FILTER)
            if not path:
                return False
        from plcbuilder.link.protocol import MAX_JOB_TEXT
        ed = self.editors.editor_for(path)
        if ed is not None:                      # what the editor shows, saved or not
            text = ed.text()
            if len(text.encode("utf-8")) > MAX_JOB_TEXT:
                QMessageBox.warning(self.parent(), "Run G-code Program",
                                    f"{Path(path).name} is over {MAX_JOB_TEXT} bytes")
                return False
        else:
            try:
                text = read_bounded(Path(path), MAX_JOB_TEXT, "G-code program").decode("utf-8")
            except (OSError, UnicodeDecodeError) as exc:
                why = getattr(exc, "strerror", None) or str(exc)
                QMessageBox.warning(self.parent(), "Run G-code Program",
                                    f"Cannot read {path}:\n\n{why}")
                return False
        name = Path(path).name
        reasons = self.stale_reasons(exclude=str(path))
        if reasons:
            answer = self.ask_stale_start(f"the G-code program {name}", reasons)
            if answer is None:
                return False
            if answer == "build":
                self.pending_gcode = (text, str(path))
                if not self._build(Step.BUILD_UPLOAD_START):
                    self.pending_gcode = None
                    return False
                return True
        self.connection.job("open", text, str(path), True)
        self.sig_message.emit(f"G-code program {name}: play", 4000)
        return True

    def job(self, verb: str) -> None:
        """Pause, play, stop or reset the G-code job."""
        if self.connection is not None:
            self.connection.job(verb)
            self.sig_message.emit(f"G-code program: {verb}", 3000)

    def stop(self) -> None:
        """Stop: the first press starts M02, the second OFF (the controller decides)."""
        if self.connection is not None:
            self.connection.stop()
            self.sig_message.emit("Stop", 3000)

    #: the project setting that keeps the codes issued last (newest first, a line each)
    CODE_HISTORY = "code_history"

    def code_history(self) -> list[str]:
        """The codes issued last in this project, newest first."""
        if self.project is None or self.settings is None:
            return []
        text = self.settings.project_value(self.project.root, self.CODE_HISTORY, "") or ""
        return [line for line in str(text).splitlines() if line.strip()]

    def issue_code(self, text: Optional[str] = None) -> bool:
        """Run › Issue Code…: the CNC issues M, S, B or T codes (``M3``,
        ``S12000 M3``) to the running controller, in order, through the link's
        ``code`` request (the controller records each, as it does a start or a
        force). ``text``: the codes, without the dialog. False: nothing issued."""
        if self.connection is None or not self.connected():
            self.sig_message.emit("No controller to issue a code to", 4000)
            return False
        from plcbuilder.ide.dialogs.issue_code import HISTORY, code_text, parse_codes
        if text is None:
            from plcbuilder.ide.dialogs.issue_code import IssueCodeDialog
            target = getattr(self.project, "target", None) or "mycnc"
            codes = IssueCodeDialog.get_codes(self.parent(), self.code_history(), target)
            if not codes:
                return False
        else:
            codes, why = parse_codes(text)
            if not codes:
                self.sig_message.emit(why or "Not a code", 5000)
                return False
        for letter, value in codes:
            self.connection.issue_code(letter, value)
        said = code_text(codes)
        if self.project is not None and self.settings is not None:
            history = [said] + [h for h in self.code_history() if h != said]
            self.settings.set_project_value(self.project.root, self.CODE_HISTORY,
                                            "\n".join(history[:HISTORY]))
        self.sig_message.emit(f"Issued {said}", 4000)
        return True

    def set_speed(self, mode: str) -> None:
        for label, m in SPEEDS:
            if m == mode:
                i = self.speed_combo.findData(m)
                if i >= 0 and self.speed_combo.currentIndex() != i:
                    self.speed_combo.blockSignals(True)
                    self.speed_combo.setCurrentIndex(i)
                    self.speed_combo.blockSignals(False)
                act = self.speed_actions.get(m)
                if act is not None:
                    act.setChecked(True)
        if mode != "pause":                 # (a project opens running, not paused)
            self._remember(speed=mode)
        if self.connection is not None:
            self.connection.set_speed(mode)

    def reset_controller(self) -> None:
        if self.connection is not None:
            self.connection.reset()

    # =========================================================== controller
    def start_controller_for_project(self) -> None:
        c = self.connection
        if c is None or not self.start_controller or not hasattr(c, "start_embedded"):
            return
        p = self.project
        address = p.settings.controller_address if p is not None else ""
        if address:
            self._connect_to_address(address)
            return
        c.start_embedded(self.controller_args())

    def prestart_controller_for_project(self) -> None:
        """Start the project's embedded controller process now, before the
        window's first paint (its own Python takes longer to start than the
        window: it runs on the other core meanwhile); the connection to it
        comes with :meth:`start_controller_for_project`."""
        c = self.connection
        if c is None or not self.start_controller or not hasattr(c, "prestart"):
            return
        p = self.project
        if p is None or p.settings.controller_address:
            return
        c.prestart(self.controller_args())

    def controller_args(self) -> list[str]:
        p = self.project
        args: list[str] = []
        if p is None:
            return args
        if p.machine_path.is_file():
            args += ["--machine", str(p.machine_path)]
        if p.variables_path.is_file():
            args += ["--variables", str(p.variables_path)]
        # always: the controller generates a missing IO.DAT (the softMC seed)
        args += ["--io-dat", str(p.root / "IO.DAT")]
        lim = p.limits
        args += ["--limits", f"{lim.hw_proc},{lim.hw_total},{lim.sw_proc}"]
        if getattr(p, "target", "mycnc") != "mycnc":
            # Huazhong's B registers are kept across restarts of the IDE too
            args += ["--state", str(p.root / "build" / STATE_FILE)]
        return args

    def connect_dialog(self) -> bool:
        if self.connection is None:
            return False
        host, port, token = "127.0.0.1", 5700, ""
        try:
            from plcbuilder.link import runtime
            ep = runtime.read()
            host, port, token = ep.host, ep.port, ep.token
        except Exception:  # noqa: BLE001
            pass
        res = dialogs.ConnectDialog.get_address(self.parent(), host, port, token)
        if res is None:
            return False
        host, port, token = res
        if not token:
            try:
                from plcbuilder.link import runtime
                token = runtime.read().token
            except Exception:  # noqa: BLE001
                pass
        self.connection.connect_to(host, port, token)
        self.sig_message.emit(f"Connecting to {host}:{port}…", 4000)
        return True

    def use_embedded(self) -> None:
        if self.connection is not None and hasattr(self.connection, "start_embedded"):
            self.connection.start_embedded(self.controller_args())

    def connected(self) -> bool:
        return bool(getattr(self.connection, "connected", False))

    def wire_connection(self) -> None:
        """Follow the connection: a controller that connects with nothing
        loaded gets the project's image (issue 13.3)."""
        c = self.connection
        if c is None or not hasattr(c, "sig_connected"):
            return
        c.sig_connected.connect(self._on_connected)
        c.sig_state.connect(self._on_state)
        c.sig_state.connect(self._follow_job)
        if hasattr(c, "sig_result"):
            c.sig_result.connect(self._on_result)

    def _on_result(self, verb: str, result: dict) -> None:
        """A code issued: the status bar says what it did (a refusal comes as
        the connection's error, with the controller's reason)."""
        if verb == "code" and isinstance(result, dict):
            started = result.get("started")
            self.sig_message.emit(f"{result.get('code', 'The code')} issued at t = "
                                  f"{result.get('t_ms', 0)} ms"
                                  + (f": started {started}" if started else ""), 5000)

    #: which of Pause / Continue / Stop G-code Program each state of the job allows
    #: (controller/job.py's STATES; no job open: none of them)
    JOB_VERBS = {"starting": ("pause", "stop"), "running": ("pause", "stop"),
                 "paused": ("play", "stop"), "ended": ("play",), "stopped": ("play",),
                 "error": ("play",), "ready": ("play",)}

    def job_allows(self, verb: str) -> bool:
        """Does the job's state allow ``verb`` (pause, play, stop)?"""
        return verb in self.JOB_VERBS.get(self.job_state, ())

    def _follow_job(self, st, _missed: int = 0) -> None:
        job = getattr(st, "job", None) or {}
        state = str(job.get("state", "")) if isinstance(job, dict) else ""
        if state != self.job_state:
            self.job_state = state
            self.sig_job_state.emit(state)

    def _on_connected(self, _address: str) -> None:
        self._image_check_due = True

    def _on_state(self, st, _missed: int = 0) -> None:
        if not self._image_check_due or self.project is None:
            return
        self._image_check_due = False
        self.check_loaded_image(st)

    def check_loaded_image(self, st) -> Optional[str]:
        """Upload build/eeprom.rom when the controller has no image; say so
        when it runs another one. Returns what was done: ``"uploaded"``,
        ``"differs"`` or None."""
        from plcbuilder.ide.image_state import image_crc, newer_sources
        p = self.project
        if p is None or self.connection is None or not p.image_path.is_file():
            return None
        loaded = getattr(st, "image_crc32", None)
        if loaded is None:
            if not self.upload_image():
                return None
            note = " — it is older than the sources: Build All (Ctrl+B) to update it" \
                if newer_sources(p) else ""
            self.sig_message.emit(f"The controller had no image: loaded the project's "
                                  f"build/eeprom.rom{note}", 10000)
            return "uploaded"
        if loaded != image_crc(p.image_path):
            self.sig_message.emit("The controller runs another image than the project's "
                                  "build/eeprom.rom: Upload (Ctrl+U) loads it", 10000)
            return "differs"
        return None

    @property
    def build_panel(self):
        """The Build Output panel."""
        p = self._build_panel
        return p() if callable(p) else p

    # ============================================================== private
    def _build(self, then: Step) -> bool:
        if self.project is None:
            self.sig_message.emit("Open a project to build it", 4000)
            return False
        if self.build_runner.running():
            return False
        if not self.ensure_saved("Build All"):
            return False
        self.build_panel.begin(self.project)
        self.sig_build_started.emit()
        self.sig_message.emit("Building…", 0)
        self.step = then
        if not self.build_runner.start(self.project):
            self.step = Step.IDLE
            return False
        return True

    def _on_build_progress(self, done: int, total: int, name: str) -> None:
        self.build_panel.on_progress(done, total, name)
        if name:
            self.sig_message.emit(f"Building {done}/{total}: {name}", 0)

    def _on_build_finished(self, result) -> None:
        self.build_panel.show_result(result, self.build_runner.elapsed)
        self.sig_build_ended.emit()
        upload = self.step in (Step.BUILD_THEN_UPLOAD, Step.BUILD_UPLOAD_START)
        start, self.pending_start = (self.pending_start if self.step is Step.BUILD_UPLOAD_START
                                     else None), None
        gcode, self.pending_gcode = (self.pending_gcode if self.step is Step.BUILD_UPLOAD_START
                                     else None), None
        self.step = Step.IDLE
        if isinstance(result, BaseException):
            self.sig_message.emit(f"Build failed: {result}", 8000)
            self.sig_build_finished.emit(result)
            return
        self.sig_build_result.emit(result)
        e, w = result.error_count, result.warning_count
        if result.ok:
            self.sig_message.emit(f"Build succeeded: {result.image_message}", 8000)
        else:
            self.sig_message.emit(f"Build failed: {e} error{'s' * (e != 1)}, "
                                  f"{w} warning{'s' * (w != 1)}", 8000)
        self.sig_build_finished.emit(result)
        if upload and result.ok and self.upload_image():
            if gcode is not None:               # the link uploads first: requests run in order
                self.connection.job("open", gcode[0], gcode[1], True)
                self.sig_message.emit(f"Built, uploaded and ran the G-code program "
                                      f"{Path(gcode[1]).name}", 5000)
            elif start is not None:
                self.connection.start(*start)
                self.sig_message.emit(f"Built, uploaded and started {start[0]} "
                                      f"(eparam {start[1]})", 5000)

    def _connect_to_address(self, address: str) -> None:
        host, _, port = address.rpartition(":")
        token = ""
        try:
            from plcbuilder.link import runtime
            ep = runtime.read()
            if str(ep.port) == port:
                token = ep.token
        except Exception:  # noqa: BLE001 - no runtime file: ask
            pass
        if not token:
            res = dialogs.ConnectDialog.get_address(self.parent(), host.strip("[]"),
                                                    int(port or 5700))
            if res is None:
                return
            host, port, token = res
        self.connection.connect_to(host.strip("[]"), int(port), token)
