"""Hover help in the editor: the text comes from :mod:`plcbuilder.lang.hover`
(the language server shows the same); this adds the editor's procedure kind."""

from __future__ import annotations

from typing import Optional

from plcbuilder.api import Kind
from plcbuilder.lang import hover as _lang_hover
from plcbuilder.lang.hover import register_text, value_text

__all__ = ["hover_text", "register_text", "value_text"]


def hover_text(word: str, before: str = "", *, kind: Kind = Kind.HARDWARE, symbols=None,
               header_defines: Optional[dict] = None, variables: tuple = (),
               procedures: dict | None = None) -> Optional[str]:
    """The hover text for word (see :func:`plcbuilder.lang.hover.hover_text`)."""
    return _lang_hover.hover_text(word, before, software=kind is Kind.SOFTWARE, symbols=symbols,
                                  header_defines=header_defines, variables=variables,
                                  procedures=procedures)
