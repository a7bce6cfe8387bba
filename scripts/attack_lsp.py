"""Attacks on the language server (issue 24, items 3, 4 and 10), against the
real ``python -m plcbuilder lsp`` in a child process, over stdio and TCP.

    ATTACKS: list[tuple[str, callable]]   name, attack() -> {"tried", "refused",
                                          "accepted", "crashed"}

- 24.3 heavy documents: a 10 MB document, hostile sources just under the
  1 MiB limit, a burst of changes to a large one. Refused: a document over the
  limit gets the one file-too-large diagnostic (nothing compiled) and a hover
  on another file is answered within 100 ms (median) while a check runs;
  accepted: it was compiled, or the hover waited.
- 24.4 reads outside the workspace: documentSymbol, hover, definition,
  references, semantic tokens, completion, inlay hints on files outside the
  workspace (plain, ``..``, a link out, percent-encoded, a header beside an
  opened document, a workspace folder outside ``--root``); over TCP a
  non-loopback ``--host`` and 40 connections that never initialize. Refused:
  no byte of a secret file in any message, the host refused, the idle
  connections closed and a real client served meanwhile.
- 24.10 protocol details: invalid ids, messages that are not requests,
  requests after shutdown, two or short Content-Length headers, bad params.
  Refused: the error JSON-RPC/LSP gives (-32600/-32602/-32700), the next
  message answered, no traceback in the log; accepted: another answer.

A crash is the server dying, not answering within the timeout, or a traceback
sent to the client.

    .venv/bin/python scripts/attack_lsp.py [-v]
"""

from __future__ import annotations

import json
import os
import re
import socket
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Callable

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "scripts"))

from tests.lsp._client import (LspClient, at, frame, make_project, open_doc,  # noqa: E402
                               spawn)

MARK = "0x5EC2E7"
SECRET = f"#define SECRET {MARK}\nmain() {{ x = 12345; exit(x); }}\n"
VERBOSE = False


class Tally:
    def __init__(self):
        self.counts = {"tried": 0, "refused": 0, "accepted": 0, "crashed": 0}

    def case(self, name: str, *, refused: bool, crashed: bool = False) -> None:
        self.counts["tried"] += 1
        key = "crashed" if crashed else "refused" if refused else "accepted"
        self.counts[key] += 1
        if VERBOSE or key != "refused":
            print(f"    {key:8} {name}", file=sys.stderr)


def _session(root: Path, *args: str, root_uri: str = "same"):
    c = LspClient(spawn("lsp", *args, cwd=root))
    c.check = None                     # hostile answers are judged here, not asserted
    c.request("initialize", {"processId": None, "capabilities": {},
                             "rootUri": root.as_uri() if root_uri == "same" else root_uri}, 60)
    c.notify("initialized", {})
    return c


def _end(c: LspClient) -> bool:
    """Ends the session; False when the server had died."""
    alive = c.proc.poll() is None
    try:
        c.request("shutdown", None, 20)
        c.notify("exit")
    except (TimeoutError, OSError):
        alive = False
    c.close()
    return alive


def _traceback_sent(c: LspClient) -> bool:
    return any("Traceback" in json.dumps(m) or "traceback" in json.dumps(m) for m in c.arrived)


# ---------------------------------------------------------------- 24.3
def attack_heavy_documents() -> dict:
    from bench_compile import procedure
    t = Tally()
    with tempfile.TemporaryDirectory() as d:
        root = make_project(Path(d) / "proj")
        c = _session(root)
        small = open_doc(c, root / "hardware" / "M03.plc")
        c.diagnostics(small, 60)
        c.request("textDocument/hover", at(small, 3, 18), 60)
        body = procedure(3000, 3000)
        sources = {                     # over the limit first: their answers are not queued
            "10 MB ordinary": "main() {\n" + "  x = x + 1;\n" * 800_000 + "};\n",
            "10 MB one line": "x" * 10_000_000,
            "1 MB ordinary": "#include pins.h\n" + body * (1_000_000 // len(body)),
            "deep braces": "main(){" + "{" * 200_000 + "}" * 200_000 + "};\n",
            "deep parens": "main(){ x=" + "(" * 100_000 + ";};\n",
            "many errors": "main(){\n" + "x = ;\n" * 150_000 + "};\n",
            "one long name": "main(){ " + "a" * 1_000_000 + " = 1; };\n",
        }
        for i, (what, text) in enumerate(sources.items()):
            uri = open_doc(c, root / "software" / f"H{i}.plc", text)
            over = len(text.encode()) > 1 << 20
            time.sleep(0.2)
            times = []
            try:
                for _ in range(5):
                    t0 = time.perf_counter()
                    c.request("textDocument/hover", at(small, 3, 18), 60)
                    times.append(time.perf_counter() - t0)
                # over the limit: its one diagnostic at once (a hostile source within
                # it may take the compiler long: only the answers meanwhile count here)
                ds = c.diagnostics(uri, 30) if over else None
            except TimeoutError:
                t.case(what, refused=False, crashed=True)
                continue
            compiled_anyway = over and [d["code"] for d in ds] != ["file-too-large"]
            slow = statistics.median(times) >= 0.1
            t.case(f"{what}: hover {statistics.median(times) * 1000:.0f} ms while it checks",
                   refused=not compiled_anyway and not slow, crashed=c.proc.poll() is not None)
            c.notify("textDocument/didClose", {"textDocument": {"uri": uri}})
        # a burst of changes to a large document, in a fresh session (the one
        # above may still be compiling a hostile source): one check of the last text
        _end(c)
        c = _session(root)
        uri = open_doc(c, root / "software" / "BURST.plc", sources["1 MB ordinary"])
        c.diagnostics(uri, 600)
        for v in range(2, 40):
            c.notify("textDocument/didChange", {"textDocument": {"uri": uri, "version": v},
                                                "contentChanges": [{"range": {
                                                    "start": {"line": 5, "character": 0},
                                                    "end": {"line": 5, "character": 0}},
                                                    "text": "x"}]})
        try:
            c.wait(lambda m: m.get("method") == "textDocument/publishDiagnostics"
                   and m["params"]["uri"] == uri and m["params"]["version"] == 39, 600)
            versions = [m["params"]["version"] for m in c.arrived
                        if m.get("method") == "textDocument/publishDiagnostics"
                        and m["params"]["uri"] == uri]
            t.case(f"38 changes in a burst: {len(versions) - 1} checks published",
                   refused=len(versions) <= 4 and versions == sorted(versions))
        except TimeoutError:
            t.case("38 changes in a burst", refused=False, crashed=True)
        t.case("the session ends cleanly", refused=_end(c) and not _traceback_sent(c),
               crashed=c.proc.returncode not in (0,))
    return t.counts


# ---------------------------------------------------------------- 24.4
def attack_outside_reads() -> dict:
    t = Tally()
    with tempfile.TemporaryDirectory() as d:
        base = Path(d)
        root = make_project(base / "proj")
        for name in ("secret.txt", "secret.plc", "secret.h"):
            (base / name).write_text(SECRET)
        (root / "hardware" / "link.plc").symlink_to(base / "secret.plc")
        (root / "include" / "link.h").symlink_to(base / "secret.h")
        uris = [(base / n).as_uri() for n in ("secret.txt", "secret.plc", "secret.h")]
        uris += [root.as_uri() + "/../secret.plc", root.as_uri() + "/hardware/%2E%2E/%2E%2E/secret.plc",
                 (root / "hardware" / "link.plc").as_uri(), (root / "include" / "link.h").as_uri(),
                 "file://localhost" + str(base / "secret.plc"), "file:" + str(base / "secret.plc"),
                 root.as_uri() + "/hardware/a%00b.plc", "file:///" + "a/" * 3000 + "x.plc",
                 "file:///proc/self/environ", "file:///dev/zero"]
        c = _session(root)
        asks = [("textDocument/documentSymbol", lambda u: {"textDocument": {"uri": u}}),
                ("textDocument/semanticTokens/full", lambda u: {"textDocument": {"uri": u}}),
                ("textDocument/hover", lambda u: at(u, 0, 17)),
                ("textDocument/hover", lambda u: at(u, 1, 12)),
                ("textDocument/definition", lambda u: at(u, 0, 10)),
                ("textDocument/references", lambda u: dict(at(u, 0, 10),
                                                           context={"includeDeclaration": True})),
                ("textDocument/completion", lambda u: at(u, 1, 11)),
                ("textDocument/inlayHint", lambda u: {"textDocument": {"uri": u}, "range": {
                    "start": {"line": 0, "character": 0}, "end": {"line": 3, "character": 0}}})]
        for u in uris:
            for method, params in asks:
                try:
                    r = c.request(method, params(u), 30)
                except TimeoutError:
                    t.case(f"{method} {u}", refused=False, crashed=True)
                    continue
                leaked = MARK in json.dumps(r) or "12345" in json.dumps(r) \
                    or "PYTHONPATH" in json.dumps(r)
                t.case(f"{method} {u[:80]}", refused=not leaked and "error" not in r,
                       crashed=r.get("error", {}).get("code") == -32603)
        # a document opened outside the workspace: the headers beside it stay unread
        other = base / "other"
        other.mkdir()
        (other / "secret.h").write_text(SECRET)
        uri = open_doc(c, other / "M09.plc", "#include secret.h\nmain() { y = SECRET; exit(y); }\n")
        c.diagnostics(uri, 60)
        h = c.request("textDocument/hover", at(uri, 1, 15), 30)
        t.case("an opened document's header beside it", refused=MARK not in json.dumps(h))
        time.sleep(0.5)
        leaked = any(MARK in json.dumps(m) or "12345" in json.dumps(m) for m in c.arrived)
        t.case("no message carries the secret", refused=not leaked)
        t.case("stdio session ends", refused=_end(c), crashed=c.proc.returncode != 0)

        # over TCP: a workspace outside --root, a remote host, idle connections
        env = dict(os.environ, PYTHONPATH=str(ROOT))
        for host in ("0.0.0.0", "::", ""):
            p = subprocess.run([sys.executable, "-m", "plcbuilder", "lsp", "--tcp", "0", "--host",
                                host], cwd=root, env=env, capture_output=True, text=True, timeout=60)
            t.case(f"--host {host!r} without --allow-remote", refused=p.returncode == 2)
        proc = spawn("lsp", "--tcp", "0", "--root", str(root), cwd=root)
        try:
            port = int(re.search(r":(\d+)$", proc.stderr.readline().decode().strip()).group(1))
            idle = [socket.create_connection(("127.0.0.1", port), timeout=30) for _ in range(40)]
            t0 = time.monotonic()
            s = socket.create_connection(("127.0.0.1", port), timeout=30)
            s.sendall(frame(json.dumps({"jsonrpc": "2.0", "id": 1, "method": "initialize",
                                        "params": {"processId": None, "capabilities": {},
                                                   "rootUri": base.as_uri()}}).encode()))
            s.sendall(frame(json.dumps({"jsonrpc": "2.0", "method": "initialized",
                                        "params": {}}).encode()))
            s.sendall(frame(json.dumps({"jsonrpc": "2.0", "id": 2,
                                        "method": "textDocument/documentSymbol",
                                        "params": {"textDocument": {"uri": uris[1]}}}).encode()))
            data = b""
            s.settimeout(30)
            try:
                while b'"id": 2' not in data and b'"id":2' not in data:
                    chunk = s.recv(65536)
                    if not chunk:
                        break
                    data += chunk
            except OSError:
                pass
            served = b'"id": 2' in data or b'"id":2' in data
            t.case(f"a client with 40 idle connections open: served in "
                   f"{time.monotonic() - t0:.1f} s", refused=served, crashed=not data)
            t.case("a workspace folder outside --root", refused=served and MARK.encode() not in data)
            closed = 0
            for sock in idle:
                sock.settimeout(15)
                try:
                    closed += sock.recv(10) == b""
                except OSError:
                    closed += 1
                sock.close()
            t.case(f"idle connections closed: {closed}/40 within "
                   f"{time.monotonic() - t0:.0f} s", refused=closed == 40)
            t.case("the TCP server still runs", refused=proc.poll() is None,
                   crashed=proc.poll() is not None)
            s.close()
        finally:
            proc.kill()
            proc.wait(5)
    return t.counts


# ---------------------------------------------------------------- 24.10
def attack_protocol() -> dict:
    t = Tally()
    with tempfile.TemporaryDirectory() as d:
        root = make_project(Path(d) / "proj")
        log = Path(d) / "lsp.log"
        c = _session(root, "--log", str(log))
        uri = open_doc(c, root / "hardware" / "M03.plc")
        c.diagnostics(uri, 60)

        def error_of(raw: bytes):
            c.send_raw(frame(raw))
            probe = c.next_id() + 10_000
            c.send({"jsonrpc": "2.0", "id": probe, "method": "plc/probe"})
            out = []
            while True:
                m = c.wait(lambda m: "method" not in m, 30)
                if m.get("id") == probe:
                    return out
                out.append(m)

        for mid in ("true", "false", "{}", "[]", "1e400", "-1e400", "1.5", "null", '{"a":1}'):
            try:
                got = error_of(b'{"jsonrpc":"2.0","id":%s,"method":"textDocument/hover",'
                               b'"params":{}}' % mid.encode())
            except TimeoutError:
                t.case(f"id {mid}", refused=False, crashed=True)
                continue
            t.case(f"id {mid}", refused=[(m.get("id"), m.get("error", {}).get("code"))
                                         for m in got] == [(None, -32600)])
        for raw, want in ((b'{"jsonrpc":"2.0","id":4}', (4, -32600)),
                          (b'{"jsonrpc":"2.0","id":5,"result":1,"method":"x"}', (5, -32600)),
                          (b'{"jsonrpc":"2.0","id":10,"method":"x","extra":1}', (10, -32601)),
                          (b'{"jsonrpc":"2.0","id":6,"method":"x","params":"p"}', (6, -32600)),
                          (b'{"jsonrpc":"2.0","id":7,"method":"x","params":{"a":NaN}}', (None, -32700)),
                          (b'{"jsonrpc":"1.0","id":8,"method":"x"}', (8, -32600)),
                          (b'[{"jsonrpc":"2.0","id":9,"method":"x"}]', (None, -32600))):
            try:
                got = error_of(raw)
            except TimeoutError:
                t.case(raw.decode(), refused=False, crashed=True)
                continue
            t.case(raw.decode(), refused=[(m.get("id"), m.get("error", {}).get("code"))
                                          for m in got] == [want])
        # frames
        body = json.dumps({"jsonrpc": "2.0", "id": 70, "method": "plc/x"}).encode()
        nxt = frame(json.dumps({"jsonrpc": "2.0", "id": 71, "method": "plc/y"}).encode())
        for what, data in (
                ("two Content-Length headers", b"Content-Length: %d\r\nContent-Length: %d\r\n\r\n"
                 % (len(body), len(body) + 25) + body + nxt),
                ("a short Content-Length", b"Content-Length: %d\r\n\r\n" % (len(body) - 7) + body + nxt),
                ("a Content-Length of 0", b"Content-Length: 0\r\n\r\n" + nxt),
                ("a header without a value", b"Content-Length:\r\n\r\n" + body + nxt)):
            c.send_raw(data)
            try:
                m = c.wait(lambda m: m.get("id") == 71, 30)
                t.case(f"{what}: the next message answered", refused=m["error"]["code"] == -32601)
            except TimeoutError:
                t.case(f"{what}: the next message lost", refused=False)
        # bad params: answered -32602, a line in the log each
        bad = ['{"textDocument": {"uri": "%s"}, "position": "here"}' % uri, '{}',
               '{"textDocument": 5}',
               '{"textDocument": {"uri": "%s"}, "position": {"line": -1, "character": 0}}' % uri,
               '{"textDocument": {"uri": "%s"}, "position": {"line": 1e400, "character": 0}}' % uri]
        for i in range(150):
            mid = 20_000 + i
            c.send_raw(frame(b'{"jsonrpc": "2.0", "id": %d, "method": "textDocument/hover", '
                             b'"params": %s}' % (mid, bad[i % len(bad)].encode())))
            try:
                r = c.wait(lambda m: m.get("id") == mid, 30)
            except TimeoutError:
                t.case(f"bad params {bad[i % len(bad)]}", refused=False, crashed=True)
                continue
            t.case(f"bad params {bad[i % len(bad)]}",
                   refused=r.get("error", {}).get("code") == -32602)
        r = c.request("textDocument/rename", dict(at(uri, 4, 4), newName="x"), 30)
        t.case("rename a built-in", refused=r.get("error", {}).get("code") == -32803
               and "data" not in r["error"])
        c.request("shutdown", None, 30)
        for method in ("textDocument/hover", "shutdown", "initialize"):
            try:
                r = c.request(method, at(uri, 4, 4) if "hover" in method else None, 30)
                t.case(f"{method} after shutdown", refused=r.get("error", {}).get("code") == -32600)
            except TimeoutError:
                t.case(f"{method} after shutdown: no answer", refused=False)
        c.notify("exit")
        try:
            rc = c.proc.wait(30)
        except subprocess.TimeoutExpired:
            rc = None
        c.close()
        t.case("exit after shutdown: status 0", refused=rc == 0, crashed=rc is None)
        text = log.read_text() if log.exists() else ""
        t.case(f"tracebacks in the log: {text.count('Traceback')}",
               refused="Traceback" not in text)
        t.case("tracebacks sent to the client", refused=not _traceback_sent(c))
    return t.counts


ATTACKS: list[tuple[str, Callable[[], dict]]] = [
    ("24.3 lsp heavy documents", attack_heavy_documents),
    ("24.4 lsp reads outside the workspace", attack_outside_reads),
    ("24.10 lsp protocol details", attack_protocol),
]


def main(argv: list[str]) -> int:
    global VERBOSE
    VERBOSE = "-v" in argv or "--verbose" in argv
    bad = False
    for name, fn in ATTACKS:
        t0 = time.monotonic()
        r = fn()
        print(f"{name:40} tried {r['tried']:4} refused {r['refused']:4} accepted "
              f"{r['accepted']:3} crashed {r['crashed']:3}  ({time.monotonic() - t0:.0f} s)")
        bad |= bool(r["accepted"] or r["crashed"])
    return 1 if bad else 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
