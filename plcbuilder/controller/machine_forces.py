"""The machine's side of a debugger's forces (controller/forces.py names and
lists them; here they take effect): inputs and ADC channels held over the
wiring and hand settings, outputs held whatever the program sets (the machine
keeps the program's own value, ``prog_out``), and registers (plain, PWM, DAC)
whose gvarget reads the held value while the program's writes only record what
it would be.

A mixin of :class:`~plcbuilder.controller.machine.Machine`: it uses the
machine's state (``in_bits``, ``out_bits``, ``prog_out``, the register tables)
and the state that ``Machine.reset`` sets up for it (``_fin_mask``,
``_fout_mask``, ``_adc_force``, ``_held`` …).
"""

from __future__ import annotations

from plcbuilder.bytecode import abi, softmc
from plcbuilder.bytecode.semantics import wrap

from .machine_config import ADC_CHANNELS

TYPE_CHECKING = False               # (typing is not imported at run time: start-up)
if TYPE_CHECKING:
    from typing import Optional


class MachineForces:
    """Force and release pins, channels and registers of the machine."""

    def force_input(self, pin: int, value: int) -> None:
        """Hold input ``pin`` at ``value`` over the wiring and hand settings."""
        self._check_pin(pin, self.input_count, "input")
        bit = 1 << pin
        self._fin_mask |= bit
        self._fin_val = self._fin_val | bit if value else self._fin_val & ~bit
        self._recompute_inputs()

    def release_input(self, pin: int, restore: bool) -> None:
        """Release input ``pin`` (forced or set by hand): back to the wiring
        (``restore``), or kept at its value as if set by hand."""
        self._check_pin(pin, self.input_count, "input")
        value = (self.in_bits >> pin) & 1
        bit = 1 << pin
        self._fin_mask &= ~bit
        self._fin_val &= ~bit
        if restore:
            self.clear_override(pin)
        else:
            self.set_input(pin, value)

    def force_output(self, pin: int, value: int) -> None:
        """Hold output ``pin`` at ``value`` whatever the program writes."""
        self._check_pin(pin, self.output_count, "output")
        bit = 1 << pin
        self._fout_mask |= bit
        self._fout_val = self._fout_val | bit if value else self._fout_val & ~bit
        self._apply_output_forces()

    def release_output(self, pin: int, restore: bool) -> None:
        """Release output ``pin``: it takes the value the program last gave it
        (``restore``), or keeps its value until the program writes it."""
        self._check_pin(pin, self.output_count, "output")
        bit = 1 << pin
        if not self._fout_mask & bit:
            return
        self._fout_mask &= ~bit
        self._fout_val &= ~bit
        if not restore:
            prog = (self.prog_out & ~bit) | (self.out_bits & bit)
            if prog != self.prog_out:
                self.prog_out = prog
                self.out_on[pin] = bool(prog & bit)
        self._apply_output_forces()

    def _apply_output_forces(self) -> None:
        fm = self._fout_mask
        new = (self.prog_out & ~fm) | (self._fout_val & fm)
        old = self.out_bits
        self.quiet = False
        self._set_physical(new)
        if (old ^ new) & self.sensors.followed_mask \
                and self.sensors.output_changed(self.t_ms, old, new):
            self._recompute_inputs()

    def force_adc(self, channel: int, value: int) -> None:
        """Hold ADC ``channel`` at ``value`` over its source and hand settings."""
        self._check_pin(channel, ADC_CHANNELS, "ADC channel")
        self._adc_force[channel] = int(value)
        self._refresh_adc()

    def release_adc(self, channel: int, restore: bool) -> None:
        """Release ADC ``channel``: back to its source (``restore``), or kept
        at its value as if set by hand."""
        self._check_pin(channel, ADC_CHANNELS, "ADC channel")
        value = self._adc[channel]
        self._adc_force.pop(channel, None)
        if restore:
            self.clear_adc(channel)
        else:
            self.set_adc(channel, value)

    def writable_register(self, addr: int) -> bool:
        """Whether gvarset(addr) does something (the register is not read-only)."""
        return self._set.get(addr) != self._read_only

    def forceable_register(self, addr: int) -> bool:
        """Whether ``force_register`` takes ``addr``: a plain register, PWM or DAC."""
        return (addr not in self._get and softmc.pls_field(addr) is None) or addr in self._held \
            or self._channel_list(addr) is not None

    def force_register(self, addr: int, value: int) -> None:
        """Hold register ``addr`` (plain, PWM or DAC) at ``value``: gvarget reads
        it and the program's writes only remember what it would be."""
        value = wrap(int(value))
        held = self._held.get(addr)
        if held is not None:
            held[0] = value
        elif not self.forceable_register(addr):
            raise ValueError(f"register {addr} cannot be forced")
        else:
            lst = self._channel_list(addr)
            if lst is None:
                self._plain_held.add(addr)
                would = self._regs.get(addr, 0)
            else:
                would = lst[self._channel(addr)]
            held = self._held[addr] = [value, would]
            self._unheld[addr] = (self._get.get(addr), self._set.get(addr))
            self._get[addr] = lambda _a, h=held: h[0]
            self._set[addr] = lambda _a, v, h=held: h.__setitem__(1, v)
        lst = self._channel_list(addr)
        if lst is not None:
            self._write_list(lst, self._channel(addr), value)

    def release_register(self, addr: int, restore: bool) -> None:
        """Release register ``addr``: it takes the value the program last wrote
        (``restore``), or keeps the forced value."""
        held = self._held.pop(addr, None)
        if held is None:
            return
        get, set_ = self._unheld.pop(addr)
        self._plain_held.discard(addr)
        for table, f in ((self._get, get), (self._set, set_)):
            if f is None:
                table.pop(addr, None)
            else:
                table[addr] = f
        value = held[1] if restore else held[0]
        lst = self._channel_list(addr)
        if lst is None:
            self._regs[addr] = value
        else:
            self._write_list(lst, self._channel(addr), value)

    def held_would_be(self, addr: int) -> Optional[int]:
        """A forced register's value as the program last wrote it (None: not forced)."""
        held = self._held.get(addr)
        return None if held is None else held[1]

    def _channel_list(self, addr: int) -> Optional[list]:
        if abi.GVAR_HW_PWM0 <= addr < abi.GVAR_HW_PWM0 + 8:
            return self._pwm
        if abi.GVAR_HW_DAC0 <= addr < abi.GVAR_HW_DAC0 + 8:
            return self._dac
        return None

    @staticmethod
    def _channel(addr: int) -> int:
        base = abi.GVAR_HW_PWM0 if abi.GVAR_HW_PWM0 <= addr < abi.GVAR_HW_PWM0 + 8 \
            else abi.GVAR_HW_DAC0
        return addr - base

    @staticmethod
    def _check_pin(n: int, count: int, what: str) -> None:
        if not 0 <= n < count:
            raise ValueError(f"no {what} {n} (0..{count - 1})")
