"""myCNC's text Server API on the simulated controller, driven as a pendant
driver or a script drives it: a real socket (and ``nc`` where installed), one
command a line, one reply a line."""

import dataclasses
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


# ---------------------------------------------------------------- myCNC's published list (issue 25.14)

#: The command list of myCNC's Server API page (docs.pv-automation.com/mycnc/server_api),
#: with its own spelling ("ProgrmaEnd"), and the older names still in use.
PUBLISHED = """EchoMode ProgramFileOpen ProgramBegin ProgramAppend ProgrmaEnd ProgramPlay
ProgramPlayBack ProgramPlayStep ProgramPlayStepBack ProgramPause ProgramStop ProgramReset
GetEstimateTime GetMachinePosition GetProcess GetWorkPosition GetMyCNCVersion GetFVariable
GetIVariable GetReady LineAppend GetScanData GetSensors GetMCC GetMCPtr GetHW GetHWDAC GetHWADC
GetHWInputBit GetHWInputs GetHWOutputs GetHWPWM GetPWMs GetPausedLine GetLastMessage
GetWorkState PendantWidgetShow PendantWidgetHide PendantWidgetHidden RunPLC SaveConfig SetG92
SetHWDAC SetHWOutputBit SetHWPWM SetPendant SetRotationAngle SetCNCVariable SetJog SetScale
SetGVariable SinglePlay ShutDown GetJobName GetSVariable8020 GetSVariable8107 GetSVariable8108
GetSVariable8109 SetHWBinaryOutput GetHWOutputBit""".split()


def test_every_published_command_is_known(line):
    """Each command of myCNC's list answers (OK, a usage, or why it means nothing
    on the simulated controller), never "unknown command"; ? lists them all."""
    listed = line.ask("?")[3:].split()
    for name in PUBLISHED:
        reply = line.ask(name)
        assert "unknown command" not in reply, (name, reply)
        assert name in listed
    from plcbuilder.link.server_api import NOT_HERE
    for name, why in NOT_HERE.items():
        assert line.ask(name) == f"ERROR {name}: {why}"


def test_sethwoutputbit_and_every_change_is_recorded(served, line):
    """SetHWOutputBit is myCNC's current name; what a command changes is
    recorded as the IDE's writes are, so replaying the session does it too."""
    assert line.ask("SetHWOutputBit 4 1") == "OK 4 1"
    assert line.ask("GetHWOutputBit 4") == "OK 1"
    assert line.ask("SetHWPWM 1 2000") == "OK 1 2000"
    assert line.ask("SetHWDAC 0 99") == "OK 0 99"
    assert line.ask("SetGVariable 9001 7") == "OK 9001 7"
    assert line.ask("SetJog x+y-") == "OK 0x0201"
    assert line.ask("SetJog xystop") == "OK 0x0000"
    acts = _controller(served, lambda c: [a.describe().split(" @")[0] for a in c.recorder.actions
                                          if a.kind == "write"])
    assert acts == ["write out 4=1", "write pwm 1=2000", "write dac 0=99", "write gvar 9001=7",
                    "write gvar 8635=513", "write gvar 8635=0"]
    assert line.ask("SetGVariable 7180 1").startswith("ERROR gvar 7180 is an input word")


def test_reading_commands(served, line):
    _controller(served, lambda c: c.set_input(2, 1))
    hw = line.ask("GetHW").split()
    assert hw[:2] == ["OK", "IN"] and int(hw[2], 16) & 4 and "OUT" in hw and "ADC" in hw
    assert line.ask("GetPWMs") == "OK 0 0 0 0 0 0 0 0"
    assert line.ask("SetGVariable 9002 1234") == "OK 9002 1234"
    assert line.ask("GetFVariable 9002") == "OK 1234.000000"
    sensors = line.ask("GetSensors").split()
    assert sensors[0] == "OK" and any(s.startswith("INPUT_HOME_X=") for s in sensors[1:])
    assert line.ask("GetMyCNCVersion").startswith("OK PLC Builder ")
    assert line.ask("GetWorkState") == "OK idle" and line.ask("GetReady") == "OK 1"
    assert line.ask("RunPLC 88") == "OK M88 0"                  # loops for ever
    deadline = time.monotonic() + 5
    while line.ask("GetWorkState") != "OK plc M88":
        assert time.monotonic() < deadline
        time.sleep(0.01)
    assert line.ask("GetReady") == "OK 0"


def test_getlastmessage(served, line):
    assert line.ask("GetLastMessage") == "OK -"
    _controller(served, lambda c: c.load(compile_programs(["M05"], overrides={"M05": (
        Kind.HARDWARE, "main(){ command = 7; parameter = 3000; message = 1100; timer = 2; "
                       "do{ timer--; }while(timer > 0); exit(99); }")})))
    assert line.ask("RunPLC M05") == "OK M05 0"
    deadline = time.monotonic() + 5
    while line.ask("GetLastMessage") == "OK -":
        assert time.monotonic() < deadline
        time.sleep(0.01)
    code, name, command, parameter = line.ask("GetLastMessage").split()[1:]
    assert (code, name, command, parameter) == ("1100", "PLCCMD_REPLY_TO_MYCNC", "7", "3000")


def test_echomode(line):
    assert line.ask("EchoMode") == "OK 0"
    assert line.ask("EchoMode 1") == "OK 1"
    line.send(b"GetMCC\n")
    assert line.line() == "GetMCC" and line.line() == "OK 77"
    assert line.ask("EchoMode 0") == "EchoMode 0"
    assert line.line() == "OK 0"
    assert line.ask("GetMCC") == "OK 77"


def test_program_commands_without_a_job_runner_say_so(served, line, tmp_path):
    """A controller with no job runner (``job_runner`` None) says so; the simulated
    controller has one (tests/link/test_server_api_job.py)."""
    _controller(served, lambda c: setattr(c, "job_runner", None))
    g = tmp_path / "job.nc"
    g.write_text("G0 X10\nM30\n")
    for cmd in (f"ProgramFileOpen {g}", "ProgramBegin", "ProgramPlay", "ProgramPause",
                "ProgramStop", "ProgramReset", "GetPausedLine", "GetJobName", "GetSVariable8020",
                "GetEstimateTime"):
        name = cmd.split()[0]
        assert line.ask(cmd) == f"ERROR {name}: no G-code job runner in this controller yet"
    assert line.ask("SetPendant 50;0x0301") == "OK X 0.000"          # selecting moves nothing
    assert line.ask("SetPendant 55;0x0301") == ("ERROR SetPendant: the handwheel moves an axis "
                                                "through the G-code job runner, and there is no "
                                                "G-code job runner in this controller yet")


class FakeJob:
    """A job runner as the program commands drive it (server_api.JobRunner)."""

    def __init__(self):
        from plcbuilder.link.server_api import JobStatus
        self.calls = []
        self.st = JobStatus()
        self.JobStatus = JobStatus

    def open(self, name, text, path=None):
        self.calls.append(("open", name, text, path))
        self.st = self.JobStatus(name=name, path=path, lines=text.count("\n"), size=len(text))

    def play(self):
        self.calls.append(("play",))
        self.st = dataclasses.replace(self.st, state="running", line=1, estimate_s=12.5)

    def pause(self):
        self.calls.append(("pause",))
        self.st = dataclasses.replace(self.st, state="paused", paused_line=2)

    def stop(self):
        self.calls.append(("stop",))

    def reset(self):
        self.calls.append(("reset",))

    def move(self, axis, mm):
        self.calls.append(("move", axis, mm))

    def status(self):
        return self.st


def test_program_commands_drive_the_job_runner(served, line, tmp_path):
    job = FakeJob()
    _controller(served, lambda c: setattr(c, "job_runner", job))
    g = tmp_path / "part.nc"
    g.write_text("G0 X10\nG0 Y5\nM30\n")
    assert line.ask(f"ProgramFileOpen {g}") == f"OK {g}"
    assert job.calls[-1] == ("open", "part.nc", "G0 X10\nG0 Y5\nM30\n", str(g.resolve()))
    assert line.ask("GetJobName") == f"OK {g.resolve()}"
    assert line.ask("GetSVariable8020") == f"OK {g.resolve()}"
    assert line.ask("GetSVariable8107") == "OK part.nc"
    assert line.ask("GetSVariable8108") == f"OK {g.resolve().parent}"
    assert line.ask("GetSVariable8109") == "OK 0.000"
    assert line.ask("GetSVariable9999").startswith("ERROR GetSVariable: the simulated controller "
                                                  "knows GetSVariable8020")
    assert line.ask("ProgramPlay") == "OK" and line.ask("GetWorkState") == "OK job running"
    assert line.ask("GetEstimateTime") == "OK 12.500"
    assert line.ask("ProgramPause") == "OK" and line.ask("GetPausedLine") == "OK 2"
    assert line.ask("ProgramStop") == "OK" and line.ask("ProgramReset") == "OK"
    assert line.ask("ProgramAppend G0 X1").startswith("ERROR ProgramAppend: no program begun")
    assert line.ask("ProgramBegin") == "OK"
    assert line.ask("ProgramAppend G0 X1") == "OK 1"
    assert line.ask("ProgramAppend M30") == "OK 2"
    assert line.ask("ProgrmaEnd") == "OK 2"                    # myCNC's list's spelling
    assert job.calls[-1] == ("open", "(server api)", "G0 X1\nM30\n", None)
    assert line.ask(f"ProgramFileOpen {tmp_path / 'none.nc'}").startswith(
        "ERROR ProgramFileOpen: cannot read")


def test_setpendant_turns_the_handwheel(served, line):
    """SetPendant WHEEL;SELECT: the wheel's clicks (0..99, wrapping) times the
    step of the high byte move the axis of the low byte; selecting moves nothing."""
    job = FakeJob()
    _controller(served, lambda c: setattr(c, "job_runner", job))
    assert line.ask("SetPendant 50;0x0300") == "OK OFF 0.000"       # axis off
    assert line.ask("SetPendant 50;0x0301") == "OK X 0.000"         # X selected, x1
    assert line.ask("SetPendant 55;0x0301") == "OK X 5.000"         # +5 clicks
    assert line.ask("SetPendant 55;0x0102") == "OK Y 0.000"         # Y, x0.01
    assert line.ask("SetPendant 65;0x0102") == "OK Y 0.100"
    assert line.ask("SetPendant 2;0x0102") == "OK Y 0.370"          # 65 -> 2: +37 the short way
    assert line.ask("SetPendant 98; 0x0203") == "OK Z 0.000"
    assert line.ask("SetPendant 1;0x0203") == "OK Z 0.300"          # 98 -> 1 wraps: +3
    assert line.ask("SetPendant 96;0x0203") == "OK Z -0.500"
    assert [c for c in job.calls if c[0] == "move"] == [
        ("move", "X", 5.0), ("move", "Y", 0.1), ("move", "Y", 0.37), ("move", "Z", 0.3),
        ("move", "Z", -0.5)]
    assert line.ask("SetPendant 100;0x0301").startswith("ERROR the handwheel's position is 0..99")
    assert line.ask("SetPendant 5;0x0409").startswith("ERROR SELECT 0x0409")
    assert line.ask("SetPendant 5").startswith("ERROR usage: SetPendant WHEEL;SELECT")


# ---------------------------------------------------------------- places (issue 24.6)

def test_idle_sockets_never_keep_a_client_from_an_answer(served):
    """16 (or 64) connections that never send anything: a new client still gets
    its answer, the oldest silent one making room (it is told why)."""
    api = served.server_api
    idle = [socket.create_connection(api.address, timeout=10) for _ in range(64)]
    try:
        time.sleep(0.2)
        c = Line(api.address)
        assert c.ask("GetMCC") == "OK 77"
        c.close()
        assert api.stats["evicted"] >= 49
        first = idle[0]
        first.settimeout(5)
        data = b""
        while True:
            chunk = first.recv(4096)
            if not chunk:
                break
            data += chunk
        assert data.startswith(b"ERROR closed to make room for a new client")
    finally:
        for s in idle:
            s.close()


def test_a_polling_pendant_is_not_pushed_out_by_idle_sockets(served):
    api = served.server_api
    pendant = Line(api.address)
    assert pendant.ask("GetMCC") == "OK 77"
    idle = [socket.create_connection(api.address, timeout=10) for _ in range(40)]
    try:
        time.sleep(0.2)
        assert pendant.ask("GetMachinePosition").startswith("OK X ")
    finally:
        for s in idle:
            s.close()
        pendant.close()


def test_a_connection_idle_too_long_is_closed_and_told_why(served):
    api = served.server_api
    api.idle_timeout = 0.5
    c = Line(api.address)
    assert c.ask("GetMCC") == "OK 77"
    time.sleep(2.5)
    assert c.line().startswith("ERROR closed: no command for")
    with pytest.raises((EOFError, OSError)):
        c.line()
    assert api.stats["idle_closed"] == 1


def test_when_every_place_is_busy_a_new_client_is_refused_with_the_reason(served):
    api = served.server_api
    busy = [Line(api.address) for _ in range(api.max_clients)]
    try:
        for b in busy:
            assert b.ask("GetMCC") == "OK 77"
        late = Line(api.address)
        assert late.line() == "ERROR too many Server API clients (16), all of them busy"
        late.close()
    finally:
        for b in busy:
            b.close()


# ---------------------------------------------------------------- the manual's example

def manual_example(marker: str) -> tuple[list[str], list[str]]:
    """The piped nc example of docs/editors.md's Server API section after
    ``<!-- MARKER -->``: its commands (the ``$`` lines) and the lines it shows."""
    import re
    from pathlib import Path
    text = (Path(__file__).resolve().parents[2] / "docs" / "editors.md").read_text()
    m = re.search(rf"<!-- {marker} -->\s*```\n(.*?)```", text, re.S)
    assert m, f"docs/editors.md lost its {marker} example"
    lines = m.group(1).splitlines()
    return [x[2:] for x in lines if x.startswith("$ ")], [x for x in lines if not x.startswith("$")]


def served_controller(cwd, *args) -> tuple[subprocess.Popen, int]:
    """``plcbuilder controller ARGS`` (which include ``--server-api 0``) started
    as a user starts it, in ``cwd``: the process and its Server API port."""
    proc = subprocess.Popen([sys.executable, "-m", "plcbuilder", "controller", *map(str, args)],
                            cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    for _ in range(10):
        out = proc.stdout.readline()
        if "Server API on" in out:
            return proc, int(out.split(":")[-1].split()[0])
    proc.terminate()
    raise AssertionError(f"no Server API: {proc.stderr.read()}")


def run_manual_example(tmp_path, marker: str, timeout: float) -> tuple[list[str], list[str]]:
    """Run the manual's nc example ``marker`` as the manual does, in a project
    made by ``plcbuilder new`` and built, with the controller started as the
    manual starts it: the lines nc printed, and the lines the manual shows."""
    commands, shown = manual_example(marker)
    assert commands[0].split() == ["plcbuilder", "controller", "--image", "build/eeprom.rom",
                                   "--server-api", "4266", "&"]
    proj = tmp_path / "proj"
    run = lambda *a: subprocess.run([sys.executable, "-m", "plcbuilder", *a],  # noqa: E731
                                    capture_output=True, text=True, timeout=120, cwd=tmp_path)
    assert run("new", str(proj)).returncode == 0
    assert run("build", str(proj)).returncode == 0
    proc, port = served_controller(proj, "--image", "build/eeprom.rom", "--server-api", "0",
                                   "--runtime-file", tmp_path / "rt.json")
    try:
        r = subprocess.run(["bash", "-c", commands[1].replace("4266", str(port))], cwd=proj,
                           capture_output=True, timeout=timeout)
        return r.stdout.decode().replace("\r\n", "\n").splitlines(), shown
    finally:
        proc.terminate()
        proc.wait(20)


@pytest.mark.skipif(shutil.which("nc") is None, reason="nc is not installed")
def test_the_manuals_nc_example_gives_the_replies_it_shows(tmp_path):
    """issue 25: the manual's piped example printed OK 0 where it shows OK 1."""
    printed, shown = run_manual_example(tmp_path, "server-api-nc", timeout=30)
    assert printed == shown
