import shutil

import pytest

from plcbuilder.bytecode.opcodes import Op, encode
from plcbuilder.bytecode.program import Kind, LineEntry, Program


def program_bytes(name: str, kind: Kind, code_size: int = 3) -> bytes:
    """A loadable compiled procedure of exactly code_size bytes of code."""
    tail = encode(Op.PUSH8, 99) + encode(Op.EXIT)
    fill = max(code_size - len(tail), 0)
    push = encode(Op.PUSH32, 0)          # few instructions: quick to load
    code = push * (fill // len(push)) + bytes([Op.NOP]) * (fill % len(push)) + tail
    assert len(code) == max(code_size, len(tail))
    p = Program(name, kind, code, 0, ["a", "b"], [f"{name}.plc"],
                [LineEntry(0, 0, 1), LineEntry(len(code) - 3, 0, 2)], [("main", 0)])
    return p.to_bytes()


@pytest.fixture
def make_program():
    return program_bytes


@pytest.fixture
def sample_programs():
    """A realistic set: several hardware and software procedures."""
    return [
        ("M03", Kind.HARDWARE, program_bytes("M03", Kind.HARDWARE, 120)),
        ("M05", Kind.HARDWARE, program_bytes("M05", Kind.HARDWARE, 40)),
        ("M80", Kind.HARDWARE, program_bytes("M80", Kind.HARDWARE, 480)),
        ("OFF", Kind.HARDWARE, program_bytes("OFF", Kind.HARDWARE, 60)),
        ("LUBE", Kind.SOFTWARE, program_bytes("LUBE", Kind.SOFTWARE, 90)),
        ("__HANDLER_INIT", Kind.SOFTWARE, program_bytes("__HANDLER_INIT", Kind.SOFTWARE, 30)),
    ]


@pytest.fixture
def genromfs():
    path = shutil.which("genromfs")
    if path is None:
        pytest.skip("genromfs is not installed (Debian: apt-get install genromfs); "
                    "the ROMFS reader/writer are not compared with it")
    return path
