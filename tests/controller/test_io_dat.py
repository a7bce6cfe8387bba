"""IO.DAT (SPEC §9, "softMC I/O"): the file's format, its errors, and how its INP
presets the machine's inputs."""

from __future__ import annotations

import pytest

from plcbuilder.bytecode import softmc
from plcbuilder.controller.io_dat import (IoDat, io_dat_of, load_io_dat, parse_io_dat,
                                          with_io_dat)
from plcbuilder.controller.machine import Machine
from plcbuilder.controller.machine_config import ConfigError, default_machine, parse_machine



def test_the_seeds_format():
    """SPEC §9: "physical inputs preset from an `IO.DAT` file in the project
    (`INP=0xXX`, `DIP=0xXX` lines, as the seed shows)"."""
    io = parse_io_dat("DIP=0x3C\nINP=0x05\n")
    assert (io.inp, io.dip) == (0x05, 0x3C)
    # either order, either case, spaces, CRLF, blank lines, decimal values
    io = parse_io_dat("\r\n inp = 0x7fffff \r\n\r\ndip=255\r\n")
    assert (io.inp, io.dip) == ((1 << 23) - 1, 255)
    assert parse_io_dat("") == IoDat(0, 0, "IO.DAT")


@pytest.mark.parametrize("text, line, words", [
    ("INP=0x01\nhello\n", 2, "expected KEY=VALUE"),
    ("INP=0x01\n\nOUT=0x02\n", 3, "unknown key 'OUT'"),
    ("DIP=0x01\nINP=0x02\ninp=0x03\n", 3, "INP is given twice (first on line 2)"),
    ("INP=0xZZ\n", 1, "'0xZZ' is not a number"),
    ("INP=-1\n", 1, "is not a number"),
    ("INP=0x800000\n", 1, "too wide: INP holds inputs 0..22"),
    ("DIP=0x100\n", 1, "too wide: DIP holds 8 bits"),
])
def test_errors_name_file_and_line(text, line, words):
    """SPEC §9: "physical inputs preset from an `IO.DAT` file in the project
    (`INP=0xXX`, `DIP=0xXX` lines, as the seed shows)"; anything else in the file
    is refused naming the file and the line (issue 15, "Bad input")."""
    with pytest.raises(ConfigError) as exc:
        parse_io_dat(text, "proj/IO.DAT")
    assert exc.value.file == "proj/IO.DAT" and exc.value.line == line
    assert str(exc.value).startswith(f"proj/IO.DAT:{line}: ")
    assert words in str(exc.value)


def test_unreadable_files(tmp_path):
    """SPEC §9: IO.DAT errors name the file; a binary file or a folder is refused."""
    p = tmp_path / "IO.DAT"
    p.write_bytes(b"INP=0x01\n\xff\n")
    with pytest.raises(ConfigError, match="not plain ASCII"):
        load_io_dat(p)
    (tmp_path / "d").mkdir()
    with pytest.raises(ConfigError, match="cannot read IO.DAT"):
        load_io_dat(tmp_path / "d")
    p.write_text("INP=0x11\n", encoding="ascii")
    assert load_io_dat(p).inp == 0x11
    assert io_dat_of(tmp_path) == p
    assert io_dat_of(tmp_path / "d") is None


def test_inp_presets_unwired_inputs():
    """SPEC §9: "physical inputs preset from an `IO.DAT` file in the project": bit
    b of INP is input b (the seed's sys.din.b+1) at power-on and after a reset; an
    input set by hand still overrides it."""
    cfg = with_io_dat(parse_machine(""), IoDat(inp=0b1000_0000_0101, dip=7))
    m = Machine(cfg)
    assert m.inputs_on() == [0, 2, 11]
    assert m.gvarget(7180) == 0b1000_0000_0101
    m.set_input(2, 0)
    assert m.inputs_on() == [0, 11]
    m.reset()
    assert m.inputs_on() == [0, 2, 11]
    assert m.gvarget(softmc.IO_DAT_DIP) == 7


def test_wired_inputs_win_with_a_warning():
    """SPEC §2: the machine file's wiring of a pin stays what it reads; an IO.DAT
    bit on a wired pin is reported, not applied."""
    base = default_machine()
    wired = sorted(i.pin for i in base.inputs)
    free = next(p for p in range(23) if p not in wired)
    m = Machine(with_io_dat(base, IoDat(inp=(1 << wired[0]) | (1 << free))))
    plain = Machine(base)
    assert free in m.inputs_on()
    assert (wired[0] in m.inputs_on()) == (wired[0] in plain.inputs_on())
    notes = m.advance()
    assert notes == [("warning", f"IO.DAT: INP presets input(s) {wired[0]}, which the "
                                 "machine file wires: the wiring wins")]


def test_without_io_dat_nothing_changes():
    """SPEC §9: "physical inputs preset from an `IO.DAT` file in the project";
    without one the
    machine is as described."""
    cfg = parse_machine("")
    assert with_io_dat(cfg, None) is cfg
    assert Machine(cfg).inputs_on() == []


def test_io_dat_is_generated_if_it_does_not_exist(tmp_path):
    """The seed: "File IO.DAT is generated automatically if it does not exist on
    the flash disk." Loading a missing IO.DAT writes one in the seed's format
    (DIP and INP, every value 0) and says so; the next load reads it."""
    p = tmp_path / "IO.DAT"
    io = load_io_dat(p)
    assert p.read_text(encoding="ascii") == "DIP=0x00\nINP=0x000000\n"
    assert (io.inp, io.dip) == (0, 0) and "generated" in io.note
    again = load_io_dat(p)
    assert again.note is None and parse_io_dat(p.read_text()).inp == 0


def test_io_dat_that_cannot_be_generated_reads_as_zeros(tmp_path):
    """Bad input never crashes anything: a folder that cannot be written gives
    all-0 presets and a note naming the file."""
    p = tmp_path / "no" / "such" / "IO.DAT"
    io = load_io_dat(p)
    assert (io.inp, io.dip) == (0, 0) and "cannot be generated" in io.note
    assert not p.exists()
