"""``plcbuilder disasm FILE`` (a .bin, or a .plc compiled first)."""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from plcbuilder import api
from plcbuilder.bytecode.program import HEADER_SIZE
from plcbuilder.cli.main import main

SRC = """#include pins.h
helper()
{
  timer=10; do{timer--;}while(timer>0);
};
main()
{
  portset(OUTPUT_SPINDLE);
  helper();
  exit(99);
};
"""
ANSI = re.compile(r"\x1b\[[0-9;]*m")


@pytest.fixture
def work(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "M03.plc").write_text(SRC)
    return tmp_path


def disasm(capsys, *argv: str) -> tuple[int, str, str]:
    rc = main(["disasm", *argv])
    cap = capsys.readouterr()
    return rc, cap.out, cap.err


def compiled(work: Path, name: str = "M03") -> Path:
    assert main(["compile", f"{name}.plc"]) == 0
    return work / f"{name}.bin"


def test_source_file_is_compiled_first(work, capsys):
    rc, out, err = disasm(capsys, "M03.plc")
    assert rc == 0, err
    assert err == ""
    assert out.startswith("; M03: hardware procedure, ")
    assert "main():" in out and "helper():" in out
    assert "    ; M03.plc:8: portset(OUTPUT_SPINDLE);" in out
    assert re.search(r"^\s+\d+\s+[0-9a-f ]+\s+PORTSET", out, re.M)
    assert re.search(r"CALL\s+-> \d+ \(helper\)", out)
    assert not (work / "M03.bin").exists(), "disasm writes nothing"


def test_binary_with_its_sources(work, capsys):
    compiled(work)
    capsys.readouterr()
    rc, out, err = disasm(capsys, "M03.bin")
    assert rc == 0, err
    assert "    ; M03.plc:4: timer=10; do{timer--;}while(timer>0);" in out
    # the listing of the binary is the listing of the source
    _rc, from_source, _err = disasm(capsys, "M03.plc")
    assert out == from_source


def test_binary_elsewhere_finds_sources_relative_to_the_current_folder_or_not_at_all(work, capsys):
    bin_path = compiled(work)
    capsys.readouterr()
    (work / "elsewhere").mkdir()
    moved = work / "elsewhere" / "M03.bin"
    shutil.move(bin_path, moved)
    rc, out, _err = disasm(capsys, str(moved))
    assert rc == 0 and "; M03.plc:8: portset" in out, "found from the current folder"
    (work / "M03.plc").unlink()
    rc, out, _err = disasm(capsys, str(moved))
    assert rc == 0
    assert re.search(r"^    ; M03\.plc:8$", out, re.M), "location without the text"
    assert "portset(" not in out


def test_project_build_folder_finds_hardware_sources(tmp_path, monkeypatch, capsys):
    (tmp_path / "proj" / "hardware").mkdir(parents=True)
    (tmp_path / "proj" / "build").mkdir()
    (tmp_path / "proj" / "hardware" / "M03.plc").write_text(SRC)
    monkeypatch.chdir(tmp_path / "proj" / "hardware")
    assert main(["compile", "M03.plc", "-o", "../build/M03.bin"]) == 0
    monkeypatch.chdir(tmp_path)
    capsys.readouterr()
    rc, out, _err = disasm(capsys, "proj/build/M03.bin")
    assert rc == 0 and "; M03.plc:8: portset(OUTPUT_SPINDLE);" in out


def test_file_with_the_magic_is_a_binary_whatever_its_name(work, capsys):
    shutil.copy(compiled(work), work / "M03.code")
    capsys.readouterr()
    rc, out, _err = disasm(capsys, "M03.code")
    assert rc == 0 and out.startswith("; M03: hardware procedure")


@pytest.mark.parametrize("damage, reason", [
    (lambda b: b[:10], "truncated"),
    (lambda b: b"", "truncated"),
    (lambda b: b"XXXX" + b[4:], "not a compiled PLC procedure"),
    (lambda b: b[:HEADER_SIZE + 2] + bytes([b[HEADER_SIZE + 2] ^ 0xFF]) + b[HEADER_SIZE + 3:],
     "CRC mismatch"),
    (lambda b: b[:4] + bytes([99]) + b[5:], "format version 99"),
])
def test_corrupt_binary_prints_the_reason(work, capsys, damage, reason):
    good = compiled(work).read_bytes()
    (work / "bad.bin").write_bytes(damage(good))
    capsys.readouterr()
    rc, out, err = disasm(capsys, "bad.bin")
    assert rc == 1
    assert out == ""
    assert err.startswith("bad.bin: error: ") and reason in err, err
    assert "Traceback" not in err


def test_missing_binary(work, capsys):
    rc, out, err = disasm(capsys, "gone.bin")
    assert rc == 1 and out == ""
    assert err.startswith("gone.bin: error: ") and "No such file" in err


def test_source_with_errors(work, capsys):
    (work / "B.plc").write_text("main() { code=gvarset(6060); exit(code); }\n")
    rc, out, err = disasm(capsys, "B.plc")
    assert rc == 1 and out == ""
    assert "B.plc:1:15: error: gvarset takes 2 arguments" in err


def test_software_binary(work, capsys):
    rc = main(["compile", "--software", "M03.plc", "-o", "sw.bin"])
    assert rc == 0
    capsys.readouterr()
    _rc, out, _err = disasm(capsys, "sw.bin")
    assert out.startswith("; M03: software procedure")


def test_color(work, capsys):
    _rc, plain, _err = disasm(capsys, "M03.plc")
    rc, out, _err = disasm(capsys, "--color=always", "M03.plc")
    assert rc == 0
    assert "\x1b[36mportset" in out, "source lines are highlighted"
    assert ANSI.sub("", out) == plain


def test_listing_matches_the_api(work, capsys):
    result = api.compile_file(Path("M03.plc"))
    _rc, out, _err = disasm(capsys, "M03.plc")
    assert out == api.disassemble(result.program, result.source_line)


def test_python_m_plcbuilder_disasm(work):
    compiled(work)
    (work / "junk.bin").write_bytes(b"\x00" * 64)
    run = lambda *a: subprocess.run([sys.executable, "-m", "plcbuilder", "disasm", *a],  # noqa: E731
                                    capture_output=True, text=True, timeout=120, cwd=work)
    ok = run("M03.bin")
    assert ok.returncode == 0 and "PORTSET" in ok.stdout
    bad = run("junk.bin")
    assert bad.returncode == 1 and "junk.bin: error: " in bad.stderr
    assert "Traceback" not in bad.stderr
