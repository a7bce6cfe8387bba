"""plcbuilder controller / upload / start / stop / input / state (SPEC §5)."""

import json
import os
import signal
import stat
import subprocess
import sys
from pathlib import Path

import pytest

from plcbuilder.cli.main import main
from plcbuilder.link import runtime
from plcbuilder.link.client import Client
from plcbuilder.link.server import ControllerServer
from tests.link.linkkit import compile_programs, image_of, wait_for

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def image_bytes():
    return image_of(compile_programs())


@pytest.fixture
def rt_file(tmp_path, monkeypatch):
    path = tmp_path / "rt" / "controller.json"
    monkeypatch.setenv("PLCBUILDER_CONTROLLER_FILE", str(path))
    return path


@pytest.fixture
def image_file(tmp_path, image_bytes):
    p = tmp_path / "eeprom.rom"
    p.write_bytes(image_bytes)
    return p


@pytest.fixture
def served(rt_file, image_bytes):
    srv = ControllerServer(port=0, speed="pause", runtime_file=rt_file)
    srv.start()
    yield srv
    srv.close()


def cli(capsys, *argv):
    code = main([*argv, "--color", "never"] if argv[0] != "controller" else list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_upload_start_state_stop(served, image_file, capsys):
    code, out, err = cli(capsys, "upload", str(image_file))
    assert code == 0 and "uploaded" in out and "procedures" in out, err
    code, out, _ = cli(capsys, "start", "M88", "--eparam", "7")
    assert code == 0 and "started M88 (eparam 7)" in out
    code, out, _ = cli(capsys, "state", "--json")
    st = json.loads(out)
    assert code == 0 and st["running"] == "M88" and isinstance(st["software"], list)
    assert isinstance(st["t_ms"], int)
    assert {p["name"] for p in st["image"]} >= {"M03", "M88", "LUBE"}
    assert all(len(p["crc32"]) == 8 and p["size"] > 0 for p in st["image"])
    code, out, _ = cli(capsys, "state")
    assert code == 0 and "running: M88" in out and "image: 8 procedures" in out
    code, out, _ = cli(capsys, "stop")
    assert code == 0 and "started M02" in out
    code, out, _ = cli(capsys, "stop")
    assert code == 0 and "started OFF" in out


def test_start_by_mcode_number_and_hex_eparam(served, image_file, capsys):
    cli(capsys, "upload", str(image_file))
    code, out, _ = cli(capsys, "start", "3", "--eparam", "0x10")
    assert code == 0 and "started M03 (eparam 16)" in out


def test_refused_requests_exit_1_with_the_reason(served, image_file, tmp_path, capsys):
    cli(capsys, "upload", str(image_file))
    bad = tmp_path / "bad.rom"
    bad.write_bytes(image_file.read_bytes()[:-7])
    code, out, err = cli(capsys, "upload", str(bad))
    assert code == 1 and "refused: image refused:" in err
    code, out, err = cli(capsys, "start", "NOPE")
    assert code == 1 and "no procedure named 'NOPE'" in err
    code, out, err = cli(capsys, "start", "77")
    assert code == 1 and "M77" in err
    code, out, err = cli(capsys, "input", "200=1")     # a pin this machine does not have
    assert code == 1 and "no input 200" in err
    code, out, err = cli(capsys, "upload", str(tmp_path / "missing.rom"))
    assert code == 1 and "cannot read" in err
    st = json.loads(cli(capsys, "state", "--json")[1])
    assert len(st["image"]) == 8                     # still the good image


def test_input_usage(served, image_file, capsys):
    cli(capsys, "upload", str(image_file))
    code, out, _ = cli(capsys, "input", "5=1", "6=0", "--adc", "1=300")
    assert code == 0 and "input 5 = 1" in out and "ADC1 = 300" in out
    st = json.loads(cli(capsys, "state", "--json")[1])
    assert 5 in st["inputs"] and 6 not in st["inputs"] and st["adc"][1] == 300
    for bad in (["5=2"], ["x=1"], ["5"], []):
        code, _, err = cli(capsys, "input", *bad)
        assert code == 2 and "plcbuilder input:" in err


@pytest.mark.parametrize("argv,msg", [
    # issue 17 item 10: numbers out of range wrapped or went through silently
    (["start", "M88", "--eparam", "4294967297"],
     "argument --eparam: must be from -2147483648 to 4294967295, not 4294967297"),
    (["start", "99999999999"], "an M-code number must be from 0 to 1000000, not 99999999999"),
    (["input", "--adc", "0=99999999999"],
     "the value of ADC channel 0 must be from -2147483648 to 2147483647, not 99999999999"),
    (["input", "--adc", "8=1"], "ADC channel must be from 0 to 7, not 8"),
    (["input", "500=1"], "input pin must be from 0 to 255, not 500"),
    (["state", "--timeout", "nan"], "argument --timeout: must be more than 0 and at most 86400"),
    (["state", "--timeout", "1e400"], "argument --timeout: must be more than 0"),
])
def test_numbers_out_of_range_exit_2_naming_the_range(served, image_file, capsys, argv, msg):
    cli(capsys, "upload", str(image_file))
    t0 = json.loads(cli(capsys, "state", "--json")[1])
    try:
        code, out, err = cli(capsys, *argv)
    except SystemExit as exc:                       # argparse's own usage errors
        code, (out, err) = exc.code, capsys.readouterr()
    assert code == 2 and msg in err and "Traceback" not in err
    st = json.loads(cli(capsys, "state", "--json")[1])
    assert st["running"] == t0["running"] and st["adc"] == t0["adc"]   # nothing was sent


def test_start_takes_an_unsigned_32_bit_eparam_as_its_signed_value(served, image_file, capsys):
    cli(capsys, "upload", str(image_file))
    code, out, _ = cli(capsys, "start", "M88", "--eparam", "0xFFFFFFFF")
    assert code == 0 and "started M88 (eparam -1)" in out


def test_explicit_address_and_token(served, tmp_path, capsys, monkeypatch):
    monkeypatch.setenv("PLCBUILDER_CONTROLLER_FILE", str(tmp_path / "none.json"))
    addr = f"{served.address[0]}:{served.address[1]}"
    code, out, _ = cli(capsys, "state", "--json", "--controller", addr, f"--token={served.token}")
    assert code == 0 and "t_ms" in json.loads(out)
    code, _, err = cli(capsys, "state", "--controller", addr, "--token", "nope")
    assert code == 1 and "refused the connection: wrong or missing token" in err
    code, _, err = cli(capsys, "state", "--controller", "nonsense")
    assert code == 2 and "HOST:PORT" in err


def test_no_controller_running(rt_file, capsys):
    code, _, err = cli(capsys, "state")
    assert code == 1 and "no controller is running" in err and "plcbuilder controller" in err
    # left over from a process that has ended
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True).stdout.strip()
    runtime.write(runtime.Endpoint("127.0.0.1", 9, "t", int(dead)), rt_file)
    code, _, err = cli(capsys, "stop")
    assert code == 1 and "left over" in err
    # a live process, but nothing listens on the port
    import socket
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    runtime.write(runtime.Endpoint("127.0.0.1", port, "t", os.getpid()), rt_file)
    code, _, err = cli(capsys, "start", "M03")
    assert code == 1 and "no controller answers" in err


def test_controller_refuses_a_bad_image_or_machine_at_start(tmp_path, rt_file, capsys):
    bad = tmp_path / "bad.rom"
    bad.write_bytes(b"-rom1fs-" + b"\0" * 100)
    code, _, err = cli(capsys, "controller", "--image", str(bad))
    assert code == 1 and "image refused" in err
    machine = tmp_path / "m.toml"
    machine.write_text("[[axis]\n")
    code, _, err = cli(capsys, "controller", "--machine", str(machine))
    assert code == 1 and "m.toml" in err
    assert not rt_file.exists()


def _spawn(rt_file, *args):
    env = dict(os.environ, PLCBUILDER_CONTROLLER_FILE=str(rt_file), PYTHONUNBUFFERED="1")
    return subprocess.Popen([sys.executable, "-m", "plcbuilder", "controller", *args],
                            cwd=ROOT, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)


@pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals")
@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT])
def test_controller_process_serves_and_stops_cleanly_on_signals(rt_file, image_file, sig):
    proc = _spawn(rt_file, "--port", "0", "--speed", "10", "--image", str(image_file))
    try:
        wait_for(lambda: rt_file.exists() or proc.poll() is not None, timeout=30, interval=0.02)
        assert proc.poll() is None, proc.communicate()
        ep = runtime.read(rt_file)
        assert ep.host == "127.0.0.1" and ep.pid == proc.pid
        assert stat.S_IMODE(rt_file.stat().st_mode) == 0o600
        c = Client.connect()                                  # found through the runtime file
        assert c.state().image and c.welcome["pid"] == proc.pid
        c.subscribe(samples=False)
        proc.send_signal(sig)
        out, err = proc.communicate(timeout=30)
        assert proc.returncode == 0, err
        assert f"listening on 127.0.0.1:{ep.port}" in out
        assert "ran __HANDLER_EXIT" in out
        wait_for(lambda: c.closed, timeout=10)
        events = [e for b in c.telemetry(timeout=0.5) for e in b.events]
        assert any(getattr(e, "register", None) == 20002 for e in events)   # __HANDLER_EXIT ran
        assert "shutting down" in (c.close_reason or "")
        c.close()
        assert not rt_file.exists()
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()


@pytest.mark.skipif(sys.platform == "win32", reason="POSIX processes")
def test_controller_stops_when_its_parent_has_ended(rt_file):
    parent = subprocess.Popen([sys.executable, "-c", "pass"])
    proc = _spawn(rt_file, "--parent", str(parent.pid))
    try:
        wait_for(lambda: rt_file.exists() or proc.poll() is not None, timeout=30, interval=0.02)
        parent.wait()
        out, err = proc.communicate(timeout=30)
        assert proc.returncode == 0 and f"process {parent.pid} has ended" in err
        assert not rt_file.exists()
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()


#: The controller with a SIGTERM that lands while its main thread holds the
#: lock of the Event it used to wait on (as a signal can: the handler runs
#: between any two steps of the main thread), then the IDE's SIGTERM after it.
_LOCKED_SIGNAL = r"""
import os, signal, sys, threading
wait = threading.Condition.wait
def wait_and_signal(self, timeout=None):
    caller = sys._getframe(2).f_code
    if caller.co_name == "run" and caller.co_filename.endswith("cmd_controller.py"):
        os.kill(os.getpid(), signal.SIGTERM)      # (handled at this thread's next step)
    return wait(self, timeout)
threading.Condition.wait = wait_and_signal
from plcbuilder.cli.main import main
raise SystemExit(main(["controller", "--port", "0"]))
"""


@pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals")
def test_a_signal_that_comes_at_any_moment_stops_the_controller(rt_file):
    """The controller's signal handler set an Event, which takes the Event's
    lock: a SIGTERM that came while the main thread held it (waiting on that
    Event, as it did every half second) left the controller waiting on itself
    forever, still running the simulation with its IDE gone. The handler now
    only notes the signal."""
    env = dict(os.environ, PLCBUILDER_CONTROLLER_FILE=str(rt_file), PYTHONUNBUFFERED="1")
    proc = subprocess.Popen([sys.executable, "-c", _LOCKED_SIGNAL], cwd=ROOT, env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        wait_for(lambda: rt_file.exists() or proc.poll() is not None, timeout=30, interval=0.02)
        if proc.poll() is None:
            proc.send_signal(signal.SIGTERM)
        out, err = proc.communicate(timeout=20)
        assert proc.returncode == 0, err
        assert not rt_file.exists()
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
