"""Attacks on the controller server (issue 17 points 1-5 and 11), for scripts/attack.py.

``ATTACKS`` is a list of ``(item, callable)``; each callable starts its own
controller (a child process on loopback, as the IDE runs it), attacks it for
a bounded time and returns ``{"tried", "refused", "accepted", "crashed"}``:
``refused`` counts the attempts the controller refused or kept within its
budgets, ``accepted`` the ones that got through (the defect reproduced), and
``crashed`` the times the controller died or stopped answering a bystander.
"""

from __future__ import annotations

import os
import signal
import socket
import struct
import sys
import tempfile
import threading
import time
from contextlib import contextmanager
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

sys.path.insert(0, str(HERE))

from bench_server import _busy_image, _image  # noqa: E402
from plcbuilder.bytecode.program import Kind  # noqa: E402
from plcbuilder.link import protocol, runtime  # noqa: E402
from plcbuilder.link.client import LinkError  # noqa: E402
from plcbuilder.link.process import ControllerProcess  # noqa: E402

SECONDS = float(os.environ.get("PLCB_ATTACK_SECONDS", "5"))


def _counts(tried=0, refused=0, accepted=0, crashed=0) -> dict:
    return {"tried": tried, "refused": refused, "accepted": accepted, "crashed": crashed}


TOGGLE = {"TOGGLE": (Kind.HARDWARE, "main(){ do{ if (t) { portclear(6); t = 0; } else "
                                    "{ portset(6); t = 1; } }while(1); }")}


@contextmanager
def controller(image: bytes = None, speed: str = "realtime", extra=()):
    with tempfile.TemporaryDirectory() as tmp:
        args = list(extra)
        if image is not None:
            path = Path(tmp) / "eeprom.rom"
            path.write_bytes(image)
            args += ["--image", str(path)]
        proc = ControllerProcess.start(speed=speed, extra_args=args, timeout=60)
        try:
            yield proc
        finally:
            proc.stop()


def _rss_mb(pid: int) -> float:
    try:
        for line in Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024
    except OSError:
        pass
    return 0.0


def _alive(proc: ControllerProcess, timeout: float = 5.0) -> bool:
    try:
        with proc.connect(timeout=timeout, connect_timeout=timeout) as c:
            return bool(c.ping()["pong"])
    except (LinkError, OSError):
        return False


def _hello(sock: socket.socket, token: str) -> None:
    protocol.send_msg(sock, {"type": "hello", "id": 0, "token": token,
                             "version": protocol.PROTOCOL_VERSION})
    protocol.recv_msg(sock)


def _non_reader(address, token: str) -> socket.socket:
    """An authenticated connection with a tiny receive buffer (it will not read)."""
    s = socket.socket()
    s.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
    s.settimeout(5)
    s.connect(address)
    _hello(s, token)
    return s


def _non_readers(proc: ControllerProcess, n: int) -> list[socket.socket]:
    token = proc.endpoint().token
    return [_non_reader(proc.address, token) for _ in range(n)]


# ------------------------------------------------------------------ 17.1

def pacing_after_stop() -> dict:
    """SIGSTOP for 2 s, SIGCONT, then states for a few seconds: simulated time must
    never run ahead of the wall clock, and every state must answer."""
    out = _counts()
    if not hasattr(signal, "SIGSTOP"):
        return out
    with controller() as proc:
        c = proc.connect(timeout=5)
        for _ in range(3):
            out["tried"] += 1
            w0, t0 = time.monotonic(), c.state().t_ms
            os.kill(proc.pid, signal.SIGSTOP)
            time.sleep(2.0)
            os.kill(proc.pid, signal.SIGCONT)
            ok = True
            end = time.monotonic() + 3.0
            while time.monotonic() < end:
                try:
                    st = c.state()
                except (LinkError, OSError):
                    out["crashed"] += 1
                    return out
                if st.t_ms - t0 > (time.monotonic() - w0) * 1000 + 200 or \
                        st.speed["dropped_ms"] > 10 ** 7:
                    ok = False
                time.sleep(0.2)
            out["refused" if ok else "accepted"] += 1
        c.close()
    return out


def pacing_at_10000x() -> dict:
    out = _counts()
    with controller(speed="10000") as proc:
        c = proc.connect(timeout=5)
        w0, t0 = time.monotonic(), c.state().t_ms
        end = time.monotonic() + SECONDS
        while time.monotonic() < end:
            out["tried"] += 1
            try:
                st = c.state()
            except (LinkError, OSError):
                out["crashed"] += 1
                break
            # t0 may lag its moment by a batch (4 ms) and a chunk: allow 20 ms of wall time
            ahead = st.t_ms - t0 > (time.monotonic() - w0 + 0.02) * 10_000_000
            out["accepted" if ahead or st.speed["dropped_ms"] > 10 ** 12 else "refused"] += 1
            time.sleep(0.25)
        c.close()
    return out


# ------------------------------------------------------------------ 17.2

def _through_idle_sockets(out: dict, proc, rounds: int, idle_count: int, open_idle,
                          answered) -> dict:
    """``rounds`` times: ``idle_count`` connections made by ``open_idle()`` and
    left open, then ``answered()`` says whether a real client got its answer
    (the attack refused) or not (accepted); a dead controller crashed."""
    for _ in range(rounds):
        out["tried"] += 1
        idle = []
        try:
            for _ in range(idle_count):
                idle.append(open_idle())
            time.sleep(0.2)
            out["refused" if answered() else "accepted"] += 1
        finally:
            for s in idle:
                s.close()
    if not _alive(proc):
        out["crashed"] += 1
    return out


def _client_answered(proc) -> bool:
    try:
        with proc.connect(timeout=5, connect_timeout=5) as c:
            c.state()
        return True
    except LinkError:
        return False


def idle_sockets_lock_out() -> dict:
    """100 idle sockets without a token, then a client with the token."""
    with controller() as proc:
        host, port = proc.address
        return _through_idle_sockets(
            _counts(), proc, 5, 100, lambda: socket.create_connection((host, port), timeout=5),
            lambda: _client_answered(proc))


# ------------------------------------------------------------------ 24.6

def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _api_ask(port: int, command: str, timeout: float = 5.0) -> str:
    """One Server API command on a fresh connection; its reply line ('' if none)."""
    with socket.create_connection(("127.0.0.1", port), timeout=timeout) as s:
        s.sendall(command.encode() + b"\n")
        data = b""
        while b"\r\n" not in data:
            chunk = s.recv(4096)
            if not chunk:
                break
            data += chunk
    return data.split(b"\r\n")[0].decode("utf-8", "replace")


def server_api_idle_sockets() -> dict:
    """64 Server API connections that never send a command, then a client: it
    must get its answer (they locked every client out: "too many Server API
    clients (16)", still at 90 s)."""
    port = _free_port()

    def answered() -> bool:
        try:
            return _api_ask(port, "GetMCC") == "OK 77"
        except OSError:
            return False

    with controller(extra=["--server-api", str(port)]) as proc:
        return _through_idle_sockets(
            _counts(), proc, 5, 64,
            lambda: socket.create_connection(("127.0.0.1", port), timeout=5), answered)


def server_api_connect_flood_vs_pendant() -> dict:
    """A pendant polling GetMachinePosition while silent connections pour in
    (each left open): the pendant keeps its place and its answers."""
    out = _counts()
    port = _free_port()
    with controller(extra=["--server-api", str(port)]) as proc:
        pendant = socket.create_connection(("127.0.0.1", port), timeout=5)
        flood: list[socket.socket] = []
        buf = b""
        try:
            deadline = time.monotonic() + SECONDS
            while time.monotonic() < deadline:
                for _ in range(10):
                    try:
                        flood.append(socket.create_connection(("127.0.0.1", port), timeout=5))
                    except OSError:
                        pass
                out["tried"] += 1
                try:
                    pendant.sendall(b"GetMachinePosition\n")
                    while b"\r\n" not in buf:
                        chunk = pendant.recv(4096)
                        if not chunk:
                            raise ConnectionError("closed")
                        buf += chunk
                    line, _, buf = buf.partition(b"\r\n")
                    out["refused" if line.startswith(b"OK X ") else "accepted"] += 1
                except OSError:
                    out["accepted"] += 1
                    break
                time.sleep(0.05)
        finally:
            pendant.close()
            for s in flood:
                s.close()
        if not _alive(proc):
            out["crashed"] += 1
    return out


def idle_sockets_mid_hello() -> dict:
    """The main protocol's slots: 64 connections each stopped in the middle of a
    hello frame (its length sent, not its body), then a client with the token."""
    with controller() as proc:
        host, port = proc.address

        def mid_hello() -> socket.socket:
            s = socket.create_connection((host, port), timeout=5)
            s.sendall(struct.pack(">I", 200) + b'{"type": "hel')
            return s

        return _through_idle_sockets(_counts(), proc, 3, 64, mid_hello,
                                     lambda: _client_answered(proc))


# ------------------------------------------------------------------ 17.3

def big_frames_before_hello() -> dict:
    """63 connections announce a 4 MiB frame and send 1 MiB of it without a hello;
    the controller must refuse each at once and hold no memory for them."""
    out = _counts()
    with controller() as proc:
        host, port = proc.address
        rss0 = _rss_mb(proc.pid)
        socks = []
        for _ in range(63):
            out["tried"] += 1
            s = socket.create_connection((host, port), timeout=5)
            s.setblocking(False)
            sent = 0
            try:
                sent += s.send(struct.pack(">I", protocol.MAX_FRAME))
                for _ in range(16):
                    sent += s.send(b" " * 65536)
            except (BlockingIOError, OSError):
                pass
            socks.append((s, sent))
        time.sleep(0.5)
        grown = _rss_mb(proc.pid) - rss0
        for s, sent in socks:
            s.setblocking(True)
            s.settimeout(2)
            try:
                data = s.recv(4096)
                closed = True if data == b"" or b"before the hello" in data else False
            except socket.timeout:
                closed = False
            except OSError:
                closed = True
            out["refused" if closed and grown < 30 else "accepted"] += 1
            s.close()
        if not _alive(proc):
            out["crashed"] += 1
    return out


# ------------------------------------------------------------------ 17.4

def _memory_verdict(proc, rss0: float, socks: list, alive: bool, limit_mb: float,
                    what: str) -> dict:
    """Each socket is refused when the controller grew less than ``limit_mb``."""
    grown = _rss_mb(proc.pid) - rss0
    out = _counts(tried=len(socks), crashed=0 if alive else 1)
    out["refused" if grown < limit_mb else "accepted"] = len(socks)
    for s in socks:
        s.close()
    print(f"    {what}: the controller grew {grown:.0f} MB", file=sys.stderr)
    return out


def subscribers_that_never_read() -> dict:
    """60 subscribers that never read, with an output toggling every tick at Max."""
    with controller(image=_image(TOGGLE), speed="pause") as proc:
        rss0, socks = _rss_mb(proc.pid), _non_readers(proc, 60)
        for s in socks:
            protocol.send_msg(s, {"type": "subscribe", "id": 1, "queue": 20000})
        c = proc.connect(timeout=10)
        c.start("TOGGLE")
        c.speed("max")
        time.sleep(SECONDS)
        a = time.perf_counter()
        alive = _alive(proc)
        print(f"    bystander answered: {alive} in {time.perf_counter() - a:.2f} s",
              file=sys.stderr)
        c.speed("pause")
        c.close()
        return _memory_verdict(proc, rss0, socks, alive, 200, "60 subscribers that never read")


def senders_that_never_read() -> dict:
    """24 clients pipelining state requests without reading a reply."""
    with controller(image=_busy_image(200), speed="realtime") as proc:
        rss0, socks = _rss_mb(proc.pid), _non_readers(proc, 24)
        for s in socks:
            s.setblocking(False)
        burst = protocol.encode_frame({"type": "state", "id": 1}) * 1000
        end = time.monotonic() + SECONDS
        while time.monotonic() < end:
            for s in socks:
                try:
                    s.send(burst)
                except (BlockingIOError, OSError):
                    pass
            time.sleep(0.01)
        return _memory_verdict(proc, rss0, socks, _alive(proc), 120,
                               "24 senders that never read")


# ------------------------------------------------------------------ 17.5

def _pings_while(proc: ControllerProcess, work) -> list[float]:
    lat: list[float] = []
    stop = threading.Event()

    def pinger():
        with proc.connect(timeout=30) as c:
            while not stop.is_set():
                a = time.perf_counter()
                c.ping()
                lat.append(time.perf_counter() - a)
                time.sleep(0.005)
    th = threading.Thread(target=pinger)
    th.start()
    try:
        work()
    finally:
        stop.set()
        th.join()
    return lat


def _stalls(proc: ControllerProcess, work) -> dict:
    """A bystander's pings while ``work`` runs: one slower than 100 ms is a stall."""
    out = _counts()
    for v in _pings_while(proc, work):
        out["tried"] += 1
        out["accepted" if v > 0.1 else "refused"] += 1
    if not _alive(proc):
        out["crashed"] += 1
    return out


def big_uploads_stall_others() -> dict:
    """Uploads of a 2,000-procedure image (its check takes a while) while a
    bystander pings: a ping slower than 100 ms is a stall."""
    image = _busy_image(2000)
    with controller() as proc:
        def work():
            with proc.connect(timeout=60) as c:
                end = time.monotonic() + SECONDS
                while time.monotonic() < end:
                    c.upload(image)
        return _stalls(proc, work)


def pipelined_requests_stall_others() -> dict:
    """20,000 pipelined pings on one connection while a bystander pings."""
    with controller() as proc:
        host, port = proc.address
        token = proc.endpoint().token

        def work():
            s = socket.create_connection((host, port), timeout=30)
            _hello(s, token)
            burst = protocol.encode_frame({"type": "ping", "id": 1}) * 20000
            got = [0]

            def reader():
                dec = protocol.FrameDecoder()
                while got[0] < 20000:
                    data = s.recv(1 << 16)
                    if not data:
                        return
                    got[0] += len(dec.feed(data))
            th = threading.Thread(target=reader)
            th.start()
            for _ in range(3):
                got[0] = 0
                s.sendall(burst)
                th.join(30)
                th = threading.Thread(target=reader)
                th.start()
            s.close()
            th.join(5)
        return _stalls(proc, work)


def busy_procedures_slow_state() -> dict:
    """1,000 busy software procedures at Max: state and stop within 100 ms."""
    out = _counts()
    with controller(image=_busy_image(1000), speed="max") as proc:
        c = proc.connect(timeout=30)
        for i in range(1000):
            c.start(f"S{i:04d}")
        end = time.monotonic() + SECONDS
        while time.monotonic() < end:
            for verb in (c.state, c.stop):
                out["tried"] += 1
                a = time.perf_counter()
                try:
                    verb()
                except LinkError:
                    out["crashed"] += 1
                    return out
                out["accepted" if time.perf_counter() - a > 0.1 else "refused"] += 1
        c.close()
    return out


# ------------------------------------------------------------------ 17.11

def _posix_only(fn):
    """Runtime-file ownership and modes are POSIX matters: elsewhere nothing is tried."""
    def run() -> dict:
        return fn() if os.name == "posix" else _counts()
    run.__doc__ = fn.__doc__
    return run


@_posix_only
def newer_controller_removes_older_file() -> dict:
    out = _counts()
    import subprocess
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "rt" / "controller.json"

        def start():
            return subprocess.Popen([sys.executable, "-m", "plcbuilder", "controller", "--port",
                                     "0", "--runtime-file", str(path)],
                                    stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)

        def wait(pid):
            end = time.monotonic() + 60
            while time.monotonic() < end:
                try:
                    if runtime.read(path).pid == pid:
                        return True
                except runtime.RuntimeFileError:
                    pass
                time.sleep(0.05)
            return False
        for _ in range(2):
            out["tried"] += 1
            older = start()
            try:
                wait(older.pid)
                newer = start()
                wait(newer.pid)
                newer.terminate()
                newer.wait(30)
                try:
                    ok = runtime.read(path).pid == older.pid
                except runtime.RuntimeFileError:
                    ok = False
                out["refused" if ok else "accepted"] += 1
            finally:
                older.terminate()
                older.wait(30)
    return out


@_posix_only
def runtime_file_in_a_shared_folder() -> dict:
    out = _counts()
    with tempfile.TemporaryDirectory() as tmp:
        for mode in (0o777, 0o1777, 0o775):
            out["tried"] += 1
            folder = Path(tmp) / f"shared{mode:o}"
            path = folder / "controller.json"
            runtime.write(runtime.Endpoint("127.0.0.1", 9, "t" * 43, os.getpid()), path)
            os.chmod(folder, mode)
            try:
                runtime.read(path)
                out["accepted"] += 1
            except runtime.RuntimeFileError:
                out["refused"] += 1
    return out


# ------------------------------------------------------------------ fuzz

def fuzz_frames() -> dict:
    from tests.link.fuzzlink import fuzz
    with controller(image=_image(TOGGLE)) as proc:
        token = proc.endpoint().token
        return fuzz(proc.address, token, SECONDS * 4, seed=int(time.time()),
                    alive=lambda: _alive(proc))


ATTACKS = [
    ("17.1 pacing after SIGSTOP 2 s", pacing_after_stop),
    ("17.1 pacing at --speed 10000", pacing_at_10000x),
    ("17.2 100 idle sockets, then a client", idle_sockets_lock_out),
    ("17.3 4 MiB frames before the hello", big_frames_before_hello),
    ("17.4 60 subscribers that never read", subscribers_that_never_read),
    ("17.4 24 senders that never read", senders_that_never_read),
    ("17.5 big uploads vs a bystander's ping", big_uploads_stall_others),
    ("17.5 20,000 pipelined vs a bystander", pipelined_requests_stall_others),
    ("17.5 state/stop, 1,000 busy procedures", busy_procedures_slow_state),
    ("17.11 newer controller stops", newer_controller_removes_older_file),
    ("17.11 runtime file in a shared folder", runtime_file_in_a_shared_folder),
    ("24.6 64 idle Server API sockets, then a client", server_api_idle_sockets),
    ("24.6 Server API connect flood vs a pendant", server_api_connect_flood_vs_pendant),
    ("24.6 64 sockets stopped mid-hello, then a client", idle_sockets_mid_hello),
    ("link fuzz (random frames)", fuzz_frames),
]
