"""Paths and line ends of the files editors show."""

from __future__ import annotations

import os


def normalise_newlines(text: str) -> tuple[str, str]:
    """(text with \\n line ends, the line end the file used: '\\n' or '\\r\\n')."""
    eol = "\r\n" if "\r\n" in text else "\n"
    if "\r" in text:
        text = text.replace("\r\n", "\n").replace("\r", "\n")
    return text, eol


def same_file(a: str, b: str) -> bool:
    return file_key(a) == file_key(b)


def file_key(path) -> str:
    """A comparable form of a path (absolute, normalised, case-folded where the
    file system is)."""
    s = str(path)
    if s.startswith("<"):
        return s
    return os.path.normcase(os.path.abspath(s))
