"""The IDE's link to a simulated controller, as one QObject with signals.

By default the IDE runs its own controller as a child process
(:meth:`ControllerConnection.start_embedded`): ``python -m plcbuilder
controller --port 0`` with a private runtime file, from which the address and
the token are read. It can also talk to a controller that is already running
(:meth:`ControllerConnection.connect_to`).

Threads: the GUI never waits for the network. A worker thread owns the
:class:`~plcbuilder.link.client.Client` (whose own reader thread receives
telemetry): it spawns and watches the child, connects, runs the requests the
GUI queued, in order, and polls the state about five times a second (once a
second while nothing runs, and again within 0.2 s of any request). Whatever
it learns goes into a queue; the first item put into an empty queue wakes the
GUI thread (a queued signal), which drains it, at most once every ~15 ms,
emitting the signals below (samples and events merged into one emission per
drain). Nothing arrives, nothing runs on the GUI thread: no polling timer. If the connection breaks or the child dies, ``sig_disconnected``
says why, and the worker connects again (restarting the child) with backoff;
after a restart it uploads the last image again (and the debug session sends
the breakpoints again on ``sig_connected``).

Debugging (SPEC §6): the request methods of the debugger contract
(:meth:`ControllerConnection.set_breakpoints`, :meth:`~ControllerConnection.debug_step`,
:meth:`~ControllerConnection.force`, ...) queue like the others. The
controller's ``halted``/``resumed`` notifications, and the ``debug_state``
the worker asks for after every debug verb and with each state poll while
debugging, become ``sig_halted`` / ``sig_resumed`` (each halt once); log and
forces events become ``sig_log`` / ``sig_forces_changed``.
"""

from __future__ import annotations

import queue
import threading
import time
import zlib
from typing import TYPE_CHECKING, Callable, Optional, Sequence

from PySide6 import QtCore

from plcbuilder.ide.link_reasons import CLOSED_BY_IDE
from plcbuilder.ide.debug.requests import DebugRequests

if TYPE_CHECKING:
    from plcbuilder.link import runtime
    from plcbuilder.link.client import Client, ControllerStatus, Telemetry
    from plcbuilder.link.process import ControllerProcess

Signal = QtCore.Signal

__all__ = ["ControllerConnection", "SPEED_CHOICES"]

#: What :meth:`ControllerConnection.set_speed` understands (any number is N× real time).
SPEED_CHOICES = ("realtime", "2", "10", "100", "max", "pause")
STATE_INTERVAL = 0.2          # seconds between state polls
IDLE_STATE_INTERVAL = 1.0     # ... while nothing runs (and again 0.2 s after any request)
PUMP_INTERVAL_MS = 15         # GUI-side drains of the worker's queue at most this often
SPAWN_TIMEOUT = 20.0          # seconds a child gets to write its runtime file
BACKOFF = (0.25, 0.5, 1.0, 2.0, 4.0, 8.0)
STABLE_AFTER = 10.0           # a connection up this long resets the backoff
MAX_SAMPLES_PER_EMIT = 60000  # samples in one sig_samples emission at most
#: One drain of the worker's queue stops taking more once this long has gone
#: (the rest comes after PUMP_INTERVAL_MS, the window answering meanwhile) ...
DRAIN_BUDGET_S = 0.02
#: ... looking at the time each time this many samples have been handed on.
DRAIN_STEP_SAMPLES = 500
#: Samples the client's reader may have handed the window and it has not taken
#: yet; beyond them the reader waits, and so does a controller at Max speed
#: (the IDE subscribes lossless) rather than the queue growing without end ...
MAX_PENDING_SAMPLES = 40000
#: ... for at most this long at a time: a controller waits for a lossless
#: subscriber for at most a second (link.pacing) before it drops changes
#: (with 0.5 s, 2 runs of 19 at Max lost changes; with 0.1 s none of 20 did).
MAX_READER_WAIT_S = 0.1
#: The debugger's requests (SPEC §6); after each the worker asks for the halted state.
DEBUG_VERBS = frozenset({"debug_continue", "debug_pause", "debug_step", "debug_run_to",
                         "debug_state", "write", "force", "release", "release_all", "forces",
                         "debug_step_back", "debug_run_back"})
#: ... and after these for the list of forces too.
FORCE_VERBS = frozenset({"write", "force", "release", "release_all", "forces"})
#: Sample changes the controller keeps for this IDE between two telemetry frames
#: (20 ms). The controller sends only the ticks where something changed, in
#: MessagePack, and the IDE subscribes ``lossless``: at Max speed the controller
#: waits for the IDE rather than drop a change (a paced one drops and counts).
TELEMETRY_QUEUE = 20000


def _link():
    """The link's client and child process, and the telemetry steps: imported
    when a connection first starts, not with the main window (its first paint
    does not wait for them)."""
    from plcbuilder.ide.panels import steps
    from plcbuilder.link import client, process
    return client, process, steps


def _telemetry_queue(speed: Optional[tuple[str, Optional[float]]] = None) -> int:
    return TELEMETRY_QUEUE


# ===================================================================== worker

class _Backlog:
    """The samples the client's reader has handed the window (through the
    worker's queue) and the window has not taken yet. At Max speed a
    controller makes changes faster than the window can take them: without
    a bound the queue grew by the second and one drain of it held the window
    1.3 s. :meth:`add` (the reader) waits while more than
    :data:`MAX_PENDING_SAMPLES` wait, for at most :data:`MAX_READER_WAIT_S`;
    :meth:`take` (the window) makes room."""

    def __init__(self):
        self._cond = threading.Condition()
        self.samples = 0

    def add(self, n: int, cancel: threading.Event) -> None:
        until = time.monotonic() + MAX_READER_WAIT_S
        with self._cond:
            while self.samples > MAX_PENDING_SAMPLES and not cancel.is_set():
                left = until - time.monotonic()
                if left <= 0:
                    break                       # the window is held up: rather late than lost
                self._cond.wait(min(0.05, left))
            self.samples += n

    def take(self, n: int) -> None:
        with self._cond:
            self.samples -= n
            self._cond.notify_all()


class _Worker(threading.Thread):
    """Owns the client (and the child): connects, reconnects, runs requests."""

    def __init__(self, inbox: "queue.SimpleQueue", *, embedded: bool,
                 address: Optional[tuple[str, int, str]] = None, extra_args: Sequence[str] = ()):
        super().__init__(name="plcbuilder-ide-link", daemon=True)
        self.inbox = inbox
        self.backlog = _Backlog()               # the samples in the inbox
        self.wake: Callable[[], None] = lambda: None   # tells the GUI thread there is mail
        self.woken = False                      # a wake is on its way, not drained yet
        self.embedded = embedded
        self.address = address
        self.extra_args = tuple(extra_args)
        self.commands: "queue.Queue" = queue.Queue()
        self.stopping = threading.Event()
        self.client: Optional[Client] = None
        self.child: Optional[ControllerProcess] = None
        self.child_told = False                 # the GUI knows the child's pid
        self.image: Optional[bytes] = None      # re-uploaded after a restart
        self.target: Optional[dict] = None      # the image's target profile (docs/targets.md)
        self.speed: Optional[tuple[str, Optional[float]]] = None
        self.variables_pending = False
        self.registers_pending = False
        self.restarts = 0
        self.steps = _link()[2].StepSamples()
        self.breakpoints: dict[str, list] = {}  # file -> specs the controller has
        self.watched: list[str] = []            # variables the controller records (watch)
        self.debugging = False                  # a debug verb was used: follow the halts
        self.notified = False                   # the client passes halted/resumed on

    # ----------------------------------------------------------------- plumbing
    def post(self, kind: str, payload=None) -> None:
        self.inbox.put((kind, payload))
        if not self.woken:                      # one wake per drain, not one per item
            self.woken = True
            try:
                self.wake()
            except RuntimeError:                # the IDE's side is gone (closing)
                pass

    def run(self) -> None:
        attempt = 0
        try:
            while not self.stopping.is_set():
                up_since = None
                try:
                    self._open()
                    up_since = time.monotonic()
                    self._serve()
                    reason = self._lost_reason()
                except _Stop:
                    break
                except (_link()[0].LinkError, OSError) as exc:
                    reason = self._lost_reason(str(exc))
                except Exception as exc:  # noqa: BLE001 - a bug here must not kill the link
                    reason = f"internal error in the IDE's link: {type(exc).__name__}: {exc}"
                self._close()
                if self.stopping.is_set():
                    break
                self.restarts += 1
                self.post("disconnected", reason)
                self._drop_waiting_commands()
                if up_since is not None and time.monotonic() - up_since > STABLE_AFTER:
                    attempt = 0
                delay = BACKOFF[min(attempt, len(BACKOFF) - 1)]
                attempt += 1
                if self.stopping.wait(delay):
                    break
        finally:
            self._close()
            if self.child is not None:
                self.child.stop()
                self.child = None
            self.post("stopped", None)

    def _drop_waiting_commands(self) -> None:
        """Requests that were waiting when the link broke: an upload or a speed
        is kept for the next connection, anything else (a start, an input...)
        is dropped and reported, rather than done later by surprise."""
        while True:
            try:
                cmd = self.commands.get_nowait()
            except queue.Empty:
                return
            if cmd is None:
                self.commands.put(None)
                return
            verb, args = cmd
            if verb == "upload":
                self.image = args[0]
            elif verb == "speed":
                self.speed = (args[0], args[1])
            elif verb == "variables":
                self.variables_pending = False
            elif verb == "set_breakpoints":
                pass                        # the session sends them all when connected
            elif verb == "watch":
                self.watched = list(args[0]["variables"])    # asked again when connected
            elif verb == "registers":
                self.registers_pending = False
            else:
                self.post("error", f"{verb}: not done, the connection to the controller "
                                   "was lost")

    def _lost_reason(self, detail: str = "") -> str:
        if self.child is not None and not self.child.alive():
            return self.child.why_dead()
        c = self.client
        if c is not None and c.close_reason:
            return c.close_reason
        return detail or "the connection to the controller was lost"

    def _open(self) -> None:
        link, process, _ = _link()
        RefusedError = link.RefusedError  # noqa: N806 - the exception class
        if self.embedded:
            if self.child is None or not self.child.alive():
                if self.child is not None:
                    self.child.stop()
                self.child = process.ControllerProcess(self.extra_args)
                self.post("child", self.child.pid)
            elif not self.child_told:                # started before (prestart)
                self.post("child", self.child.pid)
            self.child_told = True
            ep = self._wait_endpoint(self.child)
            host, port, token = ep.host, ep.port, ep.token
        else:
            host, port, token = self.address
        client = link.Client.connect(host, port, token, timeout=30.0, connect_timeout=5.0)
        self.client = client
        self.steps.reset()
        client.subscribe(self._on_telemetry, queue=_telemetry_queue(self.speed), lossless=True)
        if self.image is not None and self.restarts:
            try:
                result = client.upload(self.image, target=self.target)
                self.post("result", ("upload", result))
                self.post("note", "uploaded the image again after the controller came back")
            except RefusedError as exc:
                self.post("error", f"upload: {exc.reason}")
        if self.speed is not None:
            mode, factor = self.speed
            try:
                client.speed(mode, factor)
            except RefusedError as exc:
                self.post("error", f"speed: {exc.reason}")
        if self.watched:                        # a trigger on a variable is armed
            try:
                client.watch(self.watched)
            except RefusedError as exc:
                self.post("error", f"watch: {exc.reason}")
                self.post("refused", ("watch", exc.reason))
        self._hook_notifications(client)
        try:                                   # does this controller have the debugger?
            forces = client.request("forces").get("forces", [])
            self.post("debugger", True)
            self.post("forces", forces)
        except RefusedError:
            self.post("debugger", False)
        self.post("connected", (f"{host}:{port}", client.welcome))

    def _hook_notifications(self, client: Client) -> None:
        """The controller's own ``halted``/``resumed`` messages, when the client
        passes them on (on its reader thread: only queue them)."""
        self.notified = hasattr(client, "notification_callback")
        if self.notified:
            client.notification_callback = lambda msg: self.post(str(msg.get("type")), msg)

    def _wait_endpoint(self, child: ControllerProcess) -> runtime.Endpoint:
        ep = child.wait_endpoint(SPAWN_TIMEOUT, cancel=self.stopping)
        if ep is None:
            raise _Stop()
        return ep

    def _on_telemetry(self, batch: Telemetry) -> None:   # on the client's reader thread
        # changes -> the points to plot, here rather than on the GUI thread
        batch.samples = self.steps.feed(batch.samples, batch.t_ms)
        self.backlog.add(len(batch.samples), self.stopping)
        self.post("telemetry", batch)

    def _serve(self) -> None:
        next_state = 0.0
        client = self.client
        while not self.stopping.is_set():
            if client.closed or (self.child is not None and not self.child.alive()):
                return
            now = time.monotonic()
            if now >= next_state:
                st = client.state()
                self.post("state", st)
                idle = st.idle and not st.running and not st.software and not self.debugging
                next_state = now + (IDLE_STATE_INTERVAL if idle else STATE_INTERVAL)
                if self.debugging and not self.notified:    # no halted/resumed messages
                    self._debug_state(client)
            try:
                cmd = self.commands.get(timeout=max(0.0, min(0.25, next_state - now)))
            except queue.Empty:
                continue
            if cmd is None:
                raise _Stop()
            self._run_command(client, *cmd)
            next_state = min(next_state, time.monotonic() + STATE_INTERVAL)

    def _run_command(self, client: Client, verb: str, args: tuple) -> None:
        """One command from the GUI: its ``_do_<verb>`` method, a debugger verb,
        or a plain request; the result is posted (unless the method posted what
        it had, returning POSTED), a refusal as an error."""
        link = _link()[0]
        handler = getattr(self, "_do_" + verb, None)
        try:
            if handler is not None:
                result = handler(client, *args)
            elif verb in DEBUG_VERBS:
                result = self._debug_verb(client, verb, args)
            else:
                result = client.request(verb, **(args[0] if args else {}))
        except link.ConnectionLost:
            raise
        except link.RefusedError as exc:
            if verb == "set_breakpoints":       # the Breakpoints panel says why
                self.post("breakpoints_refused", (args[0]["file"], exc.reason))
                return
            self.post("error", f"{verb}: {exc.reason}")
            self.post("refused", (verb, exc.reason))
            return
        if result is POSTED:
            return
        self.post("result", (verb, result))
        if verb in ("upload", "reset", "start", "stop", "code") and self.debugging:
            self._debug_state(client)

    # One method a verb (the GUI's ``_send(verb, *args)``): its result, or POSTED.
    def _do_upload(self, client: Client, image: bytes, target: Optional[dict]):
        self.image, self.target = image, target
        return client.upload(image, target=target)

    def _do_start(self, client: Client, name: str, eparam: int):
        return client.start(name, int(eparam))

    def _do_stop(self, client: Client):
        return client.stop()

    def _do_input(self, client: Client, pin: int, value: int):
        return client.set_input(int(pin), int(value))

    def _do_adc(self, client: Client, channel: int, value: int):
        return client.set_adc(int(channel), int(value))

    def _do_speed(self, client: Client, mode: str, factor: Optional[float]):
        self.speed = (mode, factor)
        return client.speed(mode, factor)

    def _do_reset(self, client: Client):
        return client.reset()

    def _do_watch(self, client: Client, fields: dict):
        result = client.request("watch", **fields)
        self.watched = list(result.get("variables", []))
        return result

    def _do_event(self, client: Client, handler: str):
        return client.event(handler)

    def _do_job(self, client: Client, *args):
        return client.job(*args)

    def _do_variables(self, client: Client):
        self.variables_pending = False
        variables, target = client.variables_and_target()
        self.post("variables", variables)
        if target:
            self.post("target_report", target)
        return POSTED

    def _do_registers(self, client: Client, addresses: list):
        self.registers_pending = False
        self.post("registers", client.registers(addresses))
        return POSTED

    def _do_set_breakpoints(self, client: Client, fields: dict):
        if fields["breakpoints"]:
            self.breakpoints[fields["file"]] = fields["breakpoints"]
        else:
            self.breakpoints.pop(fields["file"], None)
        self.debugging = self.debugging or bool(self.breakpoints)
        result = client.request("set_breakpoints", **fields)
        self.post("breakpoints", (fields["file"], result.get("breakpoints", [])))
        return result

    def _debug_verb(self, client: Client, verb: str, args: tuple):
        """A debugger request (or write/force/release): the result, the halted
        state after it, and after a force the list of forces, each posted."""
        self.debugging = self.debugging or verb not in FORCE_VERBS
        if verb == "debug_state":
            self._debug_state(client)
            return POSTED
        if verb == "forces":
            self.post("forces", client.request("forces").get("forces", []))
            return POSTED
        result = client.request(verb, **(args[0] if args else {}))
        self.post("result", (verb, result))
        self._debug_state(client)
        if verb in FORCE_VERBS:
            self.post("forces", client.request("forces").get("forces", []))
        return POSTED

    def _debug_state(self, client: Client) -> None:
        """Ask for the halted state. Its answer is posted by the link's reader
        thread as it is read, so it keeps its place among the ``halted`` and
        ``resumed`` notifications, which that thread posts too: posted from
        here, a slow wake of this thread let a stale "not halted" land after
        a newer halt and hide it (seen as a halt that never came, under load)."""
        def post(result: dict) -> None:
            halted = result.get("halted")
            self.post("debug_state", halted if isinstance(halted, dict) else None)
        try:
            client.request("debug_state", on_reply=post)
        except _link()[0].RefusedError as exc:     # a controller without the debugger
            self.debugging = False
            self.post("error", f"debug_state: {exc.reason}")

    def _close(self) -> None:
        c, self.client = self.client, None
        if c is not None:
            c.close()


class _Stop(Exception):
    pass


#: what a worker's ``_do_<verb>`` returns when it has posted its results itself
POSTED = object()


# ================================================================= QObject

class ControllerConnection(DebugRequests, QtCore.QObject):
    """The IDE's connection to a controller (embedded child or external)."""

    sig_mail = Signal()
    """(Internal, emitted from the link's threads, queued to the GUI thread.)
    The worker put something into an empty inbox: drain it."""

    sig_connected = Signal(str)
    """Connected (again): the controller's address, ``host:port``."""

    sig_disconnected = Signal(str)
    """The connection is gone: why (the child's exit status and last stderr line
    when the embedded controller died). It reconnects on its own."""

    sig_state = Signal(object, int)
    """The controller's state, about 5 times a second: ``t_ms``, ``running``,
    ``software``, ``proc``, ``proc_name``, ``image``, ``speed``, ``inputs``,
    ``outputs``, ``axes``... plus ``missed`` (samples this IDE dropped or was not
    sent because it fell behind, since connecting)."""

    sig_events = Signal(list)
    """Controller events (:mod:`plcbuilder.controller.events` objects), oldest first."""

    sig_samples = Signal(list)
    """Telemetry samples (``events.Sample``), oldest first, batched."""

    sig_error = Signal(str)
    """A request was refused or failed: ``verb: reason``."""

    sig_variables = Signal(object)
    """The answer to :meth:`request_variables`: ``{procedure: {variable: value}}``,
    each procedure's variables in slot order (an ``object`` signal: a ``dict``
    signal would sort the keys)."""

    sig_registers = Signal(object)
    """The answer to :meth:`request_registers`: ``{address: value}``."""

    sig_target_report = Signal(object)
    """With :meth:`request_variables`, on a target other than myCNC: the target's
    report ``{"registers": {bank: {index: value}}, "calls": {...}, "budget": [...]}``
    (docs/targets.md)."""

    sig_result = Signal(str, dict)
    """A request was done: its verb and the controller's result object."""

    sig_refused = Signal(str, str)
    """The controller refused a request: its verb and the reason (sig_error
    says it too, for the log)."""

    sig_note = Signal(str)
    """Something worth a line in the log that is not an error (an image uploaded
    again after a restart)."""

    sig_halted = Signal(object)
    """The controller halted (SPEC §6): the halted state dict (``reason``,
    ``t_ms``, ``procedure``, ``file``, ``line``, ``procedures`` with each one's
    line, stack and variables, ``machine``, ``fault``, ``breakpoint``). Emitted
    once per halt (a step halts again: a new emission)."""

    sig_resumed = Signal(int)
    """The controller runs again after a halt (its ``t_ms``)."""

    sig_breakpoints = Signal(str, list)
    """The controller's answer to :meth:`set_breakpoints`: the file and, per
    breakpoint, ``{id, file, line, verified, reason}``."""

    sig_breakpoints_refused = Signal(str, str)
    """A file's breakpoints were refused (the file, the reason)."""

    sig_forces_changed = Signal(list)
    """What is forced now: ``[{target, value, since_ms}]``."""

    sig_log = Signal(object)
    """A logpoint wrote a line: the event (``t_ms``, the procedure, ``text``)."""

    def __init__(self, parent: Optional[QtCore.QObject] = None):
        super().__init__(parent)
        self._inbox: "queue.SimpleQueue" = queue.SimpleQueue()
        self._carry: list = []                  # samples of a batch a drain has begun
        self._worker: Optional[_Worker] = None
        self._pump = QtCore.QTimer(self)        # a drain held back to keep ~15 ms apart
        self._pump.setSingleShot(True)
        self._pump.timeout.connect(self._drain)
        self._last_drain = 0.0
        self.sig_mail.connect(self._on_mail, QtCore.Qt.ConnectionType.QueuedConnection)
        self.connected = False
        self.address = ""
        self.child_pid: Optional[int] = None
        self._last_state: Optional[ControllerStatus] = None
        self.missed = 0
        self.welcome: dict = {}
        self.halted: Optional[dict] = None      # the last halted state (None: running)
        self.debugger = False                   # the controller answers the debug requests
        #: CRC-32 (hex) of an image this connection is uploading: what the controller
        #: runs once the upload (queued in order) is done, until a state says so
        self.uploaded_crc: Optional[str] = None
        self._upload_done = False
        self.forces: list = []                  # the last list of forces
        #: (arguments, ControllerProcess) started by prestart(), not connected yet
        self._prestarted: Optional[tuple] = None

    # -------------------------------------------------------------- lifecycle
    @property
    def last_state(self) -> ControllerStatus:
        """The controller's last state (an empty one until the first arrives)."""
        if self._last_state is None:
            from plcbuilder.link.client import ControllerStatus
            self._last_state = ControllerStatus()
        return self._last_state

    @last_state.setter
    def last_state(self, st: ControllerStatus) -> None:
        self._last_state = st

    @property
    def embedded(self) -> bool:
        return self._worker is not None and self._worker.embedded

    def prestart(self, extra_args: Sequence[str] = ()) -> None:
        """Start the child process of :meth:`start_embedded` with these
        arguments now (returns at once); the start that follows with the same
        arguments connects to it rather than start another."""
        self._drop_prestarted()
        from plcbuilder.link.process import ControllerProcess
        self._prestarted = (tuple(extra_args), ControllerProcess(extra_args))

    def start_embedded(self, extra_args: Sequence[str] = ()) -> None:
        """Run a controller as a child process and connect to it (restarting it
        with backoff whenever it dies). ``extra_args`` go to ``plcbuilder
        controller`` (say ``["--machine", path]``)."""
        worker = _Worker(self._inbox, embedded=True, extra_args=extra_args)
        pre, self._prestarted = self._prestarted, None
        if pre is not None:
            if pre[0] == tuple(extra_args) and pre[1].alive():
                worker.child = pre[1]           # started before the window painted
            else:
                pre[1].stop()
        self._begin(worker)

    def _drop_prestarted(self) -> None:
        pre, self._prestarted = self._prestarted, None
        if pre is not None:
            pre[1].stop()

    def connect_to(self, host: str, port: int, token: str) -> None:
        """Talk to a controller that is already running (reconnecting with backoff
        when the connection breaks)."""
        self._begin(_Worker(self._inbox, embedded=False, address=(host, int(port), token)))

    def shutdown(self, timeout: float = 5.0) -> None:
        """Disconnect and end the embedded controller (waits for it, at most ``timeout``)."""
        self._drop_prestarted()
        w, self._worker = self._worker, None
        if w is not None:
            w.stopping.set()
            w.commands.put(None)
            c = w.client
            if c is not None:
                c.close()
            w.join(timeout)
            if w.is_alive() and w.child is not None:      # stuck: end the child anyway
                w.child.stop(1.0)
        self._drain(whole=True)
        self._pump.stop()
        if self.connected:
            self.connected = False
            self.sig_disconnected.emit(CLOSED_BY_IDE)
        self.child_pid = None

    def _begin(self, worker: _Worker) -> None:
        self.shutdown()
        self._inbox = worker.inbox = queue.SimpleQueue()
        self._worker = worker
        self.missed = 0
        self.uploaded_crc = None
        worker.wake = self.sig_mail.emit
        worker.start()

    # ---------------------------------------------------------------- requests
    def upload(self, image_bytes: bytes, target: Optional[dict] = None) -> None:
        """Upload an eeprom.rom image (kept, and uploaded again after a restart);
        ``target``: the project's target profile (None: myCNC)."""
        data = bytes(image_bytes)
        self.uploaded_crc = f"{zlib.crc32(data):08x}"
        self._send("upload", data, target)

    def start(self, name: str, eparam: int = 0) -> None:
        self._send("start", name, int(eparam))

    def stop(self) -> None:
        """Press Stop (the first time starts M02, the second OFF)."""
        self._send("stop")

    def issue_code(self, letter: str, value: int) -> None:
        """The CNC issues code ``letter`` ``value`` (M3, S12000): the link's
        ``code`` request, recorded by the controller as a scenario's ``code``."""
        self._send("code", {"letter": str(letter), "value": int(value)})

    def job(self, verb: str, text: Optional[str] = None, file: Optional[str] = None,
            play: bool = False) -> None:
        """The G-code job (docs/controller.md): ``open`` (and ``play``) a program,
        or ``play``, ``pause``, ``stop``, ``reset`` it."""
        self._send("job", verb, text, file, play)

    def set_input(self, pin: int, v: int) -> None:
        self._send("input", int(pin), 1 if v else 0)

    def set_adc(self, ch: int, v: int) -> None:
        self._send("adc", int(ch), int(v))

    def set_speed(self, mode) -> None:
        """``"realtime"``, ``"max"``, ``"pause"`` or a factor (``"10"``: 10× real time)."""
        from plcbuilder.link.protocol import parse_speed
        try:
            m, factor = parse_speed(mode)
        except ValueError as exc:
            self.sig_error.emit(f"speed: {exc}")
            return
        self._send("speed", m, factor)

    def reset(self) -> None:
        """A fresh controller with the same image (time starts again at 0)."""
        self._send("reset")

    def send_event(self, handler: str) -> None:
        """Start ``__HANDLER_GCODE_START`` or ``__HANDLER_GCODE_STOP``."""
        self._send("event", handler)

    def request_recording(self) -> None:
        """Ask for the session's recording; the answer comes as sig_result
        ("recording", {text, t_ms, actions})."""
        self._send("recording", {})

    def watch_variables(self, names) -> None:
        """Have the controller record these variables (``PROC.var``) at the end
        of every tick and send their changes as ``watch`` events (sig_events),
        which a trigger on a variable needs; [] stops. Asked again after the
        controller restarts; a refusal comes as sig_refused("watch", reason)."""
        self._send("watch", {"variables": [str(n) for n in names]})

    def request_variables(self) -> None:
        """Ask for every procedure's variables; the answer comes as sig_variables.
        A request still waiting is not repeated."""
        w = self._worker
        if w is None or not self.connected or w.variables_pending:
            return
        w.variables_pending = True
        self._send("variables")

    def request_registers(self, addresses) -> None:
        """Ask for the values of global registers; the answer comes as
        sig_registers. A request still waiting is not repeated."""
        w = self._worker
        if w is None or not self.connected or w.registers_pending:
            return
        w.registers_pending = True
        self._send("registers", [int(a) for a in addresses])

    def _send(self, verb: str, *args) -> None:
        w = self._worker
        if w is None:
            self.sig_error.emit(f"{verb}: not connected to a controller")
            return
        if not self.connected and w.restarts and verb not in ("upload", "speed"):
            # the controller is coming back: do not start things later by surprise
            self.sig_error.emit(f"{verb}: not connected to a controller (it is restarting)")
            return
        w.commands.put((verb, args))

    # ------------------------------------------------------------------- pump
    def _on_mail(self) -> None:
        """The worker posted: drain now, or when ~15 ms have passed since the last drain."""
        if self._pump.isActive():
            return
        wait_ms = PUMP_INTERVAL_MS - (time.monotonic() - self._last_drain) * 1000
        if wait_ms > 1:
            self._pump.start(int(wait_ms))
        else:
            self._drain()

    def _drain(self, whole: bool = False) -> None:
        """Hand on what the worker posted, in order: for at most
        DRAIN_BUDGET_S (the rest at the next drain), or ``whole``."""
        began = self._last_drain = time.monotonic()
        w = self._worker
        if w is not None:
            w.woken = False                     # what is posted from now on wakes us again
        samples: list = []
        events: list = []
        handed = 0

        def flush():
            for i in range(0, len(samples), MAX_SAMPLES_PER_EMIT):   # all of them, in pieces
                self.sig_samples.emit(samples[i:i + MAX_SAMPLES_PER_EMIT])
            samples.clear()
            if events:
                self.sig_events.emit(list(events))
                events.clear()

        carry, self._carry = self._carry, []   # the rest of a batch the last drain began
        for _ in range(10000):
            if handed >= DRAIN_STEP_SAMPLES:    # (handing samples on is what takes time)
                handed = 0
                flush()
                if not whole and time.monotonic() - began > DRAIN_BUDGET_S:
                    break
            if carry:
                step = carry[:DRAIN_STEP_SAMPLES - handed]
                del carry[:len(step)]
                samples.extend(step)
                handed += len(step)
                if w is not None:
                    w.backlog.take(len(step))
                continue
            try:
                kind, payload = self._inbox.get_nowait()
            except queue.Empty:
                break
            if kind == "telemetry":
                # a batch is handed on a step at a time (one of Max speed's can
                # hold 20,000 samples, 0.3 s of the window's time)
                carry = list(payload.samples)
                for e in payload.events:
                    etype = getattr(e, "type", None)
                    if etype == "log":
                        self.sig_log.emit(e)
                    elif etype == "forces":
                        self._on_forces(getattr(e, "forces", []))
                        continue
                    events.append(e)
                handed += len(payload.events)
                self.missed += payload.missed
                continue
            flush()                     # keep the order of telemetry and the rest
            handler = getattr(self, "_mail_" + kind, None)
            if handler is not None:
                handler(payload)
        flush()
        self._carry = carry
        if carry or not self._inbox.empty():    # more than one drain's worth: the rest soon
            self._pump.start(PUMP_INTERVAL_MS)

    # One method a kind of mail from the worker (its ``post(kind, payload)``).
    def _mail_state(self, status) -> None:
        self.last_state = status
        if self._upload_done:                   # this state knows the uploaded image
            self.uploaded_crc, self._upload_done = None, False
        self.sig_state.emit(status, self.missed)

    def _mail_connected(self, payload) -> None:
        self.address, self.welcome = payload
        self.connected = True
        if self.halted is not None:             # a new controller runs
            self.halted = None
            self.sig_resumed.emit(0)
        self.sig_connected.emit(self.address)

    def _mail_disconnected(self, reason) -> None:
        was = self.connected
        self.connected = False
        if was or reason:
            self.sig_disconnected.emit(str(reason))

    def _mail_child(self, pid) -> None:
        self.child_pid = pid

    def _mail_error(self, text) -> None:
        self.sig_error.emit(str(text))

    def _mail_note(self, text) -> None:
        self.sig_note.emit(str(text))

    def _mail_variables(self, variables) -> None:
        self.sig_variables.emit(dict(variables))

    def _mail_registers(self, registers) -> None:
        self.sig_registers.emit(dict(registers))

    def _mail_target_report(self, report) -> None:
        self.sig_target_report.emit(dict(report))

    def _mail_result(self, payload) -> None:
        verb, result = payload
        if verb == "upload":
            self._upload_done = True
        self.sig_result.emit(verb, dict(result) if isinstance(result, dict) else {})

    def _mail_debug_state(self, halted) -> None:
        self._on_debug_state("debug_state", halted)

    def _mail_halted(self, payload) -> None:
        self._on_debug_state("halted", payload)

    def _mail_resumed(self, payload) -> None:
        self._on_debug_state("resumed", payload)

    def _mail_refused(self, payload) -> None:
        if payload[0] == "upload":
            self.uploaded_crc = None
        self.sig_refused.emit(*payload)

    def _mail_breakpoints(self, payload) -> None:
        self.sig_breakpoints.emit(*payload)

    def _mail_breakpoints_refused(self, payload) -> None:
        self.sig_breakpoints_refused.emit(*payload)

    def _mail_forces(self, forces) -> None:
        self._on_forces(forces)

    def _mail_debugger(self, available) -> None:
        self.debugger = bool(available)
