"""``plcbuilder lsp`` with a real typed client: pygls's LanguageClient (which
reads every message into lsprotocol's structures) starts the server as an
editor does and uses what this round changed: incremental changes,
diagnostics of the latest version, completion snippets, a refused rename,
a document that is not PLC, a request after shutdown."""

from __future__ import annotations

import asyncio
import os
import sys
from pathlib import Path

import pytest
from lsprotocol import types as T
from pygls.exceptions import JsonRpcException
from pygls.lsp.client import LanguageClient

from tests.lsp._client import M03, make_project

ROOT = Path(__file__).resolve().parents[2]


def test_a_pygls_client_session(tmp_path):
    project = make_project(tmp_path / "proj")
    asyncio.run(asyncio.wait_for(_session(project), 120))


async def _session(project: Path) -> None:
    client = LanguageClient("plcbuilder-test", "1")
    diagnostics: dict[str, list] = {}
    arrived = asyncio.Event()

    @client.feature(T.TEXT_DOCUMENT_PUBLISH_DIAGNOSTICS)
    def published(params: T.PublishDiagnosticsParams):
        diagnostics.setdefault(params.uri, []).append((params.version, params.diagnostics))
        arrived.set()

    async def diagnostics_of(uri: str, version: int) -> list:
        while True:
            for v, ds in diagnostics.get(uri, ()):
                if v == version:
                    return ds
            arrived.clear()
            await arrived.wait()

    await client.start_io(sys.executable, "-m", "plcbuilder", "lsp", cwd=str(project),
                          env=dict(os.environ, PYTHONPATH=str(ROOT)))
    try:
        result = await client.initialize_async(T.InitializeParams(
            capabilities=T.ClientCapabilities(), root_uri=project.as_uri()))
        assert result.capabilities.text_document_sync.change == T.TextDocumentSyncKind.Incremental
        client.initialized(T.InitializedParams())
        uri = (project / "hardware" / "M03.plc").as_uri()
        client.text_document_did_open(T.DidOpenTextDocumentParams(
            T.TextDocumentItem(uri, "plc", 1, M03)))
        first = await diagnostics_of(uri, 1)
        assert any(d.code == "void-value" for d in first)
        # an incremental change fixes it
        client.text_document_did_change(T.DidChangeTextDocumentParams(
            T.VersionedTextDocumentIdentifier(uri=uri, version=2),
            [T.TextDocumentContentChangePartial(
                range=T.Range(T.Position(3, 9), T.Position(3, 16)), text="gvarget")]))
        second = await diagnostics_of(uri, 2)
        assert not any(d.code == "void-value" for d in second)
        # snippets with a named placeholder per argument
        items = await client.text_document_completion_async(T.CompletionParams(
            T.TextDocumentIdentifier(uri), T.Position(6, 4)))
        by = {i.label: i for i in (items.items if hasattr(items, "items") else items)}
        assert by["gvarset"].insert_text == "gvarset(${1:addr}, ${2:value})"
        assert by["gvarset"].insert_text_format == T.InsertTextFormat.Snippet
        # a built-in cannot be renamed: RequestFailed, the plain sentence
        with pytest.raises(JsonRpcException) as err:
            await client.text_document_rename_async(T.RenameParams(
                T.TextDocumentIdentifier(uri), T.Position(4, 4), "x"))
        assert err.value.code == T.LSPErrorCodes.RequestFailed
        assert err.value.message.startswith("portset is built in")
        assert err.value.data is None
        # a TOML document is not PLC: not checked, nothing to say about it
        toml = (project / "plcbuilder.toml").as_uri()
        client.text_document_did_open(T.DidOpenTextDocumentParams(
            T.TextDocumentItem(toml, "toml", 1, 'name = "t"\n')))
        hover = await client.text_document_hover_async(T.HoverParams(
            T.TextDocumentIdentifier(toml), T.Position(0, 1)))
        assert hover is None and toml not in diagnostics
        await client.shutdown_async(None)
        with pytest.raises(JsonRpcException) as err:
            await client.text_document_hover_async(T.HoverParams(
                T.TextDocumentIdentifier(uri), T.Position(4, 4)))
        assert err.value.code == -32600
        client.exit(None)
    finally:
        await client.stop()
