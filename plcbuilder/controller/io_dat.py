"""``IO.DAT``: the softMC file that presets the physical inputs.

The softMC seed: "Value of sys.din.1 to sys.din.23 is read from file IO.DAT,
from field INP", in the format ``DIP=0xXX`` / ``INP=0xXX``. In a project folder it
sets the level that inputs read while the machine file does not wire them:
bit b of INP is input b (the seed's sys.din.b+1), for the 23 inputs 0..22;
DIP is kept and read by procedures at register ``IO_DAT_DIP``.

One ``KEY=VALUE`` a line (keys INP and DIP, either case; values hexadecimal
``0x..`` or decimal; spaces around ``=`` allowed); blank lines are skipped.
Anything else — an unknown key, a key twice, a value that is not a number or
too wide — is a :class:`ConfigError` naming the file and the line.

"File IO.DAT is generated automatically if it does not exist on the flash
disk" (the seed): :func:`load_io_dat` writes one with every value 0 where it
was to be read (the project's folder is the simulated controller's flash disk)
and reads that; a folder it cannot write to gives the same zeros, with a note
saying why.
"""

from __future__ import annotations

import dataclasses
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Optional

from plcbuilder._support.files import atomic_write, read_bounded

from .machine_config import ConfigError, MachineConfig

IO_DAT_FILE = "IO.DAT"
MAX_IO_DAT_BYTES = 64 * 1024
INP_BITS = 23                  # sys.din.1 .. sys.din.23
DIP_BITS = 8                   # DIP=0xXX: one byte
_LINE = re.compile(r"^\s*([A-Za-z]+)\s*=\s*(\S+)\s*$")
_NUMBER = re.compile(r"^(0[xX][0-9A-Fa-f]+|[0-9]+)$")
#: what a generated IO.DAT holds: the seed's two fields, every input preset 0
GENERATED = "DIP=0x00\nINP=0x000000\n"


@dataclass(frozen=True)
class IoDat:
    """What an IO.DAT says (0 for a key it does not have)."""
    inp: int = 0
    dip: int = 0
    source: Optional[str] = None
    #: set when the file was generated (or could not be): a line for the run log
    note: Optional[str] = None


def parse_io_dat(text: str, name: str = IO_DAT_FILE) -> IoDat:
    """Parse the text of an IO.DAT; ``name`` is the file named in errors."""
    values: dict[str, tuple[int, int]] = {}
    widths = {"INP": INP_BITS, "DIP": DIP_BITS}
    for n, line in enumerate(text.splitlines(), 1):
        if not line.strip():
            continue
        m = _LINE.match(line)
        if not m:
            raise ConfigError(f"expected KEY=VALUE (INP=0x.. or DIP=0x..), got {line.strip()!r}",
                              name, n)
        key, raw = m.group(1).upper(), m.group(2)
        if key not in widths:
            raise ConfigError(f"unknown key {m.group(1)!r} (IO.DAT has INP and DIP)", name, n,
                              m.group(1))
        if key in values:
            raise ConfigError(f"{key} is given twice (first on line {values[key][1]})", name, n,
                              key)
        if not _NUMBER.match(raw):
            raise ConfigError(f"{raw!r} is not a number (write it as 0x.. or in decimal)",
                              name, n, key)
        v = int(raw, 0) if raw[:2].lower() == "0x" else int(raw, 10)
        if v >> widths[key]:
            what = (f"inputs 0..{INP_BITS - 1} (sys.din.1..{INP_BITS})" if key == "INP"
                    else f"{DIP_BITS} bits")
            raise ConfigError(f"{raw} is too wide: {key} holds {what}, at most "
                              f"{hex((1 << widths[key]) - 1)}", name, n, key)
        values[key] = (v, n)
    return IoDat(inp=values.get("INP", (0, 0))[0], dip=values.get("DIP", (0, 0))[0],
                 source=name)


def load_io_dat(path, generate: bool = True) -> IoDat:
    """Read and parse an IO.DAT file; one that does not exist is generated first
    (``generate``, the seed's rule), else read as all 0."""
    p = Path(path)
    if generate and not p.exists():
        try:
            atomic_write(p, GENERATED)
        except OSError as e:
            return IoDat(source=str(p), note=f"{p}: IO.DAT does not exist and cannot be "
                                             f"generated ({e.strerror or e}): every preset is 0")
        return dataclasses.replace(parse_io_dat(GENERATED, str(p)),
                                   note=f"{p}: IO.DAT did not exist; generated it with every "
                                        f"value 0 (the seed: \"generated automatically if it "
                                        f"does not exist\")")
    try:
        data = read_bounded(p, MAX_IO_DAT_BYTES, "IO.DAT")
    except OSError as e:
        raise ConfigError(f"cannot read IO.DAT: {e.strerror or e}", str(p)) from None
    try:
        text = data.decode("ascii")
    except UnicodeDecodeError as e:
        raise ConfigError(f"not plain ASCII text (byte {e.start})", str(p)) from None
    return parse_io_dat(text, str(p))


def with_io_dat(config: MachineConfig, io: Optional[IoDat]) -> MachineConfig:
    """The machine description with IO.DAT's presets (unchanged for None)."""
    if io is None:
        return config
    return dataclasses.replace(config, input_preset=io.inp, dip=io.dip)


def io_dat_of(folder) -> Optional[Path]:
    """The IO.DAT of a project folder, if it has one."""
    p = Path(folder) / IO_DAT_FILE
    return p if p.is_file() else None


def io_dat_path(folder) -> Path:
    """Where a project's IO.DAT is (or is generated): next to plcbuilder.toml."""
    return Path(folder) / IO_DAT_FILE
