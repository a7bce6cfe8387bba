"""The Huazhong target's parameters file: the values of the P registers.

The file (``parameters.toml`` unless ``[huazhong] parameters`` names another)
has one table, ``[P]``, an entry per register that is not 0::

    [P]
    0 = 500        # P[0]
    7 = 0x10       # P[7]

P has 100 registers of 16 bits (P[0] .. P[99], values 0 .. 65535). A missing
file means all 0. Every mistake raises ProjectError naming the file and line.
"""

from __future__ import annotations

import tomllib
from pathlib import Path

from plcbuilder._support.files import read_bounded
from plcbuilder._support.toml_errors import TomlLocator, decode_error
from plcbuilder._support.toml_errors import loads as toml_loads
from plcbuilder.bytecode.targets import BANKS
from plcbuilder.project.model import ProjectError

MAX_BYTES = 1 << 20


def load_parameters(path: Path) -> list[int]:
    """The P registers from ``path`` (all 0 when it does not exist)."""
    bank = BANKS["P"]
    values = [0] * bank.size
    if not path.exists():
        return values
    try:
        raw = read_bounded(path, MAX_BYTES, "parameters file")
        text = raw.decode("utf-8")
    except OSError as exc:
        raise ProjectError(f"cannot read: {exc.strerror or exc}", path) from None
    except UnicodeDecodeError as exc:
        raise ProjectError("not UTF-8 text", path, raw[:exc.start].count(b"\n") + 1) from None
    try:
        doc = toml_loads(text)
    except tomllib.TOMLDecodeError as exc:
        msg, line = decode_error(exc, text)
        raise ProjectError(f"not valid TOML: {msg}", path, line) from None
    where = TomlLocator(text)
    for key in doc:
        if key != "P":
            raise ProjectError(f"unknown table or key {key!r} (the file has one table, [P])",
                               path, where.line_of((key,)), key)
    table = doc.get("P", {})
    if not isinstance(table, dict):
        raise ProjectError("P must be a table: [P] then lines like 0 = 500", path,
                           where.line_of(("P",)), "P")
    for key, value in table.items():
        line = where.line_of(("P", key))
        if not key.isdigit() or not 0 <= int(key) < bank.size:
            raise ProjectError(f"P[{key}] does not exist: P has registers 0 to {bank.size - 1}",
                               path, line, f"P.{key}")
        if type(value) is not int or not 0 <= value <= bank.mask:
            raise ProjectError(f"P[{key}] must be a whole number from 0 to {bank.mask}, "
                               f"is {value!r}", path, line, f"P.{key}")
        values[int(key)] = value
    return values
