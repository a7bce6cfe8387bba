"""What the debug adapter's tests share: a DAP client that drives ``plcbuilder
dap`` as an editor does (a child process, frames over its stdin/stdout) and
keeps every message of the session in the order it crossed the wire, and a
small project to debug."""

from __future__ import annotations

import threading
from pathlib import Path

from tests.lsp._client import Client, spawn

M03 = """main()
{
  count = 0;
  do {
    count = count + 1;
    helper();
  } while (count < 5);
  gvarset(20001, total);
  exit(99);
}
helper()
{
  total = total + count;
}
"""

#: divides by zero on its third pass (line 6, when n is 0)
M04 = """main()
{
  n = 3;
  do {
    n = n - 1;
    q = 10 / n;
  } while (1);
}
"""

#: loops (long enough), one pass a tick
M05 = """main()
{
  do {
    m = m + 1;
  } while (m < 1000000);
}
"""

#: a software procedure: runs from the upload on, a thread of its own
LUBE = """main()
{
  do {
    k = k + 1;
  } while (1);
}
"""


def make_project(root: Path, software: bool = False) -> Path:
    (root / "hardware").mkdir(parents=True)
    (root / "software").mkdir()
    (root / "include").mkdir()
    (root / "plcbuilder.toml").write_text('name = "dap"\n')
    (root / "hardware" / "M03.plc").write_text(M03)
    (root / "hardware" / "M04.plc").write_text(M04)
    (root / "hardware" / "M05.plc").write_text(M05)
    if software:
        (root / "software" / "LUBE.plc").write_text(LUBE)
    return root


class DapClient(Client):
    """Requests out, responses and events in; ``log`` holds every message both
    ways, in wire order (``sent`` marks the client's)."""

    def __init__(self, proc):
        self.log: list[dict] = []
        self._log_lock = threading.Lock()
        super().__init__(proc)

    def _got(self, msg: dict) -> None:
        with self._log_lock:
            self.log.append(msg)
        super()._got(msg)

    def send(self, obj) -> None:
        if isinstance(obj, dict):
            with self._log_lock:
                self.log.append({**obj, "_sent": True})
        super().send(obj)

    def request(self, command: str, arguments=None, timeout: float = 60.0) -> dict:
        seq = self.next_id()
        self.send({"seq": seq, "type": "request", "command": command,
                   "arguments": arguments or {}})
        return self.wait(lambda m: m.get("type") == "response" and m.get("request_seq") == seq,
                         timeout)

    def ok(self, command: str, arguments=None, timeout: float = 60.0) -> dict:
        r = self.request(command, arguments, timeout)
        assert r["success"], r
        return r.get("body") or {}

    def event(self, name: str, timeout: float = 60.0, pred=lambda b: True) -> dict:
        m = self.wait(lambda m: m.get("type") == "event" and m.get("event") == name
                      and pred(m.get("body") or {}), timeout)
        return m.get("body") or {}

    def received(self) -> list[dict]:
        """What the adapter sent, in order."""
        with self._log_lock:
            return [m for m in self.log if not m.get("_sent")]


def start(cwd) -> DapClient:
    return DapClient(spawn("dap", cwd=cwd))


def initialize(dap: DapClient) -> dict:
    return dap.ok("initialize", {"clientID": "test", "adapterID": "plcbuilder",
                                 "linesStartAt1": True, "columnsStartAt1": True,
                                 "pathFormat": "path", "supportsVariablePaging": True})


def frames(dap: DapClient, tid: int) -> list[dict]:
    return dap.ok("stackTrace", {"threadId": tid})["stackFrames"]


def scope_ref(dap: DapClient, frame_id: int, scope: str = "Variables") -> int:
    scopes = dap.ok("scopes", {"frameId": frame_id})["scopes"]
    return next(s["variablesReference"] for s in scopes if s["name"] == scope)


def values(dap: DapClient, frame_id: int, scope: str = "Variables") -> tuple[int, dict]:
    ref = scope_ref(dap, frame_id, scope)
    got = dap.ok("variables", {"variablesReference": ref})["variables"]
    return ref, {v["name"]: v["value"] for v in got}
