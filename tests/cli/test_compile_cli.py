"""``plcbuilder compile FILE [-o OUT]``."""

from __future__ import annotations

import os
import re
import subprocess
import sys

import pytest

from plcbuilder.bytecode.program import Kind, Program
from plcbuilder.cli.main import main

GOOD = """main()
{
  portset(1);
  timer=10; do{timer--;}while(timer>0);
  exit(99);
};
"""
BAD = """main()
{
  code=gvarset(6060);
  exit(code);
};
"""


@pytest.fixture
def work(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    return tmp_path


def compile_(capsys, *argv: str) -> tuple[int, str, str]:
    rc = main(["compile", *argv])
    cap = capsys.readouterr()
    return rc, cap.out, cap.err


def test_default_output_is_the_source_with_bin(work, capsys):
    (work / "M03.plc").write_text(GOOD)
    rc, out, err = compile_(capsys, "M03.plc")
    assert rc == 0, err
    m = re.fullmatch(r"M03\.bin: hardware procedure M03, (\d+)/512 bytes\n", out)
    assert m, out
    prog = Program.from_bytes((work / "M03.bin").read_bytes())
    assert prog.name == "M03" and prog.kind is Kind.HARDWARE
    assert prog.code_size == int(m.group(1))
    assert [p.name for p in work.iterdir() if p.name.endswith(".tmp")] == []


def test_output_option_file_and_folder(work, capsys):
    (work / "M03.plc").write_text(GOOD)
    (work / "out").mkdir()
    rc, out, _err = compile_(capsys, "M03.plc", "-o", "other.bin")
    assert rc == 0 and out.startswith("other.bin: ")
    rc, out, _err = compile_(capsys, "M03.plc", "--output", "out")
    assert rc == 0 and (work / "out" / "M03.bin").is_file()
    assert (work / "other.bin").read_bytes() == (work / "out" / "M03.bin").read_bytes()
    assert not (work / "M03.bin").exists()


def test_compiling_is_deterministic(work, capsys):
    (work / "M03.plc").write_text(GOOD)
    compile_(capsys, "M03.plc", "-o", "a.bin")
    compile_(capsys, "M03.plc", "-o", "b.bin")
    assert (work / "a.bin").read_bytes() == (work / "b.bin").read_bytes()


def test_errors_write_nothing_and_keep_the_old_output(work, capsys):
    (work / "M05.plc").write_text(BAD)
    (work / "M05.bin").write_bytes(b"old")
    rc, out, err = compile_(capsys, "M05.plc")
    assert rc == 1
    assert out == ""
    assert "M05.plc:3:8: error: gvarset takes 2 arguments" in err
    assert "      code=gvarset(6060);" in err
    assert err.rstrip().endswith("M05.plc: not compiled: 1 error, 0 warnings")
    assert (work / "M05.bin").read_bytes() == b"old"
    assert sorted(p.name for p in work.iterdir()) == ["M05.bin", "M05.plc"]


def test_warnings_go_to_stderr_and_still_compile(work, capsys):
    (work / "M07.plc").write_text("main() { portset(1); }\n")
    rc, out, err = compile_(capsys, "M07.plc")
    assert rc == 0
    assert "warning: main() can reach its end without exit()" in err
    assert out.startswith("M07.bin: hardware procedure M07, ")


def test_software_procedure(work, capsys):
    (work / "software").mkdir()
    (work / "software" / "pump.plc").write_text(GOOD)
    (work / "loop.plc").write_text(GOOD)
    rc, out, _err = compile_(capsys, "software/pump.plc")
    assert rc == 0 and re.search(r"software procedure pump, \d+/16384 bytes", out)
    assert Program.from_bytes((work / "software" / "pump.bin").read_bytes()).kind is Kind.SOFTWARE
    rc, out, _err = compile_(capsys, "--software", "loop.plc", "-o", "loop.bin")
    assert Program.from_bytes((work / "loop.bin").read_bytes()).kind is Kind.SOFTWARE


def test_size_limit(work, capsys):
    body = "gvarset(20000, eparam*3+7);\n" * 60
    (work / "big.plc").write_text(f"main() {{\n{body}exit(99);\n}}\n")
    rc, _out, err = compile_(capsys, "big.plc")
    assert rc == 1 and re.search(r"error: procedure big is \d+ bytes of code; the limit for a "
                                 r"hardware procedure is 512", err)
    rc, out, _err = compile_(capsys, "--software", "big.plc")
    assert rc == 0 and "/16384 bytes" in out


def test_refuses_to_overwrite_the_source(work, capsys):
    (work / "M03.plc").write_text(GOOD)
    rc, _out, err = compile_(capsys, "M03.plc", "-o", "M03.plc")
    assert rc == 1 and "is the source file itself" in err
    assert (work / "M03.plc").read_text() == GOOD


def test_compiling_a_binary_is_a_diagnostic(work, capsys):
    (work / "M03.plc").write_text(GOOD)
    compile_(capsys, "M03.plc")
    rc, _out, err = compile_(capsys, "M03.bin")
    assert rc == 1 and "M03.bin is not a text file" in err and "Traceback" not in err


def test_unwritable_output_is_a_message(work, capsys):
    (work / "M03.plc").write_text(GOOD)
    rc, _out, err = compile_(capsys, "M03.plc", "-o", "no/such/folder/M03.bin")
    assert rc == 1
    assert "cannot write no/such/folder/M03.bin" in err and "Traceback" not in err


def test_missing_source(work, capsys):
    rc, out, err = compile_(capsys, "gone.plc")
    assert rc == 1 and out == "" and "gone.plc:1:1: error: gone.plc: no such file" in err


def test_compile_writes_atomically_replacing_and_cleaning_up(tmp_path, monkeypatch):
    from plcbuilder.api import atomic_write
    dest = tmp_path / "a.bin"
    dest.write_bytes(b"old")
    atomic_write(dest, b"new")
    assert dest.read_bytes() == b"new"
    assert os.listdir(tmp_path) == ["a.bin"]

    def fail(*_a):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(os, "replace", fail)
    with pytest.raises(OSError):
        atomic_write(dest, b"newer")
    assert dest.read_bytes() == b"new", "a failed write leaves the old file"
    assert os.listdir(tmp_path) == ["a.bin"], "and no temporary file"


def test_python_m_plcbuilder_compile(work):
    (work / "M03.plc").write_text(GOOD)
    (work / "M05.plc").write_text(BAD)
    run = lambda *a: subprocess.run([sys.executable, "-m", "plcbuilder", "compile", *a],  # noqa: E731
                                    capture_output=True, text=True, timeout=120, cwd=work)
    ok = run("M03.plc", "-o", "x.bin")
    assert ok.returncode == 0, ok.stderr
    assert Program.from_bytes((work / "x.bin").read_bytes()).name == "M03"
    bad = run("M05.plc")
    assert bad.returncode == 1 and "M05.plc:3:8: error:" in bad.stderr
    assert run().returncode == 2


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="needs FIFOs")
def test_output_that_is_not_a_regular_file_is_refused(work, capsys):
    # issue 17 item 6: `compile OK.plc -o /dev/full` replaced the device with a file
    (work / "M03.plc").write_text(GOOD)
    os.mkfifo(work / "pipe")
    rc, out, err = compile_(capsys, "M03.plc", "-o", "pipe")
    assert rc == 1 and out == ""
    assert "cannot write pipe: is a FIFO (named pipe), not a regular file" in err
    assert "Traceback" not in err
    assert os.path.exists(work / "pipe") and not os.path.isfile(work / "pipe")
    (work / "dev").symlink_to("/dev/null")
    rc, _out, err = compile_(capsys, "M03.plc", "-o", "dev")
    assert rc == 1 and "character device" in err and os.path.islink(work / "dev")
