"""TG Motion's oscilloscope: the signals the user picks, sampled after each
``Program_04`` (seed 002, 3.3: it "is used to capture the values of desired
registers within an exact time interval of Cycle_Time and their saving into
the TGM_Oscilloscope shared memory. This happens after Program_04 function is
executed").

A signal is named as the debugger names what it writes and forces
(docs/debugging.md): ``in N`` and ``out N`` (a pin, 0 or 1), ``adc N``, ``pwm N``
and ``dac N`` (a channel), ``gvar ADDR`` (any register the program reads with
gvarget: TGM_Data, the I/O words, a position) and ``PROGRAM.var`` (a variable
of the program). Without a choice it samples input word 0 and output word 0.
"""

from __future__ import annotations

from typing import Callable

from plcbuilder.bytecode import abi

from plcbuilder.bytecode.targets import DEFAULT_SIGNALS, ScopeError, Signal, parse_signal  # noqa: F401


def readers(signals, machine, gvarget: Callable[[int], int], slot_of: Callable[[str], int],
            slots: list) -> list[Callable[[], int]]:
    """One function per signal reading its value now. ``gvarget`` is the
    program's (it reaches TGM_Data); ``slot_of(var)`` the slot of a variable
    (ScopeError when the program has none)."""
    out = []
    for s in signals:
        if s.kind == "in":
            out.append(lambda n=s.n: machine.portget(n) if n < machine.input_count else 0)
        elif s.kind == "out":
            out.append(lambda n=s.n: (machine.out_bits >> n) & 1)
        elif s.kind in ("adc", "pwm", "dac"):
            base = {"adc": abi.GVAR_HW_ADC0, "pwm": abi.GVAR_HW_PWM0, "dac": abi.GVAR_HW_DAC0}
            out.append(lambda a=base[s.kind] + s.n: machine.gvarget(a))
        elif s.kind == "gvar":
            out.append(lambda a=s.n: gvarget(a))
        else:
            slot = slot_of(s.var)
            out.append(lambda k=slot: slots[k])
    return out
