"""Compiling one file again and again as it is edited (diagnostics while
typing), redoing only what the edit changed.

An :class:`Incremental` belongs to one open file and is handed to
:func:`plcbuilder.lang.pipeline.compile_source` at every compile. It keeps

- the tokens of every file read, by name and text (headers are tokenized once;
  a header on disk is read again only when its size or time stamp changed),
  and a file whose text changed is tokenized again only around the edit,
- the last parse: the next one starts at the last top-level procedure before
  the first token that changed and stops as soon as it is back where the old
  parse was, reusing the procedures after the edit (moved by the lines the
  edit added or removed) — see :func:`plcbuilder.lang.parser.parse_incremental`,
- what the checker found in each procedure (its names, variables and calls;
  whether it can reach its end): a procedure the parse reused is not walked
  again while the procedures' names and the options are the same
  (:class:`~plcbuilder.lang.checker.CheckCache`),
- the code assembled for each procedure: a procedure the parse reused whose
  names mean the same is neither walked nor assembled again; the program is
  linked from the procedures' code (so sizes, calls and the line table are
  exact).

An Enter (or a deleted line) moves the procedures below it: what is kept of
them is moved with them (a procedure's line table, its variables' and calls'
spans), not made again. The preprocessor (defines, conditionals) and the
checker's whole-file checks (names, variables, recursion, main) run in full
every time, over what the procedures' walks found. The result is the same,
diagnostic for diagnostic and byte for byte, as a compile from scratch.
"""

from __future__ import annotations

from _thread import allocate_lock

from plcbuilder.diagnostics import Diagnostic
from plcbuilder.lang import ast as A
from plcbuilder.lang.checker import CheckCache
from plcbuilder.lang.codegen import CodeCache
from plcbuilder.lang.parser import Parsed, parse_incremental
from plcbuilder.lang.preprocess import TokenCache
from plcbuilder.lang.tokens import Tok

TYPE_CHECKING = False               # (typing is not imported at run time: start-up)
if TYPE_CHECKING:
    from typing import Optional


class Incremental:
    """What one file's compiles keep for the next (see the module docstring).
    One compile at a time uses it."""

    def __init__(self):
        self.tokens = TokenCache()
        self.parsed: Optional[Parsed] = None
        self.code = CodeCache()
        self.checks = CheckCache()
        self.lock = allocate_lock()

    def parse(self, toks: list[Tok], main_file: str) -> tuple[A.Module, list[Diagnostic]]:
        self.parsed = parse_incremental(toks, self.parsed, main_file)
        self.code.moved = self.checks.moved = self.parsed.moved
        return self.parsed.module, self.parsed.diagnostics

    def done(self) -> None:
        """A compile ended: forget the tokens of files it did not read."""
        self.tokens.sweep()

    def reset(self) -> None:
        self.tokens = TokenCache()
        self.parsed = None
        self.code = CodeCache()
        self.checks = CheckCache()
