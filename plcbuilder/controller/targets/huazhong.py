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
"""

from __future__ import annotations

from typing import Optional

from plcbuilder.bytecode import targets as T
from plcbuilder.controller.plc import Process
from plcbuilder.controller.targets.base import TargetPLC
from plcbuilder.controller.vm import Host, VMFault

_NO_CALL = -(1 << 60)
_ZERO_F = [0] * T.BANKS["F"].size


class HuazhongPLC(TargetPLC):
    target = T.HUAZHONG

    def __init__(self, machine, config, **kwargs):
        super().__init__(machine, config, **kwargs)
        self.banks: dict[str, list[int]] = {b.name: [0] * b.size for b in T.BANKS.values()}
        #: the P registers' store (the project's parameters) and the B memory
        #: kept across restarts (the controller's state)
        self.parameters = list(config.parameters) + [0] * (T.BANKS["P"].size - len(config.parameters))
        kept = list(config.retained or ())
        self.retained = kept + [0] * (T.BANKS["B"].size - len(kept))
        self.periods = dict(T.HZ_DEFAULT_PERIODS)
        self._last_call = {"plc1": _NO_CALL, "plc2": _NO_CALL}
        self._g_written = [0] * T.BANKS["G"].size
        self._latch_index = 0
        self._latch_value = 0

    # ---------------------------------------------------------------- start
    def on_begin(self, p: Process) -> None:
        for b in T.BANKS.values():
            self.banks[b.name] = [0] * b.size
        self.banks["B"] = list(self.retained)
        self.periods = dict(T.HZ_DEFAULT_PERIODS)
        for name, value in self.periods.items():
            slot = self.var_slot(name)
            if slot is not None:
                p.slots[slot] = value
        self._last_call = {"plc1": _NO_CALL, "plc2": _NO_CALL}
        self._init_due = True

    # ----------------------------------------------------------------- tick
    def tick(self, t: int, p: Process) -> None:
        if self._init_due:
            self._init_due = False
            self._batch_read()                  # init() sees the inputs and P too
            self.call("init")
            if self.hw is not p or not self._read_periods(p):
                return                          # a fault ended the program
        self._batch_read()
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
        regs = getattr(m, "_regs", None)        # the machine's plain registers (as plc.py reads
        if isinstance(regs, dict):              # machine._sample): the registers set, not
            base, end = T.CNC_F_BASE, T.CNC_F_BASE + len(f)   # 256 lookups a tick
            f[:] = _ZERO_F
            for k, v in regs.items():
                if base <= k < end:
                    f[k - base] = v & 0xFFFF
        else:
            get = m.gvarget
            for n in range(len(f)):
                f[n] = get(T.CNC_F_BASE + n) & 0xFFFF
        self.banks["P"][:] = self.parameters

    def _batch_write(self) -> None:
        m = self.machine
        y = self.banks["Y"]
        count = m.output_count
        word = 0
        for n in range((count + 7) // 8):
            word |= y[n] << (8 * n)
        word &= (1 << count) - 1
        changed = word ^ m.out_bits
        while changed:
            low = changed & -changed
            pin = low.bit_length() - 1
            (m.portset if word & low else m.portclear)(pin)
            changed ^= low
        g, written = self.banks["G"], self._g_written
        if g != written:
            for n, v in enumerate(g):
                if v != written[n]:
                    m.gvarset(T.CNC_G_BASE + n, v)
                    written[n] = v
        self.retained[:] = self.banks["B"]

    # ----------------------------------------------------------------- host
    def _target_host(self, base: Host) -> Host:
        banks = self.banks
        lo, hi = T.HZ_BASE, T.HZ_BASE + 7000
        bank_at = T.bank_at
        load, store = T.INDIRECT_LOAD, T.INDIRECT_STORE
        get, put = base.gvarget, base.gvarset

        def gvarget(addr: int) -> int:
            if lo <= addr < hi:
                hit = bank_at(addr)
                if hit is not None:
                    return banks[hit[0].name][hit[1]]
            elif addr in load:
                return self._element(load[addr], self._latch_index, "read")
            elif addr == T.INDEX_LATCH:
                return self._latch_index
            elif addr == T.VALUE_LATCH:
                return self._latch_value
            return get(addr)

        def gvarset(addr: int, value: int) -> None:
            if lo <= addr < hi:
                hit = bank_at(addr)
                if hit is not None:
                    bank, i = hit
                    banks[bank.name][i] = value & bank.mask
                    return
            elif addr == T.INDEX_LATCH:
                self._latch_index = value
                return
            elif addr == T.VALUE_LATCH:
                self._latch_value = value
                return
            elif addr in store:
                bank = store[addr]
                self._element(bank, value, "write")
                banks[bank.name][value] = self._latch_value & bank.mask
                return
            put(addr, value)

        return Host(portset=base.portset, portclr=base.portclr, portget=base.portget,
                    gvarget=gvarget, gvarset=gvarset, g0move=base.g0move, plain=base.plain,
                    lat=0, pr=base.pr, raw_gvarset=gvarset, io=None)

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
        return {name: {str(i): v for i, v in enumerate(vals) if v}
                for name, vals in self.banks.items()}

    def register_value(self, bank: str, i: int) -> Optional[int]:
        vals = self.banks.get(bank)
        return vals[i] if vals is not None and 0 <= i < len(vals) else None
