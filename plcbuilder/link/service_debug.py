"""The debugger's verbs (docs/protocol.md, "Debugging"): breakpoints, continue,
pause, step, run to line and the halted state. A mixin of
:class:`~plcbuilder.link.service.Service`, one ``handle_<type>`` per request;
a bad request is refused with its reason and changes nothing.

While the controller is halted its time stands still (the pacing waits), and
every request is still answered. Halts and resumes reach the subscribers as
``halted {state}`` and ``resumed {t_ms}`` notifications.
"""

from __future__ import annotations

import base64
import binascii

from plcbuilder.controller import rewind
from plcbuilder.controller.debugger import STEP_KINDS, DebugError
from plcbuilder.link import protocol
from plcbuilder.link.protocol import BadRequest

#: Breakpoints one set_breakpoints request may carry at most.
MAX_BREAKPOINTS = 1000
#: Longest condition or log text accepted.
MAX_TEXT = 1000


class DebugVerbs:
    """``handle_set_breakpoints`` … ``handle_debug_state``; needs ``self.sim``
    and ``self._on_sim`` (the Service)."""

    def _debug(self, fn):
        """Run fn(debugger) on the simulation thread, then announce what changed
        (halted/resumed) and publish it at once: a halted controller runs no
        batch that would."""
        def go():
            c = self.sim.controller
            try:
                out = fn(c.debugger)
            finally:
                c.debugger.settle()
                self.sim.publish()
            return out
        return self._on_sim(go)            # a DebugError is refused with its reason

    def _halted(self, dbg) -> dict:
        return {"t_ms": dbg.plc.t, "halted": dbg.halted_state()}

    def handle_set_breakpoints(self, msg: dict, session) -> dict:
        file = protocol.field_str(msg, "file", max_len=512)
        raw = msg.get("breakpoints")
        if not isinstance(raw, list):
            raise BadRequest("set_breakpoints: breakpoints must be a list")
        if len(raw) > MAX_BREAKPOINTS:
            raise BadRequest(f"set_breakpoints: at most {MAX_BREAKPOINTS} breakpoints a file")
        specs = [_spec(b, k) for k, b in enumerate(raw)]
        answers = self._debug(lambda d: d.set_breakpoints(file, specs))
        return {"breakpoints": answers}

    def handle_debug_continue(self, msg: dict, session) -> dict:
        def go(d):
            if d.halt is None:
                raise DebugError("not halted")
            d.resume()
            return self._halted(d)
        return self._debug(go)

    def handle_debug_pause(self, msg: dict, session) -> dict:
        def go(d):
            d.pause()
            return self._halted(d)
        return self._debug(go)

    def handle_debug_step(self, msg: dict, session) -> dict:
        kind = protocol.field_str(msg, "kind", max_len=16)
        if kind not in STEP_KINDS:
            raise BadRequest(f"debug_step: kind must be one of {', '.join(STEP_KINDS)}")
        proc = protocol.field_str(msg, "procedure", None, max_len=128)

        def go(d):
            d.step(kind, proc)
            return self._halted(d)
        return self._debug(go)

    def handle_debug_run_to(self, msg: dict, session) -> dict:
        file = protocol.field_str(msg, "file", max_len=512)
        line = protocol.field_int(msg, "line", lo=1, hi=1 << 24)

        def go(d):
            d.run_to(file, line)
            return self._halted(d)
        return self._debug(go)

    def handle_debug_step_back(self, msg: dict, session) -> dict:
        """{kind: tick|statement}: the session run again to one tick or one
        statement before now; the new controller, halted there, takes over."""
        kind = protocol.field_str(msg, "kind", "tick", max_len=16)
        if kind not in rewind.KINDS:
            raise BadRequest(f"debug_step_back: kind must be one of {', '.join(rewind.KINDS)}")
        return self._rewind(lambda old, factory: rewind.step_back(old, factory, kind,
                                                                  self.checkpoints))

    def handle_debug_run_back(self, msg: dict, session) -> dict:
        """{}: the session run again to the previous breakpoint hit (from the
        checkpoints, when there are some before it)."""
        return self._rewind(lambda old, factory: rewind.run_back(old, factory,
                                                                 self.checkpoints))

    def start_checkpoints(self) -> None:
        """Make stepping back's checkpoints in the simulation's idle time."""
        if self.controller_factory is not None and self.checkpoints is None:
            self.checkpoints = rewind.Checkpoints(self.controller_factory)
            pool = self.checkpoints
            self.sim.idle_work = lambda s: pool.work(self.sim.controller, s)

    def _rewind(self, fn) -> dict:
        factory = self.controller_factory

        def go():
            if factory is None:
                raise DebugError("stepping back is not available on this controller (it "
                                 "cannot make a fresh controller to run the session again)")
            old = self.sim.controller
            try:
                new = fn(old, factory)
            except rewind.RewindError as exc:
                raise DebugError(str(exc)) from None
            new.sample_changes_only = old.sample_changes_only
            self.sim.replace_controller(new)
            new.record_next_sample()
            self.sim.publish()
            return self._halted(new.debugger)
        return self._on_sim(go)

    def handle_debug_evaluate(self, msg: dict, session) -> dict:
        """{code: base64 of an expression compiled as a condition, procedure?} -> {value}."""
        raw = protocol.field_str(msg, "code", max_len=4 * protocol.MAX_FRAME // 8)
        proc = protocol.field_str(msg, "procedure", None, max_len=128)
        try:
            code = base64.b64decode(raw, validate=True)
        except (binascii.Error, ValueError):
            raise BadRequest("debug_evaluate: code is not base64") from None
        return {"value": self._debug(lambda d: d.evaluate(code, proc))}

    def handle_debug_state(self, msg: dict, session) -> dict:
        return self._debug(lambda d: {**self._halted(d), "breakpoints": d.breakpoints()})


def _spec(b, k: int) -> dict:
    """One breakpoint of a set_breakpoints request, checked for shape (the
    debugger checks the rest): the condition's code decoded from base64."""
    what = f"set_breakpoints: breakpoint {k + 1}"
    if not isinstance(b, dict):
        raise BadRequest(f"{what} is not an object")
    spec = {"line": b.get("line"), "enabled": b.get("enabled", True), "hit": b.get("hit"),
            "log": b.get("log")}
    if not isinstance(spec["enabled"], bool):
        raise BadRequest(f"{what}: enabled must be true or false")
    if spec["log"] is not None and (not isinstance(spec["log"], str)
                                    or len(spec["log"]) > MAX_TEXT):
        raise BadRequest(f"{what}: log must be text of at most {MAX_TEXT} characters")
    cond = b.get("condition")
    if cond is not None:
        if not isinstance(cond, dict) or not isinstance(cond.get("code"), str) \
                or not isinstance(cond.get("text", ""), str):
            raise BadRequest(f"{what}: condition must be {{text, code: base64 of the compiled "
                             f"condition}} (plcbuilder.api.compile_condition)")
        if len(cond["code"]) > 4 * protocol.MAX_FRAME // 8 or len(cond.get("text", "")) > MAX_TEXT:
            raise BadRequest(f"{what}: condition too long")
        try:
            code = base64.b64decode(cond["code"], validate=True)
        except (binascii.Error, ValueError):
            raise BadRequest(f"{what}: condition code is not base64") from None
        spec["condition"] = {"text": cond.get("text", ""), "code": code}
    return spec
