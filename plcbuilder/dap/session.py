"""``plcbuilder dap``: the Debug Adapter Protocol, bridged to the controller's
debugger over the link (docs/editors.md, "Debugging from an editor").

One :class:`Session` per adapter process. ``launch`` builds the project (a
folder that is not a project is refused: nothing is written there), starts a
controller (an embedded one of the session's own, or the one named by
``controller`` or the project's settings), uploads the image, and on
``configurationDone`` starts the procedure with its eparam; ``attach`` joins a
controller that runs already. A second launch or attach in the same session
first ends the first: the controller it started is stopped. Halts come back
from the controller as ``stopped`` events (a resume as ``continued`` only when
no request of ours implied it); logpoints, prints and faults as ``output``;
the end of the launched procedure as ``exited`` and ``terminated``.

Threads: one reads the messages and never waits on a request. Requests that
only look at the halted state (:data:`CONCURRENT`: threads, stackTrace,
scopes, variables, evaluate) are answered by a few worker threads as they
come, so a slow one (an expression to compile) keeps no other waiting; every
other request is answered in the order it came, one at a time, on the main
thread, and the events it causes go out after its response (the wire is held
meanwhile: :meth:`Wire.hold`). One ``handle_<command>`` per request; a
request the adapter does not know, or cannot carry out, gets a response with
``success: false`` and the reason, and the session goes on.
"""

from __future__ import annotations

import os
import queue
import sys
import threading
from pathlib import Path
from typing import Optional

from plcbuilder.dap.breakpoints import Breakpoints
from plcbuilder.dap.inspect import SCOPES, Threads, View, builtin_header
from plcbuilder.dap.wire import BadMessage, Wire
from plcbuilder.link.client import Client, LinkError, parse_address
from plcbuilder.link.process import ControllerProcess
from plcbuilder.project import Project, ProjectError, build_project
from plcbuilder.project.conditions import compile_condition

_STOP_REASONS = {"breakpoint": "breakpoint", "step": "step", "pause": "pause",
                 "fault": "exception"}
_STEPS = {"next": "over", "stepIn": "into", "stepOut": "out"}
#: Requests that only look: answered beside the others, as they come.
CONCURRENT = frozenset({"threads", "stackTrace", "scopes", "variables", "evaluate"})
#: Requests whose events are not held back: launch and attach (the build's output
#: shows as it happens; what follows their response is sent after it anyway).
_UNHELD = frozenset({"initialize", "launch", "attach"})
#: Worker threads for the CONCURRENT requests.
WORKERS = 4


class Refusal(Exception):
    """A request that cannot be carried out; the message goes back to the client."""


class Session:
    def __init__(self, wire: Wire):
        self.wire = wire
        self.client: Optional[Client] = None
        self.embedded: Optional[ControllerProcess] = None
        self.project: Optional[Project] = None
        self.threads = Threads()
        self.breakpoints = Breakpoints(self)
        self.view: Optional[View] = None
        self.launch_args: dict = {}
        self.procedure: Optional[str] = None       # the one launch starts
        self.eparam = 0
        self.configured = False
        self.started = False
        self.done = False
        self._last_stop = None
        self._stop_lock = threading.Lock()
        self._ordered: "queue.Queue[Optional[dict]]" = queue.Queue()
        self._looks: "queue.Queue[dict]" = queue.Queue()
        self._own_resume = False        # the next "resumed" is one a request of ours asked for
        self._stepped_back: Optional[dict] = None
        self._generation = 0            # which launch or attach the controller's callbacks are of
        self._generation_lock = threading.Lock()

    # ------------------------------------------------------------ the loop
    def serve(self) -> None:
        """Read on a thread of its own; answer the ordered requests here, the
        others on the workers; return after disconnect or at the end of input."""
        threading.Thread(target=self._read, name="dap-reader", daemon=True).start()
        for k in range(WORKERS):
            threading.Thread(target=self._look, name=f"dap-worker-{k}", daemon=True).start()
        while not self.done:
            msg = self._ordered.get()
            if msg is None:
                break
            self.dispatch(msg)
        self.shutdown()

    def _read(self) -> None:
        for msg in self.wire.messages():
            if isinstance(msg, BadMessage):
                self._bad(msg)
            elif msg.get("type") == "request":
                (self._looks if msg["command"] in CONCURRENT else self._ordered).put(msg)
        self._ordered.put(None)

    def _look(self) -> None:
        while True:
            self.dispatch(self._looks.get())

    def dispatch(self, req: dict) -> None:
        command = req["command"]
        handler = getattr(self, "handle_" + command, None) if command.isidentifier() else None
        if handler is None:
            self.wire.respond(req, error=f"unknown request {command[:60]!r}")
            return
        if command in CONCURRENT:
            self._answer(req, command, handler)
            return
        held = command not in _UNHELD
        if held:
            self.wire.hold()
        try:
            self._answer(req, command, handler)
        finally:
            if held:
                self.wire.release()

    def _answer(self, req: dict, command: str, handler) -> None:
        show = command in ("launch", "attach")       # the session did not start: say so
        try:
            body = handler(req.get("arguments") or {})
        except (Refusal, ValueError) as exc:
            self.wire.respond(req, error=str(exc), show_user=show)
            return
        except LinkError as exc:
            self.wire.respond(req, error=f"the controller: {exc}", show_user=show)
            return
        except Exception as exc:  # noqa: BLE001 - a bug answers this request, the session goes on
            self.wire.respond(req, error=f"internal error: {type(exc).__name__}: {exc}",
                              show_user=show)
            return
        self.wire.respond(req, body)
        after = getattr(self, "after_" + command, None)
        if after is not None:
            after()

    def _bad(self, msg: BadMessage) -> None:
        if msg.seq is not None:
            self.wire.respond({"seq": msg.seq, "command": msg.command}, error=msg.reason)
        else:
            self.wire.output(f"plcbuilder dap: ignored {msg.reason}", "stderr")

    # ------------------------------------------------------------ lifecycle
    def handle_initialize(self, args: dict) -> dict:
        return {
            "supportsConfigurationDoneRequest": True,
            "supportsConditionalBreakpoints": True,
            "supportsHitConditionalBreakpoints": True,
            "supportsLogPoints": True,
            "supportsSetVariable": True,
            "supportsEvaluateForHovers": True,
            "supportsTerminateRequest": True,
            "supportsStepBack": True,
            "supportsSteppingGranularity": False,
            "supportTerminateDebuggee": True,
            "supportsRestartRequest": False,
            "supportsExceptionInfoRequest": False,
        }

    def handle_launch(self, args: dict) -> dict:
        self._end_previous()
        self.launch_args = args
        self.project = self._project(args)
        self.procedure, self.eparam = self._what_to_start(args)
        image = self._build() if args.get("build", True) else self._built_image()
        target = self._target()
        self._connect(args, launch=True)
        self.wire.output(f"plcbuilder dap: uploading {self.project.image_path}")
        self.client.upload(image, target=target)
        return {}

    def handle_attach(self, args: dict) -> dict:
        self._end_previous()
        self.launch_args = args
        self.project = self._project(args) if args.get("project") else None
        self._connect(args, launch=False)
        return {}

    def after_launch(self) -> None:
        if self.client is not None:
            self.wire.event("initialized")
            self.breakpoints.apply_pending()

    after_attach = after_launch

    def handle_configurationDone(self, args: dict) -> dict:
        self.configured = True
        return {}

    def after_configurationDone(self) -> None:
        if self.procedure is not None and not self.started and self.client is not None:
            try:
                r = self.client.start(self.procedure, self.eparam)
            except LinkError as exc:
                self.wire.output(f"plcbuilder dap: cannot start {self.procedure}: {exc}",
                                 "stderr")
                self._terminate(1)
                return
            self.started = True
            self.wire.output(f"plcbuilder dap: started {self.procedure} (eparam {self.eparam}) "
                             f"at t = {r.get('t_ms')} ms")
        elif self.client is not None:
            halted = self.client.debug_state()
            if halted is not None:                # attached to a halted controller
                self.on_halted(halted)

    def handle_disconnect(self, args: dict) -> dict:
        terminate = args.get("terminateDebuggee", self.embedded is not None)
        self._leave(terminate)
        self.done = True
        return {}

    def handle_terminate(self, args: dict) -> dict:
        self._leave(True)
        return {}

    def after_terminate(self) -> None:
        self.wire.event("terminated")

    # ------------------------------------------------------------ breakpoints
    def handle_setBreakpoints(self, args: dict) -> dict:
        return {"breakpoints": self.breakpoints.set(args)}

    def handle_setExceptionBreakpoints(self, args: dict) -> dict:
        return {"breakpoints": []}      # faults always halt (SPEC §6)

    # ------------------------------------------------------------ running
    def handle_continue(self, args: dict) -> dict:
        self._need_halt()
        self._resume(self.client.debug_continue)
        return {"allThreadsContinued": True}

    def _resume(self, command, *args) -> dict:
        """A link command that resumes the run: its "resumed" is not told as a
        continued event (DAP: the client knows; the event is for resumes no
        request of its own implied)."""
        self._own_resume = True
        try:
            return command(*args)
        except BaseException:
            self._own_resume = False
            raise

    def handle_pause(self, args: dict) -> dict:
        self._need_client()
        self.client.debug_pause()
        return {}

    def handle_next(self, args: dict) -> dict:
        return self._step("next", args)

    def handle_stepIn(self, args: dict) -> dict:
        return self._step("stepIn", args)

    def handle_stepOut(self, args: dict) -> dict:
        return self._step("stepOut", args)

    def _step(self, command: str, args: dict) -> dict:
        self._need_halt()
        proc = self.threads.name_of(args.get("threadId", 0))
        self._resume(self.client.debug_step, _STEPS[command], proc)
        return {}

    def handle_stepBack(self, args: dict) -> dict:
        """Back by one statement: the session run again to the statement before
        (docs/debugging.md, "Stepping back")."""
        self._need_halt()
        self._stepped_back = self.client.debug_step_back("statement").get("halted")
        return {}

    def handle_reverseContinue(self, args: dict) -> dict:
        """Back to the previous breakpoint hit."""
        self._need_halt()
        self._stepped_back = self.client.debug_run_back().get("halted")
        return {}

    def after_stepBack(self) -> None:
        """The controller halted where the run was taken back to: tell it (the
        new controller's halt is the answer; a notification may not come)."""
        state, self._stepped_back = self._stepped_back, None
        if isinstance(state, dict):
            self.on_halted(state)

    after_reverseContinue = after_stepBack

    # ------------------------------------------------------------ looking
    def handle_threads(self, args: dict) -> dict:
        if self.view is not None:
            return {"threads": self.view.thread_list()}
        if self.client is None:
            return {"threads": []}
        st = self.client.state()
        names = ([st.running] if st.running else []) + list(st.software)
        return {"threads": [{"id": self.threads.id_of(n), "name": n} for n in names]}

    def handle_stackTrace(self, args: dict) -> dict:
        view = self._need_halt()
        frames = view.stack(args.get("threadId", 0), args.get("startFrame", 0) or 0,
                            args.get("levels", 0) or 0)
        return {"stackFrames": frames, "totalFrames": len(view.stack(args.get("threadId", 0)))}

    def handle_scopes(self, args: dict) -> dict:
        view = self._need_halt()
        return {"scopes": view.scopes(_int(args.get("frameId"), "frameId"))}

    def handle_variables(self, args: dict) -> dict:
        """A scope's variables; ``filter`` (indexed/named), ``start`` and ``count``
        page a big scope as the client asks (0 or no count: all from start)."""
        view = self._need_halt()
        ref = _int(args.get("variablesReference"), "variablesReference")
        start = _int(args.get("start", 0), "start", lo=0)
        count = _int(args.get("count", 0), "count", lo=0)
        filt = args.get("filter")
        if filt not in (None, "indexed", "named"):
            raise Refusal(f"filter is indexed or named, not {filt!r}")
        return {"variables": view.variables(ref, filt, start, count)}

    def handle_setVariable(self, args: dict) -> dict:
        view = self._need_halt()
        ref = _int(args.get("variablesReference"), "variablesReference")
        name = str(args.get("name", ""))
        target = view.target(ref, name)
        if target is None:
            raise Refusal(f"{name} cannot be written (axes move by motion only)")
        value = self._value(args.get("value"))
        self.client.write(target, value)
        self._refresh()
        shown = self.view.value_of(ref, name) if self.view is not None else None
        return {"value": str(value if shown is None else shown)}

    def handle_evaluate(self, args: dict) -> dict:
        self._need_client()
        text = str(args.get("expression", "")).strip()
        proc = None
        if args.get("frameId") is not None and self.view is not None:
            proc = self.view.frame_procedure(_int(args["frameId"], "frameId"))
        context = self._source_file(proc) or (self.project.root if self.project else None)
        code = compile_condition(text, context)
        if isinstance(code, list):
            raise Refusal("; ".join(d.message for d in code) or "the expression does not compile")
        value = self.client.debug_evaluate(code, proc)
        return {"result": str(value), "variablesReference": 0}

    # ------------------------------------------------------------ controller events
    def on_notification(self, msg: dict) -> None:
        """From the link's reader thread: halted / resumed. A resume that a
        request of ours asked for (continue, a step, ...) is not told: the
        client knows (DAP's continued event is for the others, e.g. the IDE's)."""
        if msg.get("type") == "halted" and isinstance(msg.get("state"), dict):
            self._own_resume = False
            self.on_halted(msg["state"])
        elif msg.get("type") == "resumed":
            self.view = None
            self._last_stop = None
            if self._own_resume:
                self._own_resume = False
            else:
                self.wire.event("continued", {"threadId": self._any_thread(),
                                              "allThreadsContinued": True})

    def on_halted(self, state: dict) -> None:
        bp = state.get("breakpoint") or {}
        key = (state.get("t_ms"), state.get("reason"), state.get("procedure"), state.get("line"),
               bp.get("id"))
        with self._stop_lock:       # (the main thread and the link's reader may both see it)
            if key == self._last_stop:
                return              # the same halt, seen by debug_state and by its notification
            self._last_stop = key
        view = self.view = View(state, self.threads, self._source_path)
        tid = view.stopped_thread()
        body = {"reason": _STOP_REASONS.get(state.get("reason"), "pause"), "threadId": tid,
                "allThreadsStopped": True}
        fault = state.get("fault")
        if fault:
            body["description"] = "Fault"
            body["text"] = fault.get("text", "")
        bp = state.get("breakpoint")
        if bp and bp.get("id") is not None:
            ids = self.breakpoints.dap_ids(bp["id"])
            if ids:
                body["hitBreakpointIds"] = ids
        self.wire.event("stopped", body)

    def on_telemetry(self, batch) -> None:
        for ev in batch.events:
            kind = getattr(ev, "type", "")
            if kind == "log":
                self.wire.output(f"{ev.source}: {ev.text}")
            elif kind == "print":
                self.wire.output(f"{ev.source}: print {ev.register} = {ev.value}")
            elif kind == "fault":
                self.wire.output(f"fault in {ev.source} line {ev.line}: {ev.text}", "stderr")
            elif kind == "note" and ev.level != "info":
                self.wire.output(ev.text, "stderr")
            elif kind == "ended" and self.started and ev.name == self.procedure:
                self.wire.output(f"{ev.name} ended with exit code {ev.exit_code}"
                                 f" ({ev.exit_name or 'no name'})")
                self.wire.event("exited", {"exitCode": ev.exit_code})
                self._terminate(None)

    # ------------------------------------------------------------ helpers
    def _terminate(self, code) -> None:
        if not self.done:
            self.wire.event("terminated")

    def _any_thread(self) -> int:
        """A thread id for an event about all threads (the launched procedure's)."""
        if self.procedure is not None:
            return self.threads.id_of(self.procedure)
        return next(iter(self.threads.ids.values()), 1)

    def _need_client(self) -> Client:
        if self.client is None:
            raise Refusal("not connected to a controller: launch or attach first")
        return self.client

    def _need_halt(self) -> View:
        self._need_client()
        if self.view is None:
            halted = self.client.debug_state()
            if halted is None:
                raise Refusal("the controller is running, not halted")
            self.view = View(halted, self.threads, self._source_path)
        return self.view

    def _refresh(self) -> None:
        halted = self.client.debug_state()
        self.view = View(halted, self.threads, self._source_path) if halted else None

    @staticmethod
    def _value(v) -> int:
        try:
            return int(str(v).strip(), 0)
        except ValueError:
            raise Refusal(f"{v!r} is not a whole number (decimal or 0x hex)") from None

    def _project(self, args: dict) -> Project:
        where = args.get("project") or args.get("program") or args.get("cwd") or "."
        p = Path(str(where)).expanduser()
        if p.is_file():
            found = Project.find_for(p) if p.suffix == ".plc" else None
            if found is None:
                raise Refusal(f"{p} is not inside a project (a folder with hardware/ or "
                              "software/ and plcbuilder.toml or include/)")
            return found
        try:
            return Project.open(p, existing=True)
        except ProjectError as exc:
            raise Refusal(f"cannot open the project: {exc}") from None

    def _target(self) -> Optional[dict]:
        """The project's target for the upload (None: myCNC), as the IDE sends it."""
        try:
            target = self.project.target_settings()
        except ProjectError as exc:
            raise Refusal(str(exc)) from None
        if target.get("name") == "mycnc":
            return None
        return {k: list(v) if isinstance(v, tuple) else v for k, v in target.items()}

    def _what_to_start(self, args: dict) -> tuple[Optional[str], int]:
        name = args.get("procedure")
        if not name and args.get("program"):
            name = Path(str(args["program"])).stem
        eparam = args.get("eparam", 0)
        if isinstance(eparam, bool) or not isinstance(eparam, int):
            eparam = self._value(eparam)
        if name is not None and not isinstance(name, str):
            raise Refusal("procedure must be a procedure's name, such as M03")
        return name, eparam

    def _build(self) -> bytes:
        self.wire.output(f"plcbuilder dap: building {self.project.root}")
        try:
            result = build_project(self.project)
        except OSError as exc:
            raise Refusal(f"cannot build: {exc}") from None
        for d in result.all_diagnostics:
            s = d.span
            where = f"{s.file}:{s.line}:{s.col}: " if s is not None else ""
            self.wire.output(f"{where}{d.severity.label}: {d.message}",
                             "stderr" if d.is_error else "console")
        if not result.ok:
            raise Refusal(f"the build failed: {result.error_count} errors (see the output)")
        return self._built_image()

    def _built_image(self) -> bytes:
        try:
            return self.project.image_path.read_bytes()
        except OSError as exc:
            raise Refusal(f"no image to upload: {exc.strerror or exc}") from None

    def _connect(self, args: dict, launch: bool) -> None:
        address = args.get("controller")
        if address is None and launch and self.project is not None:
            address = self.project.settings.controller_address or None
        try:
            if address:
                host, port = parse_address(str(address))
                self.client = Client.connect(host, port, args.get("token"))
            elif launch:
                speed = str(args.get("speed", "realtime"))
                extra = []
                if self.project is not None and self.project.machine_path.is_file():
                    extra += ["--machine", str(self.project.machine_path)]
                if self.project is not None and self.project.variables_path.is_file():
                    extra += ["--variables", str(self.project.variables_path)]
                self.embedded = ControllerProcess.start(speed=speed, extra_args=extra)
                self.client = self.embedded.connect()
            else:
                self.client = Client.connect()          # the one of the runtime file
        except ValueError as exc:
            raise Refusal(str(exc)) from None
        self._listen(self.client)
        where = "an embedded controller" if self.embedded else "the controller at %s:%d" % \
            tuple(self.client.address)
        self.wire.output(f"plcbuilder dap: connected to {where}")

    def _listen(self, client) -> None:
        """Hear the controller's halts, resumes and events; once this session has
        moved on to another launch or attach, what it still tells is dropped."""
        generation = self._generation

        def notified(msg: dict) -> None:
            with self._generation_lock:
                if generation == self._generation:
                    self.on_notification(msg)

        def telemetry(batch) -> None:
            with self._generation_lock:
                if generation == self._generation:
                    self.on_telemetry(batch)
        client.notification_callback = notified
        client.subscribe(telemetry, samples=False, events=True)

    def _leave(self, terminate: bool) -> None:
        c = self.client
        if c is None:
            return
        try:
            self.breakpoints.clear_all()
            if c.debug_state() is not None:
                self._resume(c.debug_continue)
            if terminate and self.embedded is None and self.started:
                c.stop()
        except LinkError:
            pass

    def _end_previous(self) -> None:
        """A launch or attach after another: the first one's controller is left
        (as disconnect leaves it) and, if this session started it, stopped."""
        had = self.embedded is not None
        if self.client is not None or had:
            self._leave(True)
            with self._generation_lock:     # what the old controller still tells is dropped
                self._generation += 1
            self.shutdown()
            self.view = None
            self._last_stop = None
            self.started = self.configured = False
            self.procedure = None
        self.wire.reopen()
        if had:
            self.wire.output("plcbuilder dap: stopped the controller of the previous launch")

    def shutdown(self) -> None:
        c, self.client = self.client, None
        if c is not None:
            try:
                c.close()
            except Exception:  # noqa: BLE001
                pass
        if self.embedded is not None:
            self.embedded.stop()
            self.embedded = None

    # ------------------------------------------------------------ sources
    def _source_file(self, proc: Optional[str]) -> Optional[Path]:
        if proc is None or self.project is None:
            return None
        p = self.project.procedure(proc)
        return p.path if p is not None else None

    def _source_path(self, proc: str, stored: str) -> Optional[Path]:
        """Where a file named in a procedure's line table is (relative to the
        procedure's folder; built-in headers from the package)."""
        if stored.startswith("<builtin>/"):
            return builtin_header(stored)
        src = self._source_file(proc)
        if src is None:
            return None
        p = (src.parent / stored)
        try:
            return p.resolve()
        except OSError:
            return p


def _int(v, what: str, lo: Optional[int] = None) -> int:
    if isinstance(v, bool) or not isinstance(v, int) or (lo is not None and v < lo):
        more = f" from {lo}" if lo is not None else ""
        raise Refusal(f"{what} must be a whole number{more}, not {v!r}")
    return v


def serve_stdio() -> int:
    stdin, stdout = sys.stdin.buffer, sys.stdout.buffer

    def write(data: bytes) -> None:
        stdout.write(data)
        stdout.flush()
    try:                # the file descriptor itself: the reader thread may still be in a
        fd = sys.stdin.fileno()       # read at exit, and a buffered stdin's lock would abort it

        def read(n: int) -> bytes:
            return os.read(fd, n)
    except (AttributeError, OSError, ValueError):
        read = stdin.read1 if hasattr(stdin, "read1") else stdin.read
    session = Session(Wire(read, write))
    try:
        session.serve()
    finally:
        session.shutdown()
    return 0


__all__ = ["SCOPES", "Session", "serve_stdio"]
