"""What the language server reads, and who may connect (issue 24.4): files
inside the workspace folders and their projects' include folders, documents
the client opened; over TCP, loopback unless --allow-remote, one session per
connection, a connection that never initializes closed after a few seconds."""

from __future__ import annotations

import json
import re
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

from tests.lsp._client import (at, conform, frame, make_project, open_doc, spawn, start_server,
                               stop_server)

SECRET = "#define SECRET 0x5EC2E7\nmain() { x = 12345; exit(x); }\n"


@pytest.fixture
def project(tmp_path):
    return make_project(tmp_path / "proj")


def test_files_outside_the_workspace_are_not_read(project, tmp_path):
    """documentSymbol, hover, definition, references, tokens, hints on files the
    client never opened, outside the workspace: nothing of their content."""
    for name in ("secret.txt", "secret.plc", "secret.h"):
        (tmp_path / name).write_text(SECRET)
    c = start_server(project)
    try:
        for name in ("secret.txt", "secret.plc", "secret.h"):
            uri = (tmp_path / name).as_uri()
            doc = {"textDocument": {"uri": uri}}
            assert c.result("textDocument/documentSymbol", doc) == []
            for line, col in ((0, 9), (0, 17), (1, 10)):
                assert c.result("textDocument/hover", at(uri, line, col)) is None
                assert c.result("textDocument/definition", at(uri, line, col)) is None
                assert c.result("textDocument/references",
                                dict(at(uri, line, col), context={"includeDeclaration": True})) == []
            assert c.result("textDocument/semanticTokens/full", doc) == {"data": []}
            assert c.result("textDocument/completion", at(uri, 1, 10))["items"] == []
        # names no file has: nothing, not an internal error
        for uri in (project.as_uri() + "/hardware/a%00b.plc", "file://%00/x.plc",
                    "file:///" + "a/" * 3000 + "x.plc", "untitled:Untitled-1"):
            assert c.result("textDocument/hover", at(uri, 0, 0)) is None
            assert c.result("textDocument/documentSymbol", {"textDocument": {"uri": uri}}) == []
        # a document the client opens outside the workspace is its own text only:
        # the headers beside it are not read
        outside = tmp_path / "other" / "M09.plc"
        outside.parent.mkdir()
        (outside.parent / "secret.h").write_text(SECRET)
        uri = open_doc(c, outside, "#include secret.h\nmain() { y = SECRET; exit(99); }\n")
        got = c.diagnostics(uri, pred=lambda ds: len(ds) > 0)
        assert any(d["code"] == "include-not-found" for d in got), got
        refused = c.diagnostics((outside.parent / "secret.h").as_uri())
        assert "outside the workspace folders" in refused[0]["message"], refused
        h = c.result("textDocument/hover", at(uri, 1, 15))
        assert h is None or "5EC2E7" not in h["contents"]["value"]
        assert not any("5EC2E7" in json.dumps(m) or "12345" in json.dumps(m) for m in c.arrived)
    finally:
        stop_server(c)


def test_the_projects_include_folders_are_read(tmp_path):
    """[build] include naming a folder outside the workspace: the project gives
    it, so its headers are read."""
    root = make_project(tmp_path / "proj", 'name = "t"\n[build]\ninclude = ["../shared"]\n')
    (tmp_path / "shared").mkdir()
    (tmp_path / "shared" / "shared.h").write_text("#define SHARED_PIN 9\n")
    path = root / "hardware" / "M07.plc"
    path.write_text("#include shared.h\nmain() { portset(SHARED_PIN); exit(99); }\n")
    c = start_server(root)
    try:
        uri = open_doc(c, path)
        assert c.diagnostics(uri) == []
        h = c.result("textDocument/hover", at(uri, 1, 20))
        assert h["contents"]["value"].startswith("#define SHARED_PIN 9")
        loc = c.result("textDocument/definition", at(uri, 1, 20))
        assert loc["uri"] == (tmp_path / "shared" / "shared.h").as_uri()
    finally:
        stop_server(c)


def test_a_remote_address_is_refused_without_allow_remote(project):
    r = subprocess.run([sys.executable, "-m", "plcbuilder", "lsp", "--tcp", "0", "--host", "0.0.0.0"],
                       cwd=project, capture_output=True, text=True, timeout=60, env=_env())
    assert r.returncode == 2
    assert "--allow-remote" in r.stderr and "0.0.0.0" in r.stderr
    proc = spawn("lsp", "--tcp", "0", "--host", "0.0.0.0", "--allow-remote", cwd=project)
    try:
        lines = [proc.stderr.readline().decode() for _ in range(2)]
        assert "warning" in lines[0] and "other machines" in lines[0], lines
        assert re.search(r"listening on 0\.0\.0\.0:\d+", lines[1]), lines
    finally:
        proc.kill()
        proc.wait(5)


def _env():
    import os
    return dict(os.environ, PYTHONPATH=str(Path(__file__).resolve().parents[2]))


class _Tcp:
    """A raw client over TCP: framed JSON out, framed JSON in."""

    def __init__(self, port: int):
        self.s = socket.create_connection(("127.0.0.1", port), timeout=30)
        self.buf = b""
        self.methods: dict = {}

    def send(self, obj) -> None:
        if "id" in obj:
            self.methods[obj["id"]] = obj["method"]
        self.s.sendall(frame(json.dumps(obj).encode()))

    def recv(self, timeout: float = 30) -> dict:
        self.s.settimeout(timeout)
        while True:
            m = re.match(rb"Content-Length: (\d+)\r\n(?:[^\r\n]+\r\n)*\r\n", self.buf)
            if m and len(self.buf) >= m.end() + int(m.group(1)):
                body = self.buf[m.end():m.end() + int(m.group(1))]
                self.buf = self.buf[m.end() + int(m.group(1)):]
                msg = json.loads(body)
                conform(msg, self.methods)
                return msg
            data = self.s.recv(65536)
            if not data:
                raise ConnectionError("closed")
            self.buf += data

    def answer(self, mid: int) -> dict:
        while True:
            m = self.recv()
            if m.get("id") == mid and "method" not in m:
                return m

    def initialize(self, root: Path) -> dict:
        self.send({"jsonrpc": "2.0", "id": 1, "method": "initialize",
                   "params": {"processId": None, "rootUri": root.as_uri(), "capabilities": {}}})
        r = self.answer(1)
        self.send({"jsonrpc": "2.0", "method": "initialized", "params": {}})
        return r


def _listen(project: Path, *args: str):
    proc = spawn("lsp", "--tcp", "0", *args, cwd=project)
    line = proc.stderr.readline().decode()
    port = int(re.search(r":(\d+)$", line.strip()).group(1))
    return proc, port


def test_an_idle_connection_blocks_no_one_and_is_closed(project):
    proc, port = _listen(project)
    try:
        idle = [socket.create_connection(("127.0.0.1", port), timeout=30) for _ in range(40)]
        t0 = time.monotonic()
        a = _Tcp(port)                       # more idle connections than sessions: served
        assert a.initialize(project)["result"]["capabilities"]["hoverProvider"]
        b = _Tcp(port)                       # a second editor at the same time
        b.initialize(project)
        # served while the idle connections are still open (the 32 sessions are
        # full: the oldest idle ones made room, the others wait for their 5 s)
        still_open = 0
        for sock in idle:
            sock.setblocking(False)
            try:
                still_open += sock.recv(10) != b""
            except BlockingIOError:
                still_open += 1
            sock.setblocking(True)
        assert still_open >= 40 - (40 + 2 - 32), still_open
        uri = (project / "hardware" / "M03.plc").as_uri()
        for c in (a, b):
            c.send({"jsonrpc": "2.0", "id": 2, "method": "textDocument/hover",
                    "params": at(uri, 3, 18)})
            assert "GVAR_CURRENT_MOTION_CODE" in c.answer(2)["result"]["contents"]["value"]
        for sock in idle:                    # each closed by the server
            sock.settimeout(20)
            assert sock.recv(10) == b""
            sock.close()
        waited = time.monotonic() - t0
        assert 3 < waited < 15, waited
        # one client's exit ends its session, not the server
        a.send({"jsonrpc": "2.0", "id": 3, "method": "shutdown"})
        a.answer(3)
        a.send({"jsonrpc": "2.0", "method": "exit"})
        b.send({"jsonrpc": "2.0", "id": 2, "method": "textDocument/hover", "params": at(uri, 3, 18)})
        assert b.answer(2)["result"] is not None
        assert proc.poll() is None
    finally:
        proc.kill()
        proc.wait(5)


def test_a_workspace_outside_the_served_folder_is_refused(project, tmp_path):
    (tmp_path / "secret.plc").write_text(SECRET)
    proc, port = _listen(project, "--root", str(project))
    try:
        c = _Tcp(port)
        c.send({"jsonrpc": "2.0", "id": 1, "method": "initialize",
                "params": {"processId": None, "rootUri": tmp_path.as_uri(), "capabilities": {}}})
        shown = []
        while True:
            m = c.recv()
            if m.get("method") == "window/showMessage":
                shown.append(m["params"]["message"])
            if m.get("id") == 1:
                break
        assert any(str(tmp_path) in s and "outside" in s for s in shown), shown
        c.send({"jsonrpc": "2.0", "method": "initialized", "params": {}})
        c.send({"jsonrpc": "2.0", "id": 2, "method": "textDocument/documentSymbol",
                "params": {"textDocument": {"uri": (tmp_path / "secret.plc").as_uri()}}})
        assert c.answer(2)["result"] == []
    finally:
        proc.kill()
        proc.wait(5)
