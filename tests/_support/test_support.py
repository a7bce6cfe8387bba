"""_support: atomic writes, pid checks, strict JSON, TOML line numbers."""

import os
import stat
import sys
import tomllib

import pytest

from plcbuilder._support.files import atomic_write
from plcbuilder._support.procs import pid_alive
from plcbuilder._support.strictjson import strict_json_loads
from plcbuilder._support.toml_errors import TomlLocator, decode_error


def test_atomic_write(tmp_path):
    f = tmp_path / "M03.plc"
    atomic_write(f, "main(){};\n")
    assert f.read_text() == "main(){};\n"
    atomic_write(f, b"\x00\x01")
    assert f.read_bytes() == b"\x00\x01"
    os.chmod(f, 0o600)
    atomic_write(f, "é")
    assert f.read_bytes() == "é".encode() and stat.S_IMODE(f.stat().st_mode) == 0o600
    assert sorted(os.listdir(tmp_path)) == ["M03.plc"]
    with pytest.raises(TypeError):
        atomic_write(f, 42)


def test_atomic_write_failure_keeps_the_old_file(tmp_path, monkeypatch):
    f = tmp_path / "M03.plc"
    f.write_text("old")

    def boom(src, dst):
        raise OSError(28, "No space left on device")
    monkeypatch.setattr(os, "replace", boom)
    with pytest.raises(OSError):
        atomic_write(f, "new")
    assert f.read_text() == "old"
    assert sorted(os.listdir(tmp_path)) == ["M03.plc"]


def test_atomic_write_with_a_mode_has_exactly_that_mode(tmp_path):
    f = tmp_path / "controller.json"
    old = os.umask(0)
    try:
        atomic_write(f, "{}", mode=0o600)
    finally:
        os.umask(old)
    assert stat.S_IMODE(f.stat().st_mode) == 0o600
    os.chmod(f, 0o644)
    atomic_write(f, "{}", mode=0o600)
    assert stat.S_IMODE(f.stat().st_mode) == 0o600


def test_pid_alive():
    assert pid_alive(os.getpid())
    assert not pid_alive(0) and not pid_alive(-5)
    if sys.platform != "win32":
        assert pid_alive(1)              # exists, even where it may not be signalled


def test_strict_json_refuses_repeated_keys_and_nan():
    assert strict_json_loads('{"a": [1, 2.5]}') == {"a": [1, 2.5]}
    for bad in ('{"a": 1, "a": 2}', '[NaN]', '[Infinity]', '{"x": -Infinity}'):
        with pytest.raises(ValueError):
            strict_json_loads(bad)


TOML = """\
name = "x"

[axes.Z]
accel = 5
"rapid" = 7

[[inputs]]
pin = 1

[[inputs]]
pin = 2
"""


def test_toml_locator_finds_keys_tables_and_array_entries():
    loc = TomlLocator(TOML)
    assert loc.line_of(("name",)) == 1
    assert loc.line_of(("axes", "Z")) == 3
    assert loc.line_of(("axes", "Z", "accel")) == 4
    assert loc.line_of(("axes", "Z", "rapid")) == 5
    assert loc.line_of(("axes", "Z", "missing")) == 3     # the table's header
    assert loc.line_of(("inputs", 1, "pin")) == 11
    assert loc.line_of(("nowhere",)) is None


def test_decode_error_gives_the_message_and_its_line():
    for text, line in (("a = 1\nb = \n", 2), ("a = 1\nb = [1,", 2)):
        with pytest.raises(tomllib.TOMLDecodeError) as ei:
            tomllib.loads(text)
        msg, at = decode_error(ei.value, text)
        assert at == line and "(at" not in msg


# ------------------------------------------------ special files (issue 17, items 6 and 8)

from plcbuilder._support.files import FileRefused, read_bounded  # noqa: E402


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="needs FIFOs")
def test_atomic_write_refuses_a_fifo_and_keeps_it(tmp_path):
    fifo = tmp_path / "out.bin"
    os.mkfifo(fifo)
    with pytest.raises(FileRefused) as ei:
        atomic_write(fifo, b"data")
    assert isinstance(ei.value, OSError)
    assert "FIFO" in ei.value.strerror and "refusing to replace" in ei.value.strerror
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode)
    assert sorted(os.listdir(tmp_path)) == ["out.bin"]          # no temporary file left


@pytest.mark.skipif(not os.path.exists("/dev/null"), reason="needs /dev/null")
def test_atomic_write_refuses_a_link_to_a_device_and_a_folder(tmp_path):
    link = tmp_path / "full"
    link.symlink_to("/dev/null")                                # never written: refused first
    with pytest.raises(FileRefused, match="character device"):
        atomic_write(link, b"x")
    assert link.is_symlink() and os.readlink(link) == "/dev/null"
    (tmp_path / "dir").mkdir()
    with pytest.raises(FileRefused, match="a folder"):
        atomic_write(tmp_path / "dir", b"x")
    assert sorted(os.listdir(tmp_path)) == ["dir", "full"]


def test_read_bounded(tmp_path):
    f = tmp_path / "a.toml"
    f.write_bytes(b"x" * 10)
    assert read_bounded(f, 10, "machine description") == b"x" * 10
    with pytest.raises(FileRefused) as ei:
        read_bounded(f, 9, "machine description")
    assert "is 10 bytes; a machine description is at most 9 bytes" in str(ei.value)
    assert str(f) in str(ei.value)
    with pytest.raises(FileRefused, match="a folder, not a regular file"):
        read_bounded(tmp_path, 100, "source file")
    with pytest.raises(FileNotFoundError):
        read_bounded(tmp_path / "gone", 100)


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="needs FIFOs")
def test_read_bounded_never_blocks_on_a_fifo(tmp_path):
    fifo = tmp_path / "M03.plc"
    os.mkfifo(fifo)                     # nobody writes: a plain open() would hang here
    with pytest.raises(FileRefused, match="FIFO"):
        read_bounded(fifo, 100, "source file")


@pytest.mark.skipif(not os.path.exists("/dev/zero"), reason="needs /dev/zero")
def test_read_bounded_refuses_a_device_through_a_link(tmp_path):
    link = tmp_path / "plcbuilder.toml"
    link.symlink_to("/dev/zero")
    with pytest.raises(FileRefused, match="character device"):
        read_bounded(link, 1 << 20, "settings file")


def test_atomic_write_streams_chunks_and_leaves_an_identical_file_alone(tmp_path):
    f = tmp_path / "eeprom.rom"
    assert atomic_write(f, (bytes([i]) * 1000 for i in range(5)), unless_same=True) is True
    assert f.read_bytes() == b"".join(bytes([i]) * 1000 for i in range(5))
    before = f.stat().st_ino
    # the same bytes in other chunks: not replaced, no temporary file left
    assert atomic_write(f, [bytes([0]) * 500, bytes([0]) * 500 + bytes([1]) * 1000,
                            bytes([2]) * 1000, bytes([3]) * 1000 + bytes([4]) * 1000],
                        unless_same=True) is False
    assert f.stat().st_ino == before and os.listdir(tmp_path) == ["eeprom.rom"]
    # a prefix of the old contents is a change, and so is one byte more
    assert atomic_write(f, [bytes([0]) * 1000], unless_same=True) is True
    assert f.read_bytes() == bytes(1000)
    assert atomic_write(f, [bytes(1000), b"x"], unless_same=True) is True
    assert f.read_bytes() == bytes(1000) + b"x"


def test_atomic_write_of_chunks_that_fail_leaves_the_old_file(tmp_path):
    f = tmp_path / "eeprom.rom"
    atomic_write(f, b"old")

    def chunks():
        yield b"new"
        raise ValueError("the writer failed half way")

    with pytest.raises(ValueError):
        atomic_write(f, chunks())
    assert f.read_bytes() == b"old" and os.listdir(tmp_path) == ["eeprom.rom"]


def test_lazy_pattern_compiles_when_first_used():
    """Issue 26.1: a module's patterns are compiled when a command uses them,
    not at every start; used, one answers as the compiled pattern does."""
    import re

    from plcbuilder._support.lazy import Pattern

    p = Pattern(r"(in|out)\s*(\d+)", re.I)
    assert "_compiled" not in vars(p)
    compiled = re.compile(r"(in|out)\s*(\d+)", re.I)
    assert p.fullmatch("OUT 7").groups() == compiled.fullmatch("OUT 7").groups() == ("OUT", "7")
    assert vars(p)["_compiled"] is compiled                  # (the re module's cache)
    assert p.match("x") is None and p.sub("-", "in 3, out 4") == "-, -"
    assert (p.groups, p.pattern, p.flags) == (compiled.groups, compiled.pattern, compiled.flags)
    assert "fullmatch" in vars(p)                            # kept: a later use is direct


def test_modules_on_the_run_path_compile_no_pattern_at_import():
    """The controller's, the scenario's and the targets' patterns are not
    compiled when their modules load (``plcbuilder run`` of a procedure uses
    none of them)."""
    import subprocess

    code = ("import re, sys\n"
            "made = []\n"
            "real = re._compile\n"
            "def spy(pattern, flags):\n"
            "    made.append(pattern)\n"
            "    return real(pattern, flags)\n"
            "re._compile = spy\n"
            "import plcbuilder._support.numbers, plcbuilder._support.toml_errors\n"
            "import plcbuilder.bytecode.softmc, plcbuilder.bytecode.targets\n"
            "import plcbuilder.controller.forces, plcbuilder.controller.scenario\n"
            "import plcbuilder.controller.debugger, plcbuilder.controller.fastvm\n"
            "print(len(made))")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert r.stdout.strip() == "0", r.stdout + r.stderr
