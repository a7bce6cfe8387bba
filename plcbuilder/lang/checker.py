"""The checker: names, calls, variables, control flow and the warnings of
docs/language.md ("Errors and warnings").

It resolves every name once (predefined slot, mapped register, built-in
constant, user variable) and hands the compiler a :class:`Resolved` table, so
the code generator never has to guess.
"""

from __future__ import annotations

from plcbuilder._support.records import dataclass, field, replace
from plcbuilder.bytecode import abi, semantics
from plcbuilder.bytecode import targets as T
from plcbuilder.bytecode.program import Kind
from plcbuilder.diagnostics import Diagnostic, Related, Span, error, warning
from plcbuilder.lang import ast as A
from plcbuilder.lang.builtins import FUNCTIONS, PREDEFINED, REGISTERS, VALUE_TWIN, slot_names
from plcbuilder.lang.suggest import did_you_mean
from plcbuilder.lang.targets import feature_hint, near_miss, profile

TYPE_CHECKING = False               # (typing is not imported at run time: start-up)
if TYPE_CHECKING:
    from typing import Optional


SHIFT_OPS = {"<<", ">>"}
ADD_OPS = {"+", "-"}
BIT_OPS = {"&", "|", "^"}
CMP_OPS = {"==", "!=", "<", "<=", ">", ">="}
STRICT_BINARY = {"%", "^", "&&", "||"}


@dataclass
class VarInfo:
    name: str
    first: Span
    assigned: Optional[Span] = None
    read: Optional[Span] = None
    procs: set = field(default_factory=set)      # procedures that use it


@dataclass
class Resolved:
    """What every name means, for the compiler."""
    slots: dict[str, int] = field(default_factory=dict)        # variable name -> slot
    mapped: dict[str, int] = field(default_factory=dict)       # pwm01.. -> register address
    constants: dict[str, int] = field(default_factory=dict)    # built-in names used
    user_vars: list[str] = field(default_factory=list)         # in slot order
    reachable: list[str] = field(default_factory=list)         # procedures to emit, main first
    procs: dict[str, A.ProcDef] = field(default_factory=dict)


@dataclass
class Symbols:
    """What the IDE needs for completion and hover."""
    variables: list[str] = field(default_factory=list)
    procedures: dict[str, Span] = field(default_factory=dict)
    defines: dict = field(default_factory=dict)


class CheckCache:
    """What the checker found in each procedure, kept from one compile of a
    file to the next (an open file checked at every pause in typing). A
    procedure whose tree is the same object as last time (the incremental
    parser reuses the procedures an edit did not reach), or a copy of it moved
    by some lines, is not walked again while the procedures' names, the kind,
    the target and the options are the same: its names, variables and calls
    are taken from its last walk (a walk that found a mistake is not kept: its
    messages quote the text), and whether it can reach its end (with the
    warnings on the way) from its last look, as long as the procedures it
    calls still do what they did then. Procedures not checked in the last
    compile are dropped."""

    def __init__(self):
        self.key: tuple = ()
        #: id(procedure) -> (the procedure it is a copy of, the file, moved by how many lines)
        self.moved: dict = {}
        self._old: tuple = ({}, {}, {})     # walks, flows, falls: id -> (procedure, found)
        self._new: tuple = ({}, {}, {})

    def begin(self, key: tuple) -> None:
        if key != self.key:
            self.key, self._old = key, ({}, {}, {})
        self._new = ({}, {}, {})

    def end(self) -> None:
        self._old, self._new = self._new, ({}, {}, {})

    def get(self, table: int, p: A.ProcDef):
        got = self._old[table].get(id(p))
        if got is None or got[0] is not p:
            was = self.moved.get(id(p))
            got = self._old[table].get(id(was[0])) if was is not None else None
            if got is None or got[0] is not was[0]:
                return None
            got = (p, _MOVERS[table](got[1], *was[1:]))
        self._new[table][id(p)] = got
        return got[1]

    def put(self, table: int, p: A.ProcDef, found) -> None:
        self._new[table][id(p)] = (p, found)


_new_span = tuple.__new__


def _mv(s: Optional[Span], file: str, by: int) -> Optional[Span]:
    if s is not None and s[0] == file:
        return _new_span(Span, (file, s[1] + by, s[2], s[3] + by, s[4]))
    return s


def _mv_diag(d: Diagnostic, file: str, by: int) -> Diagnostic:
    return replace(d, span=_mv(d.span, file, by),
                   related=tuple(replace(r, span=_mv(r.span, file, by)) for r in d.related))


_WALK, _FLOW, _FALLS = range(3)
_MOVERS = (
    lambda w, f, by: (w[0], w[1], w[2], [(n, _mv(a, f, by), _mv(b, f, by), _mv(c, f, by))
                                         for n, a, b, c in w[3]],
                      [(n, _mv(s, f, by)) for n, s in w[4]]),
    lambda w, f, by: (w[0], [_mv_diag(d, f, by) for d in w[1]], w[2]),
    lambda w, f, by: w,
)


class Checker:
    def __init__(self, module: A.Module, kind: Kind, strict: bool, main_file: str,
                 source_line=None, syntax_errors: bool = False, target: str = T.MYCNC,
                 defines=(), cache: Optional[CheckCache] = None):
        self.syntax_errors = syntax_errors
        self.cache = cache
        self._consulted: list[list] = []    # (callee, falls) looked up, per walk being kept
        #: the #define names in scope (for "did you mean?": they are gone from the tree)
        self.defines = tuple(defines)
        self._suggested: dict = {}
        self.profile = profile(target)
        self.module = module
        self.kind = kind
        self.strict = strict
        self.main_file = main_file
        self.source_line = source_line
        self.diags: list[Diagnostic] = []
        self.res = Resolved()
        self.vars: dict[str, VarInfo] = {}
        self.calls: dict[str, list[tuple[str, Span]]] = {}
        self.slot_names = slot_names(kind is Kind.SOFTWARE)
        self._falls_cache: dict[str, bool] = {}
        self._in_progress: set[str] = set()

    # ================================================================ driver
    def run(self) -> tuple[list[Diagnostic], Resolved, Symbols]:
        procs = self.res.procs
        for p in self.module.procs:
            if p.name in procs:
                self.diags.append(error("duplicate-procedure", f"procedure '{p.name}' is defined twice",
                                        p.name_span,
                                        related=[Related(procs[p.name].name_span, "first defined here")]))
                continue
            if p.name in FUNCTIONS:
                self.diags.append(error("reserved-name", f"'{p.name}' is a built-in function; "
                                        "a procedure cannot have its name", p.name_span))
                continue
            if p.name in self.slot_names or p.name in REGISTERS \
                    or p.name in abi.BUILTIN_NAMES or (self.profile.banks and p.name in T.BANKS):
                self.diags.append(error("reserved-name", f"'{p.name}' is a predefined name; "
                                        "a procedure cannot have its name", p.name_span))
                continue
            procs[p.name] = p
        cache = self.cache
        if cache is not None:
            cache.begin((self.kind, self.strict, self.profile.name, self.syntax_errors,
                         self.main_file, tuple(procs)))
        for p in procs.values():
            self.calls[p.name] = []
            self._current = p.name
            if cache is None:
                self._stmt(p.body)
            else:
                self._walk(p, cache)
        if not self.profile.has_main:
            self._required()
        elif "main" not in procs and not (self.syntax_errors and not procs):
            first = self.module.procs[0].name_span if self.module.procs else Span(self.main_file, 1, 1, 1, 2)
            self.diags.append(error("no-main", "no main() procedure: it is where the procedure starts",
                                    first, "add main() { ... exit(99); }"))
        self._reachability()
        self._recursion()
        self._variables()
        if not self.syntax_errors:
            # with syntax errors the tree is incomplete: flow warnings would be noise
            self._flow()
        if cache is not None:
            cache.end()
        syms = Symbols(variables=list(self.res.user_vars),
                       procedures={n: p.name_span for n, p in procs.items()})
        return self.diags, self.res, syms

    def _walk(self, p: A.ProcDef, cache: CheckCache) -> None:
        """Check one procedure's statements, or take what its last walk found;
        either way merge its names, variables and calls into the file's."""
        found = cache.get(_WALK, p)
        if found is None:
            res = self.res
            outer = res.slots, res.mapped, res.constants, self.vars
            res.slots, res.mapped, res.constants, self.vars = {}, {}, {}, {}
            n = len(self.diags)
            try:
                self._stmt(p.body)
            finally:
                inner = res.slots, res.mapped, res.constants, self.vars
                res.slots, res.mapped, res.constants, self.vars = outer
            found = (inner[0], inner[1], inner[2],
                     [(v.name, v.first, v.assigned, v.read) for v in inner[3].values()],
                     list(self.calls[p.name]))
            if len(self.diags) == n:
                cache.put(_WALK, p, found)
        else:
            self.calls[p.name] = list(found[4])
        slots, mapped, constants, names, _calls = found
        self.res.slots.update(slots)
        self.res.mapped.update(mapped)
        self.res.constants.update(constants)
        at, vars_ = p.name, self.vars
        for name, first, assigned, read in names:
            v = vars_.get(name)
            if v is None:
                v = vars_[name] = VarInfo(name, first)
            v.procs.add(at)
            if v.assigned is None:
                v.assigned = assigned
            if v.read is None:
                v.read = read

    # ================================================================ statements
    def _stmt(self, s) -> None:
        t = type(s)
        if t is A.Block:
            for x in s.stmts:
                self._stmt(x)
        elif t is A.Assign:
            self._expr(s.value)
            if s.op != "=":
                if not self.profile.compound:
                    self.diags.append(error("target-syntax", f"compound assignment '{s.op}' is not "
                                            f"part of the {self.profile.name} language",
                                            s.op_span or s.span, feature_hint("compound"),
                                            f"on {self.profile.name} write x = x "
                                            f"{s.op[0]} value;"))
                if type(s.target) is A.Name:
                    self._expr(s.target)      # x |= v reads x
            if type(s.target) is A.Index:
                self._index(s.target, write=True)
                self._width(s)
            else:
                self._target(s.target)
                self._period(s)
        elif t is A.IncDec:
            self._target(s.target, incdec=True)
        elif t is A.CallStmt:
            self._call(s.call, as_value=False)
        elif t is A.If:
            self._expr(s.cond)
            self._stmt(s.then)
            if s.orelse is not None:
                if self.strict:
                    self._strict(s.else_span or s.span, "'else'",
                                 "use a second if with the opposite condition")
                self._stmt(s.orelse)
        elif t is A.DoWhile:
            self._stmt(s.body)
            self._expr(s.cond)
        elif t is A.While:
            if self.strict:
                self._strict(s.while_span, "a 'while' loop",
                             "write do { ... } while (condition); behind an if")
            self._expr(s.cond)
            self._stmt(s.body)

    def _strict(self, span: Span, what: str, hint: str) -> None:
        self.diags.append(error("strict", f"{what} is not accepted by the controller's compiler (--strict)",
                                span, hint))

    # ================================================================ targets
    def _required(self) -> None:
        """Every procedure the target calls is defined, exactly so named."""
        procs = self.res.procs
        req = self.profile.required
        if self.syntax_errors and not procs:
            return
        at = self.module.procs[0].name_span if self.module.procs else Span(self.main_file, 1, 1, 1, 2)
        for name in req:
            if name in procs:
                continue
            miss = next((p for p in procs.values() if near_miss(p.name, req) == name), None)
            if miss is not None:
                self.diags.append(error(
                    "target-procedure", f"'{miss.name}' must be spelled {name}: the "
                    f"{self.profile.name} target calls its procedures by their exact names "
                    "(letter case included)", miss.name_span, f"rename it {name}()"))
            else:
                self.diags.append(error(
                    "target-procedure", f"no {name}() procedure: the {self.profile.name} target "
                    f"needs {', '.join(n + '()' for n in req)}", at,
                    f"add {name}() {{ {'exit(1); ' if self.profile.name == T.TGMOTION else ''}}}"))

    def _index(self, e: A.Index, write: bool = False) -> None:
        """A register bank element X[n]."""
        self._expr(e.index)
        if not self.profile.banks:
            self.diags.append(error("target-syntax", f"register banks ({e.bank}[n]) are not part "
                                    f"of the {self.profile.name} language", e.span,
                                    feature_hint("banks")))
            return
        bank = T.BANKS.get(e.bank)
        if bank is None:
            self.diags.append(error("no-bank", f"no register bank '{e.bank}' (the banks are "
                                    f"{', '.join(T.STORAGE_BANKS)} and their views "
                                    f"{e.bank[:1] if e.bank[:1] in T.STORAGE_BANKS else 'R'}_uc, "
                                    f"_c, _ui, _i, _ul, _l)", e.bank_span))
            return
        n = _const(e.index)
        if n is not None and not 0 <= n < bank.size:
            self.diags.append(error("index-range", f"{e.bank}[{n}] is out of range: {e.bank} has "
                                    f"{bank.size} elements ({e.bank}[0] .. {e.bank}[{bank.size - 1}])",
                                    e.index.span))
        if write and bank.storage in T.HZ_READ_BANKS and bank.storage != "P":
            self.diags.append(warning("read-bank", f"{e.bank} is read from the "
                                      f"{'machine' if bank.storage == 'X' else 'CNC'} at the start of "
                                      f"every tick: this write is lost then", e.span))

    def _width(self, s: A.Assign) -> None:
        """Y[0] = 0x1ff; stores 0xff: say so (a write keeps the element's width)."""
        bank = T.BANKS.get(s.target.bank)
        v = _const(s.value) if s.op == "=" else None
        if bank is not None and self.profile.banks and v is not None and not bank.fits(v):
            self.diags.append(warning("element-width", f"{s.target.bank} holds {bank.bits}-bit "
                                      f"elements: this stores {bank.stored(v)} "
                                      f"(0x{v & bank.mask:x}), not {v}", s.value.span))

    def _period(self, s: A.Assign) -> None:
        """plc1_time = 0; (a period must be at least 1 ms)."""
        if s.target.id in self.profile.periods and s.op == "=":
            v = _const(s.value)
            if v is not None and v <= 0:
                self.diags.append(error("period", f"{s.target.id} must be at least 1 (ms), "
                                        f"this sets it to {v}", s.value.span,
                                        "the seed recommends plc1_time = 16 and plc2_time = 32"))

    def _bank_name(self, name: A.Name) -> bool:
        if self.profile.banks and name.id in T.BANKS:
            self.diags.append(error("bank-name", f"'{name.id}' is a register bank; use one "
                                    f"element: {name.id}[n]", name.span))
            return True
        return False

    def _target(self, name: A.Name, incdec: bool = False) -> None:
        n = name.id
        if self._bank_name(name):
            return
        if n in self.slot_names:
            self.res.slots[n] = self.slot_names[n]
            return
        if n in REGISTERS:
            if PREDEFINED[n].read_only:
                self.diags.append(error("read-only", f"'{n}' is read-only (it reads ADC{int(n[-2:]) - 1})",
                                        name.span))
            self.res.mapped[n] = REGISTERS[n]
            return
        if n in abi.BUILTIN_NAMES:
            self.diags.append(error("assign-constant",
                                    f"'{n}' is a built-in constant ({abi.BUILTIN_NAMES[n]}); "
                                    "it cannot be assigned", name.span))
            return
        if n in self.res.procs or n in FUNCTIONS:
            self.diags.append(error("assign-procedure", f"'{n}' is a procedure, not a variable",
                                    name.span))
            return
        v = self._user_var(n, name.span)
        if v.assigned is None:
            v.assigned = name.span

    def _user_var(self, n: str, span: Span) -> VarInfo:
        v = self.vars.get(n)
        if v is None:
            v = self.vars[n] = VarInfo(n, span)
        v.procs.add(self._current)
        return v

    # ================================================================ expressions
    def _expr(self, e) -> None:
        t = type(e)
        if t is A.Num:
            return
        if t is A.Index:
            self._index(e)
            return
        if t is A.Name:
            n = e.id
            if self._bank_name(e):
                return
            if n in self.slot_names:
                self.res.slots[n] = self.slot_names[n]
            elif n in REGISTERS:
                self.res.mapped[n] = REGISTERS[n]
            elif n in abi.BUILTIN_NAMES:
                self.res.constants[n] = abi.BUILTIN_NAMES[n]
            elif n in self.res.procs or n in FUNCTIONS:
                self.diags.append(error("procedure-as-value",
                                        f"'{n}' is a procedure; call it as a statement: {n}();",
                                        e.span))
            else:
                v = self._user_var(n, e.span)
                if v.read is None:
                    v.read = e.span
            return
        if t is A.Binary:
            self._expr(e.left)
            self._expr(e.right)
            if self.strict and e.op in STRICT_BINARY:
                hints = {"%": "compute a - (a/b)*b", "^": "use (a|b) - (a&b)",
                         "&&": "nest two ifs", "||": "use two ifs or (a!=0)|(b!=0)"}
                self._strict(e.op_span, f"the operator '{e.op}'", hints[e.op])
            self._precedence(e)
            return
        if t is A.Unary:
            if self.strict:
                hint = {"-": "write 0-X (the controller's compiler has no negative literals)",
                        "!": "write (X==0)", "~": "write (0-1)^X or 0xffffffff-X"}[e.op]
                self._strict(e.span, f"unary '{e.op}'", hint)
            self._expr(e.operand)
            return
        if t is A.Paren:
            self._expr(e.expr)
            return
        if t is A.Call:
            self._call(e, as_value=True)

    def _call(self, c: A.Call, as_value: bool) -> None:
        for a in c.args:
            self._expr(a)
        b = FUNCTIONS.get(c.name)
        if b is not None:
            if as_value and not b.returns:
                if c.name == "exit":
                    self.diags.append(error("void-value", "exit() ends the procedure and has no value",
                                            c.span))
                    return
                twin = VALUE_TWIN.get(c.name)
                msg = (f"{c.name} takes {b.arity} argument{'s' if b.arity != 1 else ''} "
                       "and returns nothing")
                if twin:
                    args = self._args_text(c)
                    if c.name == "gvarset" and len(c.args) == 2:
                        args = self._text(c.args[0].span) or "addr"
                    msg += f"; did you mean {twin}({args})?"
                self.diags.append(error("void-value", msg, c.span,
                                        f"{FUNCTIONS[twin].signature if twin else b.signature}"))
                return
            if len(c.args) != b.arity:
                self.diags.append(error(
                    "arity", f"{c.name} takes {b.arity} argument{'s' if b.arity != 1 else ''} "
                             f"({', '.join(b.params)}), got {len(c.args)}", c.span, b.signature))
            if c.name == "g0moveA" and len(c.args) == 3:
                f = c.args[0]
                if isinstance(f, A.Num) and f.value & ~0x83:
                    self.diags.append(warning("g0move-flags",
                                              f"g0moveA flags 0x{f.value & 0xffffffff:x} use bits the "
                                              "controller ignores (bit0 absolute, bit1 machine "
                                              "coordinates, bit7 delayed start)", f.span))
            return
        p = self.res.procs.get(c.name)
        if p is None and self.syntax_errors and c.name in ("for", "switch", "while", "if", "return",
                                                           "sizeof"):
            return
        if p is None:
            close = self._did_you_mean(c.name, "call", lambda: [*self.res.procs, *FUNCTIONS])
            hints = [f"did you mean {close}()?"] if close else []
            self.diags.append(error("undefined-procedure", f"no procedure or function named '{c.name}'",
                                    c.name_span, *hints))
            return
        if as_value:
            self.diags.append(error("void-value", f"procedure {c.name}() returns no value", c.span,
                                    "procedures take no parameters and return nothing; share "
                                    "results through variables"))
        if c.args:
            self.diags.append(error("arity", f"procedure {c.name}() takes no arguments, "
                                             f"got {len(c.args)}", c.span,
                                    "pass values through variables (all procedures of a file share them)"))
        self.calls.setdefault(self._current, []).append((c.name, c.span))

    def _text(self, span: Span) -> Optional[str]:
        if self.source_line is None or span.line != span.end_line:
            return None
        line = self.source_line(span.file, span.line)
        if line is None:
            return None
        return line[span.col - 1:span.end_col - 1]

    def _args_text(self, c: A.Call) -> str:
        parts = [self._text(a.span) for a in c.args]
        if all(p is not None for p in parts):
            return ", ".join(parts)
        return "..."

    # ================================================================ warnings
    def _precedence(self, e: A.Binary) -> None:
        if e.op in SHIFT_OPS:
            for side, child in (("left", e.left), ("right", e.right)):
                if type(child) is A.Binary and child.op in ADD_OPS:
                    lt, rt = self._text(e.left.span), self._text(e.right.span)
                    whole = self._text(e.span)
                    value = _const(e)
                    said = f"'{whole}' is " if whole else ""
                    if side == "left":
                        means = f"({lt}){e.op}{rt}" if lt and rt else f"(a{child.op}b){e.op}c"
                    else:
                        means = f"{lt}{e.op}({rt})" if lt and rt else f"a{e.op}(b{child.op}c)"
                    val = f" = {value}" if value is not None else ""
                    self.diags.append(warning(
                        "precedence", f"{said}{means}{val}: '{child.op}' binds tighter than '{e.op}'",
                        e.span, "add parentheses to say which you mean"))
                    return
        if e.op in BIT_OPS:
            for side, child in (("left", e.left), ("right", e.right)):
                if type(child) is A.Binary and child.op in CMP_OPS:
                    whole = self._text(e.span)
                    said = f"'{whole}' " if whole else ""
                    other = e.right if side == "left" else e.left
                    # what the writer probably meant: the bit operation first
                    if side == "right":
                        inner = f"{self._text(other.span) or 'a'} {e.op} {self._text(child.left.span) or 'b'}"
                        meant = f"({inner}) {child.op} {self._text(child.right.span) or 'c'}"
                    else:
                        inner = f"{self._text(child.right.span) or 'b'} {e.op} {self._text(other.span) or 'c'}"
                        meant = f"{self._text(child.left.span) or 'a'} {child.op} ({inner})"
                    self.diags.append(warning(
                        "precedence", f"{said}compares before '{e.op}': '{child.op}' binds tighter "
                                      f"than '{e.op}'",
                        e.span, f"write {meant} if that is what you mean; add parentheses either way"))
                    return

    def _reachability(self) -> None:
        procs = self.res.procs
        roots = self.profile.roots(procs)
        start = "main" if "main" in roots else None
        order: list[str] = []
        if not roots:
            order = list(procs)
        else:
            seen = set(roots)
            stack = list(reversed(roots))
            while stack:
                n = stack.pop()
                order.append(n)
                for callee, _ in reversed(self.calls.get(n, [])):
                    if callee in procs and callee not in seen:
                        seen.add(callee)
                        stack.append(callee)
            called = "main()" if start else ", ".join(f"{r}()" for r in roots)
            for n, p in procs.items():
                if n not in seen and p.name_span.file == self.main_file:
                    self.diags.append(warning("unused-procedure",
                                              f"procedure {n}() is never called from {called}",
                                              p.name_span))
        # main (or the target's procedures) first, then the rest in source order
        rank = {p.name: i for i, p in enumerate(self.module.procs)}
        rest = sorted((n for n in order if n not in roots), key=lambda n: rank.get(n, 0))
        self.res.reachable = roots + rest

    def _recursion(self) -> None:
        graph = {n: [c for c, _ in self.calls.get(n, []) if c in self.res.procs] for n in self.res.procs}
        reported: set[frozenset] = set()
        # iterative DFS looking for back edges
        color = {n: 0 for n in graph}
        for root in graph:
            if color[root]:
                continue
            stack = [(root, iter(graph[root]))]
            path = [root]
            color[root] = 1
            while stack:
                node, it = stack[-1]
                nxt = next(it, None)
                if nxt is None:
                    stack.pop()
                    path.pop()
                    color[node] = 2
                    continue
                if color[nxt] == 1:
                    cycle = path[path.index(nxt):] + [nxt]
                    key = frozenset(cycle)
                    if key not in reported:
                        reported.add(key)
                        span = next(s for c, s in self.calls[node] if c == nxt)
                        chain = " -> ".join(f"{c}()" for c in cycle)
                        self.diags.append(warning(
                            "recursion", f"recursion: {chain}", span,
                            f"calls nest at most {abi.MAX_CALL_DEPTH} deep at run time; deeper is a "
                            "runtime fault"))
                elif color[nxt] == 0:
                    color[nxt] = 1
                    path.append(nxt)
                    stack.append((nxt, iter(graph[nxt])))

    def _variables(self) -> None:
        live = set(self.res.reachable)
        # a variable gets a slot when code that is emitted uses it
        used = [v for v in self.vars.values() if v.procs & live or not live]
        names = [v.name for v in used]
        self.res.user_vars = names
        if len(names) > abi.MAX_USER_VARS:
            extra = used[abi.MAX_USER_VARS]
            self.diags.append(error(
                "too-many-variables",
                f"too many variables: {len(names)} used, the controller has room for "
                f"{abi.MAX_USER_VARS}", extra.first,
                "the variables are: " + ", ".join(names),
                "reuse variables, or move work to another procedure file"))
        for i, n in enumerate(names):
            self.res.slots[n] = abi.FIRST_USER_SLOT + i
        if self.syntax_errors:
            return
        for v in used:
            if v.read is not None and v.assigned is None:
                # a misspelled define, predefined name or variable reads as a new variable
                close = self._did_you_mean(v.name, "value", lambda: self._value_names(used))
                hints = ([f"did you mean {close}?"] if close else
                         ["variables start at 0; assign it first, or use a #define for a constant"])
                self.diags.append(warning("never-assigned",
                                          f"'{v.name}' is read but never assigned (it is always 0)",
                                          v.read, *hints))
            elif v.assigned is not None and v.read is None and v.name not in self.profile.periods:
                # a misspelled predefined variable (timr = 5;) is a new one, never read
                close = self._did_you_mean(v.name, "store", self._store_names)
                self.diags.append(warning("never-read", f"'{v.name}' is assigned but never read",
                                          v.assigned, *([f"did you mean {close}?"] if close else [])))

    # ================================================================ did you mean?
    def _did_you_mean(self, name: str, kind: str, names) -> Optional[str]:
        """The name in scope nearest a misspelled one (``names()`` gives them),
        for at most 100 misspellings of one kind (more are not reported)."""
        key = (kind, name)
        if key not in self._suggested:
            n = self._suggested.get(kind, 0)
            self._suggested[kind] = n + 1
            self._suggested[key] = None if n >= 100 else did_you_mean(name, names())
        return self._suggested[key]

    def _value_names(self, used: list[VarInfo]) -> list[str]:
        """What a name read as a value may have meant: the defines, the
        predefined variables and registers, the built-in constants, and the
        variables the program assigns."""
        names = [*self.defines, *self.slot_names, *REGISTERS, *abi.BUILTIN_NAMES]
        names += [v.name for v in used if v.assigned is not None]
        if self.profile.banks:
            names += list(T.BANKS)
        return names

    def _store_names(self) -> list[str]:
        """What a name assigned may have meant: the predefined variables and
        the registers that can be written."""
        return [*self.slot_names, *(n for n in REGISTERS if not PREDEFINED[n].read_only)]

    # ================================================================ control flow
    def _flow(self) -> None:
        for n in self.res.reachable or list(self.res.procs):
            p = self.res.procs[n]
            self._current = n
            falls = self._body_falls(p)
            if falls and self.profile.name == T.TGMOTION and n in self.profile.required:
                self.diags.append(warning(
                    "no-status", f"{n}() can reach its end without exit(): it then returns 0"
                    + (", which aborts the PLC's start" if n == "Program_Ini" else ""),
                    p.body.end_span, "end it with exit(1); (the seed: the return value must "
                                     "always be provided)"))
            if n == "main" and falls and self.profile.has_main:
                self.diags.append(warning(
                    "main-no-exit", "main() can reach its end without exit(); "
                                    "the procedure then ends with exit code 0",
                    p.body.end_span, "end it with exit(99); (plc_exit_normal)"))

    def _body_falls(self, p: A.ProcDef) -> bool:
        """Can control reach the end of procedure p (warning of the code that
        cannot be reached on the way)?"""
        cache = self.cache
        if cache is None:
            return self._falls(p.body, report=True)
        found = cache.get(_FLOW, p)
        if found is not None and self._same_callees(found[2]):
            self.diags += found[1]
            return found[0]
        n = len(self.diags)
        self._consulted.append([])
        try:
            r = self._falls(p.body, report=True)
        finally:
            consulted = self._consulted.pop()
        cache.put(_FLOW, p, (r, self.diags[n:], consulted))
        return r

    def _same_callees(self, consulted: list) -> bool:
        """Do the procedures a kept look consulted still reach their ends as
        they did (asked in the same order: the walk would ask them so)?"""
        return all(self._proc_falls(c) == was for c, was in consulted)

    def _proc_falls(self, name: str) -> bool:
        if name in self._falls_cache:
            return self._falls_cache[name]
        if name in self._in_progress or name not in self.res.procs:
            return True
        self._in_progress.add(name)
        p = self.res.procs[name]
        cache = self.cache
        found = cache.get(_FALLS, p) if cache is not None else None
        if found is not None and self._same_callees(found[1]):
            r = found[0]
        elif cache is None:
            r = self._falls(p.body, report=False)
        else:
            self._consulted.append([])
            try:
                r = self._falls(p.body, report=False)
            finally:
                consulted = self._consulted.pop()
            cache.put(_FALLS, p, (r, consulted))
        self._in_progress.discard(name)
        self._falls_cache[name] = r
        return r

    def _falls(self, s, report: bool) -> bool:
        """Can control pass the end of statement s?"""
        t = type(s)
        if t is A.Block:
            for i, x in enumerate(s.stmts):
                if not self._falls(x, report):
                    rest = [y for y in s.stmts[i + 1:] if type(y) is not A.Empty]
                    if rest and report:
                        self.diags.append(warning("unreachable", "this code never runs: it comes "
                                                  "after exit()", rest[0].span.cover(rest[-1].span)))
                    return False
            return True
        if t is A.CallStmt:
            if s.call.name == "exit":
                return False
            if s.call.name in self.res.procs:
                r = self._proc_falls(s.call.name)
                if self._consulted:
                    self._consulted[-1].append((s.call.name, r))
                return r
            return True
        if t is A.If:
            c = _const(s.cond)
            then_falls = self._falls(s.then, report)
            else_falls = self._falls(s.orelse, report) if s.orelse is not None else True
            if c is not None:
                return then_falls if c else else_falls
            return then_falls or else_falls
        if t is A.DoWhile:
            if not self._falls(s.body, report):
                return False
            c = _const(s.cond)
            return not (c is not None and c != 0)
        if t is A.While:
            self._falls(s.body, report)
            c = _const(s.cond)
            return not (c is not None and c != 0)
        return True


# ==================================================================== constants
def _const(e) -> Optional[int]:
    """The value of a constant expression (numbers and built-in names), or None.
    The operators mean what they mean on the controller (bytecode.semantics)."""
    t = type(e)
    if t is A.Num:
        return e.value
    if t is A.Name:
        return abi.BUILTIN_NAMES.get(e.id)
    if t is A.Paren:
        return _const(e.expr)
    if t is A.Unary:
        v = _const(e.operand)
        return None if v is None else semantics.fold_unary(e.op, v)
    if t is A.Binary:
        a = _const(e.left)
        if a is None:
            return None
        if e.op == "&&" and a == 0:
            return 0
        if e.op == "||" and a != 0:
            return 1
        b = _const(e.right)
        if b is None:
            return None
        return semantics.fold_binary(e.op, a, b)
    return None


const_value = _const
