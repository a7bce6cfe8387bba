"""JSON-RPC 2.0 and the Language Server Protocol's rules for messages, on top
of pygls's :class:`~pygls.protocol.LanguageServerProtocol`.

pygls trusts the envelope of a message (an id of any JSON type, a request
after ``shutdown`` silently dropped, a refusal logged with a traceback, an
unexpected error answered with its traceback in ``data``). :class:`PlcProtocol`
is handed every decoded message by :mod:`plcbuilder.lsp.transport` and answers
as the standards say before pygls dispatches it:

- not an object, no ``"jsonrpc": "2.0"``, a method that is not a string,
  params that are not an object or array, a request id that is not an integer
  or a string (``true``, ``{}``, ``1.5``, ``1e400``), or none of request,
  notification and response: ``-32600`` Invalid Request (with the id when it
  is a valid one, else ``null``);
- a request before ``initialize``: ``-32002`` ServerNotInitialized (a
  notification then is dropped, except ``exit``); a second ``initialize``:
  ``-32600``;
- a request after ``shutdown``: ``-32600`` (a notification is dropped, except
  ``exit``);
- params that do not fit the method: ``-32602`` Invalid params, saying where;
- an unknown method: ``-32601``;
- a request the server refuses on purpose (a :class:`RequestFailed`, e.g.
  renaming a built-in): ``-32803`` with the plain sentence;
- a bug: ``-32603`` with a one-line message; the traceback goes to the log,
  never to the client.

An expected refusal is one line in the log; only a bug logs a traceback.
``exit`` ends the session through :attr:`PlcProtocol.on_exit` (the
transport's: stdio ends the process, TCP closes that connection).
"""

from __future__ import annotations

import logging
import math
from concurrent.futures import Future
from typing import Any, Callable, Optional

from cattrs import transform_error
from lsprotocol import types as T
from pygls.exceptions import JsonRpcException, JsonRpcInvalidParams, JsonRpcRequestCancelled
from pygls.protocol import LanguageServerProtocol, lsp_method
from pygls.protocol.json_rpc import (JsonRPCNotification, JsonRPCRequestMessage,
                                     JsonRPCResponseMessage)

log = logging.getLogger(__name__)

PARSE_ERROR = -32700
INVALID_REQUEST = -32600
METHOD_NOT_FOUND = -32601
INVALID_PARAMS = -32602
INTERNAL_ERROR = -32603
SERVER_NOT_INITIALIZED = -32002
REQUEST_FAILED = int(T.LSPErrorCodes.RequestFailed)       # -32803


class RequestFailed(JsonRpcException):
    """A request that was understood but cannot be done (its message is a plain
    sentence for the user): LSP's RequestFailed."""
    CODE = REQUEST_FAILED
    MESSAGE = "Request failed"


def valid_id(mid: Any) -> bool:
    """A request id as LSP has it: an integer or a string (not a boolean, a
    fraction, an infinity, null, an object or an array)."""
    if isinstance(mid, bool):
        return False
    if isinstance(mid, float):
        return False                  # 1.5, 1e400 (inf), nan: JSON numbers that are not integers
    return isinstance(mid, (int, str))


def _describe(value: Any) -> str:
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return "a number out of range" if not math.isfinite(value) else f"the fraction {value!r}"
    if isinstance(value, dict):
        return "an object"
    if isinstance(value, list):
        return "an array"
    return type(value).__name__


def _params_problem(exc: BaseException) -> str:
    """Where structured params went wrong, in a few words."""
    try:
        lines = transform_error(exc)
    except Exception:  # noqa: BLE001 - not a cattrs error: say what it is
        lines = [str(exc) or type(exc).__name__]
    lines = [ln.replace("$.params", "params") for ln in lines]
    shown = "; ".join(lines[:3])
    return shown + (f" (and {len(lines) - 3} more)" if len(lines) > 3 else "")


class PlcProtocol(LanguageServerProtocol):
    """pygls's protocol with JSON-RPC's and LSP's rules for what it is sent
    (see the module docstring)."""

    def __init__(self, server, converter):
        super().__init__(server, converter)
        self.initialize_received = False
        #: called with the exit status when the client sends ``exit``
        self.on_exit: Optional[Callable[[int], None]] = None

    # ------------------------------------------------------------ receiving
    def receive(self, raw: Any) -> None:
        """One decoded JSON message: answered with an error, or dispatched."""
        if not isinstance(raw, dict):
            self.reply_error(None, INVALID_REQUEST,
                             f"a JSON-RPC message is an object, not {_describe(raw)}")
            return
        has_id = "id" in raw
        mid = raw.get("id")
        reply_id = mid if valid_id(mid) else None
        if raw.get("jsonrpc") != "2.0":
            self.reply_error(reply_id, INVALID_REQUEST, 'a JSON-RPC 2.0 message has "jsonrpc": "2.0"')
            return
        if "method" in raw:
            method = raw["method"]
            if not isinstance(method, str):
                self.reply_error(reply_id, INVALID_REQUEST, "the method is a string")
                return
            if has_id and not valid_id(mid):
                self.reply_error(None, INVALID_REQUEST,
                                 f"a request's id is an integer or a string, not {_describe(mid)}")
                return
            if "result" in raw or "error" in raw:
                self.reply_error(reply_id, INVALID_REQUEST,
                                 "a message with a method is a request or a notification: it has "
                                 "no result or error")
                return
            params = raw.get("params")
            if params is not None and not isinstance(params, (dict, list)):
                if has_id:
                    self.reply_error(mid, INVALID_REQUEST, f"the params of {method} are an object "
                                                           f"or an array, not {_describe(params)}")
                else:
                    log.info("notification %s dropped: its params are %s", method, _describe(params))
                return
            if has_id:
                self._request(raw, mid, method)
            else:
                self._notification(raw, method)
            return
        if has_id and ("result" in raw or "error" in raw):
            if not valid_id(mid):
                log.info("a response with the id %s dropped: no request has such an id",
                         _describe(mid))
                return
            self._response(raw, mid)
            return
        self.reply_error(reply_id, INVALID_REQUEST,
                         "neither a request (method and id), a notification (method) nor a "
                         "response (id and result or error)")

    def _request(self, raw: dict, mid, method: str) -> None:
        if self._shutdown:
            log.info("request %s (id %r) after shutdown: refused", method, mid)
            self.reply_error(mid, INVALID_REQUEST,
                             f"the server is shutting down: {method} is not served after "
                             "shutdown (only the exit notification is)")
            return
        if method == T.INITIALIZE:
            if self.initialize_received:
                self.reply_error(mid, INVALID_REQUEST, "initialize was sent already")
                return
        elif not self.initialize_received:
            log.info("request %s (id %r) before initialize: refused", method, mid)
            self.reply_error(mid, SERVER_NOT_INITIALIZED,
                             f"the server is not initialized: send initialize before {method}")
            return
        try:
            msg = self._structure(raw, method)
        except JsonRpcInvalidParams as exc:
            log.info("request %s (id %r) refused: %s", method, mid, exc.message)
            self.reply_error(mid, INVALID_PARAMS, exc.message)
            return
        if method == T.INITIALIZE:
            self.initialize_received = True
        self.handle_message(msg)

    def _notification(self, raw: dict, method: str) -> None:
        if method != T.EXIT:
            if self._shutdown:
                log.info("notification %s after shutdown: dropped", method)
                return
            if not self.initialize_received:
                log.info("notification %s before initialize: dropped", method)
                return
        try:
            msg = self._structure(raw, method)
        except JsonRpcInvalidParams as exc:
            log.info("notification %s dropped: %s", method, exc.message)
            return
        self.handle_message(msg)

    def _structure(self, raw: dict, method: str):
        """The lsprotocol message of a request or notification whose envelope is
        valid; params that do not fit raise JsonRpcInvalidParams (no traceback
        is logged: the caller logs one line)."""
        if "id" in raw:
            cls = self.get_message_type(method) or JsonRPCRequestMessage
        else:
            cls = self.get_message_type(method) or JsonRPCNotification
        if cls in (JsonRPCRequestMessage, JsonRPCNotification):
            # pygls's own classes take exactly their fields (an unknown method's
            # request may carry others)
            raw = {k: raw.get(k) for k in ("jsonrpc", "id", "method", "params") if k in raw or
                   k == "params"}
        try:
            return self._converter.structure(raw, cls)
        except Exception as exc:  # noqa: BLE001 - the envelope is valid: the params are not
            raise JsonRpcInvalidParams(f"invalid params for {method}: {_params_problem(exc)}") \
                from None

    def _response(self, raw: dict, mid) -> None:
        """The client's answer to a request of the server's."""
        if "error" in raw:
            cls = T.ResponseErrorMessage
        else:
            cls = self._result_types.pop(mid, None) or JsonRPCResponseMessage
        try:
            msg = self._converter.structure(raw, cls)
        except Exception as exc:  # noqa: BLE001 - a response that does not fit: dropped
            log.info("a response to %r dropped: %s", mid, _params_problem(exc))
            return
        self.handle_message(msg)

    # ------------------------------------------------------------ answering
    def reply_error(self, mid, code: int, message: str) -> None:
        """An error response, written at once."""
        self._send_data({"jsonrpc": "2.0", "id": mid, "error": {"code": code, "message": message}})

    def _send_handler_result(self, future: Future, *, msg_id):
        """A handler's outcome as the response: a refusal on purpose (any
        JsonRpcException) is logged as one line; anything else is a bug, logged
        with its traceback and answered -32603 without it."""
        self._request_futures.pop(msg_id, None)
        if future.cancelled():
            self._send_response(msg_id, error=JsonRpcRequestCancelled(
                f"request {msg_id!r} was cancelled").to_response_error())
            return
        exc = future.exception()
        if exc is None:
            self._send_response(msg_id, result=future.result())
        elif isinstance(exc, JsonRpcException):
            log.info("request %r refused (%d): %s", msg_id, exc.code, exc.message)
            self._send_response(msg_id, error=T.ResponseError(code=exc.code, message=exc.message,
                                                              data=exc.data))
        else:
            log.error("request %r failed", msg_id, exc_info=(type(exc), exc, exc.__traceback__))
            self._send_response(msg_id, error=T.ResponseError(
                code=INTERNAL_ERROR, message=f"internal error: {exc}" if str(exc)
                else f"internal error ({type(exc).__name__})"))

    def _handle_request(self, msg_id, method_name: str, params):
        """pygls's, with one log line (not a traceback) for an unknown method."""
        try:
            handler = self._get_handler(method_name)
        except JsonRpcException as error:
            log.info("request %r: unknown method %s", msg_id, method_name)
            self._send_response(msg_id, None, error.to_response_error())
            return
        self._ctx_msg_id.set(msg_id)
        self._execute_handler(msg_id=msg_id, handler=handler, args=(params,),
                              callback=lambda f: self._send_handler_result(f, msg_id=msg_id))

    # ------------------------------------------------------------ lifecycle
    @lsp_method(T.EXIT)
    def lsp_exit(self, *args):
        """Ends the session (the status is 0 after shutdown, 1 without)."""
        code = 0 if self._shutdown else 1
        if self.on_exit is not None:
            self.on_exit(code)
        else:
            raise SystemExit(code)

    # The documents are the server's (plcbuilder.lsp.analysis keeps their text
    # and applies the changes, with LSP's line breaks); pygls's workspace does
    # not keep a second copy of each (or read an unopened one from disk).
    @lsp_method(T.TEXT_DOCUMENT_DID_OPEN)
    def lsp_text_document__did_open(self, params: T.DidOpenTextDocumentParams):
        if (handler := self.fm.features.get(T.TEXT_DOCUMENT_DID_OPEN)) is not None:
            yield handler, (params,), None

    @lsp_method(T.TEXT_DOCUMENT_DID_CHANGE)
    def lsp_text_document__did_change(self, params: T.DidChangeTextDocumentParams):
        if (handler := self.fm.features.get(T.TEXT_DOCUMENT_DID_CHANGE)) is not None:
            yield handler, (params,), None

    @lsp_method(T.TEXT_DOCUMENT_DID_CLOSE)
    def lsp_text_document__did_close(self, params: T.DidCloseTextDocumentParams):
        if (handler := self.fm.features.get(T.TEXT_DOCUMENT_DID_CLOSE)) is not None:
            yield handler, (params,), None
