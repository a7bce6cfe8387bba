"""The binary format: round trip, and the loader refusing bad files with a reason."""

import random
import struct
import zlib

import pytest

from plcbuilder.api import compile_source
from plcbuilder.bytecode.opcodes import Op, decode, encode, validate
from plcbuilder.bytecode.program import FORMAT_VERSION, HEADER_SIZE, Kind, LoadError, Program

SRC = """
helper() { b=b+1; };
main() { a=eparam; timer=3; do { timer--; helper(); } while (timer>0); exit(a+b); };
"""


def program() -> Program:
    r = compile_source(SRC, "M10.plc")
    assert r.ok, r.diagnostics
    return r.program


def test_round_trip_keeps_everything():
    p = program()
    q = Program.from_bytes(p.to_bytes())
    assert (q.name, q.kind, q.code, q.entry, q.var_names, q.files, q.lines, q.procs) == \
        (p.name, p.kind, p.code, p.entry, p.var_names, p.files, p.lines, p.procs)
    assert q.nvars == 2 and q.var_names == ["b", "a"]   # in order of first appearance


def test_header_fields():
    raw = program().to_bytes()
    magic, version, kind, nvars, flags, size, entry, crc = struct.unpack_from("<4sBBBBIII", raw)
    assert magic == b"PLCB" and version == FORMAT_VERSION and kind == 0 and nvars == 2
    assert crc == zlib.crc32(raw[HEADER_SIZE:])
    assert size == len(program().code)


def test_same_source_same_bytes():
    assert program().to_bytes() == program().to_bytes()


@pytest.mark.parametrize("mutate, reason", [
    (lambda b: b[:10], "truncated"),
    (lambda b: b"XXXX" + b[4:], "not a compiled PLC procedure"),
    (lambda b: b[:4] + bytes([FORMAT_VERSION + 1]) + b[5:], "format version"),
    (lambda b: b[:-1] + bytes([b[-1] ^ 1]), "CRC mismatch"),
    (lambda b: b[:-3], "CRC mismatch"),
    (lambda b: b[:5] + bytes([7]) + b[6:], "unknown procedure kind"),
])
def test_refuses_bad_files_with_a_reason(mutate, reason):
    with pytest.raises(LoadError, match=reason):
        Program.from_bytes(mutate(program().to_bytes()))


def _recrc(raw: bytes) -> bytes:
    body = raw[HEADER_SIZE:]
    return raw[:16] + struct.pack("<I", zlib.crc32(body)) + body


def test_refuses_invalid_code_even_with_a_good_crc():
    p = program()
    bad = Program(p.name, p.kind, p.code[:-1] + bytes([0xEE]), p.entry, p.var_names, p.files,
                  p.lines, p.procs)
    with pytest.raises(LoadError, match="unknown opcode"):
        Program.from_bytes(bad.to_bytes())
    jump = Program("x", Kind.HARDWARE, encode(Op.JMP8, 50), 0)
    with pytest.raises(LoadError, match="not an instruction"):
        Program.from_bytes(jump.to_bytes())


def test_random_corruption_is_always_a_load_error():
    raw = program().to_bytes()
    rng = random.Random(5)
    for _ in range(2000):
        b = bytearray(raw)
        for _ in range(rng.randint(1, 3)):
            b[rng.randrange(len(b))] = rng.randrange(256)
        if rng.random() < 0.5:
            b = _recrc(bytes(b))          # a good CRC over damaged contents
        if rng.random() < 0.2:
            b = b[:rng.randrange(len(b))]
        try:
            Program.from_bytes(bytes(b))
        except LoadError:
            pass


def test_decoder_and_validate():
    code = encode(Op.PUSH8, 5) + encode(Op.LOOP8, -4) + encode(Op.EXIT)
    ins = validate(code)
    assert [i.op for i in ins] == [Op.PUSH8, Op.LOOP8, Op.EXIT]
    assert ins[1].target == 0
    assert list(decode(b""))== []


def test_location_and_procedure_lookup():
    p = program()
    names = [n for n, _ in p.procs]
    assert names == ["main", "helper"]
    file, line = p.location(0)
    assert file == "M10.plc" and line == 3
    assert p.proc_at(p.procs[1][1]) == "helper"


def test_every_single_header_byte_change_is_refused():
    """Header bytes are not covered by the CRC: each one is checked on its own.
    (Hardware <-> software is a valid kind either way; in an image the manifest
    says which it must be.)"""
    raw = program().to_bytes()
    for i in range(HEADER_SIZE):
        for delta in (1, 0x80):
            if (i, delta) == (5, 1):
                assert Program.from_bytes(raw[:5] + b"\x01" + raw[6:]).kind is Kind.SOFTWARE
                continue
            b = bytearray(raw)
            b[i] ^= delta
            with pytest.raises(LoadError):
                Program.from_bytes(bytes(b))
