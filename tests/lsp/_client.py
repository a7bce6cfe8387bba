"""A small JSON-RPC client for the tests: it starts ``python -m plcbuilder
lsp`` (or ``dap``) as an editor does and talks to it over its stdin/stdout in
``Content-Length`` frames; a thread reads every message the server sends."""

from __future__ import annotations

import json
import os
import queue
import subprocess
import sys
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def spawn(*args: str, cwd=None) -> subprocess.Popen:
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    return subprocess.Popen([sys.executable, "-m", "plcbuilder", *args], cwd=cwd,
                            stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, env=env)


def frame(obj) -> bytes:
    body = json.dumps(obj).encode("utf-8") if not isinstance(obj, bytes) else obj
    return b"Content-Length: %d\r\n\r\n" % len(body) + body


class Client:
    """Frames out, frames in; ``messages`` queues what the server sent."""

    def __init__(self, proc: subprocess.Popen):
        self.proc = proc
        self.messages: "queue.Queue[dict]" = queue.Queue()
        self.seen: list[dict] = []
        self._next = 0
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self) -> None:
        out = self.proc.stdout
        while True:
            length = None
            while True:
                line = out.readline()
                if not line:
                    return
                if line in (b"\r\n", b"\n"):
                    break
                name, _, value = line.decode("ascii").partition(":")
                if name.strip().lower() == "content-length":
                    length = int(value.strip())
            body = out.read(length)
            self.messages.put(json.loads(body))

    # ------------------------------------------------------------ sending
    def send_raw(self, data: bytes) -> None:
        self.proc.stdin.write(data)
        self.proc.stdin.flush()

    def send(self, obj) -> None:
        self.send_raw(frame(obj))

    def next_id(self) -> int:
        self._next += 1
        return self._next

    # ------------------------------------------------------------ receiving
    def wait(self, pred, timeout: float = 60.0) -> dict:
        """The first message (seen before or arriving) that pred accepts."""
        for m in self.seen:
            if pred(m):
                self.seen.remove(m)
                return m
        end = time.monotonic() + timeout
        while True:
            left = end - time.monotonic()
            if left <= 0:
                raise TimeoutError(f"no such message; seen: {self.seen[-5:]}")
            try:
                m = self.messages.get(timeout=left)
            except queue.Empty:
                continue
            if pred(m):
                return m
            self.seen.append(m)

    def close(self) -> None:
        try:
            self.proc.stdin.close()
        except OSError:
            pass
        try:
            self.proc.wait(10)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait(5)


class LspClient(Client):
    def request(self, method: str, params=None, timeout: float = 60.0) -> dict:
        mid = self.next_id()
        self.send({"jsonrpc": "2.0", "id": mid, "method": method, "params": params})
        return self.wait(lambda m: m.get("id") == mid and "method" not in m, timeout)

    def result(self, method: str, params=None):
        r = self.request(method, params)
        assert "error" not in r, r
        return r["result"]

    def notify(self, method: str, params=None) -> None:
        self.send({"jsonrpc": "2.0", "method": method, "params": params})

    def diagnostics(self, uri: str, timeout: float = 60.0, pred=lambda d: True) -> list:
        m = self.wait(lambda m: m.get("method") == "textDocument/publishDiagnostics"
                      and m["params"]["uri"] == uri and pred(m["params"]["diagnostics"]), timeout)
        return m["params"]["diagnostics"]
