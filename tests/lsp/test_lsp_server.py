"""``plcbuilder lsp`` driven as an editor drives it: the server is a child
process and the test speaks JSON-RPC to it over stdin/stdout (or TCP)."""

import json
import re
import socket
import time
from pathlib import Path

import pytest

from plcbuilder import api
from plcbuilder.lang import hover as lang_hover

from tests.lsp._client import HEADER, M03, at, frame, make_project, open_doc, spawn, start_server


@pytest.fixture
def project(tmp_path):
    return make_project(tmp_path / "proj")


@pytest.fixture
def client(project):
    c = start_server(project)
    yield c
    try:
        c.result("shutdown")
        c.notify("exit")
    finally:
        c.close()
    # "exit" after "shutdown": status 0 (it aborted now and then at interpreter
    # shutdown while its stdin reader held the buffered stdin's lock)
    assert c.proc.returncode == 0


def test_capabilities_name_every_feature(client):
    caps = client.caps
    for key in ("hoverProvider", "completionProvider", "signatureHelpProvider",
                "definitionProvider", "referencesProvider", "renameProvider",
                "documentSymbolProvider", "semanticTokensProvider", "inlayHintProvider"):
        assert caps.get(key), key
    assert caps["positionEncoding"] == "utf-16"


def test_diagnostics_are_the_checkers_own(client, project):
    """Diagnostics on open, on change and on save, with the compiler's codes,
    messages and hints, at the compiler's spans."""
    path = project / "hardware" / "M03.plc"
    uri = open_doc(client, path)
    got = client.diagnostics(uri)
    want = api.compile_file(path, api.Project.open(project).compile_options(path)).diagnostics
    assert [(d["code"], d["message"].split("\nhint: ")[0]) for d in got] == \
           [(d.code, d.message) for d in want]
    void = next(d for d in got if d["code"] == "void-value")
    assert "did you mean gvarget(6060)?" in void["message"]
    assert "hint: value = gvarget(addr)" in void["message"]
    assert void["severity"] == 1
    assert void["range"]["start"] == {"line": 3, "character": 9}
    # a change: the error goes once the text is fixed (no save needed)
    fixed = M03.replace("gvarset(6060)", "gvarget(6060)")
    client.notify("textDocument/didChange", {
        "textDocument": {"uri": uri, "version": 2},
        "contentChanges": [{"range": {"start": {"line": 3, "character": 9},
                                      "end": {"line": 3, "character": 22}},
                            "text": "gvarget(6060)"}]})
    got = client.diagnostics(uri, pred=lambda ds: not any(d["code"] == "void-value" for d in ds))
    assert all(d["severity"] != 1 for d in got)
    # a save with the text: checked at once
    client.notify("textDocument/didSave", {"textDocument": {"uri": uri},
                                           "text": fixed + "main2() { x = ; }\n"})
    got = client.diagnostics(uri, pred=lambda ds: any(d["severity"] == 1 for d in ds))
    assert any(d["range"]["start"]["line"] == 9 for d in got)


def test_header_diagnostics_and_unsaved_headers(client, project):
    """An included header's problems are published on the header, and the
    header's unsaved text is what the procedures are checked against."""
    header = project / "include" / "my.h"
    huri = header.as_uri()
    bad = HEADER + "#define MY_PIN_B 8\nhelper() { q = 1 / 0 + ; }\n"
    open_doc(client, header, bad)
    got = client.diagnostics(huri, pred=lambda ds: len(ds) > 0)
    codes = {d["code"] for d in got}
    assert "define-substring" in codes or any("MY_PIN_B" in d["message"] for d in got)
    assert any(d["severity"] == 1 and d["range"]["start"]["line"] == 3 for d in got)
    # the procedure sees the header's unsaved text too: MY_PIN removed -> a variable
    uri = open_doc(client, project / "hardware" / "M04.plc")
    assert client.diagnostics(uri) == []
    client.notify("textDocument/didChange", {
        "textDocument": {"uri": huri, "version": 2},
        "contentChanges": [{"text": "#define OTHER 1\n"}]})
    got = client.diagnostics(uri, pred=lambda ds: len(ds) > 0)
    assert [(d["code"], d["range"]["start"]["line"]) for d in got] == [("never-assigned", 1)]
    assert "'MY_PIN' is read but never assigned" in got[0]["message"]
    # and the header lost the problems of the text it no longer has
    assert client.diagnostics(huri, pred=lambda ds: ds == []) == []


def test_project_settings_are_read(tmp_path):
    """strict = true in the nearest plcbuilder.toml checks as the controller
    does; an unreadable settings file is reported on that file."""
    root = make_project(tmp_path / "p", 'name = "t"\n[build]\nstrict = true\n')
    path = root / "hardware" / "M05.plc"
    path.write_text("main() { if (eparam) a = 1; else a = 2; exit(a); }\n")
    c = start_server(root)
    try:
        uri = open_doc(c, path)
        got = c.diagnostics(uri)
        assert any(d["code"] == "strict" and "'else'" in d["message"] for d in got)
        (root / "plcbuilder.toml").write_text('name = "t"\nbogus = 1\n')
        c.notify("textDocument/didSave", {"textDocument": {"uri": uri}})
        toml = c.diagnostics((root / "plcbuilder.toml").as_uri())
        assert toml[0]["code"] == "project-settings" and "bogus" in toml[0]["message"]
        assert toml[0]["range"]["start"]["line"] == 1
    finally:
        c.close()


def test_hover_gives_the_ides_text(client, project):
    uri = open_doc(client, project / "hardware" / "M03.plc")
    h = client.result("textDocument/hover", at(uri, 3, 18))        # 6060
    assert h["contents"]["value"] == lang_hover.hover_text("6060", "  code = gvarset(")
    assert "GVAR_CURRENT_MOTION_CODE" in h["contents"]["value"]
    h = client.result("textDocument/hover", at(uri, 4, 12))        # MY_PIN
    assert h["contents"]["value"].startswith("#define MY_PIN 7")
    assert "my.h:1" in h["contents"]["value"]
    h = client.result("textDocument/hover", at(uri, 4, 4))         # portset
    assert h["contents"]["value"].startswith("portset(pin) — built-in function")
    assert client.result("textDocument/hover", at(uri, 2, 0)) is None   # "{"


def test_completion_and_signatures(client, project):
    uri = open_doc(client, project / "hardware" / "M03.plc", M03.replace("  exit(99);", "  gv\n  exit(99);"))
    items = client.result("textDocument/completion", at(uri, 7, 4))["items"]
    by = {i["label"]: i for i in items}
    assert {"gvarget", "gvarset"} <= set(by)
    assert by["gvarset"]["detail"] == "gvarset(addr, value)"
    assert "returns nothing" in by["gvarset"]["documentation"]["value"]
    items = client.result("textDocument/completion", at(uri, 4, 13))["items"]
    assert "MY_PIN" in {i["label"] for i in items}
    sig = client.result("textDocument/signatureHelp", at(uri, 6, 18))   # gvarset(MY_REG, |
    assert sig["signatures"][0]["label"] == "gvarset(addr, value)"
    assert sig["activeParameter"] == 1


def test_definition_references_and_rename(client, project):
    uri = open_doc(client, project / "hardware" / "M03.plc")
    loc = client.result("textDocument/definition", at(uri, 4, 12))
    assert loc["uri"] == (project / "include" / "my.h").as_uri()
    assert loc["range"]["start"] == {"line": 0, "character": 8}
    loc = client.result("textDocument/definition", at(uri, 6, 22))    # speed
    assert loc["uri"] == uri and loc["range"]["start"]["line"] == 5
    refs = client.result("textDocument/references",
                         dict(at(uri, 4, 12), context={"includeDeclaration": True}))
    files = sorted({Path(r["uri"][7:]).name for r in refs})
    assert files == ["M03.plc", "M04.plc", "my.h"]
    edit = client.result("textDocument/rename", dict(at(uri, 4, 12), newName="LAMP"))
    changes = edit["changes"]
    assert len(changes[(project / "include" / "my.h").as_uri()]) == 1
    assert len(changes[(project / "hardware" / "M04.plc").as_uri()]) == 1
    # a variable is the file's own
    edit = client.result("textDocument/rename", dict(at(uri, 5, 3), newName="feed"))
    assert list(edit["changes"]) == [uri] and len(edit["changes"][uri]) == 2
    # built-in names cannot be renamed, and a new name must be a name
    assert client.result("textDocument/prepareRename", at(uri, 4, 4)) is None
    err = client.request("textDocument/rename", dict(at(uri, 4, 4), newName="x"))
    assert "built in" in err["error"]["message"]
    err = client.request("textDocument/rename", dict(at(uri, 5, 3), newName="2x"))
    assert "not a name" in err["error"]["message"]


def test_symbols_tokens_and_inlay_hints(client, project):
    uri = open_doc(client, project / "hardware" / "M03.plc")
    syms = client.result("textDocument/documentSymbol", {"textDocument": {"uri": uri}})
    assert [(s["name"], s["kind"]) for s in syms] == [("main", 12), ("code", 13), ("speed", 13)]
    legend = client.caps["semanticTokensProvider"]["legend"]["tokenTypes"]
    data = client.result("textDocument/semanticTokens/full", {"textDocument": {"uri": uri}})["data"]
    lines = M03.split("\n")
    toks, line, col = [], 0, 0
    for i in range(0, len(data), 5):
        dl, dc, n, t, _m = data[i:i + 5]
        line, col = line + dl, (col + dc if dl == 0 else dc)
        toks.append((lines[line][col:col + n], legend[t]))
    assert ("#include", "macro") in toks and ("my.h", "string") in toks
    assert ("main", "function") in toks and ("gvarset", "function") in toks
    assert ("MY_PIN", "macro") in toks and ("code", "variable") in toks
    assert ("6060", "number") in toks and ("0x17ac", "number") in toks
    hints = client.result("textDocument/inlayHint", {
        "textDocument": {"uri": uri},
        "range": {"start": {"line": 0, "character": 0}, "end": {"line": 9, "character": 0}}})
    assert [(h["position"], h["label"]) for h in hints] == [
        ({"line": 3, "character": 21}, "GVAR_CURRENT_MOTION_CODE"),
        ({"line": 5, "character": 24}, "GVAR_CURRENT_MOTION_CODE")]


def test_utf16_columns(client, project):
    """A character outside the BMP counts two UTF-16 units, as the client counts."""
    path = project / "hardware" / "M06.plc"
    text = "main() { /* 😀 */ x = 1; exit(99); }\n"
    uri = open_doc(client, path, text)
    got = client.diagnostics(uri)
    never = next(d for d in got if d["code"] == "never-read")
    assert never["range"]["start"]["character"] == text.index("x") + 1
    h = client.result("textDocument/hover", at(uri, 0, text.index("x") + 1))
    assert "variable of this file" in h["contents"]["value"]


def test_bad_input_gets_errors_and_the_server_keeps_serving(client, project):
    uri = open_doc(client, project / "hardware" / "M03.plc")
    client.diagnostics(uri)
    client.send_raw(frame(b"{not json"))
    assert client.wait(lambda m: m.get("error", {}).get("code") == -32700)["id"] is None
    client.send_raw(frame(b"[1, 2]"))
    assert client.wait(lambda m: m.get("error", {}).get("code") == -32600)
    client.send_raw(frame(b"\xff\xfe\x00"))
    assert client.wait(lambda m: m.get("error", {}).get("code") == -32700)
    client.send_raw(b"X-Nonsense: 1\r\n\r\n")
    m = client.wait(lambda m: "Content-Length" in m.get("error", {}).get("message", ""))
    assert m["error"]["code"] == -32600
    client.send_raw(b"Content-Length: abc\r\n\r\n")
    client.wait(lambda m: "not a number" in m.get("error", {}).get("message", ""))
    huge = 17 << 20                     # over the 16 MiB limit: skipped unread
    client.send_raw(b"Content-Length: %d\r\n\r\n" % huge + b" " * huge)
    m = client.wait(lambda m: "over the limit" in m.get("error", {}).get("message", ""))
    assert m["id"] is None
    r = client.request("plc/noSuchMethod", {})
    assert r["error"]["code"] == -32601
    r = client.request("textDocument/hover", {"textDocument": {"uri": uri}, "position": "here"})
    assert r["error"]["code"] == -32602
    client.send({"jsonrpc": "1.0", "id": 99, "method": "x"})
    assert client.wait(lambda m: m.get("id") == 99)["error"]["code"] == -32600
    # and it still answers
    h = client.result("textDocument/hover", at(uri, 3, 18))
    assert "GVAR_CURRENT_MOTION_CODE" in h["contents"]["value"]
    assert client.proc.poll() is None


def test_tcp(project):
    proc = spawn("lsp", "--tcp", "0", cwd=project)
    try:
        line = proc.stderr.readline().decode()
        port = int(re.search(r":(\d+)$", line.strip()).group(1))
        assert "127.0.0.1" in line
        s = socket.create_connection(("127.0.0.1", port), timeout=10)
        body = json.dumps({"jsonrpc": "2.0", "id": 1, "method": "initialize",
                           "params": {"processId": None, "rootUri": None, "capabilities": {}}})
        s.sendall(frame(body.encode()))
        data = b""
        deadline = time.monotonic() + 20
        while b"capabilities" not in data or not data.endswith(b"}"):
            assert time.monotonic() < deadline
            data += s.recv(65536)
        assert b'"hoverProvider": true' in data or b'"hoverProvider":true' in data
        s.close()
    finally:
        proc.kill()
        proc.wait(5)
