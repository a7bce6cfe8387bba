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
    """Frames out, frames in; ``messages`` queues what the server sent.
    ``check(message)`` (when given) is called on every message received."""

    check = None

    def __init__(self, proc: subprocess.Popen):
        self.proc = proc
        self.messages: "queue.Queue[dict]" = queue.Queue()
        self.seen: list[dict] = []
        self.arrived: list[dict] = []
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
            self._got(json.loads(out.read(length)))

    def _got(self, msg: dict) -> None:
        """One message read (on the reader thread): queued for :meth:`wait`."""
        self.messages.put(msg)

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
            self.arrived.append(m)
            if self.check is not None:
                self.check(m)
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
    """Every message the server sends is checked against lsprotocol's
    structures (:func:`conform`)."""

    def __init__(self, proc: subprocess.Popen):
        self.methods: dict = {}            # request id -> method, to check the responses
        super().__init__(proc)

    def check(self, m: dict) -> None:
        conform(m, self.methods)

    def request(self, method: str, params=None, timeout: float = 60.0) -> dict:
        mid = self.next_id()
        self.methods[mid] = method
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


_CONVERTER = None


def conform(m: dict, methods: dict = None):
    """Structure one message the server sent with lsprotocol's own cattrs
    converter, as a typed client reads it: a notification or request by its
    method, a response by the method of the request (when known), an error
    response as ResponseErrorMessage. Raises when it does not fit."""
    global _CONVERTER
    from lsprotocol import converters
    from lsprotocol import types as T
    if _CONVERTER is None:
        _CONVERTER = converters.get_converter()
    assert m.get("jsonrpc") == "2.0", m
    if "method" in m:
        types = T.METHOD_TO_TYPES.get(m["method"])
        assert types is not None, f"a method LSP does not have: {m['method']}"
        return _CONVERTER.structure(m, types[0])
    assert "id" in m, m
    if "error" in m:
        assert "result" not in m, m
        err = _CONVERTER.structure(m, T.ResponseErrorMessage)
        assert isinstance(err.error.code, int) and err.error.message, m
        return err
    method = (methods or {}).get(m["id"])
    types = T.METHOD_TO_TYPES.get(method) if method else None
    if types is None or types[1] is None:
        return m
    return _CONVERTER.structure(m, types[1])


# ---------------------------------------------------------------- a project and a session
HEADER = "#define MY_PIN 7\n#define MY_REG 7500\n"
M03 = ("#include my.h\n"
       "main()\n"
       "{\n"
       "  code = gvarset(6060);\n"
       "  portset(MY_PIN);\n"
       "  speed = gvarget(0x17ac);\n"
       "  gvarset(MY_REG, speed + code);\n"
       "  exit(99);\n"
       "};\n")
M04 = "#include my.h\nmain() { portclr(MY_PIN); exit(99); };\n"


def make_project(root: Path, settings: str = 'name = "t"\n') -> Path:
    """A project: include/my.h, hardware/M03.plc and M04.plc that include it."""
    (root / "hardware").mkdir(parents=True)
    (root / "software").mkdir()
    (root / "include").mkdir()
    (root / "plcbuilder.toml").write_text(settings)
    (root / "include" / "my.h").write_text(HEADER)
    (root / "hardware" / "M03.plc").write_text(M03)
    (root / "hardware" / "M04.plc").write_text(M04)
    return root


def start_server(root: Path, *args: str, root_uri="same") -> LspClient:
    """``plcbuilder lsp ARGS`` started in ``root`` and initialized with it as the
    workspace (or ``root_uri``)."""
    c = LspClient(spawn("lsp", *args, cwd=root))
    caps = c.result("initialize", {"processId": None,
                                   "rootUri": root.as_uri() if root_uri == "same" else root_uri,
                                   "capabilities": {}})["capabilities"]
    c.notify("initialized", {})
    c.caps = caps
    return c


def open_doc(c: LspClient, path: Path, text: str = None, version: int = 1,
             language: str = "plc") -> str:
    text = path.read_text() if text is None else text
    c.notify("textDocument/didOpen", {"textDocument": {
        "uri": path.as_uri(), "languageId": language, "version": version, "text": text}})
    return path.as_uri()


def stop_server(c: LspClient) -> int:
    """shutdown, exit; the server's exit status."""
    try:
        c.result("shutdown")
        c.notify("exit")
    finally:
        c.close()
    return c.proc.returncode


def at(uri: str, line: int, character: int) -> dict:
    return {"textDocument": {"uri": uri}, "position": {"line": line, "character": character}}
