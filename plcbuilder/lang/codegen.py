"""The code generator: the checked tree -> bytecode, with a line table.

The encoding is compact: constants are folded, small numbers take one or two
bytes, conditions jump directly (``if (a==0)`` is ``LOAD a; JNZ``), jumps are
one byte of offset unless they must be two (relaxed until stable), and only the
procedures main() reaches are emitted. The same source always gives the same
bytes.
"""

from __future__ import annotations

from itertools import accumulate

from plcbuilder._support.records import dataclass
from plcbuilder.bytecode import targets as T
from plcbuilder.bytecode.opcodes import LONG_FORM, Op, Operand, encode, fits, size_of
from plcbuilder.bytecode.program import Kind, LineEntry, Program
from plcbuilder.bytecode.semantics import BINARY_SYMBOL, UNARY_SYMBOL
from plcbuilder.diagnostics import Span
from plcbuilder.lang import ast as A
from plcbuilder.lang.builtins import FUNCTIONS
from plcbuilder.lang.checker import Resolved, const_value

TYPE_CHECKING = False               # (typing is not imported at run time: start-up)
if TYPE_CHECKING:
    from typing import Optional


#: Code is addressed with 16 bits: a CALL's target (Operand.ABS16) is below this,
ADDRESS_LIMIT = 1 << 16
#: and a long jump's offset (Operand.REL16) reaches at most this far either way.
JUMP_LIMIT = (1 << 15) - 1


def generate(res: Resolved, name: str, kind: Kind, file_namer,
             cache: Optional["CodeCache"] = None) -> tuple[Optional[Program], int]:
    """(the Program of the procedures ``res.reachable``, main first; its code
    size). The Program is None when the code is too large to address (a CALL
    target at or above ADDRESS_LIMIT, a jump further than a 16-bit offset): the
    size says how large it is. ``file_namer`` maps a span's file to the name
    stored in the file table. ``cache`` (kept for one file from compile to
    compile) saves walking the procedures that did not change."""
    return Generator(res, name, kind, file_namer, cache).run()


class CodeCache:
    """Each procedure's assembled code, kept from one compile of a file to the
    next: a procedure whose tree is the same object as last time (the
    incremental parser reuses the procedures an edit did not reach), or a copy
    of it moved by some lines, and whose names mean the same (the same
    variable slots and registers) is neither walked nor assembled again: only
    the program is linked. Procedures not emitted in the last compile are
    dropped."""

    def __init__(self):
        self._procs: dict[int, tuple] = {}
        #: id(procedure) -> (the procedure it is a copy of, the file, moved by how many lines)
        self.moved: dict = {}

    def get(self, p: A.ProcDef, res: Resolved) -> Optional["_Asm"]:
        got = self._procs.get(id(p))
        shift = None
        if got is None or got[0] is not p:
            was = self.moved.get(id(p))
            got = self._procs.get(id(was[0])) if was is not None else None
            if got is None or got[0] is not was[0]:
                return None
            shift = was[1:]
        slots, mapped = res.slots, res.mapped
        for n, slot, addr in got[2]:
            if slots.get(n) != slot or mapped.get(n) != addr:
                return None
        asm = got[1]
        if shift is not None:           # the same code, its lines moved
            asm = asm.moved(*shift)
            self._procs[id(p)] = (p, asm, got[2])
        return asm

    def put(self, p: A.ProcDef, asm: "_Asm", names: set, res: Resolved, keep: dict) -> None:
        slots, mapped = res.slots, res.mapped
        keep[id(p)] = (p, asm, tuple((n, slots.get(n), mapped.get(n)) for n in names))

    def keep(self, p: A.ProcDef, keep: dict) -> None:
        """Keep a procedure that was reused."""
        keep[id(p)] = self._procs[id(p)]

    def replace(self, keep: dict) -> None:
        self._procs = keep


class _Asm:
    """One procedure assembled on its own (its jumps never leave it): its
    code with the CALLs' targets still zero, where those CALLs are, and its
    line table, offsets counted from the procedure's start."""

    __slots__ = ("code", "calls", "lines", "far")

    def __init__(self, code: bytes, calls: list, lines: list, far: bool):
        self.code = code
        self.calls = calls          # (offset of a CALL, the procedure it calls)
        self.lines = lines          # (offset, (file, line)) where the line changes
        self.far = far              # a jump further than a 16-bit offset reaches

    def moved(self, file: str, by: int) -> "_Asm":
        return _Asm(self.code, self.calls,
                    [(o, (f, n + by)) if f == file else (o, (f, n)) for o, (f, n) in self.lines],
                    self.far)


@dataclass
class _Ins:
    op: Op
    arg: Optional[int]
    loc: tuple[str, int]
    label: Optional[int] = None    # jump target label
    proc: Optional[str] = None     # CALL target


class Generator:
    def __init__(self, res: Resolved, name: str, kind: Kind, file_namer,
                 cache: Optional[CodeCache] = None):
        self.res = res
        self.name = name
        self.kind = kind
        self.file_namer = file_namer
        self.items: list = []           # _Ins or ("label", id)
        self.nlabels = 0
        self.loc = ("", 0)
        self.cache = cache
        self.names: Optional[set] = None   # the names the procedure being emitted uses

    # --------------------------------------------------------------- emit
    def label(self) -> int:
        self.nlabels += 1
        return self.nlabels

    def place(self, label: int) -> None:
        self.items.append(("label", label))

    def emit(self, op: Op, arg: Optional[int] = None) -> None:
        self.items.append(_Ins(op, arg, self.loc))

    def jump(self, op: Op, label: int) -> None:
        self.items.append(_Ins(op, 0, self.loc, label=label))

    def at(self, span: Span) -> None:
        self.loc = (span.file, span.line)

    def push(self, v: int) -> None:
        if v == 0:
            self.emit(Op.PUSH0)
        elif v == 1:
            self.emit(Op.PUSH1)
        elif fits(Operand.I8, v):
            self.emit(Op.PUSH8, v)
        elif fits(Operand.I16, v):
            self.emit(Op.PUSH16, v)
        else:
            self.emit(Op.PUSH32, v)

    # --------------------------------------------------------------- driver
    def run(self) -> tuple[Optional[Program], int]:
        cache = self.cache
        keep: dict = {}
        done: list[tuple[str, _Asm]] = []
        for n in self.res.reachable:
            p = self.res.procs[n]
            asm = cache.get(p, self.res) if cache is not None else None
            if asm is not None:             # the same procedure, its names meaning the same
                cache.keep(p, keep)
                done.append((n, asm))
                continue
            self.items, self.nlabels = [], 0
            self.names = set() if cache is not None else None
            self.at(p.name_span)
            self.stmt(p.body)
            last = p.body.stmts[-1] if p.body.stmts else None
            if not (type(last) is A.CallStmt and last.call.name == "exit"):
                self.at(p.body.end_span)
                self.emit(Op.RET)
            asm = _assemble(self.items)
            if cache is not None:
                cache.put(p, asm, self.names, self.res, keep)
            done.append((n, asm))
        if cache is not None:
            cache.replace(keep)
        return self.link(done)

    # --------------------------------------------------------------- statements
    def stmt(self, s) -> None:
        t = type(s)
        if t is A.Block:
            for x in s.stmts:
                self.stmt(x)
            return
        if t is A.Empty:
            return
        self.at(s.span)
        if t is A.Assign and (type(s.target) is A.Index or s.op != "="):
            self.assign_target(s)
        elif t is A.Assign:
            n = s.target.id
            if self.names is not None:
                self.names.add(n)
            if n in self.res.mapped:
                self.push(self.res.mapped[n])
                self.expr(s.value)
                self.emit(Op.GVARSET)
            else:
                self.expr(s.value)
                self.emit(Op.STORE, self.res.slots[n])
        elif t is A.IncDec:
            n = s.target.id
            if self.names is not None:
                self.names.add(n)
            if n in self.res.mapped:
                addr = self.res.mapped[n]
                self.push(addr)
                self.push(addr)
                self.emit(Op.GVARGET)
                self.emit(Op.PUSH1)
                self.emit(Op.ADD if s.op == "++" else Op.SUB)
                self.emit(Op.GVARSET)
            else:
                self.emit(Op.INC if s.op == "++" else Op.DEC, self.res.slots[n])
        elif t is A.CallStmt:
            c = s.call
            b = FUNCTIONS.get(c.name)
            if b is not None:
                for a in c.args:
                    self.expr(a)
                self.at(s.span)
                self.emit(b.op)
                if b.returns:
                    self.emit(Op.POP)
            else:
                self.items.append(_Ins(Op.CALL, 0, self.loc, proc=c.name))
        elif t is A.If:
            c = const_value(s.cond)
            if c is not None:
                branch = s.then if c else s.orelse
                if branch is not None:
                    self.stmt(branch)
                return
            if s.orelse is None:
                end = self.label()
                self.cond(s.cond, False, end)
                self.stmt(s.then)
                self.place(end)
            else:
                other, end = self.label(), self.label()
                self.cond(s.cond, False, other)
                self.stmt(s.then)
                self.at(s.else_span or s.span)
                self.jump(Op.JMP8, end)
                self.place(other)
                self.stmt(s.orelse)
                self.place(end)
        elif t is A.DoWhile:
            top = self.label()
            self.place(top)
            self.stmt(s.body)
            self.at(s.while_span)
            self.loop_end(s.cond, top)
        elif t is A.While:
            c = const_value(s.cond)
            if c is not None and c == 0:
                return
            top, end = self.label(), self.label()
            if c is None:
                self.cond(s.cond, False, end)
            self.place(top)
            self.stmt(s.body)
            self.at(s.while_span)
            self.loop_end(s.cond, top)
            self.place(end)

    def assign_target(self, s: A.Assign) -> None:
        """A compound assignment, or a write to a register bank element
        (bytecode/targets.py: constant index -> one register; else the latches)."""
        value = s.value
        if s.op != "=":
            value = A.Binary(s.op[0], s.target, s.value, s.span, s.op_span or s.span)
        target = s.target
        if type(target) is A.Name:
            self.stmt(A.Assign(target, value, s.span))
            return
        bank = T.BANKS[target.bank]
        i = const_value(target.index)
        if i is not None:
            self.push(bank.base + i)
            self.expr(value)
            self.emit(Op.GVARSET)
            return
        self.push(T.VALUE_LATCH)
        self.expr(value)
        self.emit(Op.GVARSET)
        self.push(bank.store)
        self.expr(target.index)
        self.emit(Op.GVARSET)

    def index(self, e: A.Index) -> None:
        """Push a register bank element's value."""
        bank = T.BANKS[e.bank]
        i = const_value(e.index)
        if i is not None:
            self.push(bank.base + i)
        else:
            self.push(T.INDEX_LATCH)
            self.expr(e.index)
            self.emit(Op.GVARSET)
            self.push(bank.load)
        self.emit(Op.GVARGET)

    def loop_end(self, cond, top: int) -> None:
        """A loop condition: evaluate it, end the tick, go round again if it held."""
        c = const_value(cond)
        if c is not None:
            self.emit(Op.YIELD)
            if c:
                self.jump(Op.JMP8, top)
            return
        self.truth(cond)
        self.jump(Op.LOOP8, top)

    def truth(self, e) -> None:
        """Push a value that is non-zero exactly when e holds (not always 0/1):
        ``x != 0`` is just x, ``x == 0`` is !x."""
        while type(e) is A.Paren:
            e = e.expr
        if type(e) is A.Binary and e.op in ("==", "!="):
            if const_value(e.right) == 0 or const_value(e.left) == 0:
                other = e.left if const_value(e.right) == 0 else e.right
                self.expr(other)
                if e.op == "==":
                    self.emit(Op.NOT)
                return
        self.expr(e)

    # --------------------------------------------------------------- conditions
    def cond(self, e, when: bool, label: int) -> None:
        """Jump to label when the truth of e equals ``when``; fall through otherwise."""
        t = type(e)
        if t is A.Paren:
            return self.cond(e.expr, when, label)
        c = const_value(e)
        if c is not None:
            if bool(c) == when:
                self.jump(Op.JMP8, label)
            return
        if t is A.Unary and e.op == "!":
            return self.cond(e.operand, not when, label)
        if t is A.Binary:
            if e.op == "&&":
                if when:
                    skip = self.label()
                    self.cond(e.left, False, skip)
                    self.cond(e.right, True, label)
                    self.place(skip)
                else:
                    self.cond(e.left, False, label)
                    self.cond(e.right, False, label)
                return
            if e.op == "||":
                if when:
                    self.cond(e.left, True, label)
                    self.cond(e.right, True, label)
                else:
                    skip = self.label()
                    self.cond(e.left, True, skip)
                    self.cond(e.right, False, label)
                    self.place(skip)
                return
            if e.op in ("==", "!=") and (const_value(e.right) == 0 or const_value(e.left) == 0):
                other = e.left if const_value(e.right) == 0 else e.right
                self.expr(other)
                zero_means = (e.op == "==")   # the comparison holds when the value is zero
                self.jump(Op.JZ8 if zero_means == when else Op.JNZ8, label)
                return
        self.expr(e)
        self.jump(Op.JNZ8 if when else Op.JZ8, label)

    # --------------------------------------------------------------- expressions
    def expr(self, e) -> None:
        c = const_value(e)
        if c is not None:
            self.push(c)
            return
        t = type(e)
        if t is A.Paren:
            self.expr(e.expr)
        elif t is A.Name:
            n = e.id
            if self.names is not None:
                self.names.add(n)
            if n in self.res.mapped:
                self.push(self.res.mapped[n])
                self.emit(Op.GVARGET)
            else:
                self.emit(Op.LOAD, self.res.slots[n])
        elif t is A.Binary:
            if e.op in ("&&", "||"):
                self.logical(e)
                return
            self.expr(e.left)
            self.expr(e.right)
            self.emit(BINARY_SYMBOL[e.op])
        elif t is A.Unary:
            self.expr(e.operand)
            self.emit(UNARY_SYMBOL[e.op])
        elif t is A.Call:
            for a in e.args:
                self.expr(a)
            self.emit(FUNCTIONS[e.name].op)
        elif t is A.Index:
            self.index(e)

    def logical(self, e: A.Binary) -> None:
        false_l, end = self.label(), self.label()
        if e.op == "&&":
            self.cond(e, False, false_l)
            self.emit(Op.PUSH1)
            self.jump(Op.JMP8, end)
            self.place(false_l)
            self.emit(Op.PUSH0)
        else:
            self.cond(e, True, false_l)
            self.emit(Op.PUSH0)
            self.jump(Op.JMP8, end)
            self.place(false_l)
            self.emit(Op.PUSH1)
        self.place(end)

    # --------------------------------------------------------------- assembly
    def link(self, done: list) -> tuple[Optional[Program], int]:
        """The program of the procedures assembled (main first): their code one
        after another, each CALL given its target, and one line table."""
        starts: dict[str, int] = {}
        pos = 0
        for n, asm in done:
            starts[n] = pos
            pos += len(asm.code)
        if pos > ADDRESS_LIMIT or any(asm.far for _n, asm in done):
            return None, pos
        code = bytearray()
        lines: list[LineEntry] = []
        files: list[str] = []
        file_index: dict[str, int] = {}
        stored_as: dict[str, int] = {}
        last_loc = None
        procs: list[tuple[str, int]] = []
        for n, asm in done:
            base = len(code)
            procs.append((n, base))
            code += asm.code
            for at, callee in asm.calls:
                code[base + at:base + at + 3] = encode(Op.CALL, starts[callee])
            for at, loc in asm.lines:
                if loc == last_loc:
                    continue
                i = stored_as.get(loc[0])
                if i is None:
                    stored = self.file_namer(loc[0])
                    if stored not in file_index:
                        file_index[stored] = len(files)
                        files.append(stored)
                    i = stored_as[loc[0]] = file_index[stored]
                lines.append(LineEntry(base + at, i, loc[1]))
                last_loc = loc
        return Program(self.name, self.kind, bytes(code), 0, list(self.res.user_vars), files, lines,
                       procs), len(code)


def _assemble(items: list) -> _Asm:
    """One procedure's instructions -> its code: a jump takes one byte of
    offset unless it must take two (lengthened until every jump reaches).
    Jumps stay within their procedure, so this is what assembling the whole
    program at once gives."""
    long: set[int] = set()   # indexes of jumps that need the long form
    sizes = [0 if type(it) is tuple else _size(it, False) for it in items]
    labels = [(i, it[1]) for i, it in enumerate(items) if type(it) is tuple]
    short = [(i, it.label) for i, it in enumerate(items)
             if type(it) is not tuple and it.label is not None]
    while True:                # relax: lengthen the jumps that do not reach, until none
        ins_pos = list(accumulate(sizes, initial=0))
        ins_pos.pop()
        offsets = {label: ins_pos[i] for i, label in labels}
        grown = [(i, label) for i, label in short
                 if not fits(Operand.REL8, offsets[label] - (ins_pos[i] + 2))]
        if not grown:
            break
        for i, _label in grown:
            long.add(i)
            sizes[i] = _size(items[i], True)
        short = [j for j in short if j[0] not in long]
    far = any(not fits(Operand.REL16, offsets[items[i].label] - (ins_pos[i] + 3)) for i in long)
    code = bytearray()
    calls: list[tuple[int, str]] = []
    lines: list[tuple[int, tuple]] = []
    last_loc = None
    for i, it in enumerate(items):
        if type(it) is tuple:
            continue
        here = len(code)
        if it.loc != last_loc and it.loc[0]:
            lines.append((here, it.loc))
            last_loc = it.loc
        op = it.op
        if it.label is not None:
            is_long = i in long
            if far:                 # no program comes of it: only its size counts
                code += bytes(3 if is_long else 2)
                continue
            rel = offsets[it.label] - (here + (3 if is_long else 2))
            code += encode(LONG_FORM[op] if is_long else op, rel)
        elif it.proc is not None:
            calls.append((here, it.proc))
            code += encode(Op.CALL, 0)
        else:
            code += encode(op, it.arg)
    return _Asm(bytes(code), calls, lines, far)


def _size(it: _Ins, long: bool) -> int:
    if it.label is not None:
        return 3 if long else 2
    return size_of(it.op)
