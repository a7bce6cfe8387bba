"""JSON-RPC 2.0 and LSP's rules for what a client sends (issue 24.10, 25.10,
25.12): invalid ids, messages that are not requests, requests around
initialize and shutdown, frames with odd headers, and what the log gets.
Every message the server sends is checked against lsprotocol's structures
(tests/lsp/_client.py: conform)."""

from __future__ import annotations

import json

import pytest

from tests.lsp._client import (LspClient, at, frame, make_project, open_doc, spawn, start_server,
                               stop_server)


@pytest.fixture
def project(tmp_path):
    return make_project(tmp_path / "proj")


def _error(c: LspClient, raw: bytes, timeout: float = 20) -> dict:
    """Send one framed body; the error response it gets."""
    c.send_raw(frame(raw))
    return c.wait(lambda m: "error" in m or ("result" in m and "method" not in m), timeout)


@pytest.mark.parametrize("mid", [b"true", b"false", b"{}", b"[]", b"1e400", b"1.5", b"null",
                                 b"-1e400"])
def test_an_invalid_request_id_is_an_invalid_request(project, mid):
    c = start_server(project)
    try:
        for method in (b"textDocument/hover", b"shutdown"):
            m = _error(c, b'{"jsonrpc":"2.0","id":%s,"method":"%s","params":{}}' % (mid, method))
            assert m["error"]["code"] == -32600, m
            assert m["id"] is None and "id" in m["error"]["message"]
        # not shut down by the "shutdown" with a bad id: it still answers
        assert c.result("textDocument/hover", at(project.joinpath("x.plc").as_uri(), 0, 0)) is None
    finally:
        assert stop_server(c) == 0


def test_a_message_that_is_not_a_request_is_an_invalid_request(project):
    c = start_server(project)
    try:
        m = _error(c, b'{"jsonrpc":"2.0","id":4}')
        assert m == {"jsonrpc": "2.0", "id": 4, "error": m["error"]}
        assert m["error"]["code"] == -32600 and "Internal" not in m["error"]["message"]
        m = _error(c, b'{"jsonrpc":"2.0","id":"x","method":"textDocument/hover","params":7}')
        assert m["id"] == "x" and m["error"]["code"] == -32600
        m = _error(c, b'{"jsonrpc":"2.0","id":5,"method":12}')
        assert m["id"] == 5 and m["error"]["code"] == -32600
        m = _error(c, b'{"jsonrpc":"2.0","id":8,"method":"x","result":1}')
        assert m["id"] == 8 and m["error"]["code"] == -32600
        m = _error(c, b'{"jsonrpc":"2.0","id":9,"method":"plc/x","extra":1}')
        assert m["id"] == 9 and m["error"]["code"] == -32601
        m = _error(c, b'{"jsonrpc":"2.0","id":6,"method":"x","params":{"a":NaN}}')
        assert m["id"] is None and m["error"]["code"] == -32700
        # a response from the client to nothing the server asked: no answer
        c.send_raw(frame(b'{"jsonrpc":"2.0","id":999,"result":null}'))
        m = _error(c, b'{"jsonrpc":"2.0","id":7}')
        assert m["id"] == 7
    finally:
        stop_server(c)


def test_requests_before_initialize_and_after_shutdown(project):
    c = LspClient(spawn("lsp", cwd=project))
    try:
        r = c.request("textDocument/hover", at(project.as_uri() + "/x.plc", 0, 0))
        assert r["error"]["code"] == -32002
        c.result("initialize", {"processId": None, "rootUri": project.as_uri(), "capabilities": {}})
        r = c.request("initialize", {"processId": None, "rootUri": None, "capabilities": {}})
        assert r["error"]["code"] == -32600 and "already" in r["error"]["message"]
        c.notify("initialized", {})
        assert c.result("shutdown") is None
        for method, params in (("textDocument/hover", at(project.as_uri() + "/x.plc", 0, 0)),
                               ("shutdown", None), ("plc/unknown", {})):
            r = c.request(method, params, timeout=20)
            assert r["error"]["code"] == -32600, r
            assert "shutting down" in r["error"]["message"]
        c.notify("exit")
        assert c.proc.wait(20) == 0
    finally:
        c.close()


def test_exit_without_shutdown_ends_with_status_1(project):
    c = start_server(project)
    c.notify("exit")
    try:
        assert c.proc.wait(20) == 1
    finally:
        c.close()


def test_odd_content_length_headers_lose_no_other_message(project):
    c = start_server(project)
    try:
        ok = json.dumps({"jsonrpc": "2.0", "id": 50, "method": "shutdown"}).encode()
        body = json.dumps({"jsonrpc": "2.0", "id": 40, "method": "plc/x", "params": {}}).encode()
        # two Content-Length headers that differ: refused; the next message answered
        c.send_raw(b"Content-Length: %d\r\nContent-Length: %d\r\n\r\n" % (len(body), len(body) + 30)
                   + body + frame(json.dumps({"jsonrpc": "2.0", "id": 41, "method": "plc/y"}).encode()))
        m = c.wait(lambda m: m.get("id") is None and "Content-Length" in m["error"]["message"], 20)
        assert m["error"]["code"] == -32600
        assert c.wait(lambda m: m.get("id") == 41, 20)["error"]["code"] == -32601
        # the same header twice: one frame
        c.send_raw(b"Content-Length: %d\r\nContent-Length: %d\r\n\r\n" % (len(body), len(body)) + body)
        assert c.wait(lambda m: m.get("id") == 40, 20)["error"]["code"] == -32601
        # a Content-Length too short: that body is not JSON, and the next message is served
        short = json.dumps({"jsonrpc": "2.0", "id": 42, "method": "plc/z", "params": {"a": 1}}).encode()
        c.send_raw(b"Content-Length: %d\r\n\r\n" % (len(short) - 9) + short
                   + frame(json.dumps({"jsonrpc": "2.0", "id": 43, "method": "plc/w"}).encode()))
        assert c.wait(lambda m: m.get("error", {}).get("code") == -32700, 20)["id"] is None
        assert c.wait(lambda m: m.get("id") == 43, 20)["error"]["code"] == -32601
        c.send_raw(frame(ok))
        assert c.wait(lambda m: m.get("id") == 50, 20)["result"] is None
        c.notify("exit")
        assert c.proc.wait(20) == 0
    finally:
        c.close()


def test_a_refusal_is_one_log_line_not_a_traceback(project, tmp_path):
    """Bad params (-32602), unknown methods, a refused rename: each one line in
    the log, no traceback; the rename's error is RequestFailed with the plain
    sentence and no data."""
    log = tmp_path / "lsp.log"
    c = start_server(project, "--log", str(log))
    try:
        uri = open_doc(c, project / "hardware" / "M03.plc")
        c.diagnostics(uri)
        n = 30
        for i in range(n):
            r = c.request("textDocument/hover", {"textDocument": {"uri": uri}, "position": "here"})
            assert r["error"]["code"] == -32602 and "position" in r["error"]["message"]
        for i in range(n):
            assert c.request("plc/nothing", {})["error"]["code"] == -32601
        r = c.request("textDocument/rename", dict(at(uri, 4, 4), newName="x"))      # portset
        assert r["error"] == {"code": -32803, "message": "portset is built in (a keyword, function, "
                              "predefined variable or table name) and cannot be renamed"}
        r = c.request("textDocument/rename", dict(at(uri, 5, 3), newName="2x"))
        assert r["error"]["code"] == -32803 and "data" not in r["error"]
        assert "Error" not in r["error"]["message"]
    finally:
        stop_server(c)
    text = log.read_text()
    assert "Traceback" not in text
    assert text.count("refused") >= n + 2, text[-2000:]
    assert len(text.splitlines()) < 4 * n + 40          # a line each, not a traceback each
