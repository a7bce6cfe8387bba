"""The halted state (docs/debugging.md, "When it halts"): for every running
procedure its line, call stack and variables; the machine; why it halted.
Built from the debugger's halt and each procedure's interpreter, on demand."""

from __future__ import annotations

from plcbuilder.bytecode.opcodes import Op, size_of
from plcbuilder.bytecode.program import Program
from plcbuilder.controller import vm

TYPE_CHECKING = False               # (typing is not imported at run time: start-up)
if TYPE_CHECKING:
    from typing import Optional

_CALL_SIZE = size_of(Op.CALL)


def position(dbg, p) -> tuple[Optional[int], tuple, bool]:
    """(offset, return addresses, at a loop's end) of a running procedure."""
    import inspect                      # (a halt is rare: not loaded at start)
    h = dbg.halt
    if h is not None and h.process is p and h.pc is not None:
        return h.pc, h.rets, False
    gen = p.gen
    if gen is None or inspect.getgeneratorstate(gen) == inspect.GEN_CREATED:
        return p.program.entry, (), False
    if not p.on_reference() and gen.gi_yieldfrom is not None:
        dbg.plc.to_reference(p)         # inside a call: the reference knows the chain
        gen = p.gen
    rets: tuple = ()
    if p.on_reference():
        rets = tuple(inspect.getgeneratorlocals(gen).get("calls", ()))
    at = p.at if p.at is not None else p.program.entry
    code = p.program.code
    loop = at < len(code) and code[at] in (Op.LOOP8, Op.LOOP16)
    return at, rets, loop


def state_of(dbg) -> Optional[dict]:
    """The halted state (docs/debugging.md), or None while running."""
    h = dbg.halt
    if h is None:
        return None
    procs = []
    for p in dbg.plc.running():
        pc, rets, loop = position(dbg, p)
        stack = _frames(p.program, pc, rets)
        top = stack[0] if stack else {"file": None, "line": None}
        procs.append({"name": p.name, "kind": p.kind.label, "file": top["file"],
                      "line": top["line"], "at_loop_end": loop, "stack": stack,
                      "vars": p.variables()})
    halting = h.process
    here = None
    if halting is not None:
        here = next((q for q in procs if q["name"] == halting.name), None)
    bp = h.breakpoint
    return {"reason": h.reason, "t_ms": dbg.plc.t,
            "procedure": halting.name if halting is not None else None,
            "file": here["file"] if here else None, "line": here["line"] if here else None,
            "procedures": procs, "machine": _machine(dbg.plc),
            "fault": {"text": h.fault} if h.fault is not None else None,
            "breakpoint": {"id": bp.id, "file": bp.file, "line": bp.at_line}
            if bp is not None else None}


def _frames(program: Program, pc: Optional[int], rets) -> list[dict]:
    sites = [pc] + [r - _CALL_SIZE for r in reversed(list(rets))]
    out = []
    for at in sites:
        if at is None:
            continue
        loc = program.location(at)
        out.append({"procedure": program.proc_at(at) or "main",
                    "file": loc[0] if loc else None, "line": loc[1] if loc else None})
    return out[:vm.MAX_CALL_DEPTH + 1]


def _machine(plc) -> dict:
    m = plc.machine
    f = m.sample_fields()
    n_in = getattr(m, "input_count", 64)
    n_out = getattr(m, "output_count", 64)
    bits = lambda words, n: [(words[i // 32] >> (i % 32)) & 1 for i in range(n)]  # noqa: E731
    regs = getattr(m, "_regs", {})
    return {"inputs": bits(f["inputs"], n_in), "outputs": bits(f["outputs"], n_out),
            "adc": list(f["adc"]), "pwm": list(f["pwm"]), "dac": list(f["dac"]),
            "axes": dict(m.axis_positions()),
            "registers": {str(k): v for k, v in sorted(regs.items())}}
