"""The debugger's requests and answers on the IDE's controller connection
(SPEC §6, the debug contract): a mixin of
:class:`~plcbuilder.ide.connection.ControllerConnection`, which declares the
signals (``sig_halted``, ``sig_resumed``, ``sig_breakpoints``,
``sig_forces_changed``, ``sig_log``) and queues the requests (``_send``).
"""

from __future__ import annotations

from typing import Optional


class DebugRequests:
    """set_breakpoints, continue/pause/step/run to, write/force/release, and
    each halt once (``_on_debug_state``)."""

    def set_breakpoints(self, file: str, breakpoints: list) -> None:
        """Replace the breakpoints of one file (its name as the line table has
        it, ``M80.plc``) with these specs (the contract's dicts; a condition
        as ``{text, code}``). Kept, and sent again after a restart; the answer
        comes as sig_breakpoints."""
        self._send("set_breakpoints", {"file": str(file), "breakpoints": list(breakpoints)})

    def debug_continue(self) -> None:
        self._send("debug_continue", {})

    def debug_pause(self) -> None:
        """Halt at the end of the current tick."""
        self._send("debug_pause", {})

    def debug_step(self, kind: str, procedure: Optional[str] = None) -> None:
        """``tick`` (one 1 ms tick), ``into``, ``over`` or ``out`` (statements of
        ``procedure``, by default the one that halted)."""
        fields = {"kind": kind}
        if procedure:
            fields["procedure"] = procedure
        self._send("debug_step", fields)

    def debug_run_to(self, file: str, line: int) -> None:
        self._send("debug_run_to", {"file": str(file), "line": int(line)})

    def debug_step_back(self, kind: str = "tick") -> None:
        """Back one ``tick`` or one ``statement`` (SPEC §7): the controller runs
        the session again and halts there."""
        self._send("debug_step_back", {"kind": kind})

    def debug_run_back(self) -> None:
        """Back to the previous breakpoint hit (SPEC §7)."""
        self._send("debug_run_back", {})

    def request_debug_state(self) -> None:
        """Ask whether the controller is halted (the answer: sig_halted or sig_resumed)."""
        self._send("debug_state", {})

    def write(self, target: str, value: int) -> None:
        """Set once: ``PROC.var``, ``in N``, ``out N``, ``adc N``, ``pwm N``,
        ``dac N`` or ``gvar N``."""
        self._send("write", {"target": str(target), "value": int(value)})

    def force(self, target: str, value: int) -> None:
        """Hold a target at a value until released (the list follows as
        sig_forces_changed)."""
        self._send("force", {"target": str(target), "value": int(value)})

    def release(self, target: str, mode: str = "keep") -> None:
        """End a force: ``keep`` the value it has, or ``restore`` what the
        program (or the wiring) would have now."""
        self._send("release", {"target": str(target), "mode": mode})

    def release_all(self, mode: str = "keep") -> None:
        self._send("release_all", {"mode": mode})

    def request_forces(self) -> None:
        self._send("forces", {})

    def _on_debug_state(self, kind: str, payload) -> None:
        """A halted state (from debug_state or a ``halted`` message) or a
        ``resumed`` message: each halt is emitted once."""
        if kind == "halted" and isinstance(payload, dict) and "state" in payload:
            payload = payload["state"]
        if kind == "resumed":
            payload = None
        if isinstance(payload, dict):
            if payload != self.halted:
                self.halted = payload
                self.sig_halted.emit(payload)
        elif self.halted is not None:
            self.halted = None
            self.sig_resumed.emit(int(self.last_state.t_ms))

    def _on_forces(self, forces) -> None:
        forces = [f for f in (forces or []) if isinstance(f, dict)]
        if forces != self.forces:
            self.forces = forces
            self.sig_forces_changed.emit(list(forces))
