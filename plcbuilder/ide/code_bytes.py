"""Where a procedure's code bytes go: the bytes of each source line, from the
disassembler's records (:func:`plcbuilder.bytecode.disasm.instructions`, via
the facade), and the editor margin that shows them (View → Code Bytes in
Margin) so a procedure over its limit shows which lines to shorten.

The compiler records an instruction's file relative to the procedure's
folder (``M03.plc``, ``../include/func.h``); :func:`resolve` makes it a path.
"""

from __future__ import annotations

from collections import defaultdict
from pathlib import Path
from typing import Iterable, Optional

from plcbuilder import api
from plcbuilder.ide.editor import file_key

#: The editor margin of the byte counts (past the ones the editor itself uses).
MARGIN_BYTES = 5
SC_MARGIN_RTEXT = 5


def resolve(file: Optional[str], procedure_path: str) -> Optional[str]:
    """The path of an instruction's file (built-in headers keep their name)."""
    if not file:
        return None
    if file.startswith("<"):
        return file
    p = Path(file)
    if not p.is_absolute():
        p = Path(procedure_path).parent / p
    try:
        return str(p.resolve())
    except OSError:
        return str(p)


def instructions_of(result) -> list:
    """The disassembly records of a CompileResult ([] when it has no program)."""
    program = getattr(result, "program", None)
    return api.instructions(program) if program is not None else []


def bytes_by_line(instructions: Iterable, procedure_path: str) -> dict[tuple[str, int], int]:
    """{(file key, line): code bytes} of every source line that made code."""
    out: dict[tuple[str, int], int] = defaultdict(int)
    for d in instructions:
        f = resolve(d.file, procedure_path)
        if f is None or d.line is None:
            continue
        out[(file_key(f), d.line)] += d.size
    return dict(out)


def lines_of_file(counts: dict[tuple[str, int], int], path: str) -> dict[int, int]:
    """{line: bytes} of one file."""
    key = file_key(path)
    return {line: n for (f, line), n in counts.items() if f == key}


def show_margin(ed, per_line: Optional[dict[int, int]]) -> None:
    """Show the byte counts in the editor's margin (None: hide the margin)."""
    from plcbuilder.ide import highlighter as hl     # (loaded with the editors)
    if ed.margins() <= MARGIN_BYTES:
        ed.setMargins(MARGIN_BYTES + 1)
    ed.marginTextClearAll()
    if per_line is None:
        ed.setMarginWidthN(MARGIN_BYTES, 0)
        return
    ed.setMarginTypeN(MARGIN_BYTES, SC_MARGIN_RTEXT)
    ed.setMarginMaskN(MARGIN_BYTES, 0)
    widest = max((len(str(n)) for n in per_line.values()), default=1)
    ed.setMarginWidthN(MARGIN_BYTES, ed.textWidth(hl.STYLE_LINENUMBER, "9" * (widest + 2)))
    lines = ed.lineCount()
    for line, n in per_line.items():
        if 1 <= line <= lines:
            ed.marginSetText(line - 1, f"{n} ")
            ed.marginSetStyle(line - 1, hl.STYLE_LINENUMBER)


def margin_texts(ed) -> dict[int, str]:
    """{line: text} the margin shows now (1-based lines; for tests and screenshots)."""
    out = {}
    if ed.margins() <= MARGIN_BYTES or ed.marginWidthN(MARGIN_BYTES) == 0:
        return out
    for line0 in range(ed.lineCount()):
        t = ed.marginText(line0)
        if hasattr(t, "data"):                 # a QByteArray
            t = bytes(t.data())
        if isinstance(t, (bytes, bytearray)):
            t = bytes(t).decode("utf-8", "replace")
        if t:
            out[line0 + 1] = str(t).strip()
    return out
