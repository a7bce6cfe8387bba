"""``plcbuilder lsp``: the PLC language over the Language Server Protocol.

A pygls server whose protocol is :class:`~plcbuilder.lsp.protocol.PlcProtocol`
(JSON-RPC's and LSP's rules for what it is sent), whose features are
:mod:`plcbuilder.lsp.features` and whose diagnostics come from
:mod:`plcbuilder.lsp.analysis`, compiled off the message loop by
:mod:`plcbuilder.lsp.checks`; it reads its messages through
:mod:`plcbuilder.lsp.transport`. Documents are synchronised incrementally.
Diagnostics are sent when a document is opened and saved, and a moment after
the last change while typing. Files are read only inside the workspace
(:mod:`plcbuilder.lsp.access`).
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Iterable, Optional

from lsprotocol import types as T
from pygls.lsp.server import LanguageServer

from plcbuilder import __version__
from plcbuilder.lsp import features as F
from plcbuilder.lsp.access import Access
from plcbuilder.lsp.analysis import Analysis, uri_path
from plcbuilder.lsp.checks import CHANGE_DELAY, Checks
from plcbuilder.lsp.positions import UTF16
from plcbuilder.lsp.protocol import PlcProtocol
from plcbuilder.project.model import SETTINGS_FILE

log = logging.getLogger(__name__)

__all__ = ["CHANGE_DELAY", "PlcLanguageServer", "make_server"]


class PlcLanguageServer(LanguageServer):
    def __init__(self, confine: Optional[Iterable[Path]] = None):
        super().__init__("plcbuilder", __version__, protocol_cls=PlcProtocol,
                         text_document_sync_kind=T.TextDocumentSyncKind.Incremental)
        self.analysis = Analysis(access=Access(confine))
        self.checks = Checks(self.analysis, self._publish)

    def _publish(self, versions: dict, published: dict) -> None:
        for target, diags in published.items():
            version = versions.get(target)
            if version is None:
                doc = self.analysis.docs.get(target)
                version = doc.version if doc is not None else None
            self.text_document_publish_diagnostics(
                T.PublishDiagnosticsParams(uri=target, diagnostics=diags, version=version))

    def report_server_error(self, error: Exception, source) -> None:
        """A failure outside a request (a notification's handler): logged, not
        shown to the user as a pop-up for every keystroke."""
        log.error("%s", error)

    def set_folders(self, uris: Iterable[str]) -> None:
        paths = [p for p in (uri_path(u) for u in uris) if p is not None]
        refused = self.analysis.access.set_folders(paths)
        self._tell_refused(refused)

    def _tell_refused(self, refused) -> None:
        if refused:
            self.window_show_message(T.ShowMessageParams(
                type=T.MessageType.Warning,
                message="plcbuilder lsp does not serve " + ", ".join(map(str, refused))
                        + ": outside the folders it was started for"))

    def stop(self) -> None:
        self.checks.stop()


def make_server(confine: Optional[Iterable[Path]] = None) -> PlcLanguageServer:
    """A server for one session. ``confine``: the folders a workspace must be
    inside (a TCP server's ``--root``); None: any the client names."""
    ls = PlcLanguageServer(confine)

    @ls.feature(T.INITIALIZE)
    def initialize(ls: PlcLanguageServer, params: T.InitializeParams):
        uris = [f.uri for f in params.workspace_folders or ()]
        if not uris and params.root_uri:
            uris = [params.root_uri]
        elif not uris and params.root_path:
            uris = [Path(params.root_path).absolute().as_uri()]
        if uris:
            ls.set_folders(uris)

    @ls.feature(T.INITIALIZED)
    def initialized(ls: PlcLanguageServer, params):
        enc = ls.workspace.position_encoding or UTF16
        ls.analysis.encoding = str(getattr(enc, "value", enc))

    @ls.feature(T.WORKSPACE_DID_CHANGE_WORKSPACE_FOLDERS)
    def folders_changed(ls: PlcLanguageServer, params: T.DidChangeWorkspaceFoldersParams):
        added = [p for p in (uri_path(f.uri) for f in params.event.added or ()) if p]
        removed = [p for p in (uri_path(f.uri) for f in params.event.removed or ()) if p]
        ls._tell_refused(ls.analysis.access.change_folders(added, removed))

    @ls.feature(T.TEXT_DOCUMENT_DID_OPEN)
    def did_open(ls: PlcLanguageServer, params: T.DidOpenTextDocumentParams):
        doc = params.text_document
        ls.analysis.open(doc.uri, doc.text, doc.version, doc.language_id or "")
        if ls.analysis.is_plc(doc.uri):
            ls.checks.now(doc.uri)

    @ls.feature(T.TEXT_DOCUMENT_DID_CHANGE)
    def did_change(ls: PlcLanguageServer, params: T.DidChangeTextDocumentParams):
        uri = params.text_document.uri
        if not ls.analysis.change(uri, params.text_document.version, params.content_changes):
            log.info("a change to %s, which is not open: ignored", uri)
            return
        if ls.analysis.is_plc(uri):
            ls.checks.later(uri)

    @ls.feature(T.TEXT_DOCUMENT_DID_SAVE, T.SaveOptions(include_text=True))
    def did_save(ls: PlcLanguageServer, params: T.DidSaveTextDocumentParams):
        uri = params.text_document.uri
        doc = ls.analysis.docs.get(uri)
        if params.text is not None and doc is not None:
            ls.analysis.open(uri, params.text, doc.version)
        if ls.analysis.is_plc(uri):
            ls.checks.now(uri)
        path = uri_path(uri)
        if path is not None and path.name == SETTINGS_FILE:
            # the project's settings changed: its open procedures compile differently
            for other in list(ls.analysis.docs):
                if other != uri and ls.analysis.is_plc(other):
                    ls.checks.now(other)

    @ls.feature(T.TEXT_DOCUMENT_DID_CLOSE)
    def did_close(ls: PlcLanguageServer, params: T.DidCloseTextDocumentParams):
        uri = params.text_document.uri
        ls.checks.cancel(uri)
        for target, diags in ls.analysis.close(uri).items():
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
