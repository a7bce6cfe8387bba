"""The machine's own wiring of its inputs and ADC channels.

- Inputs tied to an axis position (home and limit switches, a probe, plasma IHC
  contact): active while the axis' reported position (0.01 mm, rounded) is at or
  below ``below`` and/or at or above ``above``.
- Inputs that follow an output after a delay (arc-OK after the plasma torch
  output, coolant flow after flood).
- Constant inputs (air pressure OK).
- ADC channels: a constant, a ramp, a linear function of an axis position, each
  optionally with deterministic noise drawn from a seed.

All of this is "the wiring": what a pin reads when nobody has set it by hand.
The machine combines it with manual overrides (which win).
"""

from __future__ import annotations

from plcbuilder.bytecode.abi import AXES

from .machine_config import ADC_CHANNELS, AdcConfig, MachineConfig

TYPE_CHECKING = False               # (typing is not imported at run time: start-up)
if TYPE_CHECKING:
    from typing import Optional


_I32_MIN, _I32_MAX = -(1 << 31), (1 << 31) - 1


class PositionInput:
    __slots__ = ("pin", "bit", "axis", "lo", "hi", "active", "name", "hard_limit", "toward")

    def __init__(self, pin: int, axis: int, lo: Optional[int], hi: Optional[int], active: int,
                 name: str, hard_limit: bool):
        self.pin = pin
        self.bit = 1 << pin
        self.axis = axis
        self.lo = lo            # active at position >= lo (the "above" key)
        self.hi = hi            # active at position <= hi (the "below" key)
        self.active = active
        self.name = name
        self.hard_limit = hard_limit
        # the direction of travel that runs into the switch: -1, +1, or 0 (both)
        self.toward = -1 if lo is None else (1 if hi is None else 0)

    def is_active(self, ipos: list[int]) -> bool:
        p = ipos[self.axis]
        return (self.lo is None or p >= self.lo) and (self.hi is None or p <= self.hi)


def _noise(cfg: AdcConfig):
    """A channel's noise generator, seeded (None for a channel without noise:
    ``random`` is imported only for a machine that has some)."""
    if not cfg.noise:
        return None
    import random
    return random.Random(cfg.seed)


class AdcSource:
    __slots__ = ("cfg", "axis", "rng", "dynamic")

    def __init__(self, cfg: AdcConfig):
        self.cfg = cfg
        self.axis = AXES.index(cfg.axis) if cfg.axis else None
        self.rng = _noise(cfg)
        self.dynamic = cfg.source == "ramp" or cfg.noise > 0

    def reset(self) -> None:
        self.rng = _noise(self.cfg)

    def value(self, t_ms: int, ipos: list[int]) -> int:
        c = self.cfg
        if c.source == "constant":
            v = float(c.value)
        elif c.source == "ramp":
            if c.repeat:
                frac = (t_ms % c.period_ms) / c.period_ms
            else:
                frac = min(t_ms / c.period_ms, 1.0)
            v = c.start + (c.end - c.start) * frac
        else:
            v = c.offset + c.scale * ipos[self.axis] / 100.0
        iv = round(v)
        if c.noise:
            iv += self.rng.randint(-c.noise, c.noise)
        if c.min is not None and iv < c.min:
            iv = c.min
        if c.max is not None and iv > c.max:
            iv = c.max
        return min(max(iv, _I32_MIN), _I32_MAX)     # a register holds 32 bits: saturate


class Sensors:
    """Computes the wired input bits and the ADC values; holds delayed changes."""

    def __init__(self, config: MachineConfig):
        self.position: list[PositionInput] = []
        self.followers: dict[int, list[tuple[int, int, int, int]]] = {}  # out -> (pin, on, off, active)
        self.const_bits = 0
        self.hard_limits: list[PositionInput] = []
        self.names: dict[int, str] = {}
        for w in config.inputs:
            self.names[w.pin] = w.name
            if w.kind == "axis":
                lo = None if w.above is None else round(w.above * 100)
                hi = None if w.below is None else round(w.below * 100)
                pi = PositionInput(w.pin, AXES.index(w.axis), lo, hi, w.active, w.name,
                                   w.hard_limit)
                self.position.append(pi)
                if w.hard_limit:
                    self.hard_limits.append(pi)
            else:
                if w.kind == "output":
                    self.followers.setdefault(w.output, []).append(
                        (w.pin, w.delay_ms, w.off_delay_ms, w.active))
                elif w.value:
                    self.const_bits |= 1 << w.pin
        self.followed_mask = 0
        for out in self.followers:
            self.followed_mask |= 1 << out
        self.adc_sources: dict[int, AdcSource] = {a.channel: AdcSource(a) for a in config.adc}
        self.dynamic_adc = [s for s in self.adc_sources.values() if s.dynamic]
        self.axis_adc = [s for s in self.adc_sources.values()
                         if s.cfg.source == "axis" and not s.dynamic]
        self.wired = 0
        self.pending: dict[int, tuple[int, int]] = {}   # pin -> (due tick, level)
        self.adc = [0] * ADC_CHANNELS

    def reset(self, ipos: list[int], outputs: int = 0) -> None:
        """The wiring at power-on: outputs off, no change pending."""
        self.pending.clear()
        w = self.const_bits
        for out, fl in self.followers.items():
            on = outputs >> out & 1
            for pin, _, _, active in fl:
                if (active if on else 1 - active):
                    w |= 1 << pin
        self.wired = w
        self.update_positions(ipos)
        for s in self.adc_sources.values():
            s.reset()
        self.adc = [0] * ADC_CHANNELS
        for ch, s in self.adc_sources.items():
            self.adc[ch] = s.value(0, ipos)

    def update_positions(self, ipos: list[int]) -> bool:
        """Re-evaluate the position switches. True when a wired bit changed."""
        w = old = self.wired
        for pi in self.position:
            if pi.is_active(ipos) == (pi.active == 1):
                w |= pi.bit
            else:
                w &= ~pi.bit
        self.wired = w
        return w != old

    def output_changed(self, t: int, old: int, new: int) -> bool:
        """Outputs changed in tick t: schedule the followers. True when a wired
        bit changed at once (a zero delay)."""
        changed = (old ^ new) & self.followed_mask
        now = False
        out = 0
        while changed:
            if changed & 1:
                on = new >> out & 1
                for pin, d_on, d_off, active in self.followers[out]:
                    level = active if on else 1 - active
                    delay = d_on if on else d_off
                    if delay <= 0:
                        self.pending.pop(pin, None)
                        now |= self._set(pin, level)
                    else:
                        self.pending[pin] = (t + delay, level)
            changed >>= 1
            out += 1
        return now

    def apply_due(self, t: int) -> bool:
        """Apply the delayed changes due by tick t. True when a wired bit changed."""
        changed = False
        for pin, (due, level) in list(self.pending.items()):
            if due <= t:
                del self.pending[pin]
                changed |= self._set(pin, level)
        return changed

    def _set(self, pin: int, level: int) -> bool:
        old = self.wired
        self.wired = old | (1 << pin) if level else old & ~(1 << pin)
        return self.wired != old

    def update_adc(self, t: int, ipos: list[int], moved: bool) -> bool:
        """Recompute the ADC channels that may have changed. True if any did."""
        changed = False
        adc = self.adc
        for s in self.dynamic_adc:
            v = s.value(t, ipos)
            if adc[s.cfg.channel] != v:
                adc[s.cfg.channel] = v
                changed = True
        if moved:
            for s in self.axis_adc:
                v = s.value(t, ipos)
                if adc[s.cfg.channel] != v:
                    adc[s.cfg.channel] = v
                    changed = True
        return changed
