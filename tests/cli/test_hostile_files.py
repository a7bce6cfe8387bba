"""Files that are not what they claim (issue 17, item 8): devices, FIFOs, links
to them, huge and deeply nested files. Each is refused with one clear line
naming the file; nothing hangs, nothing prints a traceback. /dev/zero is only
ever named (it is never read: the reader looks at what a file is first)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from tests.cli._run import run_cli as cli

ROOT = Path(__file__).resolve().parents[2]
OK = "main(){ exit(99); };\n"
needs_fifo = pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="needs FIFOs")
needs_zero = pytest.mark.skipif(not os.path.exists("/dev/zero"), reason="needs /dev/zero")


def plcbuilder(*argv, cwd=None, timeout=30, env=None) -> subprocess.CompletedProcess:
    """The real command in a child (a hang is a timeout, not a stuck test run)."""
    e = dict(os.environ, PYTHONPATH=str(ROOT), **(env or {}))
    return subprocess.run([sys.executable, "-m", "plcbuilder", *map(str, argv)], cwd=cwd,
                          capture_output=True, text=True, timeout=timeout, env=e)


def deep_toml(path: Path, n: int = 50_000) -> Path:
    path.write_text("a = " + "[" * n + "\n")
    return path


@needs_zero
@pytest.mark.parametrize("opt,what", [("--machine", "machine description"),
                                      ("--variables", "variables file"),
                                      ("--image", "controller image")])
def test_controller_refuses_a_device(tmp_path, capsys, monkeypatch, opt, what):
    monkeypatch.setenv("PLCBUILDER_CONTROLLER_FILE", str(tmp_path / "rt.json"))
    code, out, err = cli(capsys, "controller", opt, "/dev/zero")
    assert code == 1
    assert f"/dev/zero" in err and f"is a character device, not a regular file; a {what} " \
                                   "must be a regular file" in err
    assert "Traceback" not in err and "MemoryError" not in err


def test_a_deeply_nested_machine_is_a_clear_error(tmp_path, capsys, monkeypatch):
    monkeypatch.setenv("PLCBUILDER_CONTROLLER_FILE", str(tmp_path / "rt.json"))
    deep = deep_toml(tmp_path / "deep.toml")
    code, _out, err = cli(capsys, "controller", "--machine", deep)
    assert code == 1 and "deep.toml: TOML syntax error: arrays or tables are nested too " \
                         "deeply" in err
    assert "RecursionError" not in err and "Traceback" not in err
    src = tmp_path / "M03.plc"
    src.write_text(OK)
    code, _out, err = cli(capsys, "run", src, "--machine", deep)
    assert code == 2 and "nested too deeply" in err


def test_a_deeply_nested_settings_file_is_a_clear_error(tmp_path, capsys):
    (tmp_path / "hardware").mkdir()
    (tmp_path / "hardware" / "M03.plc").write_text(OK)
    deep_toml(tmp_path / "plcbuilder.toml")
    code, out, err = cli(capsys, "build", tmp_path)
    assert code == 1 and "plcbuilder.toml: not valid TOML: arrays or tables are nested" in err


def test_a_huge_machine_file_is_refused_unread(tmp_path, capsys):
    big = tmp_path / "big.toml"
    with open(big, "wb") as f:
        f.truncate(2 << 30)             # 2 GiB, sparse: reading it would take the memory
    src = tmp_path / "M03.plc"
    src.write_text(OK)
    code, _out, err = cli(capsys, "run", src, "--machine", big)
    assert code == 2
    assert "big.toml: cannot read the machine file: is 2147483648 bytes; a machine " \
           "description is at most 1 MiB (1048576 bytes)" in err


@needs_zero
def test_check_a_device_and_settings_linked_to_one(tmp_path, capsys):
    code, out, err = cli(capsys, "check", "/dev/zero")
    assert code == 1 and "/dev/zero is a character device, not a regular file" in out
    assert "internal error" not in out + err
    proj = tmp_path / "proj"
    (proj / "hardware").mkdir(parents=True)
    (proj / "hardware" / "M03.plc").write_text(OK)
    (proj / "plcbuilder.toml").symlink_to("/dev/zero")
    (proj / "include").mkdir()                  # now it is a project: settings are read
    code, out, err = cli(capsys, "check", proj / "hardware" / "M03.plc")
    assert code == 0 and "ignoring the project's settings" in err
    assert "plcbuilder.toml: cannot read: is a character device" in err
    code, out, err = cli(capsys, "build", proj)
    assert code == 1 and "plcbuilder.toml: cannot read: is a character device" in err
    assert "internal error" not in out + err


@needs_fifo
def test_nothing_hangs_on_a_fifo(tmp_path):
    os.mkfifo(tmp_path / "M03.plc")          # nobody ever writes to it
    os.mkfifo(tmp_path / "scenario.txt")
    os.mkfifo(tmp_path / "eeprom.rom")
    os.mkfifo(tmp_path / "rt.json")
    (tmp_path / "OK.plc").write_text(OK)
    env = {"PLCBUILDER_CONTROLLER_FILE": str(tmp_path / "rt.json")}
    cases = [
        (["check", "M03.plc"], 1, "M03.plc is a FIFO (named pipe), not a regular file"),
        (["disasm", "M03.plc"], 1, "M03.plc is a FIFO (named pipe)"),
        (["run", "OK.plc", "--scenario", "scenario.txt"], 2,
         "scenario.txt: cannot read the scenario: is a FIFO (named pipe)"),
        (["run", "OK.plc", "--machine", "M03.plc"], 2, "is a FIFO"),
        (["upload", "eeprom.rom"], 1, "cannot read eeprom.rom: is a FIFO"),
        (["state"], 1, "is a FIFO"),
    ]
    for argv, code, msg in cases:
        r = plcbuilder(*argv, cwd=tmp_path, timeout=60, env=env)
        assert r.returncode == code and msg in r.stdout + r.stderr, (argv, r.stdout, r.stderr)
        assert "Traceback" not in r.stderr


@needs_fifo
def test_build_all_refuses_a_fifo_in_build(tmp_path, capsys):
    (tmp_path / "hardware").mkdir()
    (tmp_path / "hardware" / "M03.plc").write_text(OK)
    (tmp_path / "build").mkdir()
    os.mkfifo(tmp_path / "build" / "eeprom.rom")
    code, out, err = cli(capsys, "build", tmp_path)
    assert code == 1
    assert "eeprom.rom: is a FIFO (named pipe), not a regular file; refusing to replace it" in err
    assert not (tmp_path / "build" / "eeprom.rom").is_file()


def test_a_damaged_build_cache_is_ignored(tmp_path, capsys):
    (tmp_path / "hardware").mkdir()
    (tmp_path / "hardware" / "M03.plc").write_text(OK)
    (tmp_path / "build").mkdir()
    (tmp_path / "build" / ".cache.json").write_text("[" * 100_000)
    code, out, err = cli(capsys, "build", tmp_path)
    assert code == 0 and "Build All ok" in out


def test_check_does_not_echo_a_file_included_from_outside(tmp_path, capsys):
    # issue 17 item 12: `#include "/etc/passwd"` printed its lines in diagnostics
    other = tmp_path / "etc"
    other.mkdir()
    (other / "passwd").write_text("root:x:0:0:secret-line:/root:/bin/bash\n")
    proc = tmp_path / "proc"
    proc.mkdir()
    (proc / "M03.plc").write_text(f'#include "{other / "passwd"}"\nmain(){{ exit(99); }};\n')
    code, out, err = cli(capsys, "check", proc / "M03.plc")
    assert code == 1 and "secret-line" not in out + err
    assert f"error: '{other / 'passwd'}' resolves to {other / 'passwd'}, outside the " \
           "procedure's folder" in out
    assert f"--include {other}" in out
    code, out, err = cli(capsys, "check", proc / "M03.plc", "--include", other)
    assert code == 1 and "include-outside" not in out and "resolves to" not in out
