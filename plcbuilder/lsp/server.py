"""``plcbuilder lsp``: the PLC language over the Language Server Protocol.

A pygls server whose features are :mod:`plcbuilder.lsp.features` and whose
diagnostics come from :mod:`plcbuilder.lsp.analysis`; it reads its messages
through :mod:`plcbuilder.lsp.transport` (bounded frames, JSON-RPC errors for
what cannot be served). Diagnostics are sent when a document is opened and
saved, and a moment after the last change while typing.
"""

from __future__ import annotations

import asyncio
import logging
from typing import Optional

from lsprotocol import types as T
from pygls.lsp.server import LanguageServer

from plcbuilder import __version__
from plcbuilder.lsp import features as F
from plcbuilder.lsp.analysis import Analysis
from plcbuilder.lsp.positions import UTF16
from plcbuilder.lsp.transport import Transport

log = logging.getLogger(__name__)

#: Seconds after the last change before a document is checked again.
CHANGE_DELAY = 0.15


class PlcLanguageServer(LanguageServer):
    def __init__(self):
        super().__init__("plcbuilder", __version__, text_document_sync_kind=T.TextDocumentSyncKind.Incremental)
        self.analysis = Analysis()
        self._pending: dict[str, asyncio.TimerHandle] = {}

    # ------------------------------------------------------------ diagnostics
    def check_now(self, uri: str) -> None:
        self._pending.pop(uri, None)
        try:
            published = self.analysis.check(uri)
        except Exception:  # noqa: BLE001 - a checker bug must not end the session
            log.exception("checking %s failed", uri)
            return
        for target, diags in published.items():
            self.text_document_publish_diagnostics(
                T.PublishDiagnosticsParams(uri=target, diagnostics=diags,
                                           version=self._version(target)))

    def check_later(self, uri: str) -> None:
        old = self._pending.pop(uri, None)
        if old is not None:
            old.cancel()
        try:
            loop = asyncio.get_running_loop()
        except RuntimeError:
            self.check_now(uri)
            return
        self._pending[uri] = loop.call_later(CHANGE_DELAY, self.check_now, uri)

    def _version(self, uri: str) -> Optional[int]:
        doc = self.analysis.docs.get(uri)
        return doc.version if doc is not None else None

    def sync(self, uri: str) -> None:
        """The analysis takes the workspace's text of ``uri`` (after an edit)."""
        doc = self.workspace.get_text_document(uri)
        self.analysis.open(uri, doc.source, doc.version or 0)


def make_server() -> PlcLanguageServer:
    ls = PlcLanguageServer()

    @ls.feature(T.INITIALIZED)
    def initialized(ls: PlcLanguageServer, params):
        enc = ls.workspace.position_encoding or UTF16
        ls.analysis.encoding = str(getattr(enc, "value", enc))

    @ls.feature(T.TEXT_DOCUMENT_DID_OPEN)
    def did_open(ls: PlcLanguageServer, params: T.DidOpenTextDocumentParams):
        ls.analysis.open(params.text_document.uri, params.text_document.text,
                         params.text_document.version)
        ls.check_now(params.text_document.uri)

    @ls.feature(T.TEXT_DOCUMENT_DID_CHANGE)
    def did_change(ls: PlcLanguageServer, params: T.DidChangeTextDocumentParams):
        ls.sync(params.text_document.uri)
        ls.check_later(params.text_document.uri)

    @ls.feature(T.TEXT_DOCUMENT_DID_SAVE, T.SaveOptions(include_text=True))
    def did_save(ls: PlcLanguageServer, params: T.DidSaveTextDocumentParams):
        if params.text is not None:
            doc = ls.analysis.docs.get(params.text_document.uri)
            ls.analysis.open(params.text_document.uri, params.text,
                             doc.version if doc is not None else 0)
        ls.check_now(params.text_document.uri)

    @ls.feature(T.TEXT_DOCUMENT_DID_CLOSE)
    def did_close(ls: PlcLanguageServer, params: T.DidCloseTextDocumentParams):
        pending = ls._pending.pop(params.text_document.uri, None)
        if pending is not None:
            pending.cancel()
        for target, diags in ls.analysis.close(params.text_document.uri).items():
            ls.text_document_publish_diagnostics(
                T.PublishDiagnosticsParams(uri=target, diagnostics=diags))

    @ls.feature(T.TEXT_DOCUMENT_HOVER)
    def hover(ls: PlcLanguageServer, params: T.HoverParams):
        return F.hover(ls.analysis, params.text_document.uri, params.position)

    @ls.feature(T.TEXT_DOCUMENT_COMPLETION, T.CompletionOptions(trigger_characters=["_"]))
    def completion(ls: PlcLanguageServer, params: T.CompletionParams):
        return F.completion(ls.analysis, params.text_document.uri, params.position)

    @ls.feature(T.TEXT_DOCUMENT_SIGNATURE_HELP,
                T.SignatureHelpOptions(trigger_characters=["(", ","]))
    def signature_help(ls: PlcLanguageServer, params: T.SignatureHelpParams):
        return F.signature_help(ls.analysis, params.text_document.uri, params.position)

    @ls.feature(T.TEXT_DOCUMENT_DEFINITION)
    def definition(ls: PlcLanguageServer, params: T.DefinitionParams):
        return F.definition(ls.analysis, params.text_document.uri, params.position)

    @ls.feature(T.TEXT_DOCUMENT_REFERENCES)
    def references(ls: PlcLanguageServer, params: T.ReferenceParams):
        return F.references(ls.analysis, params.text_document.uri, params.position)

    @ls.feature(T.TEXT_DOCUMENT_PREPARE_RENAME)
    def prepare_rename(ls: PlcLanguageServer, params: T.PrepareRenameParams):
        return F.prepare_rename(ls.analysis, params.text_document.uri, params.position)

    @ls.feature(T.TEXT_DOCUMENT_RENAME, T.RenameOptions(prepare_provider=True))
    def rename(ls: PlcLanguageServer, params: T.RenameParams):
        return F.rename(ls.analysis, params.text_document.uri, params.position, params.new_name)

    @ls.feature(T.TEXT_DOCUMENT_DOCUMENT_SYMBOL)
    def document_symbols(ls: PlcLanguageServer, params: T.DocumentSymbolParams):
        return F.document_symbols(ls.analysis, params.text_document.uri)

    @ls.feature(T.TEXT_DOCUMENT_SEMANTIC_TOKENS_FULL,
                T.SemanticTokensRegistrationOptions(legend=F.LEGEND, full=True))
    def semantic_tokens(ls: PlcLanguageServer, params: T.SemanticTokensParams):
        return F.semantic_tokens(ls.analysis, params.text_document.uri)

    @ls.feature(T.TEXT_DOCUMENT_INLAY_HINT)
    def inlay_hints(ls: PlcLanguageServer, params: T.InlayHintParams):
        return F.inlay_hints(ls.analysis, params.text_document.uri, params.range)

    return ls


def serve_stdio() -> None:
    ls = make_server()
    Transport(ls).serve_stdio()


def serve_tcp(host: str, port: int, ready=None) -> None:
    ls = make_server()
    Transport(ls).serve_tcp(host, port, ready)
