"""The schedulers of the target profiles (SPEC §9, docs/targets.md): how a
Huazhong or TG Motion program is called, in place of myCNC's hardware and
software PLC. The controller picks one with :func:`make_plc`.

    TargetConfig    what a target needs beyond the program: its name, the P
                    registers, the B registers kept from the last run, TG
                    Motion's cycle times and instruction cost
    calls           one call of a procedure to its end, counting instructions
    base            TargetPLC: what both schedulers share (a PLC subclass)
    huazhong        batch read -> plc1/plc2 by period -> batch write, every ms
    tgmotion        slots: Program_05 each, Program_04 in the fourth, 01..03 in the time left
"""

from __future__ import annotations

from plcbuilder._support.records import dataclass
from plcbuilder.bytecode import targets as T

TYPE_CHECKING = False               # (typing is not imported at run time: start-up)
if TYPE_CHECKING:
    from typing import Optional


class TargetConfigError(ValueError):
    """A target configuration the controller cannot run; the message says why."""


@dataclass(frozen=True)
class TargetConfig:
    name: str = T.MYCNC
    #: Huazhong: the P registers (100 16-bit values) and the B registers kept
    #: from the controller's last run (None: all 0)
    parameters: tuple[int, ...] = ()
    retained: Optional[tuple[int, ...]] = None
    #: TG Motion
    cycle_time_us: int = 500
    program_periods_us: tuple[int, int, int] = (1000, 1000, 1000)
    instruction_ns: int = T.TGM_DEFAULT_INSTRUCTION_NS
    #: the signals the oscilloscope samples after each Program_04 ("in 9", "out 7",
    #: "adc 0", "pwm 1", "dac 0", "gvar ADDR", "Program.var"); () for its default
    scope: tuple[str, ...] = ()

    def check(self) -> None:
        """Raise TargetConfigError naming the first value out of range."""
        if self.name not in T.TARGETS:
            raise TargetConfigError(f"unknown target {self.name!r} (one of {', '.join(T.TARGETS)})")
        p, b = T.BANKS["P"], T.BANKS["B"]
        for what, vals, bank in (("parameters", self.parameters, p),
                                 ("retained B registers", self.retained or (), b)):
            if len(vals) > bank.size:
                raise TargetConfigError(f"{len(vals)} {what}, {bank.name} has {bank.size}")
            for i, v in enumerate(vals):
                if not isinstance(v, int) or not 0 <= v <= bank.mask:
                    raise TargetConfigError(f"{bank.name}[{i}] must be from 0 to {bank.mask}, "
                                            f"not {v!r}")
        if self.cycle_time_us not in T.TGM_CYCLE_TIMES:
            raise TargetConfigError(f"cycle_time_us must be 250, 500 or 1000, not "
                                    f"{self.cycle_time_us}")
        lo = T.TGM_PERIOD_MIN
        if len(self.program_periods_us) != 3:
            raise TargetConfigError("three periods: Program_01, Program_02, Program_03")
        for i, v in enumerate(self.program_periods_us):
            if not isinstance(v, int) or isinstance(v, bool) or v < lo:
                raise TargetConfigError(f"cycle_time_program_0{i + 1}_us must be at least {lo} "
                                        f"(µs), not {v!r}")
        from plcbuilder.controller.targets.scope import ScopeError, parse_signal
        if len(self.scope) > T.TGM_OSC_SIGNALS_MAX:
            raise TargetConfigError(f"{len(self.scope)} oscilloscope signals: at most "
                                    f"{T.TGM_OSC_SIGNALS_MAX}")
        for text in self.scope:
            try:
                parse_signal(text)
            except ScopeError as exc:
                raise TargetConfigError(f"oscilloscope: {exc}") from None
        if not isinstance(self.instruction_ns, int) or not 1 <= self.instruction_ns <= 1_000_000:
            raise TargetConfigError(f"instruction_ns must be from 1 to 1000000, not "
                                    f"{self.instruction_ns!r}")


def make_plc(config: TargetConfig, machine, **kwargs):
    """The scheduler of ``config``'s target over ``machine`` (a PLC subclass)."""
    config.check()
    if config.name == T.HUAZHONG:
        from plcbuilder.controller.targets.huazhong import HuazhongPLC
        return HuazhongPLC(machine, config, **kwargs)
    if config.name == T.TGMOTION:
        from plcbuilder.controller.targets.tgmotion import TgMotionPLC
        return TgMotionPLC(machine, config, **kwargs)
    raise TargetConfigError(f"{config.name} is scheduled by the myCNC PLC, not a target scheduler")
