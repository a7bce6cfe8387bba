"""The fast backend: a procedure's bytecode translated once into Python.

Each procedure of a program (``main`` and every ``CALL`` target) becomes one
Python function; one that can end a tick is a generator with one ``yield`` per
tick end, so the controller drives it exactly like the reference interpreter
(:mod:`plcbuilder.controller.vm`), whose behaviour it must match exactly.

How the code is translated:

- The stack is simulated at translation time: within a basic block stack
  values are Python expressions, so ``x = x + 1`` becomes one statement. At a
  block boundary the values are stored in locals named by stack position
  (``_0``, ``_1``, …). Each operator is written as its source in
  :mod:`plcbuilder.bytecode.semantics` (the table the reference interpreter and
  the checker's folding use), over the operands' expressions. Wrapping to 32
  bits is deferred while it cannot change the result (the operators marked
  ``modular``: ``+ - * & | ^ <<``, unary ``-`` and ``~``) and applied where a
  value is stored, compared, divided, shifted right or passed out.
- Value ranges: in a function that keeps its variables in locals, the range
  of each is known at every instruction (an interval analysis, see
  :class:`_Ranges`), so ``n++`` under ``while (n < K)`` and sums of bounded
  values need no wrap at all. After a SYNC (the controller may have written
  the slots), the values read back are checked against those ranges, and one
  outside hands the procedure to the reference interpreter where it is.
- Tick ends: a plain ``yield`` whose answer is tested against None (SYNC);
  a loop's condition is taken before the tick ends, and each way ends it.
  ``HANDOVER`` (after a SYNC, where the tick end answers SYNC) raises
  :class:`~plcbuilder.controller.vm.Handoff` there, so that the reference
  interpreter goes on from that point (a debugger forcing a variable).
- A constant pin's ``portget`` reads ``io.in_bits`` where the value is used,
  and ``portset``/``portclr`` test ``io.out_bits`` before calling.
- A constant address's ``gvarget`` (not a PLS field) reads the host's register
  store (``Host.registers``) when ``make`` found it a plain register and no
  register is forced; otherwise it calls ``gvarget``.
- Control flow: a block with exactly one predecessor is written inline at its
  predecessor's branch (``if``/``else``); every other block is a *label*. A
  function with several labels is a ``while True`` loop dispatching on ``pc``
  over the labels in address order; a label whose own code jumps back to it
  (a ``do … while`` loop) is wrapped in its own ``while True`` and loops with
  ``continue``.
- Calls are ``yield from`` (or plain calls to procedures that never end a
  tick). Return addresses are only tracked where the call depth can exceed the
  limit or the code is recursive.
- The tick budget (100 000 instructions) is only counted when the program can
  possibly run that many instructions in one tick (a loop without a tick end,
  or recursion). Then every block adds its length to a counter, and a block
  that would cross the budget hands its exact state to the reference
  interpreter (:class:`~plcbuilder.controller.vm.Handoff`), which finishes the
  tick instruction by instruction and faults where it must.

Programs whose stack depth is not the same on every path into an instruction,
that pop an empty stack, or that call or return with values on the stack, are
not translated: :func:`make_runner` runs them on the reference interpreter.

Why this is one long module: the translation is one pass over one program
(stack simulation, ranges, blocks, emitting), and its parts share the same
per-block state; split, each would reach into the others' internals. The
reference interpreter (vm.py) is the short, readable definition; this file
is where the speed is, read section by section (the ``# ---`` headings).
"""

from __future__ import annotations

import zlib
from collections import namedtuple

from plcbuilder._support.lazy import Pattern
from plcbuilder._support.records import dataclass, field
from plcbuilder.bytecode import abi, semantics, softmc
from plcbuilder.bytecode.opcodes import (BINARY, BUILTINS, COND_JUMPS, ENDS_TICK, HAS_CONST, HAS_JREL,
                                         HAS_SLOT, IMPLICIT_CONST, JUMPS_IF_NOT_ZERO, JUMPS_IF_ZERO,
                                         NO_FALLTHROUGH, STACK_EFFECT, UNARY, Instruction, Op,
                                         validate)
from plcbuilder.bytecode.program import Kind, Program
from plcbuilder.bytecode.semantics import INT_MAX, INT_MIN, SHIFT_MASK, WRAP_SOURCE, Result
from plcbuilder.controller import vm
from plcbuilder.controller.vm import (FAULT_DEPTH, FAULT_DIV, FAULT_END, FAULT_MOD,
                                      MAX_CALL_DEPTH, STACK_LIMIT, TICK_BUDGET, Halted, Handoff,
                                      Host, Migrate, ProcExit, VMFault)

TYPE_CHECKING = False               # (typing is not imported at run time: start-up)
if TYPE_CHECKING:
    from typing import Callable, Iterator, Optional

__all__ = ["Unsupported", "translate", "make_runner", "factory", "io_shape"]

_LOOPS = COND_JUMPS & ENDS_TICK
_JZ = JUMPS_IF_ZERO
_JNZ = JUMPS_IF_NOT_ZERO - ENDS_TICK
_JMP = HAS_JREL & NO_FALLTHROUGH
#: Instructions that end a basic block.
_TERMINATORS = HAS_JREL | {Op.YIELD, Op.CALL, Op.RET, Op.EXIT, Op.GVARGET}
_MAX_NEST = 40            # deepest inline nesting before a block becomes a label
_SIMPLE = Pattern(r"^(_?\w+|s\[\d+\]|\(-\d+\))$")
_BITS_CAP = 62
_DUP_MAX_INS = 12         # a join block this small is written at each predecessor
_DUP_MAX_BLOCKS = 400
_YIELD = Pattern(r"\byield\b")
#: Slots the controller reads at every tick end, never kept in locals.
_UNCACHED = frozenset({abi.SLOT_MESSAGE, abi.SLOT_PROC, abi.SLOT_VEXIT, abi.SLOT_VAR00,
                       abi.SLOT_VAR00 + 1})
#: The Host attributes the translated code calls by name (make(s, host, debug) takes them)
_HOST_NAMES = (*vm.CALLS, "raw_gvarset", "pr", "plain", "lat", "seteparam", "starthw", "softjog",
               "io")
#: What the controller sends a suspended procedure to have its variables written back.
SYNC = object()
#: What the controller sends a procedure suspended at a tick end to have it raise
#: Handoff there (the reference interpreter then runs it: vm.HANDOVER); the
#: debugger throws vm.Migrate in for the same
HANDOVER = vm.HANDOVER
#: How a tick end that answers SYNC begins (then the offset it yields).
_SYNC_ANSWER = "if (yield "
#: How it waits, answering SYNC, for the tick to go on (or HANDOVER): only there.
_SYNC_WAIT = "while (_m := (yield "
#: A pseudo slot that values read from the host's ``io`` depend on: any call
#: out (which may change the pins) first writes them to temporaries.
_IO = -1


def _plain_flag(addr: int) -> str:
    """The generated code's name saying that constant address ``addr`` is a plain register."""
    return f"_g{addr}" if addr >= 0 else f"_gm{-addr}"


class Unsupported(Exception):
    """The program cannot be translated (the reason says why)."""


# ------------------------------------------------------------------ analysis

@dataclass
class _Block:
    start: int
    ins: list[Instruction]
    depth: int
    succ: list[int] = field(default_factory=list)

    @property
    def last(self) -> Optional[Instruction]:
        return self.ins[-1] if self.ins else None

    @property
    def ends_tick(self) -> bool:
        last = self.last
        return last is not None and (last.op in _LOOPS or last.op is Op.YIELD)


@dataclass
class _Func:
    start: int
    blocks: dict[int, _Block]
    callees: set[int]
    labels: set[int] = field(default_factory=set)
    gen: bool = False


def _analyze(code: bytes, entry: int,
             stops: frozenset = frozenset()) -> tuple[dict[int, _Func], int]:
    instrs = validate(code, entry)
    at = {i.offset: i for i in instrs}
    end = len(code)
    funcs: dict[int, _Func] = {}
    todo = [entry]
    while todo:
        f = todo.pop()
        if f in funcs:
            continue
        funcs[f] = func = _function(f, at, end, stops)
        todo.extend(c for c in func.callees if c not in funcs)
    return funcs, end


def _function(fstart: int, at: dict[int, Instruction], end: int,
              stops: frozenset = frozenset()) -> _Func:
    depth = {fstart: 0}
    work = [fstart]
    callees: set[int] = set()
    leaders = {fstart}
    leaders |= stops                      # a watched offset begins a block
    while work:
        pc = work.pop()
        if pc == end:
            continue
        i = at[pc]
        d = depth[pc]
        pops, pushes = STACK_EFFECT[i.op]
        if d < pops:
            raise Unsupported(f"stack underflow at {pc}")
        if i.op in (Op.CALL, Op.RET) and d:
            raise Unsupported(f"{i.op.name} with values on the stack at {pc}")
        nd = d - pops + pushes
        if nd > STACK_LIMIT:
            raise Unsupported(f"stack deeper than {STACK_LIMIT} at {pc}")
        succ = []
        if i.op in HAS_JREL:
            succ.append(i.target)
            leaders.add(i.target)
        if i.op is Op.CALL:
            callees.add(i.target)
        if i.op not in NO_FALLTHROUGH:
            succ.append(i.end)
        if i.op in _TERMINATORS:
            leaders.add(i.end)
        for t in succ:
            if t == end:
                leaders.add(end)
                depth.setdefault(end, nd)
                continue
            if t in depth:
                if depth[t] != nd:
                    raise Unsupported(f"stack depth {depth[t]} or {nd} at {t}")
            else:
                depth[t] = nd
                work.append(t)
    blocks: dict[int, _Block] = {}
    cur: Optional[_Block] = None
    for pc in sorted(depth):
        if pc == end:
            blocks[end] = _Block(end, [], depth[end])
            if cur is not None and cur.last.op not in _TERMINATORS:
                cur.succ = [end]
            cur = None
            continue
        i = at[pc]
        if cur is None or pc in leaders:
            if cur is not None and cur.last.op not in _TERMINATORS:
                cur.succ = [pc]         # falls through into a leader
            cur = blocks[pc] = _Block(pc, [], depth[pc])
        cur.ins.append(i)
        if i.op in _TERMINATORS:
            if i.op in HAS_JREL:
                cur.succ = [i.target] + ([i.end] if i.op not in NO_FALLTHROUGH else [])
            elif i.op in (Op.YIELD, Op.CALL, Op.GVARGET):
                cur.succ = [i.end]
            cur = None
    return _Func(fstart, blocks, callees)


def _postorder(roots, succ) -> tuple[list, bool]:
    """Nodes reachable from roots, each after all of its successors; and whether
    there is a cycle. Iterative (procedures can be long)."""
    color: dict = {}
    order: list = []
    cycle = False
    for root in roots:
        if root in color:
            continue
        color[root] = 1
        stack = [(root, iter(succ(root)))]
        while stack:
            node, it = stack[-1]
            for nxt in it:
                c = color.get(nxt)
                if c == 1:
                    cycle = True
                elif c is None:
                    color[nxt] = 1
                    stack.append((nxt, iter(succ(nxt))))
                    break
            else:
                stack.pop()
                color[node] = 2
                order.append(node)
    return order, cycle


def _plan(funcs: dict[int, _Func], entry: int, latency: bool) -> tuple[bool, bool]:
    """Decide (tracked, budget): whether return addresses are tracked and
    whether the tick budget must be counted at run time."""
    order, recursive = _postorder([entry], lambda f: sorted(funcs[f].callees))
    chain: dict[int, int] = {}
    for f in order:
        chain[f] = max((1 + chain.get(c, 0) for c in funcs[f].callees), default=0)
    # generator-ness: ends a tick, or calls something that does (a fixpoint: calls may recurse)
    for f in funcs.values():
        f.gen = any(b.ends_tick or (latency and b.last is not None and b.last.op is Op.GVARGET)
                    for b in f.blocks.values())
    changed = True
    while changed:
        changed = False
        for f in funcs.values():
            if not f.gen and any(funcs[c].gen for c in f.callees):
                f.gen = changed = True
    funcs[entry].gen = True
    if recursive:
        return True, True
    tracked = chain[entry] > MAX_CALL_DEPTH
    # The most instructions one frame runs between two tick ends (callees
    # included); a tick can touch every frame of a call chain.
    frame: dict[int, int] = {}
    stacked: dict[int, int] = {}
    for f in order:
        blocks = funcs[f].blocks

        def succ(b, blocks=blocks):
            blk = blocks[b]
            return () if blk.ends_tick else blk.succ

        border, cycle = _postorder(sorted(blocks), succ)
        if cycle:
            return True, True
        best: dict[int, int] = {}
        for b in border:
            blk = blocks[b]
            w = len(blk.ins)
            if blk.last is not None and blk.last.op is Op.CALL:
                w += frame[blk.last.target]
            best[b] = w + max((best[s] for s in succ(b)), default=0)
        frame[f] = max(best.values(), default=0)
        stacked[f] = frame[f] + max((stacked[c] for c in funcs[f].callees), default=0)
    budget = stacked[entry] > TICK_BUDGET
    return tracked or budget, budget


# ------------------------------------------------------------- value ranges
# In a function that keeps its variables in locals, the range of each one is
# known at every instruction (an interval analysis over its blocks: widened at
# joins, then narrowed): an increment, an add or a compare over values known
# bounded needs no 32-bit wrap. Only the function itself writes those locals
# between tick ends, except after a SYNC (the controller may have written the
# slots): then the values read back are checked against what the code after
# the tick end assumes, and if one falls outside, the reference interpreter
# takes over from there (Handoff), exactly where the procedure is.

_TOP = (INT_MIN, INT_MAX)
_WIDEN_AFTER = 3          # joins at a block before its bounds jump to the extremes
_NARROW_PASSES = 3
_CMP = {Op.LT: "<", Op.LE: "<=", Op.GT: ">", Op.GE: ">=", Op.EQ: "==", Op.NE: "!="}
_MIRROR = {"<": ">", "<=": ">=", ">": "<", ">=": "<=", "==": "==", "!=": "!="}
_NEGATE = {"<": ">=", "<=": ">", ">": "<=", ">=": "<", "==": "!=", "!=": "=="}


def _fits(lo: int, hi: int) -> tuple[int, int]:
    return (lo, hi) if INT_MIN <= lo and hi <= INT_MAX else _TOP


def _sum_range(op: Op, a: tuple[int, int], b: tuple[int, int]) -> tuple[int, int]:
    """The range of a + b, a - b or a * b before any wrap; _TOP unless it fits in 32 bits
    (then the unwrapped value is the 32-bit result)."""
    (alo, ahi), (blo, bhi) = a, b
    if op is Op.ADD:
        return _fits(alo + blo, ahi + bhi)
    if op is Op.SUB:
        return _fits(alo - bhi, ahi - blo)
    c = (alo * blo, alo * bhi, ahi * blo, ahi * bhi)
    return _fits(min(c), max(c))


def _binary_range(op: Op, a: tuple[int, int], b: tuple[int, int]) -> tuple[int, int]:
    """The range of a OP b's 32-bit result over a and b in their ranges."""
    (alo, ahi), (blo, bhi) = a, b
    o = semantics.BINARY[op]
    if alo == ahi and blo == bhi and not (o.divides and blo == 0):
        v = o.fn(alo, blo)
        return v, v
    if op in (Op.ADD, Op.SUB, Op.MUL):
        return _sum_range(op, a, b)
    if op is Op.AND:
        if alo >= 0 or blo >= 0:
            return 0, min(h for lo, h in (a, b) if lo >= 0)
        return _TOP
    if op in (Op.OR, Op.XOR):
        if alo >= 0 and blo >= 0:
            return 0, (1 << max(ahi, bhi).bit_length()) - 1
        return _TOP
    if op in _CMP:
        return 0, 1
    if op is Op.MOD and alo >= 0 and blo > 0:
        return 0, min(ahi, bhi - 1)
    if op is Op.DIV and alo >= 0 and blo > 0:
        return alo // bhi, ahi // blo
    if op is Op.SHR and alo >= 0:
        if blo == bhi:
            sh = blo & SHIFT_MASK
            return alo >> sh, ahi >> sh
        return 0, ahi
    return _TOP


def _unary_range(op: Op, a: tuple[int, int]) -> tuple[int, int]:
    lo, hi = a
    if op is Op.NEG:
        return (-hi, -lo) if lo > INT_MIN else _TOP
    if op is Op.BNOT:
        return ~hi, ~lo
    return 0, 1                       # NOT, BOOL


def _refine(state: dict, test, truth: bool) -> Optional[dict]:
    """state where the branch condition ``test`` is ``truth``; None if it cannot be."""
    if test is None:
        return state
    slot, rel, k = test
    if not truth:
        rel = _NEGATE[rel]
    lo, hi = state.get(slot, _TOP)
    if rel == "<":
        hi = min(hi, k - 1)
    elif rel == "<=":
        hi = min(hi, k)
    elif rel == ">":
        lo = max(lo, k + 1)
    elif rel == ">=":
        lo = max(lo, k)
    elif rel == "==":
        lo, hi = max(lo, k), min(hi, k)
    else:
        lo += lo == k
        hi -= hi == k
    if lo > hi:
        return None
    out = dict(state)
    if (lo, hi) == _TOP:
        out.pop(slot, None)
    else:
        out[slot] = (lo, hi)
    return out


def _join_ranges(a: dict, b: dict) -> dict:
    out = {}
    for slot, (lo, hi) in a.items():
        r = b.get(slot)
        if r is not None:
            j = (min(lo, r[0]), max(hi, r[1]))
            if j != _TOP:
                out[slot] = j
    return out


def _widen(old: dict, new: dict) -> dict:
    out = {}
    for slot, (lo, hi) in new.items():
        olo, ohi = old.get(slot, _TOP)
        r = (INT_MIN if lo < olo else lo, INT_MAX if hi > ohi else hi)
        if r != _TOP:
            out[slot] = r
    return out


class _Ranges:
    """The ranges of a function's cached variables: ``entry[b]`` at the start of
    each reachable block, ``at[offset]`` of the variable a LOAD, INC or DEC names."""

    def __init__(self, func: _Func, cached: frozenset[int], across_ticks: bool,
                 pins: Optional[tuple[int, int]]):
        self.func, self.cached, self.across, self.pins = func, cached, across_ticks, pins
        self.entry: dict[int, dict] = {}
        self.at: dict[int, tuple[int, int]] = {}
        if not cached:
            return
        blocks = func.blocks
        entry = {func.start: {}}
        seen: dict[int, int] = {}
        work = [func.start]
        while work:
            b = work.pop()
            for succ, st in self._transfer(blocks[b], entry[b]):
                old = entry.get(succ)
                if old is None:
                    new = st
                else:
                    new = _join_ranges(old, st)
                    if seen.get(succ, 0) >= _WIDEN_AFTER:
                        new = _widen(old, new)
                if new != old:
                    entry[succ] = new
                    seen[succ] = seen.get(succ, 0) + 1
                    if succ not in work:
                        work.append(succ)
        # narrowing: a block's state again from its predecessors' (in address order,
        # each update using the latest); from a post-fixpoint, each step stays one
        preds: dict[int, list[int]] = {b: [] for b in blocks}
        for b, blk in blocks.items():
            for succ in blk.succ:
                preds[succ].append(b)
        for _ in range(_NARROW_PASSES):
            for b in sorted(entry):
                new = {} if b == func.start else None
                for p in preds[b]:
                    if p not in entry:
                        continue
                    for succ, st in self._transfer(blocks[p], entry[p]):
                        if succ == b:
                            new = st if new is None else _join_ranges(new, st)
                if new is None:
                    del entry[b]
                else:
                    entry[b] = new
        self.entry = entry
        for b in entry:
            self._transfer(blocks[b], entry[b], self.at)

    def _transfer(self, blk: _Block, state: dict, record: Optional[dict] = None):
        """Run blk over state: the (successor, state) of each way out that can be taken."""
        cached = self.cached
        state = dict(state)
        stack: list = [(_TOP, None)] * blk.depth     # (range, test or ("val", slot))

        def modified(slot):
            for k, (r, t) in enumerate(stack):
                if t is not None and t[0 if len(t) == 3 else 1] == slot:
                    stack[k] = (r, None)

        test = None
        for i in blk.ins:
            op = i.op
            if op in HAS_CONST or op in IMPLICIT_CONST:
                v = IMPLICIT_CONST.get(op, i.arg)
                stack.append(((v, v), None))
            elif op is Op.LOAD:
                r = state.get(i.arg, _TOP) if i.arg in cached else _TOP
                if record is not None and i.arg in cached:
                    record[i.offset] = r
                stack.append((r, ("val", i.arg) if i.arg in cached else None))
            elif op is Op.STORE:
                (r, _t) = stack.pop()
                modified(i.arg)
                if i.arg in cached:
                    if r == _TOP:
                        state.pop(i.arg, None)
                    else:
                        state[i.arg] = r
            elif op in (Op.INC, Op.DEC):
                modified(i.arg)
                if i.arg in cached:
                    lo, hi = state.get(i.arg, _TOP)
                    if record is not None:
                        record[i.offset] = (lo, hi)
                    d = 1 if op is Op.INC else -1
                    r = _fits(lo + d, hi + d)
                    if lo == hi:
                        r = (semantics.wrap(lo + d),) * 2
                    if r == _TOP:
                        state.pop(i.arg, None)
                    else:
                        state[i.arg] = r
            elif op in BINARY:
                (b, tb), (a, ta) = stack.pop(), stack.pop()
                t = None
                if op in _CMP:
                    if ta is not None and ta[0] == "val" and b[0] == b[1]:
                        t = (ta[1], _CMP[op], b[0])
                    elif tb is not None and tb[0] == "val" and a[0] == a[1]:
                        t = (tb[1], _MIRROR[_CMP[op]], a[0])
                stack.append((_binary_range(op, a, b), t))
            elif op in UNARY:
                a, ta = stack.pop()
                t = None
                if ta is not None and op in (Op.NOT, Op.BOOL):
                    if ta[0] == "val":
                        t = (ta[1], "==" if op is Op.NOT else "!=", 0)
                    else:
                        t = ta if op is Op.BOOL else (ta[0], _NEGATE[ta[1]], ta[2])
                stack.append((_unary_range(op, a), t))
            elif op is Op.PORTGET:
                (a, _t) = stack.pop()
                pin = a[0] if a[0] == a[1] else None
                bit = self.pins is not None and pin is not None and 0 <= pin < self.pins[0]
                stack.append(((0, 1) if bit else _TOP, None))
            elif op is Op.GVARGET:
                stack.pop()
                stack.append((_TOP, None))
            elif op in (Op.JZ8, Op.JZ16, Op.JNZ8, Op.JNZ16, Op.LOOP8, Op.LOOP16):
                r, t = stack.pop()
                if t is not None and t[0] == "val":
                    t = (t[1], "!=", 0)
                test = (r, t)
            else:
                pops, pushes = STACK_EFFECT[op]
                for _ in range(pops):
                    stack.pop()
                stack.extend([(_TOP, None)] * pushes)
        last = blk.last
        outs = []
        if last is not None and (last.op in _JZ or last.op in _JNZ or last.op in _LOOPS):
            (lo, hi), t = test
            for succ, truth in ((last.target, last.op not in _JZ), (last.end, last.op in _JZ)):
                if (truth and hi == lo == 0) or (not truth and not lo <= 0 <= hi):
                    continue                   # a condition that cannot be so
                st = _refine(state, t, truth)
                if st is not None:
                    outs.append((succ, st if self.across or last.op not in _LOOPS else {}))
            return outs
        if blk.ends_tick and not self.across:
            state = {}
        return [(succ, state) for succ in blk.succ]


# ---------------------------------------------------------------- code gen

class _V:
    """A value on the simulated stack: a Python expression and what is known about it."""

    __slots__ = ("e", "exact", "isbool", "slots", "temps", "bits", "const", "rng")

    def __init__(self, e: str, exact: bool = True, isbool: bool = False, slots=frozenset(),
                 temps=frozenset(), bits: int = 31, const: Optional[int] = None,
                 rng: Optional[tuple[int, int]] = None):
        self.e, self.exact, self.isbool = e, exact, isbool
        self.slots, self.temps, self.bits, self.const = slots, temps, bits, const
        #: the range of an exact value, where it is known narrower than 32 bits
        self.rng = rng if rng != _TOP else None
        if self.rng is not None:
            self.bits = max(abs(rng[0]).bit_length(), abs(rng[1]).bit_length(), 1)


def _const(v: int) -> _V:
    return _V(str(v) if v >= 0 else f"({v})", const=v, bits=max(v.bit_length(), 1), rng=(v, v))


def _pos(k: int) -> _V:
    name = f"_{k}"
    return _V(name, temps=frozenset({name}))


def _join(*vs: _V) -> tuple[frozenset, frozenset]:
    slots = frozenset().union(*(v.slots for v in vs))
    temps = frozenset().union(*(v.temps for v in vs))
    return slots, temps


class _TooDeep(Exception):
    def __init__(self, block: int):
        self.block = block


@dataclass
class _Ctx:
    func: _Func
    label: int
    wrapped: bool


class _Gen:
    def __init__(self, program: Program, latency: bool, pins: Optional[tuple[int, int]] = None,
                 debug: bool = False):
        self.program = program
        #: watched: every statement start asks the debugger (``B[pc] and brk(pc, rets)``)
        self.debug = debug
        self.stops = frozenset(e.pc for e in program.lines) if debug else frozenset()
        self.latency = latency
        #: (input count, output count[, levels]) of a host whose ``io`` may be read directly
        self.pins = pins
        #: its io also keeps a list per pin (in_levels, out_on)
        self.levels = bool(pins and len(pins) > 2 and pins[2])
        #: slots the function being written keeps in locals (``v<slot>``)
        self.cached: frozenset[int] = frozenset()
        self.software = program.kind is Kind.SOFTWARE
        self.funcs, self.end = _analyze(program.code, program.entry, self.stops)
        self.tracked, self.budget = _plan(self.funcs, program.entry, latency)
        if debug:
            self.tracked = True            # a halt names the call stack
        self.out: list[str] = []
        self.ntemp = 0
        #: the constant addresses gvarget reads (from the host's register store
        #: where they are plain registers: ``_g<addr>`` says so, set by make)
        self.reads: set[int] = set()
        self.ranges = _Ranges(None, frozenset(), False, pins)

    # -------------------------------------------------------------- helpers
    def emit(self, ind: int, text: str) -> None:
        self.out.append("    " * ind + text)

    def temp(self, prefix: str = "_t") -> str:
        self.ntemp += 1
        return f"{prefix}{self.ntemp}"

    @staticmethod
    def as_int(v: _V) -> str:
        """An expression for v's exact 32-bit value."""
        if v.const is not None:
            return v.e
        if v.isbool:
            return f"(1 if {v.e} else 0)"
        if v.exact:
            return v.e
        return WRAP_SOURCE.format(v=v.e)

    @staticmethod
    def as_cond(v: _V) -> str:
        if v.isbool or v.exact:
            return v.e
        return f"({v.e} & 4294967295)"

    def tight(self, v: _V) -> _V:
        if v.exact or v.const is not None:
            return v
        return _V(self.as_int(v), slots=v.slots, temps=v.temps)

    def materialize(self, v: _V, ind: int) -> _V:
        if v.const is not None:
            return v
        name = self.temp()
        self.emit(ind, f"{name} = {self.as_int(v)}")
        return _V(name, rng=v.rng if v.exact and not v.isbool else None)

    def invalidate(self, stack: list[_V], slot: int, ind: int) -> None:
        for k, v in enumerate(stack):
            if slot in v.slots:
                stack[k] = self.materialize(v, ind)

    @staticmethod
    def flushed_names(stack: list[_V]) -> set[str]:
        """The position names flush(stack) assigns."""
        return {f"_{k}" for k, v in enumerate(stack)
                if not (v.e == f"_{k}" and v.exact and not v.isbool)}

    def flush(self, stack: list[_V], ind: int) -> list[_V]:
        names, values = [], []
        for k, v in enumerate(stack):
            name = f"_{k}"
            if v.e == name and v.exact and not v.isbool:
                continue
            names.append(name)
            values.append(self.as_int(v))
        if names:
            self.emit(ind, f"{', '.join(names)} = {', '.join(values)}")
        return [_pos(k) for k in range(len(stack))]

    def call_args(self, ret: int) -> str:
        if self.budget:
            return f"rets + ({ret},), n"
        if self.tracked:
            return f"rets + ({ret},)"
        return ""

    # ------------------------------------------------------------ functions
    def generate(self) -> str:
        self.out = []
        #: some function keeps variables in locals: every tick end answers SYNC
        self.syncs = any(self._cacheable(f) for f in self.funcs.values())
        self.emit(0, "def make(s, host, debug):")
        # the host's functions as the closures' free variables (Host's own names)
        self.emit(1, f"{', '.join(_HOST_NAMES)}, = {', '.join('host.' + n for n in _HOST_NAMES)},")
        self.emit(1, "B, brk = (debug.marks, debug.brk) if debug is not None else (None, None)")
        mark = len(self.out)
        for start in sorted(self.funcs):
            self.function(self.funcs[start])
        if self.reads:
            # Host.registers: a constant plain register is read from the store
            # while no register is forced (what gvarget would do, without the call)
            self.out[mark:mark] = [
                "    _rget, _held = (host.registers[0].get, host.registers[1]) "
                "if host.registers is not None else (None, None)",
                *(f"    {_plain_flag(a)} = _rget is not None and plain({a})"
                  for a in sorted(self.reads))]
        entry = self.program.entry
        args = "(), 0" if self.budget else "()" if self.tracked else ""
        self.emit(1, f"return f_{entry}({args})")
        return "\n".join(self.out) + "\n"

    def function(self, func: _Func) -> None:
        blocks = func.blocks
        indeg = {b: 0 for b in blocks}
        indeg[func.start] += 1
        for b in blocks.values():
            for s in b.succ:
                indeg[s] += 1
        func.labels = {b for b, n in indeg.items() if n != 1} | {func.start}
        self._duplicate_tails(func)
        while True:
            mark = len(self.out)
            try:
                self._function_body(func)
                return
            except _TooDeep as exc:
                del self.out[mark:]
                func.labels.add(exc.block)

    def _duplicate_tails(self, func: _Func) -> None:
        """Write small join blocks inline at each of their predecessors instead
        of dispatching to them (an ``if`` without ``else`` then loops without
        going through the dispatcher). Keeps every cycle through a label and
        the code at most about twice as large."""
        blocks = func.blocks
        if len(blocks) > _DUP_MAX_BLOCKS:
            return
        size = sum(len(b.ins) for b in blocks.values())
        budget = 2 * size + 64
        for b in sorted(func.labels):
            if b == func.start or len(blocks[b].ins) > _DUP_MAX_INS:
                continue
            trial = func.labels - {b}
            emitted = self._emitted(func, trial)
            if emitted is not None and emitted <= budget:
                func.labels = trial

    @staticmethod
    def _emitted(func: _Func, labels: set[int]) -> Optional[int]:
        """How many instructions the function's code has with these labels, or
        None if some cycle would pass through no label."""
        blocks = func.blocks
        inline = [b for b in blocks if b not in labels]
        order, cycle = _postorder(inline, lambda b: [s for s in blocks[b].succ
                                                     if s not in labels])
        if cycle:
            return None
        preds: dict[int, list[int]] = {b: [] for b in blocks}
        for b, blk in blocks.items():
            for s in blk.succ:
                preds[s].append(b)
        count = {b: 1 for b in labels}
        for b in reversed(order):          # predecessors first
            count[b] = sum(count.get(p, 0) for p in preds[b])
        return sum(count.get(b, 0) * len(blk.ins) for b, blk in blocks.items())

    def _cacheable(self, func: _Func) -> frozenset[int]:
        """The slots a function may keep in locals: a function that ends ticks
        and calls nothing, in a program that neither counts the tick budget nor
        waits for gvarget, keeps the variables that only it can see between
        tick ends (not those the controller reads every tick: message, proc,
        vexit, var00 and var01, which a message carries)."""
        if self.budget or self.latency or self.debug or not func.gen or func.callees:
            return frozenset()
        used = {i.arg for b in func.blocks.values() for i in b.ins
                if i.op in HAS_SLOT}
        return frozenset(used - _UNCACHED)

    def _function_body(self, func: _Func) -> None:
        params = ["rets", "n"] if self.budget else ["rets"] if self.tracked else []
        # the slots and the pins as the function's own locals (cheaper than the closure's)
        params += ["s=s"]
        if self.pins:
            params += ["ins=io.in_levels", "outs=io.out_on"] if self.levels else ["io=io"]
        self.emit(1, f"def f_{func.start}({', '.join(params)}):")
        mark = len(self.out)
        self.cached = self._cacheable(func)
        # ranges hold across tick ends in main (a SYNC that breaks one hands over)
        self.ranges = _Ranges(func, self.cached, func.start == self.program.entry, self.pins)
        base = 2
        if self.cached:
            # locals from the slots at entry, back to the slots however the function
            # leaves (return, exit, fault, close) and whenever the controller asks (SYNC)
            self.emit(2, self._load_cached())
            self.emit(2, "try:")
            base = 3
        labels = sorted(func.labels)
        if len(labels) == 1:
            self.region(func, labels[0], base)
        else:
            self.emit(base, f"pc = {func.start}")
            self.emit(base, "while True:")
            for lab in labels:
                self.emit(base + 1, f"if pc == {lab}:")
                self.region(func, lab, base + 2)
        if self.cached:
            self.emit(2, "finally:")
            self.emit(3, self._store_cached())
            self.cached = frozenset()
        # a generator even where constant conditions removed every tick end
        if func.gen and not any(_YIELD.search(line) for line in self.out[mark:]):
            self.out[mark:mark] = ["        if 0:", "            yield"]

    def _load_cached(self) -> str:
        order = sorted(self.cached)
        return f"{', '.join(f'v{k}' for k in order)}, = {', '.join(f's[{k}]' for k in order)},"

    def _store_cached(self) -> str:
        order = sorted(self.cached)
        return f"{', '.join(f's[{k}]' for k in order)}, = {', '.join(f'v{k}' for k in order)},"

    def region(self, func: _Func, label: int, ind: int) -> None:
        # does the code under this label jump back to it?
        seen, todo, wrapped = set(), [label], False
        while todo:
            b = todo.pop()
            if b in seen:
                continue
            seen.add(b)
            for s in func.blocks[b].succ:
                if s == label:
                    wrapped = True
                elif s not in func.labels:
                    todo.append(s)
        ctx = _Ctx(func, label, wrapped)
        if wrapped:
            self.emit(ind, "while True:")
            ind += 1
        depth = func.blocks[label].depth
        self.known = {}
        self.block(func.blocks[label], [_pos(k) for k in range(depth)], ind, ctx)

    def edge(self, target: int, stack: list[_V], ind: int, ctx: _Ctx) -> None:
        func = ctx.func
        if target not in func.labels:
            self.block(func.blocks[target], stack, ind, ctx)
            return
        self.flush(stack, ind)
        if target == ctx.label and ctx.wrapped:
            self.emit(ind, "continue")
            return
        self.emit(ind, f"pc = {target}")
        if ctx.wrapped:
            self.emit(ind, "break")
        elif target <= ctx.label:
            self.emit(ind, "continue")

    def rets(self) -> str:
        """The return addresses where a Handoff is raised: tracked, or added by
        each caller on its way out (see :meth:`terminator`, CALL)."""
        return "rets" if self.tracked else "()"

    def tick_end(self, ind: int, resume: Optional[int] = None, depth: int = 0,
                 at: int = 0) -> None:
        """A tick end: yields ``at`` (the offset of the instruction ending the
        tick); a Migrate thrown in, or HANDOVER sent, while suspended hands the
        exact state over (the variables written back first)."""
        self.emit(ind, "try:")
        if self.syncs:
            # between ticks the controller may ask for the variables (send(SYNC)):
            # they go back to the slots, and are read again when the tick goes on
            self.emit(ind + 1, f"{_SYNC_ANSWER}{at}) is not None:")
            if self.cached:
                self.emit(ind + 2, self._store_cached())
            self.emit(ind + 2, f"{_SYNC_WAIT}{at})) is not None:")
            self.emit(ind + 3, "if _m is HANDOVER:")
            self.emit(ind + 4, "raise Migrate")
            if self.cached:
                self.emit(ind + 2, self._load_cached())
                self._check_ranges(ind + 2, resume, depth)
        else:
            self.emit(ind + 1, f"if (yield {at}) is HANDOVER:")
            self.emit(ind + 2, "raise Migrate")
        self.emit(ind, "except Migrate:")
        stack = ", ".join(f"_{k}" for k in range(depth))
        self.emit(ind + 1, f"raise Handoff({resume}, [{stack}], {self.rets()}, 0) from None")
        if self.budget:
            self.emit(ind, "n = 0")
        # the controller clears message at a tick end, and a debugger may write any slot
        self.known = {}

    def _check_ranges(self, ind: int, resume: Optional[int], depth: int) -> None:
        """After a SYNC: the variables read back must be in the ranges the code
        from ``resume`` on assumes, or the reference interpreter goes on from there."""
        ranges = self.ranges
        facts = ranges.entry.get(resume) if ranges.across and resume is not None else None
        if not facts:
            return
        tests = [f"{lo} <= v{slot} <= {hi}" for slot, (lo, hi) in sorted(facts.items())]
        self.emit(ind, f"if not ({' and '.join(tests)}):")
        stack = ", ".join(f"_{k}" for k in range(depth))
        self.emit(ind + 1, f"raise Handoff({resume}, [{stack}], (), 0)")

    def branch(self, cond: str, on_true: int, on_false: int, stack: list[_V], ind: int,
               ctx: _Ctx, tick_end: Optional[int] = None) -> None:
        """``tick_end``: the offset of the LOOP whose condition this is (each way ends the tick)."""
        known = self.known
        self.emit(ind, f"if {cond}:")
        self.known = dict(known)
        if tick_end is not None:
            self.tick_end(ind + 1, on_true, len(stack), tick_end)
        self.edge(on_true, stack, ind + 1, ctx)
        self.emit(ind, "else:")
        self.known = dict(known)
        if tick_end is not None:
            self.tick_end(ind + 1, on_false, len(stack), tick_end)
        self.edge(on_false, stack, ind + 1, ctx)

    # --------------------------------------------------------------- blocks
    def block(self, blk: _Block, stack: list[_V], ind: int, ctx: _Ctx) -> None:
        """Write blk and, in a loop, every inline block that follows it at the
        same nesting level (branches recurse one level deeper)."""
        stack = list(stack)
        while True:
            if ind > _MAX_NEST and blk.start not in ctx.func.labels:
                raise _TooDeep(blk.start)
            if blk.start == self.end:
                self.emit(ind, f"raise VMFault({self.end}, {FAULT_END!r})")
                return
            if blk.start in self.stops:
                items = ", ".join(self.as_int(v) for v in stack)
                self.emit(ind, f"if B[{blk.start}] and brk({blk.start}, rets):")
                self.emit(ind + 1, f"raise Halted({blk.start}, [{items}], rets, "
                                   f"{'n' if self.budget else '0'})")
            if self.budget:
                k = len(blk.ins)
                self.emit(ind, f"n += {k}")
                self.emit(ind, f"if n > {TICK_BUDGET}:")
                items = ", ".join(self.as_int(v) for v in stack)
                self.emit(ind + 1, f"raise Handoff({blk.start}, [{items}], rets, n - {k})")
            last = blk.last
            body = blk.ins
            if last is not None and last.op in _TERMINATORS:
                body = body[:-1]
            else:
                last = None
            for i in body:
                self.instruction(i, stack, ind)
            if last is None:
                tail = blk.succ[0], stack
            else:
                tail = self.terminator(last, stack, ind, ctx)
            if tail is None:
                return
            target, stack = tail
            if target in ctx.func.labels:
                self.edge(target, stack, ind, ctx)
                return
            blk = ctx.func.blocks[target]

    def instruction(self, i: Instruction, stack: list[_V], ind: int) -> None:
        op = i.op
        if op in HAS_CONST or op in IMPLICIT_CONST:
            stack.append(_const(IMPLICIT_CONST.get(op, i.arg)))
        elif op is Op.LOAD and i.arg in self.cached:
            stack.append(_V(f"v{i.arg}", slots=frozenset({i.arg}),
                            rng=self.ranges.at.get(i.offset)))
        elif op is Op.STORE and i.arg in self.cached:
            v = stack.pop()
            self.invalidate(stack, i.arg, ind)
            self.emit(ind, f"v{i.arg} = {self.as_int(v)}")
        elif op in (Op.INC, Op.DEC) and i.arg in self.cached:
            self.invalidate(stack, i.arg, ind)
            name = f"v{i.arg}"
            lo, hi = self.ranges.at.get(i.offset, _TOP)
            if op is Op.INC:
                self.emit(ind, f"{name} += 1")
                if hi == INT_MAX:             # it may wrap
                    self.emit(ind, f"if {name} > {INT_MAX}:")
                    self.emit(ind + 1, f"{name} = {INT_MIN}")
            else:
                self.emit(ind, f"{name} -= 1")
                if lo == INT_MIN:
                    self.emit(ind, f"if {name} < {INT_MIN}:")
                    self.emit(ind + 1, f"{name} = {INT_MAX}")
        elif op is Op.LOAD:
            known = self.known.get(i.arg)
            stack.append(known if known is not None
                         else _V(f"s[{i.arg}]", slots=frozenset({i.arg})))
        elif op is Op.STORE:
            # the value is also kept in a local, so that loading it again reads the local
            v = stack.pop()
            self.invalidate(stack, i.arg, ind)
            if v.const is not None or (v.e.startswith("_t") and v.exact and not v.isbool):
                self.emit(ind, f"s[{i.arg}] = {v.e}")
                self.known[i.arg] = v if v.const is not None else _V(v.e)
            else:
                name = self.temp()
                self.emit(ind, f"s[{i.arg}] = {name} = {self.as_int(v)}")
                self.known[i.arg] = _V(name)
        elif op in (Op.INC, Op.DEC):
            self.invalidate(stack, i.arg, ind)
            known = self.known.get(i.arg)
            old = known.e if known is not None else f"s[{i.arg}]"
            name = self.temp()
            if op is Op.INC:
                self.emit(ind, f"{name} = {old} + 1")
                self.emit(ind, f"if {name} > {INT_MAX}:")
                self.emit(ind + 1, f"{name} = {INT_MIN}")
            else:
                self.emit(ind, f"{name} = {old} - 1")
                self.emit(ind, f"if {name} < {INT_MIN}:")
                self.emit(ind + 1, f"{name} = {INT_MAX}")
            self.emit(ind, f"s[{i.arg}] = {name}")
            self.known[i.arg] = _V(name)
        elif op is Op.POP:
            stack.pop()
        elif op is Op.NOP:
            pass
        elif op in BINARY:
            b = stack.pop()
            a = stack.pop()
            stack.append(self.binary(op, a, b, i.offset, ind))
        elif op in UNARY:
            stack.append(self.unary(op, stack.pop()))
        elif op in (Op.PORTSET, Op.PORTCLR):
            a = stack.pop()
            fn = "portset" if op is Op.PORTSET else "portclr"
            self.invalidate(stack, _IO, ind)
            if self.pins and a.const is not None and 0 <= a.const < self.pins[1]:
                # called only when it changes the output (the host's io contract)
                bit = f"outs[{a.const}]" if self.levels else f"io.out_bits & {1 << a.const}"
                self.emit(ind, f"if {'not ' if op is Op.PORTSET else ''}{bit}:")
                self.emit(ind + 1, f"{fn}({a.const})")
            else:
                self.emit(ind, f"{fn}({self.as_int(a)})")
        elif op is Op.PORTGET:
            a = stack.pop()
            if self.pins and a.const is not None and 0 <= a.const < self.pins[0]:
                # read where it is used (until a call out might change the pins)
                read = f"ins[{a.const}]" if self.levels else f"(io.in_bits >> {a.const} & 1)"
                stack.append(_V(read, slots=frozenset({_IO}), rng=(0, 1)))
            else:
                self.invalidate(stack, _IO, ind)
                name = self.temp()
                self.emit(ind, f"{name} = portget({self.as_int(a)})")
                stack.append(_V(name))
        elif op is Op.GVARSET:
            v = stack.pop()
            a = stack.pop()
            self.invalidate(stack, _IO, ind)
            self.emit(ind, self.gvarset(a, self.as_int(v)))
        elif op in BUILTINS:            # any other built-in call: its Host function
            c = BUILTINS[op]
            argv = stack[len(stack) - c.args:]
            del stack[len(stack) - c.args:]
            self.invalidate(stack, _IO, ind)
            call = f"{c.host}({', '.join(self.as_int(a) for a in argv)})"
            if c.value:
                name = self.temp()
                self.emit(ind, f"{name} = {call}")
                stack.append(_V(name))
            else:
                self.emit(ind, call)
        else:  # pragma: no cover - every opcode is handled above or as a terminator
            raise Unsupported(f"{op.name} inside a block")

    def gvarset(self, a: _V, value: str) -> str:
        c = a.const
        if c is None:
            return f"gvarset({self.as_int(a)}, {value})"
        if self.software:
            if c == abi.SOFT_START_HW:
                return f"starthw({value})"
            if c == abi.SOFT_START_EPARAM:
                return f"seteparam({value})"
            if abi.SOFT_JOG_BASE <= c < abi.SOFT_JOG_BASE + 8:
                return f"softjog({c - abi.SOFT_JOG_BASE}, {value})"
        if abi.PRINT_FIRST <= c <= abi.PRINT_LAST:
            return f"pr({c}, {value})"
        return f"raw_gvarset({c}, {value})"

    def binary(self, op: Op, a: _V, b: _V, pc: int, ind: int) -> _V:
        """The operator's source (semantics.BINARY) over the operands' expressions,
        wrapped only where the value must be exact."""
        o = semantics.BINARY[op]
        if a.const is not None and b.const is not None and not (o.divides and b.const == 0):
            return _const(o.fn(a.const, b.const))
        if o.divides:
            return self.divide(o, a, b, pc, ind)
        slots, temps = _join(a, b)
        if o.shifts:
            # the count is taken modulo 32, so b may stay unwrapped; >> needs an exact a
            if op is Op.SHR:
                a = self.tight(a)
                return _V(f"({o.text(a.e, b.e)})", slots=slots, temps=temps)
            shift = b.const & SHIFT_MASK if b.const is not None else SHIFT_MASK
            if a.bits + shift > _BITS_CAP:
                a = self.tight(a)
            return _V(f"({o.text(a.e, b.e)})", exact=False, slots=slots, temps=temps,
                      bits=a.bits + shift)
        if o.result is Result.BOOL:
            a, b = self.tight(a), self.tight(b)
            return _V(f"({o.text(a.e, b.e)})", isbool=True, slots=slots, temps=temps, bits=1)
        assert o.modular
        if a.rng is not None and b.rng is not None:
            # both exact and bounded: a result known to fit in 32 bits needs no wrap
            if op in (Op.ADD, Op.SUB, Op.MUL):
                r = _sum_range(op, a.rng, b.rng)
            elif o.result is Result.EXACT:        # & | ^ of exact values are exact
                r = _binary_range(op, a.rng, b.rng)
            else:
                r = _TOP
            if r != _TOP:
                return _V(f"({o.text(a.e, b.e)})", slots=slots, temps=temps, rng=r)
        if op is Op.AND:                  # a mask 0..INT_MAX bounds the value: no wrap
            c = a.const if a.const is not None else b.const
            if c is not None and 0 <= c <= INT_MAX:
                x = b if a.const is not None else a
                return _V(f"({o.text(x.e, str(c))})", slots=slots, temps=temps,
                          rng=(0, c))
        if o.result is Result.EXACT:      # & | ^: exact when both operands are
            return _V(f"({o.text(a.e, b.e)})", exact=a.exact and b.exact,
                      isbool=a.isbool and b.isbool, slots=slots, temps=temps,
                      bits=max(a.bits, b.bits))
        # + - *: wrapped later, while the value stays below 2**_BITS_CAP
        if op is Op.MUL:
            if a.bits + b.bits > _BITS_CAP:
                a, b = self.tight(a), self.tight(b)
            bits = a.bits + b.bits
        else:
            if max(a.bits, b.bits) >= _BITS_CAP:
                a, b = self.tight(a), self.tight(b)
            bits = max(a.bits, b.bits) + 1
        return _V(f"({o.text(a.e, b.e)})", exact=False, slots=slots, temps=temps, bits=bits)

    def divide(self, o: semantics.Operator, a: _V, b: _V, pc: int, ind: int) -> _V:
        """DIV / MOD: statements, in order, with the zero check."""
        fault = FAULT_DIV if o.op is Op.DIV else FAULT_MOD
        x = self.as_int(a)
        if b.const is not None and b.const == 0:
            self.emit(ind, f"raise VMFault({pc}, {fault!r})")
            return _const(0)
        if not _SIMPLE.match(x):
            t = self.temp()
            self.emit(ind, f"{t} = {x}")
            x = t
        name = self.temp()
        if b.const is not None and b.const > 0:
            self.emit(ind, f"{name} = {o.positive_divisor.format(a=x, b=b.const)}")
            return _V(name)
        y = self.as_int(b)
        if not _SIMPLE.match(y):
            t = self.temp()
            self.emit(ind, f"{t} = {y}")
            y = t
        self.emit(ind, f"if {y} == 0:")
        self.emit(ind + 1, f"raise VMFault({pc}, {fault!r})")
        self.emit(ind, f"{name} = {o.text(x, y)}")
        if o.result is Result.WRAP:        # INT_MIN / -1
            return _V(name, exact=False, bits=32)
        return _V(name)

    def unary(self, op: Op, a: _V) -> _V:
        o = semantics.UNARY[op]
        if a.const is not None:
            return _const(o.fn(a.const))
        if o.result is Result.BOOL:        # NOT, BOOL: on the value modulo 2**32
            if op is Op.BOOL and a.isbool:
                return a
            return _V(f"({o.text(self.as_cond(a))})", isbool=True, slots=a.slots, temps=a.temps,
                      bits=1)
        # NEG, BNOT
        return _V(f"({o.text(a.e)})", exact=a.exact and o.result is Result.EXACT, slots=a.slots,
                  temps=a.temps, bits=a.bits + 1)

    def terminator(self, i: Instruction, stack: list[_V], ind: int,
                   ctx: _Ctx) -> Optional[tuple[int, list[_V]]]:
        """Write a block's last instruction; returns the single successor to
        continue with at the same level, or None when it has been written."""
        op = i.op
        if op in _JMP:
            return i.target, stack
        if op in _JZ or op in _JNZ:
            c = stack.pop()
            taken_if_true = op in _JNZ
            if c.const is not None:
                jump = bool(c.const) == taken_if_true
                return (i.target if jump else i.end), stack
            on_true, on_false = (i.target, i.end) if taken_if_true else (i.end, i.target)
            self.branch(self.as_cond(c), on_true, on_false, stack, ind, ctx)
            return None
        if op in _LOOPS:
            c = stack.pop()
            if c.const is not None:
                stack = self.flush(stack, ind)
                resume = i.target if c.const else i.end
                self.tick_end(ind, resume, len(stack), i.offset)
                return resume, stack
            cond = self.as_cond(c)
            if c.temps & self.flushed_names(stack):
                cond = self.temp("_c")
                self.emit(ind, f"{cond} = {self.as_cond(c)}")
            stack = self.flush(stack, ind)
            # the condition is taken before the tick ends; each way ends it
            self.branch(cond, i.target, i.end, stack, ind, ctx, tick_end=i.offset)
            return None
        if op is Op.YIELD:
            stack = self.flush(stack, ind)
            self.tick_end(ind, i.end, len(stack), i.offset)
            return i.end, stack
        if op is Op.CALL:
            callee = self.funcs[i.target]
            if self.tracked:
                self.emit(ind, f"if len(rets) >= {MAX_CALL_DEPTH}:")
                self.emit(ind + 1, f"raise VMFault({i.offset}, {FAULT_DEPTH!r})")
            call = f"f_{i.target}({self.call_args(i.end)})"
            if callee.gen:
                call = f"yield from {call}"
            self.emit(ind, "try:")
            self.emit(ind + 1, f"n = {call}" if self.budget else call)
            self.emit(ind, "except VMFault as _e:")      # a fault names its callers
            self.emit(ind + 1, f"_e.callers.append({i.offset})")
            self.emit(ind + 1, "raise")
            if not self.tracked and callee.gen:        # a handover names them too
                self.emit(ind, "except Handoff as _h:")
                self.emit(ind + 1, f"_h.rets = ({i.end},) + tuple(_h.rets)")
                self.emit(ind + 1, "raise")
            self.known = {}
            return i.end, stack
        if op is Op.GVARGET:
            a = stack.pop()
            addr = self.as_int(a)
            if a.const is None:
                t = self.temp("_a")
                self.emit(ind, f"{t} = {addr}")
                addr = t
            stack = self.flush(stack, ind)
            if self.latency:
                self.emit(ind, f"if lat and plain({addr}):")
                self.emit(ind + 1, "for _ in range(lat):")
                self.emit(ind + 2, "try:")                   # no handover while waiting
                self.emit(ind + 3, f"while (yield {i.offset}) is not None:")
                self.emit(ind + 4, "pass")
                self.emit(ind + 2, "except Migrate:")        # the wait starts again there
                items = "".join(f"_{k}, " for k in range(len(stack)))
                self.emit(ind + 3, f"raise Handoff({i.offset}, [{items}{addr}], {self.rets()}, 0)"
                                   " from None")
                if self.budget:
                    self.emit(ind + 1, "n = 0")
                self.known.pop(abi.SLOT_MESSAGE, None)
            k = len(stack)
            if a.const is not None and softmc.pls_field(a.const) is None:
                self.reads.add(a.const)
                self.emit(ind, f"_{k} = _rget({addr}, 0) if {_plain_flag(a.const)} and not _held "
                               f"else gvarget({addr})")
            else:
                self.emit(ind, f"_{k} = gvarget({addr})")
            stack.append(_pos(k))
            return i.end, stack
        if op is Op.RET:
            if ctx.func.start == self.program.entry:
                if not self.tracked:
                    self.emit(ind, "raise ProcExit(0)")
                    return None
                self.emit(ind, "if not rets:")
                self.emit(ind + 1, "raise ProcExit(0)")
            self.emit(ind, "return n" if self.budget else "return")
            return None
        if op is Op.EXIT:
            c = stack.pop()
            self.emit(ind, f"raise ProcExit({self.as_int(c)})")
            return None
        raise Unsupported(f"terminator {op.name}")  # pragma: no cover


# ------------------------------------------------------------------ runtime

_NAMESPACE = {"VMFault": VMFault, "ProcExit": ProcExit, "Handoff": Handoff, "Halted": Halted,
              "Migrate": Migrate, "HANDOVER": HANDOVER, "tuple": tuple,
              "__builtins__": {"len": len, "range": range}}


#: A cache entry: one program translated for one host shape: ``code`` the
#: program's code (the key has only its CRC), ``make`` the compiled
#: make(s, host, debug) or None, ``why_not`` why it was not translated ("" when
#: it was), ``answers_sync`` whether its tick ends answer SYNC. (collections'
#: namedtuple: typing.NamedTuple would load typing at every command's start.)
_Translated = namedtuple("_Translated", "code make why_not answers_sync")


_CACHE: dict[tuple, _Translated] = {}


def translate(program: Program, latency: bool = False,
              pins: Optional[tuple] = None, debug: bool = False) -> str:
    """The Python source the fast backend runs for ``program`` (raises Unsupported).
    With ``pins`` (input and output count of a host with ``io``, and whether it
    keeps a list per pin: :func:`io_shape`), constant-pin port calls read and
    test ``io`` directly. ``debug``: every statement start asks the debugger
    whether it is watched and whether to halt there (then the procedure is
    handed to the reference interpreter, :class:`~plcbuilder.controller.vm.Halted`)."""
    return _Gen(program, latency, pins, debug).generate()


def _key(program: Program, latency: bool, pins, debug: bool = False) -> tuple:
    return (zlib.crc32(program.code), program.entry, int(program.kind), bool(latency), pins,
            bool(debug), tuple(e.pc for e in program.lines) if debug else ())


def factory(program: Program, latency: bool = False,
            pins: Optional[tuple] = None, debug: bool = False) -> Optional[Callable]:
    """The compiled ``make(...)`` of ``program``, or None if it cannot be translated.
    Translated once per program (by CRC of its code, entry and kind) and host shape."""
    key = _key(program, latency, pins, debug)
    hit = _CACHE.get(key)
    if hit is not None and hit.code == program.code:
        return hit.make
    try:
        src = translate(program, latency, pins, debug)
    except Unsupported as exc:
        _CACHE[key] = _Translated(program.code, None, str(exc), False)
        return None
    ns = dict(_NAMESPACE)
    _run_source(src, f"<plc {program.name} {key[0]:08x}>", ns)
    if len(_CACHE) > 256:
        _CACHE.clear()
    _CACHE[key] = _Translated(program.code, ns["make"], "", _SYNC_WAIT in src)
    return ns["make"]


def _run_source(src: str, filename: str, ns: dict) -> None:
    """Run a translation's source in ``ns``, its code named ``filename`` (what
    a traceback through it shows). ``exec`` of the text, not of
    ``compile(src, filename)``: the first ``compile()`` of a process makes the
    ast module's node types (9 M instructions, a twentieth of ``plcbuilder
    run``'s start); the name is put on the code objects after."""
    exec(src, ns)                                   # noqa: S102 - our own translation
    for name, value in ns.items():
        code = getattr(value, "__code__", None)
        if code is not None and code.co_filename == "<string>":
            value.__code__ = _renamed(code, filename)


def _renamed(code, filename: str):
    """``code`` and the code objects in it (nested functions) named ``filename``."""
    consts = tuple(_renamed(c, filename) if hasattr(c, "co_filename") else c
                   for c in code.co_consts)
    return code.replace(co_filename=filename, co_consts=consts)


def unsupported_reason(program: Program, latency: bool = False) -> Optional[str]:
    """Why ``program`` runs on the reference interpreter, or None if it is translated."""
    if factory(program, latency) is not None:
        return None
    return _CACHE[_key(program, latency, None)].why_not


def io_shape(io) -> Optional[tuple[int, int, bool]]:
    """What the translation needs to know of a host's ``io`` (see :class:`Host`):
    its pin counts, and whether it keeps a list per pin."""
    if io is None:
        return None
    return io.input_count, io.output_count, hasattr(io, "in_levels") and hasattr(io, "out_on")


def _pins(host: Host) -> Optional[tuple[int, int, bool]]:
    return io_shape(host.io)


def answers_sync(program: Program, host: Host) -> bool:
    """Whether the generator make_runner gives for this program and host keeps
    variables in locals between ticks: then ``gen.send(SYNC)`` while it is
    suspended writes them back to the slots (and the next tick reads them
    again), which is what must happen before anyone reads or writes its slots."""
    if factory(program, host.lat > 0, _pins(host)) is None:
        return False
    return _CACHE[_key(program, host.lat > 0, _pins(host))].answers_sync


def make_runner(program: Program, s: list[int], host: Host,
                watched: bool = False) -> Iterator[None]:
    """A generator running ``program`` on the slots ``s``: translated code, or the
    reference interpreter where the program cannot be translated. ``watched``
    (with ``host.debug``): the translation that asks the debugger at every
    statement start."""
    debug = host.debug if watched else None
    make = factory(program, host.lat > 0, _pins(host), debug is not None)
    if make is None:
        return vm.run_reference(program, s, host)
    return make(s, host, debug)
