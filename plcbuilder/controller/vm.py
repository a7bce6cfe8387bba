"""The reference interpreter: runs a procedure's bytecode one instruction at a time.

This is the executable definition of the bytecode's meaning. The fast backend
(:mod:`plcbuilder.controller.fastvm`) must behave identically, and falls back to
this interpreter for anything it does not translate.

A running procedure is a generator: each ``next()`` runs one tick, until an
instruction that ends the tick (``yield``), or the procedure ends. It ends by
raising :class:`ProcExit` (``exit(code)``, or falling off ``main`` with 0) or
:class:`VMFault` (a runtime fault, with the code offset that caused it).

The meaning of the code, in short (values are 32-bit two's complement; what
each operator computes is :mod:`plcbuilder.bytecode.semantics`):

- binary operators pop b, then a, and push ``a OP b``; a zero divisor is a fault;
- jumps are relative to the end of the instruction; ``LOOP`` pops a condition,
  ends the tick, and when the procedure resumes goes to its target if the
  condition was not 0; ``YIELD`` ends the tick;
- ``CALL`` nests at most :data:`MAX_CALL_DEPTH` deep; ``RET`` in ``main`` ends
  the procedure with exit code 0; ``EXIT`` pops the exit code;
- built-in calls pop their arguments (first argument pushed first);
- more than :data:`TICK_BUDGET` instructions in one tick is a fault.
- ``gvarget`` of a plain register with a host latency of L ms (``Host.lat``)
  suspends the procedure for L ticks; the register is read when it resumes.
"""

from __future__ import annotations

from plcbuilder.bytecode import semantics
from plcbuilder.bytecode.abi import MAX_CALL_DEPTH, STACK_LIMIT, TICK_BUDGET
from plcbuilder.bytecode.opcodes import (BINARY, BUILTINS, COND_JUMPS, ENDS_TICK, HAS_CONST,
                                         HAS_JREL, IMPLICIT_CONST, JUMPS_IF_NOT_ZERO,
                                         JUMPS_IF_ZERO, NO_FALLTHROUGH, UNARY, Op, size_of,
                                         validate)
from plcbuilder.bytecode.program import Program
from plcbuilder.bytecode.semantics import wrap

TYPE_CHECKING = False               # (typing is not imported at run time: start-up)
if TYPE_CHECKING:
    from typing import Callable, Iterator, Optional

FAULT_DIV = "division by zero"
FAULT_MOD = "modulo by zero"
FAULT_DEPTH = f"call depth over {MAX_CALL_DEPTH}"
FAULT_BUDGET = f"more than {TICK_BUDGET} instructions in one tick (a loop that never ends an iteration?)"
FAULT_END = "ran past the end of the code"
FAULT_UNDERFLOW = "stack underflow"
FAULT_OVERFLOW = f"stack overflow (more than {STACK_LIMIT} values)"

_CALL_SIZE = size_of(Op.CALL)


class VMFault(Exception):
    """A runtime fault at code offset ``pc``."""

    def __init__(self, pc: int, text: str):
        super().__init__(f"at code offset {pc}: {text}")
        self.pc = pc
        self.text = text
        #: code offsets of the calls that led here, innermost first
        self.callers: list[int] = []


class ProcExit(Exception):
    """The procedure ended with an exit code."""

    def __init__(self, code: int):
        super().__init__(code)
        self.code = code


class Handoff(Exception):
    """Raised by the fast backend when it cannot finish a tick exactly (the tick's
    instruction budget runs out inside a block): the reference interpreter
    continues from this state."""

    def __init__(self, pc: int, stack: list[int], rets: tuple[int, ...], count: int):
        super().__init__(pc)
        self.pc = pc
        self.stack = stack
        self.rets = rets
        self.count = count


class Halted(Handoff):
    """Raised by the fast backend where the debugger halts a procedure mid-tick:
    the reference interpreter goes on from this state when it resumes, without
    asking the debugger again at ``pc``."""


class Migrate(Exception):
    """Thrown into a fast-backend generator suspended at a tick end: it answers
    with a :class:`Handoff` of its exact state, so that the reference interpreter
    can go on from there (the debugger does this to watch or step it)."""


#: Sent to a procedure suspended at a tick end (``gen.send(HANDOVER)``): it raises
#: :class:`Handoff` with its state there, so that a new reference interpreter
#: (over other slots: a debugger's forces) goes on from that point. A fast-backend
#: procedure that keeps variables in locals takes it after a SYNC; one waiting for
#: a gvarget's latency ignores it (it stays suspended).
HANDOVER = object()


#: The Host's functions the built-in calls reach, by name (opcodes.BUILTINS).
CALLS = tuple(dict.fromkeys(c.host for c in BUILTINS.values()))


class Host:
    """What a running procedure reaches outside itself: a function for each
    built-in call (:data:`CALLS`), and what the fast backend uses besides.

    ``gvarset`` is the general register write (prints and, for software
    procedures, the command registers 100020.., 100040, 100041 are handled by
    it); the fast backend calls the specialised functions (``pr``, ``raw_gvarset``,
    ``starthw``, ``seteparam``, ``softjog``) directly where the address is a
    constant, which must have the same effect. ``lat`` is the gvarget latency
    in ticks for addresses where ``plain(addr)`` is true.

    ``io``, when given, is the machine's pin state that the fast backend may read
    directly instead of calling (an object with ``in_bits``, ``out_bits``,
    ``input_count`` and ``output_count``): ``portget`` of a constant pin reads
    ``io.in_bits``, and ``portset``/``portclr`` of a constant pin are only called
    when they would change ``io.out_bits``. So ``portget(n)`` must return bit n of
    ``in_bits``, and writing an output its current value must do nothing. An
    ``io`` may also keep a list per pin, ``in_levels`` (0 or 1) and ``out_on``
    (False or True), always equal to the bits and never replaced (changed in
    place): then those are read instead (a list item is cheaper than a bit).

    ``registers``, when given, is the register store ``gvarget`` reads, as a
    pair of dicts ``(store, forced)`` (the machine's ``register_store()``): while
    ``forced`` is empty, ``gvarget(addr)`` of an address ``plain(addr)`` is true
    for is ``store.get(addr, 0)``, and the fast backend reads a constant plain
    register so instead of calling. :meth:`replace` drops it with a new ``gvarget``.
    """

    __slots__ = (*CALLS, "plain", "lat", "pr", "raw_gvarset", "starthw", "seteparam", "softjog",
                 "software", "io", "registers", "debug")

    def __init__(self, *, plain=None, lat: int = 0, pr=None, raw_gvarset=None, starthw=None,
                 seteparam=None, softjog=None, software: bool = False, io=None, registers=None,
                 **calls):
        if calls.keys() != set(CALLS):
            raise TypeError(f"Host takes the built-in calls {', '.join(CALLS)}: "
                            f"missing {sorted(set(CALLS) - calls.keys())}, "
                            f"unknown {sorted(calls.keys() - set(CALLS))}")
        for name, fn in calls.items():       # portset=..., portget=..., (opcodes.BUILTINS)
            setattr(self, name, fn)
        self.plain = plain or (lambda _addr: True)
        self.lat = int(lat)
        self.pr = pr
        self.raw_gvarset = raw_gvarset or calls["gvarset"]
        self.starthw, self.seteparam, self.softjog = starthw, seteparam, softjog
        self.software = software
        self.io = io
        self.registers = registers
        #: the debugger's view of this procedure (controller/debugger.py ``Watch``):
        #: ``marks`` (per code offset, watched or not), ``brk(pc, rets)`` (True: halt
        #: before pc), ``table(program, base)`` (a list true where marked or ``base``
        #: is, kept so as marks change)
        self.debug = None

    def for_expression(self, write=None) -> "Host":
        """The host an expression (a breakpoint condition, an evaluate) runs on
        through the reference interpreter: this one's reads and its writes, or
        ``write`` (a function refusing them) in place of each write; no
        latency, no debugger."""
        return Host(plain=self.plain, **{
            c.host: write if write is not None and c.writes else getattr(self, c.host)
            for c in BUILTINS.values()})

    def replace(self, **changes) -> "Host":
        """A copy of this host (its debugger view aside) with ``changes`` (a
        target's own gvarget and gvarset over this one's, say)."""
        kw = {name: getattr(self, name) for name in self.__slots__ if name != "debug"}
        if "gvarget" in changes and "registers" not in changes:
            kw["registers"] = None          # the store read was the old gvarget's
        kw.update(changes)
        return Host(**kw)


# ------------------------------------------------------------- pre-decoding
# The interpreter walks the bytes once per program into per-offset tables
# (kind, argument, next offset). A kind is what the interpreter does for an
# opcode; opcodes of one role in opcodes.py share one (every constant push is
# K_CONST, every binary operator K_BINARY with its semantics function as the
# argument, LOOP and YIELD K_TICK_END, every built-in call K_BUILTIN with its
# row of opcodes.BUILTINS).

(K_NOP, K_CONST, K_LOAD, K_STORE, K_INC, K_DEC, K_POP, K_BINARY, K_DIVIDE, K_UNARY,
 K_JMP, K_JZ, K_JNZ, K_TICK_END, K_CALL, K_RET, K_EXIT, K_BUILTIN, K_GVARGET, K_END) = range(20)

#: What a procedure's generator yields when the debugger halts it mid-tick (a tick
#: end yields the code offset of the instruction that ended the tick).
HALT = object()

_KIND_OF: dict[Op, int] = {
    Op.NOP: K_NOP, Op.LOAD: K_LOAD, Op.STORE: K_STORE, Op.INC: K_INC, Op.DEC: K_DEC,
    Op.POP: K_POP, Op.CALL: K_CALL, Op.RET: K_RET, Op.EXIT: K_EXIT,
    **{op: K_BUILTIN for op in BUILTINS},
    Op.GVARGET: K_GVARGET,                 # a built-in call with a latency of its own
    **{op: K_CONST for op in HAS_CONST | set(IMPLICIT_CONST)},
    **{op: K_DIVIDE if semantics.BINARY[op].divides else K_BINARY for op in BINARY},
    **{op: K_UNARY for op in UNARY},
    **{op: K_TICK_END for op in ENDS_TICK},
    **{op: K_JMP for op in HAS_JREL & NO_FALLTHROUGH},
    **{op: K_JZ for op in JUMPS_IF_ZERO},
    **{op: K_JNZ for op in JUMPS_IF_NOT_ZERO - ENDS_TICK},
}
assert set(_KIND_OF) == set(Op), set(Op) - set(_KIND_OF)

#: the fault of a zero divisor, by opcode
_ZERO_DIVISOR = {Op.DIV: FAULT_DIV, Op.MOD: FAULT_MOD}

_DECODED: dict[tuple[bytes, int], tuple[list, list, list]] = {}


def decoded(program: Program) -> tuple[list, list, list]:
    """(kinds, args, nexts), each indexed by code offset; offset len(code) is
    K_END. The argument of an instruction is what its kind needs: a constant's
    value, a slot, a jump's or call's target, an operator's function
    (K_DIVIDE: with its fault), a tick end's (target, whether it pops a
    condition), a built-in call's (Host function, arguments, gives a value)."""
    key = (program.code, program.entry)
    hit = _DECODED.get(key)
    if hit is not None:
        return hit
    code = program.code
    n = len(code)
    kinds: list = [None] * (n + 1)
    args: list = [None] * (n + 1)
    nexts: list = [None] * (n + 1)
    for ins in validate(code, program.entry):
        op, k = ins.op, _KIND_OF[ins.op]
        kinds[ins.offset] = k
        nexts[ins.offset] = ins.end
        if k == K_CONST:
            arg = IMPLICIT_CONST.get(op, ins.arg)
        elif k == K_BINARY:
            arg = semantics.BINARY[op].fn
        elif k == K_DIVIDE:
            arg = (semantics.BINARY[op].fn, _ZERO_DIVISOR[op])
        elif k == K_UNARY:
            arg = semantics.UNARY[op].fn
        elif k == K_TICK_END:
            arg = (ins.end if op is Op.YIELD else ins.target, op in COND_JUMPS)
        elif k == K_BUILTIN:
            c = BUILTINS[op]
            arg = (c.host, c.args, c.value)
        elif ins.target is not None:
            arg = ins.target
        else:
            arg = ins.arg
        args[ins.offset] = arg
    kinds[n] = K_END
    if len(_DECODED) > 512:
        _DECODED.clear()
    _DECODED[key] = (kinds, args, nexts)
    return kinds, args, nexts


# ------------------------------------------------------------------ hooks
# The debugger and coverage see the code through one per-instruction hook: a
# list ``watch`` (per code offset, true where the hook wants to see the
# instruction before it runs) and ``hook(pc, stack, calls)`` (True: halt
# before pc). Both change their lists in place while procedures run.

_UNWATCHED: dict[int, list] = {}


def _hooks(program: Program, debug, cover) -> tuple[list, Optional[Callable]]:
    """(watch, hook) for one run: the debugger's (``Host.debug``, a
    controller/debugger.py ``Watch``), coverage's (a
    controller/coverage.py ``CodeCoverage``), both, or neither."""
    if debug is None and cover is None:
        size = len(program.code) + 1
        never = _UNWATCHED.get(size)
        if never is None:
            never = _UNWATCHED[size] = [False] * size
        return never, None
    if cover is not None:
        unseen, seen = cover.watch(program)
    if debug is None:
        def cover_hook(pc: int, stack: list, calls: list) -> bool:
            seen(pc, stack)
            return False
        return unseen, cover_hook
    marks, brk = debug.marks, debug.brk
    if cover is None:
        def debug_hook(pc: int, stack: list, calls: list) -> bool:
            return brk(pc, calls)
        return marks, debug_hook
    # both: the debugger keeps a list true where marked or not yet seen
    watch = debug.table(program, unseen)

    def both(pc: int, stack: list, calls: list) -> bool:
        if unseen[pc]:
            seen(pc, stack)
            watch[pc] = marks[pc] or unseen[pc]
        return marks[pc] and brk(pc, calls)
    return watch, both


# ------------------------------------------------------------ interpreter

def run_reference(program: Program, s: list[int], host: Host, *, pc: Optional[int] = None,
                  stack: Optional[list[int]] = None, rets: tuple[int, ...] | list[int] = (),
                  count: int = 0, cover=None, passed: int = -1) -> Iterator[None]:
    """Run ``program`` over the variable slots ``s``; one ``next()`` per tick.

    The keyword arguments resume a procedure mid-tick from the state the fast
    backend hands over (see :class:`Handoff`). ``cover``, a
    :class:`~plcbuilder.controller.coverage.CodeCoverage`, records which
    instructions run (and the ways each conditional jump goes); the debugger
    (``host.debug``) may halt before an instruction: at an instruction either
    watches (see :func:`_hooks`) it is asked first, and when it halts the
    generator yields :data:`HALT` (mid-tick), then runs the instruction when
    resumed. ``passed``: the offset where a halt already happened (not asked
    again). Each tick end yields the offset of the instruction that ended the
    tick.
    """
    kinds, args, nexts = decoded(program)
    watch, hook = _hooks(program, host.debug, cover)
    if pc is None:
        pc = program.entry
    stack = [] if stack is None else list(stack)
    calls = list(rets)
    push, pop = stack.append, stack.pop
    reach = {name: getattr(host, name) for name in CALLS}
    gvarget, plain, lat = host.gvarget, host.plain, host.lat
    try:
        while True:
            if watch[pc]:                  # the debugger or coverage sees it first
                if pc != passed and hook(pc, stack, calls):
                    yield HALT             # halted before pc: it runs when resumed
                passed = -1
            k = kinds[pc]
            if count >= TICK_BUDGET:       # (running off the end is not an instruction)
                raise VMFault(pc, FAULT_END if k == K_END else FAULT_BUDGET)
            count += 1
            if k == K_LOAD:
                push(s[args[pc]])
            elif k == K_CONST:
                push(args[pc])
            elif k == K_STORE:
                s[args[pc]] = pop()
            elif k == K_BINARY:
                b = pop()
                push(args[pc](pop(), b))
            elif k == K_JZ:
                if not pop():
                    pc = args[pc]
                    continue
            elif k == K_JNZ:
                if pop():
                    pc = args[pc]
                    continue
            elif k == K_JMP:
                pc = args[pc]
                continue
            elif k == K_INC:
                i = args[pc]
                s[i] = wrap(s[i] + 1)
            elif k == K_DEC:
                i = args[pc]
                s[i] = wrap(s[i] - 1)
            elif k == K_UNARY:
                push(args[pc](pop()))
            elif k == K_TICK_END:          # LOOP pops its condition: to its target if not 0
                target, conditional = args[pc]
                at, pc = pc, target if not conditional or pop() else nexts[pc]
                if len(stack) > STACK_LIMIT:
                    raise VMFault(at, FAULT_OVERFLOW)
                passed = -1
                if (yield at) is not None:
                    raise Handoff(pc, stack, tuple(calls), 0)
                count = 0
                continue
            elif k == K_BUILTIN:           # pop the arguments, call the host, push its value
                name, n, value = args[pc]
                if n == 1:                 # (the common case, without a list)
                    r = reach[name](pop())
                else:
                    first = len(stack) - n
                    if first < 0:
                        raise VMFault(pc, FAULT_UNDERFLOW)
                    argv = stack[first:]
                    del stack[first:]
                    r = reach[name](*argv)
                if value:
                    push(r)
            elif k == K_GVARGET:           # a plain register waits for the host's latency
                a = pop()
                if lat and plain(a):
                    if len(stack) > STACK_LIMIT:
                        raise VMFault(pc, FAULT_OVERFLOW)
                    for _ in range(lat):
                        while (yield pc) is not None:
                            pass
                    count = 0
                push(gvarget(a))
            elif k == K_POP:
                pop()
            elif k == K_CALL:
                if len(calls) >= MAX_CALL_DEPTH:
                    raise VMFault(pc, FAULT_DEPTH)
                if len(stack) > STACK_LIMIT:
                    raise VMFault(pc, FAULT_OVERFLOW)
                calls.append(nexts[pc])
                pc = args[pc]
                continue
            elif k == K_RET:
                if not calls:
                    raise ProcExit(0)
                pc = calls.pop()
                continue
            elif k == K_EXIT:
                raise ProcExit(pop())
            elif k == K_DIVIDE:
                fn, fault = args[pc]
                b = pop()
                a = pop()
                if b == 0:
                    raise VMFault(pc, fault)
                push(fn(a, b))
            elif k == K_END:
                raise VMFault(pc, FAULT_END)
            # K_NOP: nothing
            pc = nexts[pc]
    except IndexError:
        if not stack or kinds[pc] is None:
            fault = VMFault(pc, FAULT_UNDERFLOW)
            fault.callers = [r - _CALL_SIZE for r in reversed(calls)]
            raise fault from None
        raise
    except VMFault as fault:
        fault.callers = [r - _CALL_SIZE for r in reversed(calls)]
        raise
