"""Hover help: what the name or number under the mouse is (the IDE's
tooltips and the language server's hover give this same text).

- a register number (``gvarget(6060)``) or name (``GVAR_CURRENT_MOTION_CODE``)
  says what the register is (from :func:`plcbuilder.bytecode.abi.describe_register`);
- a number given to ``exit()`` names the exit code, one assigned to
  ``message`` or ``proc`` names the message or proc state;
- a define shows its value and where it is defined; built-in names their
  value and table; built-in functions their signature; predefined variables
  what they hold; the file's own variables and procedures what they are.

:func:`hover_text` is pure (word + context -> text); the editor or the
language server supplies the word and the text before it.
:func:`register_name` is the short name of a register number (the language
server's inlay hints), :func:`signature_text` a built-in's call tip.
"""

from __future__ import annotations

from pathlib import Path
from typing import Optional

from plcbuilder.bytecode import abi
from plcbuilder.lang import symbols as lang_symbols


def _num(v: int) -> str:
    return f"{v} (0x{v & 0xFFFFFFFF:x})" if v >= 0 else f"{v}"


def register_text(value: int) -> Optional[str]:
    desc = abi.describe_register(value)
    if desc is None:
        return None
    return f"register {_num(value)}: {desc}"


def value_text(value: int, context: str = "") -> Optional[str]:
    """Hover text for a number (given what precedes it)."""
    if context == "exit":
        name = abi.exit_name(value)
        desc = abi.EXIT_DESCRIPTIONS.get(value)
        if name:
            return f"exit code {value}: {name}" + (f" — {desc}" if desc else "")
        return f"exit code {value}"
    if context == "message":
        name = abi.message_name(value)
        return f"message {value}: {name}" if name else f"message {value}"
    if context == "proc":
        name = abi.proc_name(value)
        return f"proc state {value}: {name}" if name else f"proc state {value}"
    if context == "pin":
        return f"pin {value}"
    reg = register_text(value)
    if context == "register":
        return reg or f"register {_num(value)}: a plain global register (keeps what is written)"
    if reg and value >= 1000:
        return reg
    if value > 9 or value < 0:
        return _num(value)
    return None


def register_name(value: int) -> Optional[str]:
    """The short name of register ``value`` (``6060`` -> ``GVAR_CURRENT_MOTION_CODE``,
    ``0x403`` -> ``output 3 state``), or None for a plain register."""
    name = _REGISTER_NAMES.get(value)
    if name is not None:
        return name
    desc = abi.describe_register(value)
    if desc is None:
        return None
    return desc.split(":")[0].replace(" (read-only)", "").replace(" (0.01 mm)", "") \
        .replace(" (0.01 mm / 0.01 deg)", "")


_REGISTER_NAMES: dict[int, str] = {}
for _name, _value in abi.GVAR.items():
    if not _name.startswith(("GVAR_CURRENT_MACHINE_POSITION", "GVAR_CURRENT_PROGRAM_POSITION")):
        _REGISTER_NAMES.setdefault(_value, _name)


def signature_text(name: str) -> Optional[str]:
    """The call tip of a built-in function: its signature and what it does."""
    b = lang_symbols.FUNCTIONS.get(name)
    if b is None:
        return None
    return f"{b.call_text}  — {b.returns_text}\n{b.doc}"


def hover_text(word: str, before: str = "", *, software: bool = False, symbols=None,
               header_defines: Optional[dict] = None, variables: tuple = (),
               procedures: dict | None = None) -> Optional[str]:
    """The hover text for word (an identifier or a number); ``before`` is the
    text of the line before it. ``symbols`` is the last compile's
    CompileResult.symbols; ``header_defines`` {name: (value, file, line)}."""
    if not word:
        return None
    if word[:1].isdigit():
        value = lang_symbols.number_of(word)
        if value is None:
            return None
        return value_text(value, lang_symbols.number_context(before))
    if word in lang_symbols.KEYWORDS:
        return None
    b = lang_symbols.FUNCTIONS.get(word)
    if b is not None:
        return f"{b.call_text} — built-in function, {b.returns_text}\n{b.doc}"
    v = lang_symbols.PREDEFINED.get(word)
    if v is not None and v.register is not None:
        return f"{word}: predefined variable, {v.doc} (register {v.register})"
    if v is not None and (not v.software_only or software):
        return f"{word}: predefined variable — {v.doc}"
    defines = getattr(symbols, "defines", None) or {}
    if word in defines:
        value, span = defines[word]
        where = f"{Path(span.file).name}:{span.line}" if span is not None else ""
        return _define_text(word, value, where)
    if header_defines and word in header_defines:
        value, file, line = header_defines[word]
        return _define_text(word, value, f"{Path(file).name}:{line}")
    if word in abi.BUILTIN_NAMES:
        value = abi.BUILTIN_NAMES[word]
        kind_name = abi.BUILTIN_KIND.get(word, "built-in name")
        text = f"{word} = {_num(value)} — built-in {kind_name}"
        if kind_name == "register":
            desc = abi.describe_register(value)
            if desc and desc != word:
                text += f"\n{desc}"
        elif kind_name == "exit code" and value in abi.EXIT_DESCRIPTIONS:
            text += f"\n{abi.EXIT_DESCRIPTIONS[value]}"
        return text
    procs = dict(procedures or {})
    procs.update(getattr(symbols, "procedures", None) or {})
    if word in procs:
        span = procs[word]
        line = f", line {span.line}" if span is not None else ""
        return f"{word}(): procedure of this file{line}"
    own = set(variables) | set(getattr(symbols, "variables", None) or [])
    if word in own:
        return f"{word}: variable of this file (0 when the procedure starts)"
    return None


def _define_text(name: str, value: str, where: str) -> str:
    text = f"#define {name} {value}".rstrip()
    if where:
        text += f"    ({where})"
    n = lang_symbols.number_of(value)
    if n is not None and n >= 0:
        reg = abi.describe_register(n) if n >= 1000 else None
        if reg:
            text += f"\nas a register: {reg}"
        elif name.startswith(("INPUT_", "OUTPUT_")):
            text += f"\n{'input' if name.startswith('INPUT_') else 'output'} pin {n}"
    return text
