"""One table of the language's own words: keywords, built-in functions and
predefined variables. The tokenizer, the checker, the code generator, the
highlighter, completion and hover all read it, so a word is added in one place.

Built-in *constants* (``PLCCMD_LINE_STOP``, ``GVAR_HW_PWM0``, ...) are the
controller's ABI and live in :mod:`plcbuilder.bytecode.abi`; :data:`CONSTANTS`
names that table here.
"""

from __future__ import annotations

from plcbuilder._support.records import dataclass
from plcbuilder.bytecode import abi
from plcbuilder.bytecode.opcodes import Op

TYPE_CHECKING = False               # (typing is not imported at run time: start-up)
if TYPE_CHECKING:
    from typing import Optional

#: Statement keywords -> the parser's terminal name.
KEYWORDS: dict[str, str] = {"if": "IF", "else": "ELSE", "do": "DO", "while": "WHILE"}


@dataclass(frozen=True)
class Builtin:
    """A built-in function: what it takes, whether it gives a value, its opcode."""
    name: str
    params: tuple[str, ...]
    returns: bool
    op: Optional[Op]
    doc: str

    @property
    def arity(self) -> int:
        return len(self.params)

    @property
    def signature(self) -> str:
        ret = "value = " if self.returns else ""
        return f"{ret}{self.name}({', '.join(self.params)})"

    @property
    def call_text(self) -> str:
        """``name(params)``: how a call is written."""
        return f"{self.name}({', '.join(self.params)})"

    @property
    def returns_text(self) -> str:
        return "returns a value" if self.returns else "returns nothing"


FUNCTIONS: dict[str, Builtin] = {b.name: b for b in (
    Builtin("portset", ("pin",), False, Op.PORTSET, "Set output pin to 1."),
    Builtin("portclear", ("pin",), False, Op.PORTCLR, "Clear output pin to 0."),
    Builtin("portclr", ("pin",), False, Op.PORTCLR, "Clear output pin to 0 (same as portclear)."),
    Builtin("portget", ("pin",), True, Op.PORTGET, "The state of input pin (0 or 1)."),
    Builtin("gvarget", ("addr",), True, Op.GVARGET, "Read global variable register addr."),
    Builtin("gvarset", ("addr", "value"), False, Op.GVARSET, "Write value to global register addr."),
    Builtin("g0moveA", ("flags", "axis_mask", "distance"), False, Op.G0MOVE,
            "Positioning move: flags bit0 absolute, bit1 machine coordinates, bit7 delayed start; "
            "axis_mask X=1 Y=2 Z=4 ...; distance in 0.01 mm."),
    Builtin("exit", ("code",), False, Op.EXIT, "End the procedure with an exit code (99 = normal)."),
)}
#: what to suggest when a function that returns nothing is used as a value
VALUE_TWIN = {"gvarset": "gvarget", "portset": "portget", "portclear": "portget", "portclr": "portget"}
#: the functions whose first argument is a register / a pin / an exit code (for hover help)
REGISTER_FUNCTIONS = frozenset({"gvarget", "gvarset"})
PIN_FUNCTIONS = frozenset({"portset", "portclear", "portclr", "portget"})


@dataclass(frozen=True)
class Predefined:
    """A predefined variable: a slot of the procedure's variables, or a
    hardware register read and written through gvarget/gvarset."""
    name: str
    slot: Optional[int]          # the variable slot (None for register-mapped ones)
    register: Optional[int]      # the register address (None for slot variables)
    software_only: bool
    read_only: bool
    doc: str

    @property
    def kind(self) -> str:
        return "register" if self.register is not None else "slot"


_SLOT_DOCS = {
    "eparam": "the parameter the procedure was started with (M-code P/eparam)",
    "proc": "the procedure's state code, shown by myCNC (plc_proc_* / proc_* names)",
    "timer": "an ordinary variable; the manual's delays count it down by hand, one per tick",
    "vexit": "a value sent with the exit event (beside the exit code)",
    "message": "a message to the host: at the end of the tick it is sent with command "
               "(var00) and parameter (var01), then set back to 0",
    "command": "the same variable as var00 (sent with a message)",
    "parameter": "the same variable as var01 (sent with a message)",
    "Param": "software procedures: the procedure's parameter",
}
for _i in range(16):
    _SLOT_DOCS.setdefault(f"var{_i:02d}", "initialised from plc-variables.xml before the "
                                         "procedure starts" + (" (also 'command')" if _i == 0 else
                                                               " (also 'parameter')" if _i == 1 else ""))
_REGISTER_DOCS = {
    "pwm01": "PWM0", "pwm02": "PWM1", "pwm03": "PWM2", "pwm04": "PWM3",
    "dac01": "DAC0", "dac02": "DAC1", "adc01": "ADC0 (read-only)", "adc02": "ADC1 (read-only)",
}

PREDEFINED: dict[str, Predefined] = {
    **{n: Predefined(n, s, None, False, False, _SLOT_DOCS[n]) for n, s in abi.SLOT_NAMES.items()},
    **{n: Predefined(n, None, r, False, n in abi.READ_ONLY_VARIABLES, _REGISTER_DOCS[n])
       for n, r in abi.MAPPED_VARIABLES.items()},
    **{n: Predefined(n, s, None, True, False, _SLOT_DOCS[n])
       for n, s in abi.SOFTWARE_SLOT_NAMES.items()},
}

#: Built-in constant names and their values (the manual's tables).
CONSTANTS: dict[str, int] = abi.BUILTIN_NAMES


def predefined(software: bool) -> dict[str, Predefined]:
    """The predefined variables a procedure of that kind has."""
    return {n: p for n, p in PREDEFINED.items() if software or not p.software_only}


def slot_names(software: bool) -> dict[str, int]:
    """Predefined slot variables -> their slot, for a procedure of that kind."""
    return {n: p.slot for n, p in predefined(software).items() if p.slot is not None}


#: Register-mapped predefined variables -> their register address.
REGISTERS: dict[str, int] = {n: p.register for n, p in PREDEFINED.items() if p.register is not None}


def is_reserved(name: str) -> bool:
    """A keyword, a built-in function, a predefined variable or a built-in constant."""
    return name in KEYWORDS or name in FUNCTIONS or name in PREDEFINED or name in CONSTANTS
