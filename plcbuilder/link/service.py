"""The controller's verbs: one ``handle_<type>(msg, session)`` method per request
type, returning the ``result`` object or raising :class:`Refused` /
:class:`~plcbuilder.link.protocol.BadRequest`. No sockets: tests call it
directly; :mod:`plcbuilder.link.server` puts it on the network.
"""

from __future__ import annotations

import os
import time
import traceback
import zlib
from dataclasses import dataclass, field, replace
from typing import Callable, Optional

from plcbuilder.controller.controller import Controller, ControllerError
from plcbuilder.controller.debugger import DebugError
from plcbuilder.controller.events import ControllerStatus
from plcbuilder.controller.targets import TargetConfig
from plcbuilder.image.manifest import Image, ImageError, Limits, read_image
from plcbuilder.link import protocol
from plcbuilder.link.pacing import Simulation, SimulationDown, TelemetryQueue
from plcbuilder.link.protocol import (MAX_IMAGE, REQUESTS, SAMPLE_FIELDS, BadRequest, ErrorCode,
                                      ProtocolError)
from plcbuilder.link.protocol import debug as _debug
from plcbuilder.link.service_debug import DebugVerbs

__all__ = ["EVENT_HANDLERS", "Refused", "Service", "Session", "image_summary"]

#: Handlers that a host may start with the ``event`` request.
EVENT_HANDLERS = ("__HANDLER_GCODE_START", "__HANDLER_GCODE_STOP")
#: Variables one ``watch`` request may name at most.
MAX_WATCHED = 32


class Refused(Exception):
    """The controller refuses a request; ``reason`` goes back to the client."""

    def __init__(self, reason: str):
        super().__init__(reason)
        self.reason = reason


# ===================================================================== the verbs

@dataclass
class Session:
    """What the service keeps per client."""
    telemetry: Optional[TelemetryQueue] = None
    peer: str = ""
    #: told when the telemetry queue has something new (the server wakes up for it)
    notify: Optional[Callable[[], None]] = None
    changes: protocol.ChangeEncoder = field(default_factory=protocol.ChangeEncoder)


def image_summary(image: Optional[Image]) -> list[dict]:
    if image is None:
        return []
    return [{"name": p.name, "kind": p.kind.label, "size": p.code_size, "code_size": p.code_size,
             "file_size": p.file_size, "crc32": f"{p.crc32:08x}"} for p in image.procedures]


class Service(DebugVerbs):
    """The controller's verbs, one ``handle_<type>`` per request type (the
    debugger's in :class:`~plcbuilder.link.service_debug.DebugVerbs`).

    ``controller_factory`` makes a fresh controller for ``reset`` (None: reset
    is refused). ``limits`` are the controller's code size limits that an
    uploaded image is checked against.
    """

    def __init__(self, sim: Simulation, *, limits: Optional[Limits] = None,
                 controller_factory: Optional[Callable[[], Controller]] = None,
                 max_image: int = MAX_IMAGE):
        self.sim = sim
        self.limits = limits or Limits()
        self.controller_factory = controller_factory
        self.max_image = max_image
        self.image: Optional[Image] = None
        self._summary: tuple = ()              # image_summary of the image, made once
        self.image_crc32: Optional[int] = None
        self.image_size = 0
        self.uploads = 0
        self.refused = 0
        self.clients = 0            # kept up to date by the Server
        self.step_budget = 2.0      # seconds of wall time one step request may take
        #: the controller's kept state (Huazhong's B registers) by target, and the
        #: file it is kept in across restarts of the server (None: in memory only)
        self.state_path = None
        self.kept: dict[str, tuple] = {}
        #: stepping back's checkpoints (controller/rewind.py), made while idle
        self.checkpoints = None
        self.start_checkpoints()

    # ---------------------------------------------------------------- dispatch
    def dispatch(self, msg: dict, session: Session) -> dict:
        mtype = msg.get("type")
        if mtype not in REQUESTS:
            raise ProtocolError(f"unknown request type {mtype!r}", ErrorCode.UNKNOWN_TYPE)
        handler = getattr(self, f"handle_{mtype}", None)
        if handler is None:
            raise ProtocolError(f"{mtype} is not handled here", ErrorCode.UNKNOWN_TYPE)
        return handler(msg, session)

    def _on_sim(self, fn: Callable):
        """Run fn on the simulation thread; a ControllerError becomes Refused."""
        try:
            return self.sim.call(fn)
        except (ControllerError, DebugError) as exc:
            raise Refused(str(exc)) from None
        except SimulationDown as exc:
            raise Refused(str(exc)) from None

    # ---------------------------------------------------------------- image
    def check_image(self, data: bytes) -> Image:
        """read_image against the controller's limits; Refused with the reason."""
        if len(data) > self.max_image:
            raise Refused(f"image refused: it is {len(data)} bytes, more than {self.max_image}")
        try:
            return read_image(data, self.limits)
        except ImageError as exc:
            raise Refused(f"image refused: {exc}") from None
        except Exception as exc:  # noqa: BLE001 - a reader bug still means "refused"
            _debug(traceback.format_exc())
            raise Refused(f"image refused: unreadable ({type(exc).__name__}: {exc})") from None

    def load_image(self, data: bytes, target: Optional[dict] = None) -> dict:
        """Validate a whole image, then load it at once; on refusal nothing changes.
        ``target`` (docs/targets.md): the controller runs that target's schedule
        from now on (a new controller on the same machine when it changes)."""
        try:
            image = self.check_image(data)
        except Refused:
            self.refused += 1
            raise

        def swap():
            controller = self._for_target(target)
            previous = list(controller.programs.values())
            try:
                controller.load([p.program for p in image.procedures])
            except ControllerError:
                raise
            except Exception as exc:  # noqa: BLE001 - a loader bug: put the old image back
                _debug(traceback.format_exc())
                try:
                    controller.load(previous)
                except Exception:  # noqa: BLE001
                    _debug(traceback.format_exc())
                raise ControllerError(f"the controller could not load it "
                                      f"({type(exc).__name__}: {exc})") from None
            self.image = image
            self._summary = tuple(image_summary(image))
            self.image_crc32 = zlib.crc32(data)
            self.image_size = len(data)
            return self.sim.controller.t_ms

        try:
            t = self._on_sim(swap)
        except Refused as exc:
            self.refused += 1
            raise Refused(f"image refused: {exc.reason}") from None
        self.uploads += 1
        return {"accepted": True, "t_ms": t, "size": len(data),
                "image_crc32": f"{self.image_crc32:08x}", "procedures": list(self._summary),
                "hw_total": image.hw_total}

    def handle_upload(self, msg: dict, session: Session) -> dict:
        try:
            data = protocol.decode_image(msg, self.max_image)
        except BadRequest:
            self.refused += 1
            raise
        return self.load_image(data, protocol.decode_target(msg))

    def _for_target(self, target: Optional[dict]) -> Controller:
        """The controller to load an image for ``target`` into: the one running,
        or a new one on the same machine when the target changes (Huazhong's
        B registers carried over). Runs on the simulation thread."""
        current = self.sim.controller
        name = (target or {}).get("name", "mycnc")
        config = None
        if name != "mycnc":
            fields = dict(target)
            for key in ("parameters", "program_periods_us", "scope"):
                if key in fields:
                    fields[key] = tuple(fields[key])
            kept = current.retained() if current.target is not None and \
                current.target.name == name else self.kept.get(name)
            try:
                config = TargetConfig(**fields, retained=tuple(kept) if kept else None)
            except TypeError as exc:
                raise ControllerError(f"target: {exc}") from None
        if config == current.target:
            return current
        new = Controller(current.machine.config, backend=current.backend, target=config)
        self.sim.replace_controller(new)
        return new

    # ---------------------------------------------------------------- procedures
    def handle_start(self, msg: dict, session: Session) -> dict:
        eparam = protocol.field_int(msg, "eparam", 0)
        has_name, has_mcode = "name" in msg, "mcode" in msg
        if has_name == has_mcode:
            raise BadRequest("start: give either 'name' or 'mcode'")
        if has_name:
            name = protocol.field_str(msg, "name", max_len=128)

            def go():
                self.sim.controller.start(name, eparam)
                return name, self.sim.controller.t_ms
        else:
            n = protocol.field_int(msg, "mcode", lo=0, hi=1_000_000)

            def go():
                started = self.sim.controller.start_mcode(n, eparam)
                return started, self.sim.controller.t_ms
        started, t = self._on_sim(go)
        return {"started": started, "eparam": eparam, "t_ms": t}

    def handle_stop(self, msg: dict, session: Session) -> dict:
        def go():
            return self.sim.controller.stop(), self.sim.controller.t_ms
        started, t = self._on_sim(go)
        return {"started": started, "t_ms": t}

    def handle_event(self, msg: dict, session: Session) -> dict:
        handler = protocol.field_str(msg, "handler", max_len=64)
        if handler not in EVENT_HANDLERS:
            raise BadRequest(f"event: handler must be one of {', '.join(EVENT_HANDLERS)}")
        started = self._on_sim(lambda: self.sim.controller.event(handler))
        return {"handler": handler, "started": bool(started)}

    def handle_code(self, msg: dict, session: Session) -> dict:
        """The simulated CNC issues a code (a scenario's ``code M3``): ``letter``
        M, S, B or T and ``value``; on myCNC an M code starts its procedure, on
        Huazhong the code goes to the handler init() registered (recorded as
        the run's other actions are)."""
        letter = protocol.field_str(msg, "letter", max_len=1).upper()
        if letter not in ("M", "S", "B", "T"):
            raise BadRequest("code: letter must be one of M, S, B, T")
        value = protocol.field_int(msg, "value", lo=0, hi=(1 << 31) - 1)

        def go():
            started = self.sim.controller.issue_code(letter, value)
            return started, self.sim.controller.t_ms
        started, t = self._on_sim(go)
        return {"code": f"{letter}{value}", "started": started, "t_ms": t}

    def handle_job(self, msg: dict, session: Session) -> dict:
        """The G-code job (SPEC §10): ``open`` (``text``, ``file``; ``play``: start it
        too), ``play``, ``pause``, ``stop``, ``reset``."""
        verb = protocol.field_str(msg, "verb", max_len=16)
        if verb not in protocol.JOB_VERBS:
            raise BadRequest(f"job: verb must be one of {', '.join(protocol.JOB_VERBS)}")
        if verb == "open":
            text = protocol.field_str(msg, "text", max_len=protocol.MAX_JOB_TEXT)
            file = protocol.field_str(msg, "file", "job.nc", max_len=4096)
            play = bool(msg.get("play", False))

            def go():
                self.sim.controller.job_open(text, file, play=play)
        else:
            def go():
                self.sim.controller.job_control(verb)

        def done():
            go()
            return self.sim.controller.job_report(), self.sim.controller.t_ms
        job, t = self._on_sim(done)
        return {"job": {k: v for k, v in job.items() if k != "mcodes"}, "t_ms": t}

    # ---------------------------------------------------------------- I/O
    def handle_input(self, msg: dict, session: Session) -> dict:
        pin = protocol.field_int(msg, "pin", lo=0, hi=1 << 16)
        value = protocol.field_int(msg, "value", lo=0, hi=1)
        t = self._on_sim(lambda: (self.sim.controller.set_input(pin, value),
                                  self.sim.controller.t_ms)[1])
        return {"pin": pin, "value": value, "t_ms": t}

    def handle_adc(self, msg: dict, session: Session) -> dict:
        ch = protocol.field_int(msg, "channel", lo=0, hi=1 << 16)
        value = protocol.field_int(msg, "value")
        t = self._on_sim(lambda: (self.sim.controller.set_adc(ch, value),
                                  self.sim.controller.t_ms)[1])
        return {"channel": ch, "value": value, "t_ms": t}

    # ---------------------------------------------------------------- write and force
    def _forcing(self, fn: Callable) -> dict:
        """Run fn(controller) on the simulation thread; the answer adds t_ms and
        the forces now."""
        def go():
            c = self.sim.controller
            out = fn(c)
            return {**out, "t_ms": c.t_ms, "forces": c.forces()}
        return self._on_sim(go)

    @staticmethod
    def _target(msg: dict) -> str:
        return protocol.field_str(msg, "target", max_len=128)

    @staticmethod
    def _mode(msg: dict) -> str:
        mode = protocol.field_str(msg, "mode", "restore", max_len=16)
        if mode not in protocol.RELEASE_MODES:
            raise BadRequest(f"mode must be one of {', '.join(protocol.RELEASE_MODES)}")
        return mode

    def handle_write(self, msg: dict, session: Session) -> dict:
        target = self._target(msg)
        value = protocol.field_int(msg, "value", lo=-(1 << 31), hi=(1 << 32) - 1)
        return self._forcing(lambda c: {"target": c.write(target, value), "value": value})

    def handle_force(self, msg: dict, session: Session) -> dict:
        target = self._target(msg)
        value = protocol.field_int(msg, "value", lo=-(1 << 31), hi=(1 << 32) - 1)
        return self._forcing(lambda c: {"target": c.force(target, value), "value": value})

    def handle_release(self, msg: dict, session: Session) -> dict:
        target, mode = self._target(msg), self._mode(msg)
        return self._forcing(lambda c: {"target": c.release(target, mode), "mode": mode})

    def handle_release_all(self, msg: dict, session: Session) -> dict:
        mode = self._mode(msg)
        return self._forcing(lambda c: {"released": c.release_all(mode), "mode": mode})

    def handle_forces(self, msg: dict, session: Session) -> dict:
        return {"forces": self._on_sim(lambda: self.sim.controller.forces())}

    # ---------------------------------------------------------------- state
    def state(self) -> ControllerStatus:
        st = self._on_sim(self.sim.controller.state)
        return replace(
            st, image=self._summary,
            image_crc32=None if self.image_crc32 is None else f"{self.image_crc32:08x}",
            speed=self.sim.speed(),
            server={"clients": self.clients, "subscribers": self.sim.subscribers,
                    "uploads": self.uploads, "refused": self.refused, "pid": os.getpid(),
                    "error": self.sim.error})

    def handle_state(self, msg: dict, session: Session) -> dict:
        return self.state().to_dict()

    def handle_variables(self, msg: dict, session: Session) -> dict:
        def read():
            c = self.sim.controller
            out = {"variables": c.variables()}
            if c.target is not None:
                out["target"] = c.target_report()
            return out
        return self._on_sim(read)

    def handle_watch(self, msg: dict, session: Session) -> dict:
        """{variables: [PROC.var]}: the controller records them at the end of
        every tick, as ``watch`` events in the telemetry (a trigger on a
        variable needs them); [] stops. A name that is not a variable of a
        loaded procedure is refused and nothing changes."""
        names = msg.get("variables")
        if not isinstance(names, list) or len(names) > MAX_WATCHED or \
                not all(isinstance(n, str) and 0 < len(n) <= 160 for n in names):
            raise BadRequest(f"watch: 'variables' must be a list of at most {MAX_WATCHED} "
                             f"names (PROC.var)")
        return {"variables": self._on_sim(lambda: self.sim.controller.watch_variables(names))}

    def handle_registers(self, msg: dict, session: Session) -> dict:
        addresses = protocol.field_int_list(msg, "addresses", protocol.MAX_REGISTERS)
        gvarget = self.sim.controller.machine.gvarget
        values = self._on_sim(lambda: [gvarget(a) for a in addresses])
        return {"addresses": addresses, "values": values}

    def handle_recording(self, msg: dict, session: Session) -> dict:
        """The session's recording: every outside action since the controller
        started (or was reset), as a scenario file (docs/traces.md)."""
        def read():
            c = self.sim.controller
            end = max(0, c.t_ms - 1)
            head = [f"controller: {c.machine.config.name if hasattr(c.machine.config, 'name') else 'simulated'}"]
            if self.image_crc32 is not None:
                head.append(f"last image uploaded: eeprom.rom CRC-32 {self.image_crc32:08x}")
            return {"text": c.recorder.text(end, head), "t_ms": end,
                    "actions": len(c.recorder.actions)}
        return self._on_sim(read)

    # ---------------------------------------------------------------- time
    def handle_speed(self, msg: dict, session: Session) -> dict:
        mode = protocol.field_str(msg, "mode", max_len=16)
        if mode not in protocol.SPEED_MODES:
            raise BadRequest(f"speed: mode must be one of {', '.join(protocol.SPEED_MODES)}")
        factor = None
        if mode == "factor":
            factor = protocol.field_number(msg, "factor", protocol.MIN_FACTOR, protocol.MAX_FACTOR)

        def go():
            self.sim.set_speed(mode, factor)
            return self.sim.speed()
        return self._on_sim(go)

    def handle_step(self, msg: dict, session: Session) -> dict:
        ms = protocol.field_int(msg, "ms", lo=1, hi=600_000)
        budget = self.step_budget

        slice_s = 0.02

        def go(left: int):
            # One slice of at most ``slice_s`` seconds of wall time on the
            # simulation thread: between slices other requests are answered.
            c = self.sim.controller
            start, done = time.perf_counter(), 0
            while done < left:
                n = min(left - done, self.sim._chunk())
                c.step(n)
                done += n
                self.sim.publish()
                if time.perf_counter() - start > slice_s:
                    break
            self.sim.rebase()
            return c.t_ms, done

        # At most ``step_budget`` seconds of wall time in all, so that a runaway
        # procedure cannot hold the client up for minutes.
        start, done, t = time.perf_counter(), 0, None
        while done < ms:
            t, n = self._on_sim(lambda: go(ms - done))
            done += n
            if time.perf_counter() - start > budget:
                break
        return {"t_ms": t, "stepped": done, "complete": done == ms}

    def handle_reset(self, msg: dict, session: Session) -> dict:
        if self.controller_factory is None:
            raise Refused("reset is not available on this controller")
        factory = self.controller_factory

        def go():
            new = factory()
            old = self.sim.controller
            if old.target is not None:         # a restart: the same target, B kept
                kept = old.retained()
                new = Controller(new.machine.config, backend=new.backend,
                                 target=replace(old.target,
                                                retained=tuple(kept) if kept else None))
            if self.image is not None:
                new.load([p.program for p in self.image.procedures])
            self.sim.replace_controller(new)
            if self.checkpoints is not None:
                self.checkpoints.clear()
            return new.t_ms
        return {"t_ms": self._on_sim(go)}

    def load_state(self, path) -> None:
        """Read the kept state from ``path`` (docs/targets.md: a restart keeps
        Huazhong's B registers); a missing file is an empty state. Raises
        ValueError naming the file when it cannot be used."""
        import json
        from pathlib import Path
        from plcbuilder._support.files import read_bounded
        path = Path(path)
        if path.exists():
            try:
                doc = json.loads(read_bounded(path, 1 << 20, "state file").decode("utf-8"))
                self.kept = {name: tuple(int(v) for v in doc[name]["B"]) for name in doc}
            except (OSError, ValueError, KeyError, TypeError, UnicodeDecodeError) as exc:
                raise ValueError(f"{path}: not a controller state file: {exc}") from None
        self.state_path = path          # only a state read (or none yet) is written back

    def save_state(self) -> None:
        """Write the kept state (the running controller's B registers) to the
        state file, when there is one."""
        if self.state_path is None:
            return
        import json
        from plcbuilder._support.files import atomic_write
        c = self.sim.controller
        kept = c.retained()
        if kept is not None:
            self.kept[c.target.name] = tuple(kept)
        if self.kept:
            atomic_write(self.state_path, json.dumps(
                {name: {"B": list(v)} for name, v in sorted(self.kept.items())}) + "\n")

    def handle_ping(self, msg: dict, session: Session) -> dict:
        return {"pong": True}

    # ---------------------------------------------------------------- telemetry
    #: Sample changes a subscriber's queue may hold at most (memory: ~100 bytes each).
    max_queue = 20_000

    def handle_subscribe(self, msg: dict, session: Session) -> dict:
        samples = protocol.field_bool(msg, "samples", True)
        events = protocol.field_bool(msg, "events", True)
        lossless = protocol.field_bool(msg, "lossless", False)
        size = protocol.field_int(msg, "queue", 1000, lo=16, hi=self.max_queue)
        if session.telemetry is not None:
            self.end_session(session)
        q = TelemetryQueue(max_samples=size, samples=samples, events=events, lossless=lossless,
                           notify=session.notify)
        session.changes.reset()
        session.telemetry = q
        self.sim.call(lambda: self.sim.subscribe(q))
        return {"sample_fields": list(SAMPLE_FIELDS), "interval_ms": 20, "samples": samples,
                "events": events, "queue": size, "lossless": lossless,
                "encoding": "msgpack-changes"}

    def handle_unsubscribe(self, msg: dict, session: Session) -> dict:
        self.end_session(session)
        return {}

    def end_session(self, session: Session) -> None:
        if session.telemetry is not None:
            q, session.telemetry = session.telemetry, None
            try:
                self.sim.call(lambda: self.sim.unsubscribe(q), timeout=5.0)
            except SimulationDown:
                self.sim.unsubscribe(q)
