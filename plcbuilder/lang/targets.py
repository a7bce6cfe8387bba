"""Target profiles for the compiler: what each controller of SPEC §9 adds to
the language, and what a program for it must define (docs/targets.md).

- ``mycnc`` (the default): §1 as it is; ``main()`` is where a procedure starts.
- ``huazhong``: one source with ``init()``, ``plc1()`` and ``plc2()``; the
  register banks ``X[n]`` … ``B[n]``, compound assignment; the periods
  ``plc1_time``/``plc2_time`` are ordinary variables the controller reads.
- ``tgmotion``: ``Program_Ini`` and ``Program_01`` … ``Program_05``, exactly
  so spelled (the seed: "mandatory, including the letter case"); compound
  assignment; shared memory through gvarget/gvarset (``tgmotion.h``).

The checker asks a :class:`Profile` what is allowed; a construct only a target
has is refused on the others with a hint that names the target that has it.

:func:`lower` rewrites, before the checker sees them, the calls a target's C
library has that the language has no construct for (the seed's macros and
function pointers); each becomes what the language already has:

- huazhong: ``axis_stat(x)`` (the seed's ``#define axis_stat(x) (F_ui[(x)*10])``)
  is ``F_ui[(x) * 10]``; ``set_m_func(proc);`` (likewise ``s``, ``b``, ``t``:
  init() "sets the response functions of the system's M, S, B, T functions")
  is ``gvarset(HZ_FUNC_REGISTER["M"], id of proc)``, and proc becomes one of the
  procedures the controller calls (:meth:`Profile.roots`);
- tgmotion: the diagnostic prints of PLC_DATA, ``RtWprintf_String(v);``,
  ``RtWprintf_Long(v);`` and ``RtWprintf_Ex(severity, v);``, are writes to the
  print registers ``TGM_RTW_*`` (the language has no strings: the value is
  printed, with the line it came from).
"""

from __future__ import annotations

from plcbuilder._support.records import dataclass, replace

from plcbuilder.bytecode import targets as T
from plcbuilder.diagnostics import Diagnostic, error
from plcbuilder.lang import ast as A

TYPE_CHECKING = False               # (typing is not imported at run time: start-up)
if TYPE_CHECKING:
    from typing import Optional

COMPOUND_OPS = ("|=", "&=", "^=", "+=", "-=")


def _is_node(x) -> bool:
    """Is ``x`` a syntax-tree node (a record of lang.ast)?"""
    return hasattr(type(x), "__record_fields__")


@dataclass(frozen=True)
class Profile:
    name: str
    required: tuple[str, ...]          # procedures that must be defined, exactly so named
    banks: bool                        # X[n] register banks
    compound: bool                     # |= &= ^= += -=
    periods: tuple[str, ...] = ()      # variables the controller reads as periods (ms)

    @property
    def has_main(self) -> bool:
        """Whether programs start at main() (myCNC) rather than at the target's procedures."""
        return not self.required

    def roots(self, defined) -> list[str]:
        """The procedures the controller calls, in the order they are emitted:
        the target's own, then the function handlers a program registers."""
        if self.has_main:
            return ["main"] if "main" in defined else []
        out = [n for n in self.required if n in defined]
        if self.name == T.HUAZHONG:
            out += [n for n in registered_handlers(defined.values()) if n not in out]
        return out


PROFILES: dict[str, Profile] = {
    T.MYCNC: Profile(T.MYCNC, (), banks=False, compound=False),
    T.HUAZHONG: Profile(T.HUAZHONG, T.HZ_PROCEDURES, banks=True, compound=True,
                        periods=T.HZ_PERIODS),
    T.TGMOTION: Profile(T.TGMOTION, T.TGM_PROCEDURES, banks=False, compound=True),
}


def profile(target: str) -> Profile:
    """The profile of a target name (an unknown name is the project's error to
    report; here it falls back to myCNC)."""
    return PROFILES.get(target, PROFILES[T.MYCNC])


def targets_with(feature: str) -> list[str]:
    """The targets that accept a feature ("banks" or "compound")."""
    return [p.name for p in PROFILES.values() if getattr(p, feature)]


def feature_hint(feature: str) -> str:
    names = targets_with(feature)
    which = " or ".join(f'"{n}"' for n in names)
    return f"this is {' and '.join(names)} syntax: set target = {which} in plcbuilder.toml"


def near_miss(name: str, required: tuple[str, ...]) -> Optional[str]:
    """The required name that ``name`` misspells by letter case or by its
    number's zero (``program_01``, ``Program_1``), or None."""
    low = name.lower().replace("_0", "_")
    for r in required:
        if r != name and r.lower().replace("_0", "_") == low:
            return r
    return None


def slots_per_cycle(cycle_us: int) -> int:
    """TG Motion: the slots of one cycle (5 for 250 and 500 µs, 10 for 1000 µs)."""
    return T.TGM_SLOTS[cycle_us]


def bank_names() -> str:
    return (", ".join(f"{n}[0..{T.BANKS[n].size - 1}]" for n in T.STORAGE_BANKS)
            + ", and their views X_uc … B_l (unsigned char, char, unsigned, int, "
              "unsigned long, long)")


# ------------------------------------------------------------------ lowering
#: the calls :func:`lower` rewrites, by target: name -> (arguments, gives a value)
MACROS: dict[str, dict[str, tuple[int, bool]]] = {
    T.HUAZHONG: {"axis_stat": (1, True),
                 **{f"set_{k.lower()}_func": (1, False) for k in T.HZ_FUNCTIONS}},
    T.TGMOTION: {"RtWprintf_String": (1, False), "RtWprintf_Long": (1, False),
                 "RtWprintf_Ex": (2, False)},
}


def lower(module: A.Module, target: str) -> tuple[A.Module, list[Diagnostic]]:
    """``module`` with the target's macro calls rewritten (see the module
    docstring) and the diagnostics of the ones that cannot be: a new Module,
    sharing every procedure that has none (so the incremental caches still hit)."""
    macros = MACROS.get(target)
    if not macros:
        return module, []
    procs = {p.name for p in module.procs}
    diags: list[Diagnostic] = []
    low = _Lowering(macros, procs, diags)
    new = [low.proc(p) for p in module.procs]
    if all(a is b for a, b in zip(new, module.procs)):
        return module, diags
    return A.Module(new), diags


def registered_handlers(procs) -> list[str]:
    """The procedures that ``set_m_func(proc)`` (lowered) registers, in order."""
    out: list[str] = []
    regs = set(T.HZ_FUNC_REGISTER.values())

    def walk(node) -> None:
        if isinstance(node, list):
            for x in node:
                walk(x)
            return
        if node is None or isinstance(node, (int, str, bool)) or not _is_node(node):
            return
        if isinstance(node, A.Call) and node.name == "gvarset" and len(node.args) == 2:
            a, b = node.args
            if isinstance(a, A.Num) and a.value in regs and isinstance(b, A.Num) and b.text \
                    and b.synthetic and b.text not in out:
                out.append(b.text)
        for name, kind in A._parts(type(node)):
            if kind in ("n", "l"):
                walk(getattr(node, name))
    for p in procs:
        walk(p.body)
    return out


class _Lowering:
    def __init__(self, macros: dict, procs: set, diags: list):
        self.macros = macros
        self.procs = procs
        self.diags = diags

    def proc(self, p: A.ProcDef) -> A.ProcDef:
        body = self.node(p.body)
        return p if body is p.body else replace(p, body=body)

    def node(self, node):
        """The node with its macro calls rewritten (the same object when it has none)."""
        if isinstance(node, list):
            new = [self.node(x) for x in node]
            return node if all(a is b for a, b in zip(new, node)) else new
        if node is None or not _is_node(node):
            return node
        if isinstance(node, A.CallStmt) and node.call.name in self.macros:
            return self.statement(node)
        if isinstance(node, A.Call) and node.name in self.macros:
            return self.value(node)
        changes = {}
        for name, kind in A._parts(type(node)):
            if kind in ("n", "l"):
                old = getattr(node, name)
                new = self.node(old)
                if new is not old:
                    changes[name] = new
        return replace(node, **changes) if changes else node

    def _arity(self, c: A.Call) -> bool:
        n, _value = self.macros[c.name]
        if len(c.args) != n:
            self.diags.append(error("arity", f"{c.name} takes {n} argument"
                                    f"{'s' if n != 1 else ''}, not {len(c.args)}", c.span))
            return False
        return True

    def value(self, c: A.Call):
        """A macro used as a value: only axis_stat(x) gives one."""
        args = [self.node(a) for a in c.args]
        if not self.macros[c.name][1]:
            self.diags.append(error("no-value", f"{c.name} returns nothing", c.span,
                                    f"call it as a statement: {c.name}(...);"))
            return A.Num(0, c.span, synthetic=True)
        if not self._arity(c):
            return A.Num(0, c.span, synthetic=True)
        x = args[0]
        index = A.Binary("*", A.Paren(x, x.span), A.Num(T.HZ_AXIS_STAT_STRIDE, c.span, "10", True),
                         c.span, c.name_span)
        return A.Index("F_ui", c.name_span, index, c.span)

    def statement(self, s: A.CallStmt):
        c = s.call
        if self.macros[c.name][1]:                 # axis_stat(x); computes and drops a value
            return replace(s, call=replace(
                c, args=[self.node(a) for a in c.args]))
        if not self._arity(c):
            return A.Empty(s.span)
        args = [self.node(a) for a in c.args]
        if c.name.startswith("set_"):
            return self._register(s, c)
        regs = {"RtWprintf_String": [T.TGM_RTW_STRING], "RtWprintf_Long": [T.TGM_RTW_LONG],
                "RtWprintf_Ex": [T.TGM_RTW_EX_SEVERITY, T.TGM_RTW_EX]}[c.name]
        stmts = [A.CallStmt(A.Call("gvarset", c.name_span,
                                   [A.Num(r, c.name_span, str(r), True), a], c.span), s.span)
                 for r, a in zip(regs, args)]
        return stmts[0] if len(stmts) == 1 else A.Block(stmts, s.span, s.span)

    def _register(self, s: A.CallStmt, c: A.Call):
        kind = c.name[4].upper()
        arg = c.args[0]
        if not isinstance(arg, A.Name) or arg.id not in self.procs:
            what = f"'{arg.id}' is not a procedure of this program" if isinstance(arg, A.Name) \
                else "its argument must name a procedure"
            self.diags.append(error("handler", f"{c.name}: {what}", arg.span,
                                    f"write {c.name}(name); with a procedure name() {{ ... }} "
                                    f"of this file"))
            return A.Empty(s.span)
        reg = T.HZ_FUNC_REGISTER[kind]
        call = A.Call("gvarset", c.name_span,
                      [A.Num(reg, c.name_span, str(reg), True),
                       A.Num(T.handler_id(arg.id), arg.span, arg.id, True)], c.span)
        return A.CallStmt(call, s.span)
