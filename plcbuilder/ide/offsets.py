"""Character <-> UTF-8 byte offsets: the one place the IDE converts between them.

Python strings (and so diagnostics, whose columns count characters) index by
character; Scintilla indexes its document by UTF-8 byte. Every conversion in
the IDE goes through :func:`char_to_byte` / :func:`byte_to_char` (or the line
helpers below, which are built on them), and tests/ide/test_offsets.py holds
them to it with non-ASCII text.

Lone surrogates (which a Python str may hold) are counted as the three bytes
that ``surrogatepass`` encodes them to, so the functions are total.
"""

from __future__ import annotations

__all__ = ["char_to_byte", "byte_to_char", "utf8_len"]


def utf8_len(text: str) -> int:
    """The number of UTF-8 bytes of text."""
    if text.isascii():
        return len(text)
    return len(text.encode("utf-8", "surrogatepass"))


def char_to_byte(text: str, index: int) -> int:
    """The UTF-8 byte offset of character ``index`` of text.

    ``index`` is clamped to ``0..len(text)``, so the end of the text (and any
    index past it) maps to the byte length."""
    if index <= 0:
        return 0
    if text.isascii():
        return min(index, len(text))
    return utf8_len(text[:index])


def byte_to_char(text: str, offset: int) -> int:
    """The character index of UTF-8 byte ``offset`` of text.

    An offset inside a multi-byte character maps to that character (the
    character it is part of); ``offset`` is clamped to the byte length."""
    if offset <= 0:
        return 0
    if text.isascii():
        return min(offset, len(text))
    data = text.encode("utf-8", "surrogatepass")
    if offset >= len(data):
        return len(text)
    # Back up to the first byte of the character that ``offset`` falls in.
    while offset > 0 and (data[offset] & 0xC0) == 0x80:
        offset -= 1
    return len(data[:offset].decode("utf-8", "surrogatepass"))
