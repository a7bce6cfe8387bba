"""The Huazhong built-in PLC (seed 001, SPEC §9 "huazhong").

At the start ``init()`` runs once (after a first batch read, so that it sees
the inputs and the parameters). Then every 1 ms tick:

1. the batch read: X from the machine's inputs (input pin 8n+b is bit b of
   X[n]), F from the CNC (the plain registers ``CNC_F_BASE + n``), P from the
   parameters (the project's file);
2. ``plc1()`` when ``plc1_time`` ms have passed since its last call (the first
   tick calls it), then ``plc2()`` likewise with ``plc2_time``: each call runs
   to its end; the periods are the program's variables, 16 and 32 until it
   sets them, read again after every call (0 or less is a fault);
3. the batch write: Y to the machine's outputs, G to the CNC (``CNC_G_BASE +
   n``), B to the memory that is kept across restarts (:attr:`retained`).

Until the batch write the machine sees nothing of the tick's writes. The
program reaches the banks through gvarget/gvarset at the addresses of
:mod:`plcbuilder.bytecode.targets`; a write keeps the element's width, an
index out of range is a fault.

Each bank is its bytes (a bytearray); the plain name and the seed's typed
views (``R_uc`` … ``R_l``) are memoryviews of them, so ``R_ui[0]`` is R[0] and
R[1] (x86 byte order, the seed's Borland C++ 3.1 widths).

The CNC's side of F: F[10·x] (the seed's ``axis_stat(x)``) is the status word
of axis x of the machine, with the seed's AX_* bits, made again at every batch
read; the other F words come from the registers ``CNC_F_BASE + n``.

M, S, B and T functions: ``init()`` registers a handler procedure for each
kind (``set_m_func(proc)``, the seed: init() "sets the response functions of
the system's M, S, B, T functions"); when the CNC issues a code (a scenario's
``code M3``, a G-code job), the handler is called after the next batch read,
before ``plc1()``, with the code at ``HZ_FUNC_CODE[kind]``.
"""


from __future__ import annotations

import sys
from collections import deque
from typing import Callable, Optional

from plcbuilder.bytecode import targets as T
from plcbuilder.bytecode.semantics import wrap
from plcbuilder.controller.events import Note
from plcbuilder.controller.plc import Process
from plcbuilder.controller.targets.base import TargetPLC
from plcbuilder.controller.vm import Host, VMFault

_NO_CALL = -(1 << 60)
_FORMAT = {(8, False): "B", (8, True): "b", (16, False): "H", (16, True): "h",
           (32, False): "I", (32, True): "i"}
if sys.byteorder != "little":        # pragma: no cover - the views are the seed's x86 layout
    raise ImportError("the Huazhong target's register views need a little-endian machine")


class HuazhongPLC(TargetPLC):
    target = T.HUAZHONG

    def __init__(self, machine, config, **kwargs):
        super().__init__(machine, config, **kwargs)
        #: each bank's bytes, and every bank name (plain and typed views) over them
        self.mem: dict[str, bytearray] = {n: bytearray(T.STORAGE_BYTES[n])
                                          for n in T.STORAGE_BANKS}
        self.banks: dict[str, memoryview] = {}
        self._views()
        #: the P registers' store (the project's parameters) and the B memory
        #: kept across restarts (the controller's state)
        p_size, b_size = T.BANKS["P"].size, T.BANKS["B"].size
        self.parameters = list(config.parameters) + [0] * (p_size - len(config.parameters))
        kept = list(config.retained or ())
        self.retained = kept + [0] * (b_size - len(kept))
        self.periods = dict(T.HZ_DEFAULT_PERIODS)
        self._last_call = {"plc1": _NO_CALL, "plc2": _NO_CALL}
        self._g_written = [0] * T.BANKS["G"].size
        self._latch_index = 0
        self._latch_value = 0
        #: M/S/B/T: the handler registered for each kind, the last code issued, and
        #: the codes issued and not handled yet: (kind, value, done callback)
        self.handlers: dict[str, Optional[str]] = {k: None for k in T.HZ_FUNCTIONS}
        self.codes: dict[str, int] = {k: 0 for k in T.HZ_FUNCTIONS}
        self._issued: deque = deque()
        self._ids: dict[int, str] = {}

    def _views(self) -> None:
        for name, bank in T.BANKS.items():
            self.banks[name] = memoryview(self.mem[bank.storage]).cast(
                _FORMAT[(bank.bits, bank.signed)])

    # ---------------------------------------------------------------- start
    def on_begin(self, p: Process) -> None:
        for buf in self.mem.values():
            buf[:] = bytes(len(buf))
        _fill(self.banks["B"], self.retained)
        self.periods = dict(T.HZ_DEFAULT_PERIODS)
        for name, value in self.periods.items():
            slot = self.var_slot(name)
            if slot is not None:
                p.slots[slot] = value
        self._last_call = {"plc1": _NO_CALL, "plc2": _NO_CALL}
        self._init_due = True
        self.handlers = {k: None for k in T.HZ_FUNCTIONS}
        self.codes = {k: 0 for k in T.HZ_FUNCTIONS}
        self._ids = {T.handler_id(name): name for name, _off in self.program.procs}

    # ----------------------------------------------------------------- tick
    def tick(self, t: int, p: Process) -> None:
        if self._init_due:
            self._init_due = False
            self._batch_read()                  # init() sees the inputs and P too
            self.call("init")
            if self.hw is not p or not self._read_periods(p):
                return                          # a fault ended the program
        self._batch_read()
        while self._issued:
            if not self._handle(p, *self._issued.popleft()):
                return
        for name, var in (("plc1", "plc1_time"), ("plc2", "plc2_time")):
            if t - self._last_call[name] >= self.periods[var]:
                self._last_call[name] = t
                self.call(name)
                if self.hw is not p or not self._read_periods(p):
                    return
        self._batch_write()

    def _read_periods(self, p: Process) -> bool:
        """Take plc1_time/plc2_time from the program's variables; one 0 or less
        ends the program with a fault."""
        for var in T.HZ_PERIODS:
            slot = self.var_slot(var)
            if slot is None:
                continue
            v = p.slots[slot]
            if v <= 0:
                self._fault(p, None, f"{var} is {v}: a period is at least 1 ms")
                return False
            self.periods[var] = v
        return True

    def _batch_read(self) -> None:
        m = self.machine
        x = self.banks["X"]
        bits = m.in_bits
        for n in range(min(len(x), (m.input_count + 7) // 8)):
            x[n] = (bits >> (8 * n)) & 0xFF
        f = self.banks["F"]
        self.mem["F"][:] = bytes(len(self.mem["F"]))
        regs = getattr(m, "_regs", None)        # the machine's plain registers (as plc.py reads
        if isinstance(regs, dict):              # machine._sample): the registers set, not
            base, end = T.CNC_F_BASE, T.CNC_F_BASE + len(f)   # 256 lookups a tick
            for k, v in regs.items():
                if base <= k < end:
                    f[k - base] = v & 0xFFFF
        else:
            get = m.gvarget
            for n in range(len(f)):
                f[n] = get(T.CNC_F_BASE + n) & 0xFFFF
        status = getattr(m, "axis_status", None)
        if status is not None:                  # axis_stat(x): the CNC's status of axis x
            for i, word in status().items():
                f[i * T.HZ_AXIS_STAT_STRIDE] = word
        _fill(self.banks["P"], self.parameters)

    def _batch_write(self) -> None:
        m = self.machine
        y = self.banks["Y"]
        count = m.output_count
        word = int.from_bytes(self.mem["Y"][:(count + 7) // 8], "little")
        word &= (1 << count) - 1
        changed = word ^ m.out_bits
        while changed:
            low = changed & -changed
            pin = low.bit_length() - 1
            (m.portset if word & low else m.portclear)(pin)
            changed ^= low
        del y
        g, written = self.banks["G"], self._g_written
        if g.tolist() != written:
            for n, v in enumerate(g):
                if v != written[n]:
                    m.gvarset(T.CNC_G_BASE + n, v)
                    written[n] = v
        self.retained[:] = self.banks["B"].tolist()

    # ------------------------------------------------------- M, S, B, T
    def issue_function(self, kind: str, value: int,
                       done: Optional[Callable[[Optional[str], Optional[int]], None]] = None
                       ) -> None:
        """The CNC issues code ``kind`` ``value`` (M3, S1200, T5, B2): the handler
        init() registered for that kind is called in the next tick, after the
        batch read; ``done(handler, exit code)`` then (handler None: none is
        registered; exit code None: it faulted)."""
        if kind not in T.HZ_FUNCTIONS:
            raise ValueError(f"{kind}{value}: the functions are M, S, B and T")
        self._issued.append((kind, wrap(int(value)), done))

    def functions_pending(self) -> bool:
        return bool(self._issued)

    def _handle(self, p: Process, kind: str, value: int, done) -> bool:
        self.codes[kind] = value
        name = self.handlers[kind]
        code = None
        if name is None:
            self.events.append(Note(self.t, f"{kind}{value}: no {kind} function handler is "
                                            f"registered (init() registers one with "
                                            f"set_{kind.lower()}_func(procedure))", "warning"))
        else:
            r = self.call(name)
            code = r.code if r is not None else None
        if done is not None:
            done(name, code)
        return self.hw is p

    def _register(self, kind: str, ident: int) -> None:
        if ident == 0:
            self.handlers[kind] = None
            return
        name = self._ids.get(ident)
        if name is None or name not in self.entries:
            raise VMFault(-1, f"set_{kind.lower()}_func: no procedure of the program has id "
                              f"{ident}")
        self.handlers[kind] = name

    # ----------------------------------------------------------------- host
    def _target_host(self, base: Host) -> Host:
        banks = self.banks
        lo, hi = T.HZ_BASE, T.HZ_BASE + 100_000
        bank_at = T.bank_at
        load, store = T.INDIRECT_LOAD, T.INDIRECT_STORE
        register = {a: k for k, a in T.HZ_FUNC_REGISTER.items()}
        codes = {a: k for k, a in T.HZ_FUNC_CODE.items()}
        get, put = base.gvarget, base.gvarset

        def gvarget(addr: int) -> int:
            if lo <= addr < hi:
                hit = bank_at(addr)
                if hit is not None:
                    return wrap(banks[hit[0].name][hit[1]])
                if addr in load:
                    return wrap(self._element(load[addr], self._latch_index, "read"))
                if addr == T.INDEX_LATCH:
                    return self._latch_index
                if addr == T.VALUE_LATCH:
                    return self._latch_value
                if addr in codes:
                    return self.codes[codes[addr]]
            return get(addr)

        def gvarset(addr: int, value: int) -> None:
            if lo <= addr < hi:
                hit = bank_at(addr)
                if hit is not None:
                    bank, i = hit
                    banks[bank.name][i] = bank.stored(value)
                    return
                if addr == T.INDEX_LATCH:
                    self._latch_index = value
                    return
                if addr == T.VALUE_LATCH:
                    self._latch_value = value
                    return
                if addr in store:
                    bank = store[addr]
                    self._element(bank, value, "write")
                    banks[bank.name][value] = bank.stored(self._latch_value)
                    return
                if addr in register:
                    self._register(register[addr], value)
                    return
            put(addr, value)

        return base.replace(gvarget=gvarget, gvarset=gvarset, raw_gvarset=gvarset, lat=0,
                            io=None, software=False, starthw=None, seteparam=None,
                            softjog=None)

    def _element(self, bank: T.Bank, i: int, what: str) -> int:
        if not 0 <= i < bank.size:
            raise VMFault(-1, f"{bank.name}[{i}] is out of range ({what}): {bank.name} has "
                              f"{bank.size} elements ({bank.name}[0] .. {bank.name}[{bank.size - 1}])")
        return self.banks[bank.name][i]

    # --------------------------------------------------------------- report
    def set_parameter(self, i: int, value: int) -> None:
        """Change P[i] (the user's parameter): the next batch read sees it."""
        bank = T.BANKS["P"]
        if not 0 <= i < bank.size or not 0 <= value <= bank.mask:
            raise ValueError(f"P[{i}] = {value}: P has {bank.size} elements of 0..{bank.mask}")
        self.parameters[i] = value

    def registers(self) -> dict[str, dict[str, int]]:
        return {name: {str(i): v for i, v in enumerate(self.banks[name].tolist()) if v}
                for name in T.STORAGE_BANKS}

    def register_value(self, bank: str, i: int) -> Optional[int]:
        vals = self.banks.get(bank)
        return vals[i] if vals is not None and 0 <= i < len(vals) else None

    def report(self) -> dict:
        out = super().report()
        out["handlers"] = {k: v for k, v in self.handlers.items() if v is not None}
        return out


def _fill(view: memoryview, values: list[int]) -> None:
    for i, v in enumerate(values):
        view[i] = v
