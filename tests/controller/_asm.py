"""A tiny assembler for hand-written bytecode in tests (labels resolve to offsets)."""

from __future__ import annotations

from plcbuilder.bytecode.opcodes import (HAS_JABS, HAS_JREL, LONG_FORM, SHORT_FORM, Op, encode,
                                         fits, OPERAND, size_of)
from plcbuilder.bytecode.program import Kind, LineEntry, Program


def L(name: str) -> tuple:
    """A label at this point of the code."""
    return ("label", name)


def assemble(items, *, name: str = "T", kind: Kind = Kind.HARDWARE, entry: str | int = 0,
             var_names=(), file: str = "t.plc", lines: dict | None = None,
             relax: bool = False) -> Program:
    """items: Op, (Op, arg) or L(name); jump/call args may be label names.
    Every instruction gets its own source line (its index + 1) unless ``lines``
    maps instruction index -> line. ``relax``: use the short form of every jump
    whose distance fits (the long form otherwise)."""
    items = list(items)
    if relax:
        shortened = [(SHORT_FORM[it[0]],) + tuple(it[1:]) if isinstance(it, tuple)
                     and it and it[0] in SHORT_FORM else it for it in items]
        while True:
            prog = _assemble(shortened, name=name, kind=kind, entry=entry, var_names=var_names,
                            file=file, lines=lines, _check=True)
            if isinstance(prog, Program):
                return prog
            for idx in prog:
                it = shortened[idx]
                shortened[idx] = (LONG_FORM[it[0]],) + tuple(it[1:])
    return _assemble(items, name=name, kind=kind, entry=entry, var_names=var_names, file=file,
                     lines=lines, _check=False)


def _assemble(items, *, name, kind, entry, var_names, file, lines, _check):
    labels: dict[str, int] = {}
    pc = 0
    flat = []
    for it in items:
        if isinstance(it, tuple) and it and it[0] == "label":
            labels[it[1]] = pc
            continue
        op, arg = (it, None) if isinstance(it, Op) else (it[0], it[1] if len(it) > 1 else None)
        flat.append((pc, op, arg))
        pc += size_of(op)
    code = bytearray()
    line_table = []
    too_far = []
    for idx, (off, op, arg) in enumerate(flat):
        if isinstance(arg, str):
            target = labels[arg]
            if op in HAS_JREL:
                arg = target - (off + size_of(op))
                if not fits(OPERAND[op], arg):
                    too_far.append(idx)
                    continue
            elif op in HAS_JABS:
                arg = target
        code += encode(op, arg)
        line_table.append(LineEntry(off, 0, (lines or {}).get(idx, idx + 1)))
    if too_far:
        if not _check:
            raise ValueError(f"jumps out of range: {too_far}")
        return _item_indexes(items, too_far)
    ent = labels[entry] if isinstance(entry, str) else entry
    procs = [(n, o) for n, o in labels.items() if not n.startswith(".")]
    return Program(name, kind, bytes(code), ent, list(var_names), [file], line_table, procs)


def _item_indexes(items, instr_indexes):
    """Map instruction indexes back to indexes in items (labels are not instructions)."""
    out, n = [], 0
    wanted = set(instr_indexes)
    for i, it in enumerate(items):
        if isinstance(it, tuple) and it and it[0] == "label":
            continue
        if n in wanted:
            out.append(i)
        n += 1
    return out
