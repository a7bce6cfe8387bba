"""myCNC's text Server API on the simulated controller, driven as a pendant
driver or a script drives it: a real socket (and ``nc`` where installed), one
command a line, one reply a line."""

import shutil
import socket
import subprocess
import sys
import threading
import time

import pytest

from plcbuilder.bytecode.program import Kind
from plcbuilder.link.client import Client
from plcbuilder.link.server import ControllerServer
from plcbuilder.link.server_api import COMMANDS, ServerApi
from tests.link.linkkit import compile_programs, image_of


class Line:
    """A line client: send a command, read its reply line."""

    def __init__(self, address, timeout: float = 10.0):
        self.sock = socket.create_connection(address, timeout=timeout)
        self.buf = b""

    def send(self, data: bytes) -> None:
        self.sock.sendall(data)

    def line(self) -> str:
        while b"\r\n" not in self.buf:
            chunk = self.sock.recv(65536)
            if not chunk:
                raise EOFError(self.buf)
            self.buf += chunk
        line, _, self.buf = self.buf.partition(b"\r\n")
        return line.decode()

    def ask(self, command: str) -> str:
        self.send(command.encode() + b"\n")
        return self.line()

    def close(self) -> None:
        self.sock.close()


@pytest.fixture(scope="module")
def api_image():
    return image_of(compile_programs(["M03", "M05", "M88"], {
        "M03": (Kind.HARDWARE,
                "main(){ portset(3); gvarset(5000, eparam); timer=300; "
                "do{ timer--; }while(timer>0); exit(99); }")}))


@pytest.fixture
def served(api_image):
    srv = ControllerServer(port=0, image=api_image, server_api=("127.0.0.1", 0))
    srv.start()
    yield srv
    srv.close()


@pytest.fixture
def line(served):
    c = Line(served.server_api.address)
    yield c
    c.close()


def _controller(served, fn):
    return served.sim.call(lambda: fn(served.controller))


def test_off_by_default_and_loopback_by_default(api_image):
    srv = ControllerServer(port=0, image=api_image)
    try:
        assert srv.server_api is None
    finally:
        srv.server.stop()
    api = ServerApi(srv.sim, "127.0.0.1", 0)
    assert api.address[0] == "127.0.0.1"
    api._lsock.close()


def test_question_mark_lists_the_commands(line):
    reply = line.ask("?")
    assert reply.startswith("OK ")
    names = reply[3:].split()
    for name in ("RunPLC", "SetHWBinaryOutput", "SetHWPWM", "SetHWDAC", "GetHWInputs",
                 "GetHWInputBit", "GetHWOutputs", "GetHWPWM", "GetIVariable", "SetGVariable",
                 "GetMachinePosition", "GetWorkPosition", "GetMCC", "GetProcess", "SetJog"):
        assert name in names
    assert names == list(COMMANDS)


def test_outputs_pwm_dac_and_registers(served, line):
    assert line.ask("SetHWBinaryOutput 3 1") == "OK 3 1"
    assert _controller(served, lambda c: c.machine.outputs_on()) == [3]
    assert line.ask("GetHWOutputs").split()[1] == "0x00000008"
    assert line.ask("gethwoutputbit 3") == "OK 1"          # names are not case sensitive
    assert line.ask("SetHWBinaryOutput 3 0") == "OK 3 0"
    assert line.ask("SetHWPWM 2 0x80") == "OK 2 128"
    assert line.ask("SetHWDAC 1 1000") == "OK 1 1000"
    assert line.ask("GetHWPWM") == "OK 0 0 128 0 0 0 0 0"
    assert line.ask("GetHWPWM 2") == "OK 128"
    assert line.ask("GetHWDAC 1") == "OK 1000"
    assert line.ask("GetIVariable 7280") == "OK 128"        # GVAR_HW_PWM2, as gvarget reads it
    assert line.ask("SetGVariable 9000 -5") == "OK 9000 -5"
    assert line.ask("GetIVariable 9000") == "OK -5"
    assert line.ask("GetMCC") == "OK 77"
    assert line.ask("GetProcess") == "OK 0 plc_proc_idle"


def test_inputs(served, line):
    _controller(served, lambda c: c.set_input(5, 1))
    words = line.ask("GetHWInputs").split()
    assert words[0] == "OK" and int(words[1], 16) >> 5 & 1 == 1
    assert line.ask("GetHWInputBit 5") == "OK 1"
    _controller(served, lambda c: c.set_input(5, 0))
    assert line.ask("GetHWInputBit 5") == "OK 0"


def test_runplc_starts_a_procedure_with_eparam(served, line):
    assert line.ask("RunPLC M03 1234") == "OK M03 1234"
    deadline = time.monotonic() + 5
    while line.ask("GetIVariable 5000") != "OK 1234":
        assert time.monotonic() < deadline
        time.sleep(0.01)
    assert line.ask("GetRunning").split()[1] == "M03"
    assert line.ask("GetHWOutputBit 3") == "OK 1"
    assert line.ask("RunPLC 5") == "OK M05 0"               # an M-code number
    assert line.ask("RunPLC NOPE").startswith("ERROR no procedure named 'NOPE'")


def test_positions_and_jog(served, line):
    pos = line.ask("GetMachinePosition").split()
    assert pos[0] == "OK" and pos[1::2] == ["X", "Y", "Z"]
    x0 = float(pos[2])
    assert line.ask("GetWorkPosition").split()[1::2] == ["X", "Y", "Z"]
    assert line.ask("SetJog x+") == "OK 0x0001"
    deadline = time.monotonic() + 5
    while line.ask("GetMCC") != "OK 0":                     # the jog has started
        assert time.monotonic() < deadline
        time.sleep(0.01)
    time.sleep(0.2)
    assert float(line.ask("GetMachinePosition").split()[2]) > x0
    assert line.ask("SetJog y- xstop") == "OK 0x0200"
    assert line.ask("SetJog stop") == "OK 0x0000"
    assert line.ask("SetJog q+").startswith("ERROR SetJog: 'q+'")


def test_bad_commands_get_an_error_and_the_connection_stays(line):
    assert line.ask("Frobnicate 1 2") == "ERROR unknown command 'Frobnicate' (? lists the commands)"
    assert line.ask("SetHWBinaryOutput 3").startswith("ERROR usage: SetHWBinaryOutput PORT 0|1")
    assert line.ask("SetHWBinaryOutput 999 1") == "ERROR no output 999 (0..63)"
    assert line.ask("SetHWBinaryOutput 3 7") == "ERROR an output is 0 or 1, not 7"
    assert line.ask("SetHWPWM x 1").startswith("ERROR CHANNEL must be a whole number")
    assert line.ask("SetGVariable 1 0x1ffffffff") == "ERROR 8589934591 is not a 32-bit value"
    assert line.ask("") == "ERROR empty command (? lists the commands)"
    assert line.ask("\x00\xff garbage").startswith("ERROR unknown command")
    line.send(b"A" * 100_000 + b"\nGetMCC\n")
    assert line.line() == "ERROR line longer than 1024 bytes; ignored"
    assert line.line() == "OK 77"
    assert line.ask("GetMCC") == "OK 77"


def test_a_flood_does_not_stall_the_controller_or_other_clients(served, line):
    """One client sends 20 000 commands without reading a reply; the
    controller's time goes on and another client is answered at once."""
    flood = Line(served.server_api.address)
    stop = threading.Event()

    def pour():
        try:
            while not stop.is_set():
                flood.send(b"GetHWInputs\n" * 1000)
        except OSError:
            pass
    t = threading.Thread(target=pour, daemon=True)
    t.start()
    time.sleep(0.3)
    t0 = _controller(served, lambda c: c.t_ms)
    start = time.monotonic()
    for _ in range(20):
        assert line.ask("GetMCC") == "OK 77"
    took = time.monotonic() - start
    time.sleep(0.3)
    t1 = _controller(served, lambda c: c.t_ms)
    assert t1 - t0 >= 200                  # real time went on: ~300 ms of ticks and more
    assert took < 5.0, f"20 answers took {took:.2f} s during the flood"
    # the binary protocol is answered too
    c = Client.connect(*served.address, served.token, timeout=5.0)
    assert c.state().t_ms >= t1
    c.close()
    stop.set()
    flood.close()
    t.join(5)


def test_many_commands_then_end_of_input_are_all_answered(served):
    """A script that sends its commands and closes its side gets every reply."""
    s = socket.create_connection(served.server_api.address, timeout=10)
    s.sendall(b"GetMCC\n" * 100 + b"GetProcess")        # the last line without its newline
    s.shutdown(socket.SHUT_WR)
    data = b""
    while True:
        chunk = s.recv(65536)
        if not chunk:
            break
        data += chunk
    lines = data.decode().split("\r\n")
    assert lines[:100] == ["OK 77"] * 100 and lines[100] == "OK 0 plc_proc_idle"


@pytest.mark.skipif(shutil.which("nc") is None, reason="nc is not installed")
def test_with_nc(served):
    host, port = served.server_api.address
    r = subprocess.run(["nc", "-q", "1", host, str(port)], input=b"GetMCC\nNope\nGetHWPWM 0\n",
                       capture_output=True, timeout=20)
    assert r.stdout.decode().split("\r\n")[:3] == [
        "OK 77", "ERROR unknown command 'Nope' (? lists the commands)", "OK 0"]


def test_the_command_line_option(tmp_path):
    """plcbuilder controller --server-api PORT: loopback, said so, and no token needed."""
    env_file = tmp_path / "rt" / "controller.json"
    env_file.parent.mkdir(mode=0o700)
    proc = subprocess.Popen([sys.executable, "-m", "plcbuilder", "controller", "--server-api", "0",
                             "--runtime-file", str(env_file)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        port = None
        for _ in range(10):
            out = proc.stdout.readline()
            if "Server API on" in out:
                assert "127.0.0.1" in out and "no token" in out
                port = int(out.split(":")[-1].split()[0])
                break
        assert port is not None
        c = Line(("127.0.0.1", port))
        assert c.ask("GetMCC") == "OK 77"
        c.close()
    finally:
        proc.terminate()
        proc.wait(20)
