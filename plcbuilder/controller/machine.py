"""The simulated machine: I/O, PWM, DAC, ADC, the global registers, motion and sensors.

The PLC (hardware or software) reaches it through ``portset``/``portclear``/
``portget``/``gvarget``/``gvarset``/``g0moveA`` and the messages it sends; the host
(scenarios, the IDE, the server) through ``set_input``, ``set_adc``, ``advance``
and the sampling methods. One ``advance()`` is 1 ms of machine time.

Register map (for users: docs/machine.md, "Registers"):

=====================  ==================================================
0x400 + n              state of output n (read-only)
7180..7183, 7188..91   input words 0..7 (read-only)
7184..7187, 7192..95   output words 0..7 (writing one sets its 32 outputs)
7196..7203             ADC0..7 (read-only)
7270..7277             DAC0..7 (stored as written)
7278..7285             PWM0..7 (stored as written; no clamping)
6060                   0 while a PLC move or jog runs, 0x4d when idle
5021..5026, 5041..46   machine / program position X..C (0.01 mm)
17001..09, 17021..29   program / machine position X..W
5521, 5525             non-zero disables hardware / software limits
8631, 8632, 8634, 8635 jog: acceleration time, speed units, axis speed, direction
30000..30232           softMC virtual I/O (controller/virtual_io.py)
31100000 and on        softMC programmable limit switches, 100000 a PLS (controller/pls.py)
everything else        plain register: keeps what was written, reads 0 before
=====================  ==================================================

Inputs that the machine file does not wire read the project's IO.DAT preset
(``MachineConfig.input_preset``) instead of 0.
"""

from __future__ import annotations

import struct

from plcbuilder.bytecode import abi, softmc, targets
from plcbuilder.bytecode.abi import AXES
from plcbuilder.bytecode.semantics import wrap

from .machine_config import ADC_CHANNELS, MachineConfig, default_machine
from .machine_forces import MachineForces
from .motion import N_AXES, Motion, fmt_mm
from .pls import PlsBank
from .sensors import Sensors
from .virtual_io import VirtualIO

TYPE_CHECKING = False               # (typing is not imported at run time: start-up)
if TYPE_CHECKING:
    from typing import Callable, Optional

STOP_MESSAGES = frozenset(abi.PLCCMD[n] for n in (
    "PLCCMD_LINE_STOP", "PLCCMD_LINE_SOFT_STOP", "PLCCMD_MOTION_SKIP",
    "PLCCMD_MOTION_ABORT", "PLCCMD_MOTION_BREAK"))

_PLS_FIRST, _PLS_END = softmc.PLS_FIRST, softmc.PLS_END
_AX = targets.AX_BITS
_M32 = 0xFFFFFFFF
_M256 = (1 << 256) - 1
_WORDS = struct.Struct("<8I")              # 8 words of 32 pins, from 32 little-endian bytes


class Machine(MachineForces):
    """The simulated machine. ``Machine()`` is the default machine. What a
    debugger forces is held by the methods of :class:`MachineForces`."""

    def __init__(self, config: Optional[MachineConfig] = None):
        self.config = config if config is not None else default_machine()
        cfg = self.config
        self.input_count = cfg.input_count
        self.output_count = cfg.output_count
        self._in_mask = (1 << cfg.input_count) - 1
        self._out_mask = (1 << cfg.output_count) - 1
        self._notes: list[tuple[str, str]] = []
        #: the notes not yet returned by advance() (the same list, read-only for callers)
        self.pending_notes = self._notes
        self.motion = Motion(cfg, self._notes)
        self.sensors = Sensors(cfg)
        self._input_names = cfg.input_names()
        wired = 0
        for w in cfg.inputs:
            wired |= 1 << w.pin
        self._preset = cfg.input_preset & ~wired & self._in_mask   # IO.DAT's INP
        self._preset_lost = cfg.input_preset & wired & self._in_mask
        self.vio = VirtualIO(cfg.dip, self._forget_sample)
        present = set(self.motion.present_idx)
        self.pls = PlsBank(cfg.pls, output_count=cfg.output_count,
                           axis_present=present.__contains__,
                           position=lambda i: self.motion.ipos[i], write=self._pls_write,
                           notes=self._notes)
        self._get: dict[int, Callable[[int], int]] = {}
        self._set: dict[int, Callable[[int, int], None]] = {}
        self._build_register_map()
        #: each pin's state as a list, changed in place (the fast backend reads them:
        #: Host.io): in_levels equals in_bits; out_on is the outputs as the program
        #: last set them (prog_out), equal to out_bits unless an output is forced
        self.in_levels = [0] * cfg.input_count
        self.out_on = [False] * cfg.output_count
        self.reset()

    # ------------------------------------------------------------ setup
    #: True while advance() has nothing to do but count the ms (nothing moves,
    #: nothing is due); every call that could change that clears it.
    quiet = False

    def reset(self) -> None:
        """Power-on state: start positions, outputs off, no overrides, registers
        cleared, t_ms = 0."""
        for addr in list(getattr(self, "_held", ())):
            self.release_register(addr, True)     # its own functions back in the tables
        self.quiet = False
        self.t_ms = 0
        self._notes.clear()
        self.motion.reset()
        self.out_bits = 0
        self.prog_out = 0                  # the outputs as the program set them
        self.out_on[:] = [False] * self.output_count
        self._ov_mask = 0
        self._ov_val = 0
        # forces (controller/forces.py): pins and channels held by the debugger
        self._fin_mask = self._fin_val = 0
        self._fout_mask = self._fout_val = 0
        self._adc_force: dict[int, int] = {}
        #: forced register address -> [held value, the program's last write]
        #: (one dict for the machine's life: register_store() gives it out)
        self._held: dict[int, list[int]] = getattr(self, "_held", {})
        self._held.clear()
        self._plain_held: set[int] = set()
        self._unheld: dict[int, tuple] = {}     # address -> its own (get, set) functions
        self.sensors.reset(self.motion.ipos, 0)
        self.in_bits = 0
        self.in_levels[:] = [0] * self.input_count
        self._regs: dict[int, int] = getattr(self, "_regs", {})    # (one dict, as _held)
        self._regs.clear()
        self._special: dict[int, int] = {}
        self._pwm = [0] * 8
        self._dac = [0] * 8
        self._adc_override: dict[int, int] = {}
        self._adc = list(self.sensors.adc)
        self._hw_limits = True
        self._warned: set = set()
        self._recompute_inputs()
        self._sample: Optional[dict] = None
        self._words: dict[str, tuple[int, tuple]] = {}   # "inputs"/"outputs": (bits, words)
        self.vio.reset()
        if self._preset_lost:
            self._notes.append(("warning", "IO.DAT: INP presets input(s) "
                                f"{', '.join(map(str, _bits_on(self._preset_lost)))}, which "
                                "the machine file wires: the wiring wins"))
        self.pls.reset()

    def _build_register_map(self) -> None:
        g, s = self._get, self._set
        ro = self._read_only
        for n in range(256):
            g[abi.OUTPUT_STATE_BASE + n] = self._get_output_bit
            s[abi.OUTPUT_STATE_BASE + n] = ro
        for k, a in enumerate(abi.GVAR_HW_INPUTS):
            g[a] = (lambda _a, k=k: wrap(self.in_bits >> (32 * k)))
            s[a] = ro
        for k, a in enumerate(abi.GVAR_HW_OUTPUTS):
            g[a] = (lambda _a, k=k: wrap(self.out_bits >> (32 * k)))
            s[a] = (lambda _a, v, k=k: self._set_output_word(k, v))
        for ch in range(ADC_CHANNELS):
            g[abi.GVAR_HW_ADC0 + ch] = (lambda _a, ch=ch: self._adc[ch])
            s[abi.GVAR_HW_ADC0 + ch] = ro
        for ch in range(8):
            g[abi.GVAR_HW_DAC0 + ch] = (lambda _a, ch=ch: self._dac[ch])
            s[abi.GVAR_HW_DAC0 + ch] = (lambda _a, v, ch=ch: self._write_list(self._dac, ch, v))
            g[abi.GVAR_HW_PWM0 + ch] = (lambda _a, ch=ch: self._pwm[ch])
            s[abi.GVAR_HW_PWM0 + ch] = (lambda _a, v, ch=ch: self._write_list(self._pwm, ch, v))
        g[abi.MOTION_CODE] = lambda _a: self.motion.motion_code
        s[abi.MOTION_CODE] = ro
        for i in range(6):
            g[abi.MACHINE_POS_BASE + i] = (lambda _a, i=i: self.motion.ipos[i])
            g[abi.PROGRAM_POS_BASE + i] = (lambda _a, i=i: self.motion.program_position(i))
            s[abi.MACHINE_POS_BASE + i] = ro
            s[abi.PROGRAM_POS_BASE + i] = ro
        for i in range(N_AXES):
            g[abi.MACHINE_POS9_BASE + i] = (lambda _a, i=i: self.motion.ipos[i])
            g[abi.PROGRAM_POS9_BASE + i] = (lambda _a, i=i: self.motion.program_position(i))
            s[abi.MACHINE_POS9_BASE + i] = ro
            s[abi.PROGRAM_POS9_BASE + i] = ro
        stored = lambda a: self._special.get(a, 0)  # noqa: E731
        for a in (abi.DISABLE_HW_LIMITS, abi.DISABLE_SW_LIMITS, abi.JOG_ACCEL_TIME,
                  abi.JOG_SPEED_UNITS, abi.JOG_AXIS_SPEED, abi.JOG):
            g[a] = stored
        s[abi.DISABLE_HW_LIMITS] = self._set_hw_limits
        s[abi.DISABLE_SW_LIMITS] = self._set_sw_limits
        s[abi.JOG_ACCEL_TIME] = self._set_jog_time
        s[abi.JOG_SPEED_UNITS] = self._set_jog_units
        s[abi.JOG_AXIS_SPEED] = self._set_jog_speed
        s[abi.JOG] = self._set_jog
        self.vio.install(g, s, ro)

    # ------------------------------------------------------- PLC-facing
    def portset(self, pin: int) -> None:
        """Turn output ``pin`` on (at once). Writing the value an output already
        has changes nothing, and costs little: the machine stays quiet."""
        if 0 <= pin < self.output_count:
            new = self.prog_out | (1 << pin)
            if new != self.prog_out:
                self._set_outputs(new)
        else:
            self._bad_pin("portset", pin, self.output_count, "outputs")

    def portclear(self, pin: int) -> None:
        """Turn output ``pin`` off (at once)."""
        if 0 <= pin < self.output_count:
            new = self.prog_out & ~(1 << pin)
            if new != self.prog_out:
                self._set_outputs(new)
        else:
            self._bad_pin("portclear", pin, self.output_count, "outputs")

    def portget(self, pin: int) -> int:
        """The state of input ``pin``, 0 or 1 (a manual override wins over the wiring)."""
        if 0 <= pin < self.input_count:
            return (self.in_bits >> pin) & 1
        self._bad_pin("portget", pin, self.input_count, "inputs")
        return 0

    def gvarget(self, addr: int) -> int:
        f = self._get.get(addr)
        if f is None:
            if _PLS_FIRST <= addr < _PLS_END and softmc.pls_field(addr) is not None:
                return self.pls.read_register(addr)
            return self._regs.get(addr, 0)
        return f(addr)

    def gvarset(self, addr: int, value: int) -> None:
        f = self._set.get(addr)
        if f is None:
            if _PLS_FIRST <= addr < _PLS_END and softmc.pls_field(addr) is not None:
                self.quiet = False
                self.pls.write_register(addr, value)
            else:
                self._regs[addr] = value
        else:
            self.quiet = False
            f(addr, value)

    def is_plain_register(self, addr: int) -> bool:
        """True when gvarget(addr) reads the plain global register store."""
        if addr in self._plain_held:
            return True
        return addr not in self._get and softmc.pls_field(addr) is None

    def register_store(self) -> tuple[dict, dict]:
        """``(store, forced)``: while ``forced`` is empty, gvarget(addr) of an
        address ``is_plain_register(addr)`` is true for reads ``store.get(addr, 0)``
        (the fast backend reads constant plain registers so). Both dicts are
        this machine's for its whole life, changed in place."""
        return self._regs, self._held

    def g0move(self, flags: int, mask: int, distance: int) -> None:
        """g0moveA(flags, mask, distance): bit 0 absolute, bit 1 machine coordinates,
        bit 7 delayed start; distance in 0.01 mm."""
        self.quiet = False
        self.motion.g0move(self.t_ms, flags, mask, distance)

    def on_message(self, code: int) -> None:
        """A PLC message; the stop messages stop the motion in progress (decelerating)."""
        if code in STOP_MESSAGES:
            self.quiet = False
            self.motion.stop()

    def soft_jog(self, axis_index: int, speed: int) -> None:
        """The software PLC's gvarset(100020 + axis, speed): jog one axis (negative
        speed: negative direction) until it is set to 0. Speed is in jog speed
        units (mm/min while 8632 is 0 or 1000). No watchdog."""
        self.quiet = False
        self.motion.soft_jog(axis_index, speed)

    # ------------------------------------------------------ host-facing
    def set_input(self, pin: int, value: int) -> None:
        """Set input ``pin`` by hand; it overrides the wiring from then on."""
        if not 0 <= pin < self.input_count:
            raise ValueError(f"no input {pin} (the machine has inputs 0..{self.input_count - 1})")
        bit = 1 << pin
        self._ov_mask |= bit
        if value:
            self._ov_val |= bit
        else:
            self._ov_val &= ~bit
        self._recompute_inputs()

    def clear_override(self, pin: int) -> None:
        """Give input ``pin`` back to the machine's wiring."""
        if not 0 <= pin < self.input_count:
            raise ValueError(f"no input {pin} (the machine has inputs 0..{self.input_count - 1})")
        bit = 1 << pin
        self._ov_mask &= ~bit
        self._ov_val &= ~bit
        self._recompute_inputs()

    def overrides(self) -> dict[int, int]:
        """The inputs set by hand: {pin: value}."""
        out, m, n = {}, self._ov_mask, 0
        while m:
            if m & 1:
                out[n] = (self._ov_val >> n) & 1
            m >>= 1
            n += 1
        return out

    def set_adc(self, channel: int, value: int) -> None:
        """Set ADC ``channel`` by hand; it overrides its source from then on."""
        if not 0 <= channel < ADC_CHANNELS:
            raise ValueError(f"no ADC channel {channel} (0..{ADC_CHANNELS - 1})")
        self._adc_override[channel] = int(value)
        self._refresh_adc()

    def clear_adc(self, channel: int) -> None:
        """Give ADC ``channel`` back to its source."""
        self._adc_override.pop(channel, None)
        self._refresh_adc()

    def advance(self) -> list[tuple[str, str]]:
        """Advance 1 ms: motion, jog watchdog, delayed inputs, ADC sources, limits.
        Returns the notes of this ms (and of the PLC calls since the last advance)
        as (level, text), level "info", "warning" or "error"."""
        t = self.t_ms = self.t_ms + 1
        if self.quiet and not self._notes:
            return []          # nothing moves or is due: the common case, kept cheap
        if not (self.motion.needs_advance or self.sensors.pending or self.sensors.dynamic_adc
                or self._notes):
            # idle until a PLC call or the host changes something (they clear _idle)
            self.quiet = True
            return []
        return self._advance(t)

    def _advance(self, t: int) -> list[tuple[str, str]]:
        m, sens = self.motion, self.sensors
        moved = m.advance(t)
        wired_changed = False
        if moved:
            self._sample = None
            wired_changed = sens.update_positions(m.ipos)
        if sens.pending:
            wired_changed |= sens.apply_due(t)
        if (sens.dynamic_adc or (moved and sens.axis_adc)) and sens.update_adc(t, m.ipos, moved):
            self._refresh_adc()
        if wired_changed:
            self._recompute_inputs()
        if moved and self._hw_limits and sens.hard_limits:
            self._check_hard_limits()
        if moved and self.pls.active:
            self.pls.update()              # the PLSs follow the new positions
        if not self._notes:
            return []
        notes = list(self._notes)
        self._notes.clear()
        return notes

    def sample_fields(self) -> dict:
        """inputs/outputs (8 words each), pwm, dac, adc (8 each), axes (9 machine
        positions, 0.01 mm), velocities (9, 0.01 mm/s) and vio (the virtual input
        and output words, unsigned), all tuples of ints.
        The same dict is returned until something changes: do not modify it."""
        s = self._sample
        if s is None:
            m = self.motion
            s = self._sample = {
                "inputs": self._words_of("inputs", self.in_bits),
                "outputs": self._words_of("outputs", self.out_bits),
                "pwm": tuple(self._pwm),
                "dac": tuple(self._dac),
                "adc": tuple(self._adc),
                "axes": tuple(m.ipos),
                "velocities": m.velocity_report(),
                "vio": (self.vio.vin, self.vio.vout),
            }
        return s

    def _words_of(self, kind: str, bits: int) -> tuple:
        """The 8 words of 32 pins of ``bits`` (the same tuple while they do not change)."""
        seen = self._words.get(kind)
        if seen is None or seen[0] != bits:
            seen = self._words[kind] = (bits, _WORDS.unpack((bits & _M256).to_bytes(32, "little")))
        return seen[1]

    def outputs_on(self) -> list[int]:
        """The output pins that are on, sorted."""
        return _bits_on(self.out_bits)

    def inputs_on(self) -> list[int]:
        """The input pins that read 1, sorted."""
        return _bits_on(self.in_bits)

    def axis_positions(self) -> dict[str, int]:
        """Machine positions (0.01 mm) of the configured axes, in X..W order."""
        ipos = self.motion.ipos
        return {AXES[i]: ipos[i] for i in self.motion.present_idx}

    def program_positions(self) -> dict[str, int]:
        """Program positions (machine − work offset) of the configured axes."""
        m = self.motion
        return {AXES[i]: m.program_position(i) for i in m.present_idx}

    @property
    def motion_code(self) -> int:
        """What 6060 reads now."""
        return self.motion.motion_code

    def axis_status(self) -> dict[int, int]:
        """Each configured axis's status word, with the Huazhong seed's AX_* bits
        (``axis_stat(x)``): limits reached (the soft limit, or a hard-limit
        switch active), homing, homed, stopped in position, moving. No backlash
        compensation is modelled (AX_CMP_LAMP stays 0)."""
        m = self.motion
        home = set(m.move.homing) if m.move is not None else set()
        ins = self.in_bits
        out = {}
        for i in m.present_idx:
            w = 0
            p = m.pos[i]
            if m.soft_max[i] is not None and p >= m.soft_max[i]:
                w |= _AX["AX_SLSP"]
            if m.soft_min[i] is not None and p <= m.soft_min[i]:
                w |= _AX["AX_SLSN"]
            for sw in self.sensors.hard_limits:
                if sw.axis == i and ((ins >> sw.pin) & 1) == sw.active:
                    w |= _AX["AX_SLSP"] if sw.toward > 0 else _AX["AX_SLSN"]
            if i in home:
                w |= _AX["AX_HOME_LAMP"] | _AX["AX_HOME_GOING"]
            if m.homed[i]:
                w |= _AX["AX_HOME_FIN"]
            if m.vel[i]:
                w |= _AX["AX_MOVING_LAMP"]
            elif m.move is None or i not in m.move.axes:
                w |= _AX["AX_FSTOP_LAMP"]
            out[i] = w
        return out

    def home_position(self, i: int) -> Optional[float]:
        """Where axis i's home switch trips (0.01 mm): the edge of the machine
        file's input marked ``home = true`` (or named like INPUT_HOME_X) on that
        axis; None when it has none."""
        for w in self.config.inputs:
            if w.kind == "axis" and w.axis == AXES[i] and not w.hard_limit and \
                    (w.home or "HOME" in w.name.upper()):
                edge = w.below if w.below is not None else w.above
                return None if edge is None else float(round(edge * 100))
        return None

    # --------------------------------------------------------- internals
    def _recompute_inputs(self) -> None:
        m = self._ov_mask
        v = (((self.sensors.wired | self._preset) & ~m) | (self._ov_val & m)) & self._in_mask
        fm = self._fin_mask
        if fm:
            v = (v & ~fm) | (self._fin_val & fm)
        if v != self.in_bits:
            changed = v ^ self.in_bits
            self.in_bits = v
            levels = self.in_levels
            while changed:
                low = changed & -changed
                pin = low.bit_length() - 1
                levels[pin] = (v >> pin) & 1
                changed ^= low
            self._sample = None

    def _set_outputs(self, new: int) -> None:
        """The program sets the outputs to ``new``; forced ones keep their value."""
        old = self.prog_out
        if new == old:
            return
        self.prog_out = new
        on = self.out_on
        changed = old ^ new
        while changed:
            low = changed & -changed
            on[low.bit_length() - 1] = bool(new & low)
            changed ^= low
        fm = self._fout_mask
        self._set_physical((new & ~fm) | (self._fout_val & fm) if fm else new)

    def _set_physical(self, new: int) -> None:
        old = self.out_bits
        if new == old:
            return
        self.out_bits = new
        self._sample = None
        if (old ^ new) & self.sensors.followed_mask:
            self.quiet = False             # a wired input may follow after a delay
            if self.sensors.output_changed(self.t_ms, old, new):
                self._recompute_inputs()

    def _set_output_word(self, k: int, value: int) -> None:
        shift = 32 * k
        new = (self.prog_out & ~(_M32 << shift)) | ((value & _M32) << shift)
        self._set_outputs(new & self._out_mask)

    def _forget_sample(self) -> None:
        self._sample = None

    def _pls_write(self, target: int, level: int) -> None:
        """A PLS sets its output: physical output ``target``, or VOUT.n for PLS_VOUT + n."""
        if target >= softmc.PLS_VOUT:
            self.vio.set_vout(target - softmc.PLS_VOUT, level)
        else:
            bit = 1 << target
            self._set_outputs(self.out_bits | bit if level else self.out_bits & ~bit)

    def _get_output_bit(self, addr: int) -> int:
        return (self.out_bits >> (addr - abi.OUTPUT_STATE_BASE)) & 1

    def _write_list(self, lst: list, ch: int, value: int) -> None:
        if lst[ch] != value:
            lst[ch] = value
            self._sample = None

    def _refresh_adc(self) -> None:
        adc = list(self.sensors.adc)
        for ch, v in self._adc_override.items():
            adc[ch] = v
        for ch, v in self._adc_force.items():
            adc[ch] = v
        if adc != self._adc:
            self._adc = adc
            self._sample = None

    def _read_only(self, addr: int, value: int) -> None:
        if ("ro", addr) not in self._warned:
            self._warned.add(("ro", addr))
            what = abi.describe_register(addr) or str(addr)
            self._notes.append(("warning", f"gvarset({addr}, {value}) ignored: {what} is "
                                           f"read-only"))

    def _bad_pin(self, func: str, pin: int, count: int, what: str) -> None:
        if (func, pin) not in self._warned:
            self._warned.add((func, pin))
            self._notes.append(("warning", f"{func}({pin}): no such pin (the machine has "
                                           f"{what} 0..{count - 1})"))

    def _set_hw_limits(self, addr: int, value: int) -> None:
        self._special[addr] = value
        self._hw_limits = value == 0

    def _set_sw_limits(self, addr: int, value: int) -> None:
        self._special[addr] = value
        self.motion.soft_limits = value == 0

    def _set_jog_time(self, addr: int, value: int) -> None:
        self._special[addr] = value
        self.motion.set_jog_time(max(0, value))

    def _set_jog_units(self, addr: int, value: int) -> None:
        self._special[addr] = value
        self.motion.set_jog_units(max(0, value))

    def _set_jog_speed(self, addr: int, value: int) -> None:
        self._special[addr] = value
        self.motion.set_jog_speed(value)

    def _set_jog(self, addr: int, value: int) -> None:
        self._special[addr] = value
        self.motion.jog_write(self.t_ms, value)

    def _check_hard_limits(self) -> None:
        m = self.motion
        vel = m.vel
        ins = self.in_bits
        for sw in self.sensors.hard_limits:
            v = vel[sw.axis]
            if v == 0.0 or ((ins >> sw.pin) & 1) != sw.active:
                continue
            if sw.toward == 0 or (v < 0) == (sw.toward < 0):
                name = f" {sw.name}" if sw.name else ""
                self._notes.append((
                    "error", f"hard limit: input {sw.pin}{name} tripped with "
                             f"{AXES[sw.axis]} at {fmt_mm(m.pos[sw.axis])} "
                             f"{m.unit[sw.axis]}; motion stopped"))
                m.halt()
                self._sample = None
                return


def _bits_on(v: int) -> list[int]:
    """The numbers of the bits set in v, ascending."""
    out, n = [], 0
    while v:
        if v & 1:
            out.append(n)
        v >>= 1
        n += 1
    return out
