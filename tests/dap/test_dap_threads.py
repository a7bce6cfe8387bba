"""The adapter's threads (issue 24.2): a request that takes long (an
expression whose compile is slow, made slow here on purpose) keeps no other
request waiting, while the requests that change the session are still answered
one at a time, in the order they came. The Session runs in this process over a
pipe, as ``plcbuilder dap`` runs it over stdin/stdout."""

from __future__ import annotations

import json
import os
import threading
import time

import pytest

from plcbuilder.dap import breakpoints as dap_breakpoints
from plcbuilder.dap import session as dap_session
from plcbuilder.dap.wire import Wire
from tests.lsp._client import frame


class _Status:
    running = "M03"
    software = ("LUBE",)


class _Controller:
    """What the session asks a controller for, answered at once."""

    def state(self):
        return _Status()

    def debug_state(self):
        return None

    def debug_evaluate(self, code, procedure=None):
        return 42

    def set_breakpoints(self, file, specs):
        return [{"id": k + 1, "verified": True, "line": b["line"]} for k, b in enumerate(specs)]


class _Adapter:
    def __init__(self):
        r_in, self._w_in = os.pipe()
        self.out: list[dict] = []
        self._got = threading.Condition()
        self._buf = b""

        def write(data: bytes) -> None:
            self._buf += data
            while b"\r\n\r\n" in self._buf:
                head, rest = self._buf.split(b"\r\n\r\n", 1)
                n = int(head.split(b":")[1])
                if len(rest) < n:
                    return
                self._buf = rest[n:]
                with self._got:
                    self.out.append(json.loads(rest[:n]))
                    self._got.notify_all()

        self.session = dap_session.Session(Wire(lambda n: os.read(r_in, n), write))
        self.session.client = _Controller()
        self.thread = threading.Thread(target=self.session.serve, daemon=True)
        self.thread.start()
        self._seq = 0

    def send(self, command: str, arguments=None) -> int:
        self._seq += 1
        os.write(self._w_in, frame({"seq": self._seq, "type": "request", "command": command,
                                    "arguments": arguments or {}}))
        return self._seq

    def response(self, seq: int, timeout: float) -> dict:
        end = time.monotonic() + timeout
        with self._got:
            while True:
                for m in self.out:
                    if m.get("type") == "response" and m["request_seq"] == seq:
                        return m
                left = end - time.monotonic()
                if left <= 0:
                    raise TimeoutError(f"no response to request {seq}")
                self._got.wait(left)

    def close(self) -> None:
        os.close(self._w_in)
        self.thread.join(10)


@pytest.fixture
def slow_compile(monkeypatch):
    """compile_condition that waits for the test to let it finish."""
    go = threading.Event()
    entered = threading.Event()

    def compile_condition(text, context=None):
        entered.set()
        assert go.wait(30)
        return b"compiled"
    monkeypatch.setattr(dap_session, "compile_condition", compile_condition)
    monkeypatch.setattr(dap_breakpoints, "compile_condition", compile_condition)
    yield go, entered
    go.set()


def test_a_slow_evaluate_keeps_no_request_waiting(slow_compile):
    go, entered = slow_compile
    a = _Adapter()
    try:
        slow = a.send("evaluate", {"expression": "count > 1", "context": "watch"})
        assert entered.wait(10)
        t0 = time.monotonic()
        threads = a.response(a.send("threads"), timeout=5)
        assert threads["success"] and threads["body"]["threads"] == [
            {"id": 1, "name": "M03"}, {"id": 2, "name": "LUBE"}]
        init = a.response(a.send("initialize", {"adapterID": "plcbuilder"}), timeout=5)
        assert init["success"] and time.monotonic() - t0 < 2.0
        assert not any(m.get("request_seq") == slow for m in a.out)    # still compiling
        go.set()
        assert a.response(slow, timeout=10)["body"]["result"] == "42"
        a.response(a.send("disconnect"), timeout=10)
    finally:
        go.set()
        a.close()


def test_requests_that_change_the_session_are_answered_in_order(slow_compile):
    """setBreakpoints (its conditions compiled) then configurationDone: the
    second waits for the first, so the procedure never starts before its
    breakpoints are set; the looking requests are answered meanwhile."""
    go, entered = slow_compile
    a = _Adapter()
    try:
        first = a.send("setBreakpoints", {"source": {"path": "/p/hardware/M03.plc"},
                                          "breakpoints": [{"line": 5, "condition": "n > 1"}]})
        second = a.send("configurationDone")
        assert entered.wait(10)
        assert a.response(a.send("threads"), timeout=5)["success"]
        time.sleep(0.3)
        assert not [m for m in a.out if m.get("request_seq") in (first, second)]
        go.set()
        a.response(second, timeout=10)
        order = [m["request_seq"] for m in a.out if m.get("request_seq") in (first, second)]
        assert order == [first, second]
        a.response(a.send("disconnect"), timeout=10)
    finally:
        go.set()
        a.close()


def test_what_the_previous_controller_still_tells_is_dropped():
    """A relaunch after the first procedure ended: its 'ended' event came late
    (the telemetry of a busy machine), while the relaunch was leaving the first
    controller, and its terminated closed the session the relaunch had already
    reopened: the new launch's initialized and every later event were dropped.
    Now the first session's end is told before the new one opens, and what the
    old controller tells after that is dropped."""
    from types import SimpleNamespace

    ended = SimpleNamespace(type="ended", name="M03", exit_code=99, exit_name="x", source="M03")

    class Old(_Controller):
        def subscribe(self, fn, **kw):
            self.telemetry = fn

        def stop(self):                             # the late news, while being left
            self.telemetry(SimpleNamespace(events=[ended]))
            return {}

        def close(self):
            pass

    sent: list[dict] = []
    s = dap_session.Session(Wire(lambda n: b"", lambda data: sent.append(
        json.loads(data.split(b"\r\n\r\n", 1)[1]))))
    old = Old()
    s.client, s.started, s.procedure = old, True, "M03"
    s._listen(old)
    s._end_previous()                               # a second launch begins
    old.telemetry(SimpleNamespace(events=[ended]))  # later still: dropped
    s.wire.event("initialized")
    assert [m["event"] for m in sent if m["type"] == "event" and m["event"] != "output"] == \
        ["exited", "terminated", "initialized"]
