"""The code generator and the whole compile pipeline.

    compile_source / compile_file:
        preprocess -> parse -> check -> generate -> Program (+ diagnostics)

The encoding is compact: constants are folded, small numbers take one or two
bytes, conditions jump directly (``if (a==0)`` is ``LOAD a; JNZ``), jumps are
one byte of offset unless they must be two (relaxed until stable), and only the
procedures main() reaches are emitted. The same source always gives the same
bytes.
"""

from __future__ import annotations

import os
import sys
import threading
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Optional

from plcbuilder.bytecode.opcodes import LONG_FORM, Op, Operand, encode, fits, size_of
from plcbuilder.bytecode.program import Kind, LineEntry, Program
from plcbuilder.bytecode.semantics import BINARY_SYMBOL, UNARY_SYMBOL
from plcbuilder.diagnostics import Diagnostic, Span, error
from plcbuilder.lang import ast as A
from plcbuilder.lang.checker import BUILTINS, Checker, Resolved, Symbols, const_value
from plcbuilder.lang.parser import parse_tokens
from plcbuilder.lang.preprocess import BUILTIN_PREFIX, Preprocessed, Preprocessor
from plcbuilder.lang.source import SourceSet, decode_source, read_source

COMPILER_VERSION = "1"

#: The recursion limit while compiling: the preprocessor expands a chain of
#: #defines (each naming the next) one Python frame a link, and a chain may be
#: longer than Python's default limit allows. (The checker and generator recurse
#: over the tree too, but the parser caps its depth at 256 levels.)
RECURSION_LIMIT = 4000
_limit_lock = threading.Lock()
_limit_users = 0                   # compiles running (in any thread)
_limit_saved: Optional[int] = None  # the limit to restore when the last one ends


@contextmanager
def _recursion_limit():
    """Raise the recursion limit to RECURSION_LIMIT while the block runs. The
    limit is global to the process: the first compile to start raises it and
    the last to end restores it, so concurrent compiles do not undo each other."""
    global _limit_users, _limit_saved
    with _limit_lock:
        if _limit_users == 0:
            old = sys.getrecursionlimit()
            _limit_saved = old if old < RECURSION_LIMIT else None
            if _limit_saved is not None:
                sys.setrecursionlimit(RECURSION_LIMIT)
        _limit_users += 1
    try:
        yield
    finally:
        with _limit_lock:
            _limit_users -= 1
            if _limit_users == 0 and _limit_saved is not None:
                if sys.getrecursionlimit() == RECURSION_LIMIT:   # unless changed meanwhile
                    sys.setrecursionlimit(_limit_saved)
                _limit_saved = None


# ====================================================================== options
@dataclass(frozen=True)
class CompileOptions:
    kind: Kind = Kind.HARDWARE
    strict: bool = False
    include_dirs: tuple = ()
    code_limit: Optional[int] = None   # None: the kind's default (512 / 16384)

    @property
    def limit(self) -> int:
        return self.code_limit if self.code_limit is not None else self.kind.code_limit


@dataclass
class CompileResult:
    name: str
    path: str
    kind: Kind
    program: Optional[Program]
    diagnostics: list[Diagnostic]
    sources: SourceSet
    size: Optional[int]
    limit: int
    symbols: Symbols = field(default_factory=Symbols)
    module: Optional[A.Module] = None
    includes: list[str] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        return not any(d.is_error for d in self.diagnostics)

    @property
    def errors(self) -> list[Diagnostic]:
        return [d for d in self.diagnostics if d.is_error]

    @property
    def warnings(self) -> list[Diagnostic]:
        return [d for d in self.diagnostics if not d.is_error]

    def source_line(self, file: str, line: int) -> Optional[str]:
        return self.sources.line(file, line)


# ====================================================================== pipeline
def procedure_name(path: str) -> str:
    stem = Path(path).stem
    return stem if stem and not stem.startswith("<") else "main"


def compile_source(text: str, path: str = "<input>", options: CompileOptions = CompileOptions(),
                   *, file_path: Optional[Path] = None) -> CompileResult:
    """Compile source text. ``path`` is the name diagnostics use; ``file_path``
    (when the text is a file's) locates the procedure's folder for #include."""
    if file_path is None and not path.startswith("<"):
        p = Path(path)
        file_path = p if p.parent != Path("") or p.exists() else None
    return _compile(Preprocessor(options.include_dirs), text, path, file_path, options)


def compile_bytes(data: bytes, path: str, options: CompileOptions = CompileOptions(),
                  *, file_path: Optional[Path] = None) -> CompileResult:
    text, diags = decode_source(data, path)
    if text is None:
        return _failed(path, options, diags)
    r = compile_source(text, path, options, file_path=file_path)
    r.diagnostics = sorted(diags + r.diagnostics, key=lambda d: (d.sort_key(), d.severity))
    return r


def compile_file(path, options: CompileOptions = CompileOptions(), *,
                 data: Optional[bytes] = None) -> CompileResult:
    """Compile a .plc file. Never raises on bad input: it becomes diagnostics.
    ``data``: the file's bytes when the caller has read them already."""
    p = Path(path)
    name = str(path)
    text, diags = read_source(p, name) if data is None else decode_source(data, name)
    if text is None:
        return _failed(name, options, diags)
    pp = Preprocessor(options.include_dirs)
    pp.diags.extend(diags)
    return _compile(pp, text, name, p, options)


def _failed(path: str, options: CompileOptions, diags: list[Diagnostic]) -> CompileResult:
    return CompileResult(procedure_name(path), path, options.kind, None, diags, SourceSet(), None,
                         options.limit)


def _compile(pp: Preprocessor, text: str, path: str, file_path: Optional[Path],
             options: CompileOptions) -> CompileResult:
    with _recursion_limit():
        return _compile_preprocessed(pp.run_text(text, path, file_path), path, file_path, options)


def _compile_preprocessed(pre: Preprocessed, path: str, file_path: Optional[Path],
                          options: CompileOptions) -> CompileResult:
    name = procedure_name(path)
    diags = list(pre.diagnostics)
    if options.strict:
        for span in pre.block_comments:
            diags.append(error("strict", "/* */ comments are not accepted by the controller's "
                                         "compiler (--strict)", span, "use // comments"))
        for word, span in pre.directives:
            if word not in ("include", "define"):
                diags.append(error("strict", f"#{word} is not accepted by the controller's "
                                             "compiler (--strict)", span))
    module, parse_diags = parse_tokens(pre.tokens)
    diags += parse_diags
    checker = Checker(module, options.kind, options.strict, path, pre.sources.line,
                      syntax_errors=any(d.is_error for d in diags))
    check_diags, resolved, symbols = checker.run()
    diags += check_diags
    symbols.defines = {n: (d.text, d.span) for n, d in pre.defines.items()}
    program = None
    size = None
    if not any(d.is_error for d in diags):
        program = Generator(resolved, name, options.kind, _file_namer(path, file_path)).run()
        size = program.code_size
        if size > options.limit:
            main = resolved.procs.get("main")
            diags.append(error(
                "size-limit",
                f"procedure {name} is {size} bytes of code; the limit for a "
                f"{options.kind.label} procedure is {options.limit} ({size}/{options.limit} bytes)",
                main.name_span if main else Span.point(path, 1, 1),
                "move work into a software procedure, or split it into procedures started "
                "one after another"))
            program = None
    diags.sort(key=lambda d: (d.sort_key(), d.severity))
    return CompileResult(name, path, options.kind, program, diags, pre.sources, size, options.limit,
                         symbols, module, list(pre.includes))


def _file_namer(path: str, file_path: Optional[Path]):
    """Display name of a file -> the name stored in the binary's file table:
    relative to the procedure's folder, so a build does not depend on where the
    project lives."""
    base = file_path.resolve().parent if file_path is not None else None
    main_stored = file_path.name if file_path is not None else path

    def name(display: str) -> str:
        if display == path:
            return main_stored
        if display.startswith(BUILTIN_PREFIX) or base is None:
            return display
        try:
            return os.path.relpath(Path(display).resolve(), base).replace(os.sep, "/")
        except (ValueError, OSError):
            return Path(display).name
    return name


# ====================================================================== generator
@dataclass
class _Ins:
    op: Op
    arg: Optional[int]
    loc: tuple[str, int]
    label: Optional[int] = None    # jump target label
    proc: Optional[str] = None     # CALL target


class Generator:
    def __init__(self, res: Resolved, name: str, kind: Kind, file_namer):
        self.res = res
        self.name = name
        self.kind = kind
        self.file_namer = file_namer
        self.items: list = []           # _Ins or ("label", id)
        self.nlabels = 0
        self.loc = ("", 0)

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
    def run(self) -> Program:
        proc_labels = {n: self.label() for n in self.res.reachable}
        self.proc_labels = proc_labels
        for n in self.res.reachable:
            p = self.res.procs[n]
            self.place(proc_labels[n])
            self.at(p.name_span)
            self.stmt(p.body)
            last = p.body.stmts[-1] if p.body.stmts else None
            if not (type(last) is A.CallStmt and last.call.name == "exit"):
                self.at(p.body.end_span)
                self.emit(Op.RET)
        return self.assemble()

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
        if t is A.Assign:
            n = s.target.id
            if n in self.res.mapped:
                self.push(self.res.mapped[n])
                self.expr(s.value)
                self.emit(Op.GVARSET)
            else:
                self.expr(s.value)
                self.emit(Op.STORE, self.res.slots[n])
        elif t is A.IncDec:
            n = s.target.id
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
            b = BUILTINS.get(c.name)
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
            self.emit(BUILTINS[e.name].op)

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
    def assemble(self) -> Program:
        items = self.items
        long: set[int] = set()   # indexes of jumps that need the long form
        while True:
            offsets: dict[int, int] = {}
            pos = 0
            ins_pos: list[int] = []
            for i, it in enumerate(items):
                if type(it) is tuple:
                    offsets[it[1]] = pos
                    ins_pos.append(pos)
                    continue
                ins_pos.append(pos)
                pos += _size(it, i in long)
            changed = False
            for i, it in enumerate(items):
                if type(it) is tuple or it.label is None or i in long:
                    continue
                rel = offsets[it.label] - (ins_pos[i] + 2)
                if not fits(Operand.REL8, rel):
                    long.add(i)
                    changed = True
            if not changed:
                break
        code = bytearray()
        lines: list[LineEntry] = []
        files: list[str] = []
        file_index: dict[str, int] = {}
        last_loc = None
        procs: list[tuple[str, int]] = []
        label_names = {lbl: n for n, lbl in self.proc_labels.items()}
        for i, it in enumerate(items):
            if type(it) is tuple:
                if it[1] in label_names:
                    procs.append((label_names[it[1]], len(code)))
                continue
            here = len(code)
            if it.loc != last_loc and it.loc[0]:
                stored = self.file_namer(it.loc[0])
                if stored not in file_index:
                    file_index[stored] = len(files)
                    files.append(stored)
                lines.append(LineEntry(here, file_index[stored], it.loc[1]))
                last_loc = it.loc
            op = it.op
            if it.label is not None:
                if i in long:
                    op = LONG_FORM[op]
                rel = offsets[it.label] - (here + (3 if i in long else 2))
                code += encode(op, rel)
            elif it.proc is not None:
                code += encode(Op.CALL, offsets[self.proc_labels[it.proc]])
            else:
                code += encode(op, it.arg)
        return Program(self.name, self.kind, bytes(code), 0, list(self.res.user_vars), files, lines,
                       procs)


def _size(it: _Ins, long: bool) -> int:
    if it.label is not None:
        return 3 if long else 2
    return size_of(it.op)
