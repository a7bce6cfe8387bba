"""The disassembler: records first (like dis.get_instructions), text second."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Iterator, Optional

from plcbuilder.bytecode import abi
from plcbuilder.bytecode.opcodes import (HAS_CONST, HAS_SLOT, IMPLICIT_CONST, STACK_EFFECT, Op,
                                         decode)
from plcbuilder.bytecode.program import Program


@dataclass(frozen=True)
class DisInstr:
    offset: int
    op: Op
    arg: Optional[int]
    size: int
    target: Optional[int]      # jump/call destination
    operand: str               # the operand as text ("", "42", "timer", "-> 12 (find_home_z)")
    file: Optional[str]
    line: Optional[int]
    proc: Optional[str]        # procedure whose code this is
    starts_proc: bool          # first instruction of a procedure
    raw: bytes


def instructions(program: Program) -> list[DisInstr]:
    return list(iter_instructions(program))


def _register_operands(decoded) -> set[int]:
    """Offsets of the constants that are gvarget/gvarset addresses, found by
    following the stack through straight-line code."""
    targets = {i.target for i in decoded if i.target is not None}
    found: set[int] = set()
    stack: list[int | None] = []       # the offset of the constant of each value, or None
    for ins in decoded:
        if ins.offset in targets:
            stack = []
        op = ins.op
        if op in (Op.GVARGET, Op.GVARSET):
            depth = 1 if op is Op.GVARGET else 2
            if len(stack) >= depth and stack[-depth] is not None:
                found.add(stack[-depth])
        pops, pushes = STACK_EFFECT[op]
        del stack[len(stack) - min(pops, len(stack)):]
        if op in HAS_CONST or op in IMPLICIT_CONST:
            stack.append(ins.offset)
        else:
            stack.extend([None] * pushes)
        if ins.target is not None or op in (Op.RET, Op.YIELD):
            stack = []
    return found


def iter_instructions(program: Program) -> Iterator[DisInstr]:
    names = program.slot_names()
    starts = {off: name for name, off in program.procs}
    code = program.code
    decoded = list(decode(code))
    registers = _register_operands(decoded)
    for ins in decoded:
        target = ins.target
        if ins.op in HAS_CONST:
            operand = _const_text(ins.arg, ins.offset in registers)
        elif ins.op in HAS_SLOT:
            operand = names.get(ins.arg, f"v{ins.arg}")
        elif target is not None:
            operand = f"-> {target}" + (f" ({starts[target]})" if target in starts else "")
        else:
            operand = ""
        loc = program.location(ins.offset)
        yield DisInstr(ins.offset, ins.op, ins.arg, ins.size, target, operand,
                       loc[0] if loc else None, loc[1] if loc else None,
                       program.proc_at(ins.offset), ins.offset in starts,
                       bytes(code[ins.offset:ins.end]))


def _const_text(v: int, register: bool) -> str:
    text = str(v)
    if v > 255 or v < -255:
        text += f" (0x{v & 0xffffffff:x})"
    desc = abi.describe_register(v) if register else None
    return text + (f"  ; {desc}" if desc else "")


def render_text(program: Program, source_line: Optional[Callable[[str, int], Optional[str]]] = None,
                *, bytes_column: bool = True) -> str:
    """The listing: a header, then per procedure its instructions with the
    source lines they come from interleaved (when ``source_line`` can give them)."""
    out = [f"; {program.name}: {program.kind.label} procedure, {program.code_size} bytes of code, "
           f"{program.nvars} variable{'s' if program.nvars != 1 else ''}"
           + (f" ({', '.join(program.var_names)})" if program.var_names else "")]
    last = None
    for d in iter_instructions(program):
        if d.starts_proc:
            out.append("")
            out.append(f"{d.proc}():")
        if d.file is not None and (d.file, d.line) != last:
            last = (d.file, d.line)
            text = source_line(d.file, d.line) if source_line else None
            where = f"{d.file}:{d.line}"
            out.append(f"    ; {where}: {text.strip()}" if text is not None else f"    ; {where}")
        raw = d.raw.hex(" ") if bytes_column else ""
        out.append(f"  {d.offset:5d}  {raw:<15} {d.op.name:<8} {d.operand}".rstrip())
    return "\n".join(out) + "\n"
