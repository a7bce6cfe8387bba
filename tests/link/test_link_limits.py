"""The server's budgets (issue 17 points 2-5): connections without a hello, work
before the token check, memory held for clients that do not read, and one
client stalling the others."""

import dataclasses
import socket
import statistics
import struct
import threading
import time

import pytest

from plcbuilder import api
from plcbuilder.bytecode.program import Kind
from plcbuilder.image.manifest import write_image
from plcbuilder.link import protocol
from plcbuilder.link.client import Client
from plcbuilder.link.server import ControllerServer
from tests.link.linkkit import hello, msg_frame, raw_connect, read_until_closed, wait_for


def non_reader(srv) -> socket.socket:
    """An authenticated raw connection with a tiny receive buffer."""
    s = socket.socket()
    s.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
    s.settimeout(5)
    s.connect(srv.address)
    hello(s, srv.token)
    return s


def held(srv) -> int:
    return sum(c.held for c in list(srv.server._conns.values()))


# ------------------------------------------------------------------ 2. unauthenticated budget

def test_idle_sockets_without_a_token_never_lock_out_a_client(image):
    srv = ControllerServer(port=0, image=image)          # the defaults: 64 clients
    srv.start()
    idle = []
    try:
        for _ in range(100):
            idle.append(socket.create_connection(srv.address, timeout=5))
        wait_for(lambda: srv.server.stats["accepted"] >= 100)
        assert srv.server.connections <= srv.server.max_unauthed
        for _ in range(3):
            c = Client.connect(*srv.address, srv.token, connect_timeout=2)
            assert c.state().server["clients"] >= 1
            c.close()
        # the evicted ones were told why
        msgs, closed = read_until_closed(idle[0], timeout=2)
        assert closed and "hello" in msgs[0]["reason"]
    finally:
        for s in idle:
            s.close()
        srv.close()


def test_authenticated_clients_have_their_own_limit(image):
    srv = ControllerServer(port=0, max_clients=3, max_unauthed=2)
    srv.start()
    try:
        clients = [Client.connect(*srv.address, srv.token) for _ in range(3)]
        s = raw_connect(srv.address)
        msgs, closed = read_until_closed(s)
        assert closed and msgs[0]["code"] == "busy"
        clients[0].close()
        wait_for(lambda: srv.server.clients == 2)
        clients[0] = Client.connect(*srv.address, srv.token)
        for c in clients:
            c.close()
    finally:
        srv.close()


# ------------------------------------------------------------------ 3. nothing big before the hello

@pytest.mark.parametrize("announce", [protocol.MAX_FRAME, 4096, 1025])
def test_before_the_hello_only_a_small_frame_is_accepted(server, client, announce):
    s = raw_connect(server.address)
    s.sendall(struct.pack(">I", announce) + b"{" * 1000)
    msgs, closed = read_until_closed(s, timeout=3)
    assert closed and msgs[0]["code"] == "bad_frame" and "before the hello" in msgs[0]["reason"]
    s.close()
    assert client.ping()["pong"]


def test_big_frames_from_many_strangers_hold_no_memory(server, client):
    socks = []
    for _ in range(40):
        s = raw_connect(server.address)
        s.sendall(struct.pack(">I", protocol.MAX_FRAME))
        try:
            s.sendall(b" " * (256 << 10))
        except OSError:
            pass
        socks.append(s)
    assert held(server) < 64 << 10
    a = time.perf_counter()
    client.ping()
    assert time.perf_counter() - a < 0.5
    for s in socks:
        s.close()


def test_the_hello_is_the_only_message_parsed_before_the_token(server, monkeypatch):
    seen = []
    real = protocol.decode_payload

    def spy(payload, allowed=None, binary=False):
        if threading.current_thread().name == "plcbuilder-server":
            seen.append(len(payload))
        return real(payload, allowed, binary)
    monkeypatch.setattr(protocol, "decode_payload", spy)
    s = raw_connect(server.address)
    s.sendall(msg_frame({"type": "hello", "version": protocol.PROTOCOL_VERSION, "token": "x"})
              + msg_frame({"type": "ping", "id": 1}) * 100)
    msgs, closed = read_until_closed(s, timeout=3)
    assert closed and msgs[0]["code"] == "unauthorized"
    assert len(seen) == 1
    s.close()


def test_a_hello_pipelined_with_big_requests_still_works(server, image):
    s = raw_connect(server.address)
    s.sendall(msg_frame({"type": "hello", "id": 0, "version": protocol.PROTOCOL_VERSION,
                         "token": server.token})
              + msg_frame({"type": "upload", "id": 1, "image": protocol.encode_image(image)}))
    assert protocol.recv_msg(s)["type"] == "welcome"
    r = protocol.recv_msg(s)
    assert r["type"] == "result" and r["result"]["accepted"]
    s.close()


# ------------------------------------------------------------------ 4. memory

def test_subscribers_that_never_read_hold_bounded_memory(server, client):
    socks = []
    for _ in range(30):
        s = non_reader(server)
        s.sendall(msg_frame({"type": "subscribe", "id": 1, "queue": 100_000}))
        socks.append(s)
    client.start("M03")
    client.speed("max")
    peak = 0
    end = time.monotonic() + 3
    while time.monotonic() < end:
        peak = max(peak, held(server))
        time.sleep(0.05)
    client.speed("pause")
    per = server.server.telemetry_high_water + protocol.MAX_FRAME
    assert peak < 30 * per
    assert peak < server.server.max_total_held
    for s in socks:
        s.close()


def test_a_client_that_sends_but_never_reads_is_paused_then_closed(server, client):
    s = non_reader(server)
    s.setblocking(False)
    burst = msg_frame({"type": "state", "id": 1}) * 2000
    sent = 0
    end = time.monotonic() + 3
    while time.monotonic() < end and sent < 200 * len(burst):
        try:
            sent += s.send(burst)
        except BlockingIOError:
            time.sleep(0.01)
        except OSError:
            break
        assert held(server) < server.server.read_pause + (1 << 20) + 600_000
    assert client.ping()["pong"]
    s.close()


def test_above_the_total_budget_the_largest_holder_goes_with_a_reason(server, client):
    server.server.max_total_held = 64 << 10
    s = non_reader(server)
    s.setblocking(False)
    burst = msg_frame({"type": "state", "id": 1}) * 500
    end = time.monotonic() + 10
    while server.server.stats["overflow"] == 0 and time.monotonic() < end:
        try:
            s.send(burst)
        except BlockingIOError:
            time.sleep(0.01)
        except OSError:
            break
    assert server.server.stats["overflow"] >= 1
    assert client.ping()["pong"]
    s.setblocking(True)
    s.settimeout(2)
    dec = protocol.FrameDecoder()
    reasons, closed = [], False
    try:
        while True:
            data = s.recv(1 << 16)
            if not data:
                closed = True
                break
            reasons += [m.get("reason", "") for m in map(protocol.decode_payload, dec.feed(data))
                        if m["type"] == "error"]
    except ConnectionResetError:
        closed = True
    except OSError:
        pass
    # closed; the reason goes with it when its socket has room for it
    assert closed
    assert all("held" in r for r in reasons)
    s.close()


# ------------------------------------------------------------------ 5. fairness

def _p99(values):
    values = sorted(values)
    return values[min(len(values) - 1, int(0.99 * len(values)))]


def _pings(c, stop, out):
    while not stop.is_set():
        a = time.perf_counter()
        c.ping()
        out.append(time.perf_counter() - a)
        time.sleep(0.005)


def test_a_slow_image_check_does_not_stall_the_others(server, client, image, monkeypatch):
    real = server.service.check_image

    def slow(data):
        end = time.perf_counter() + 1.5
        while time.perf_counter() < end:       # CPU, holding the GIL as a real check does
            sum(range(1000))
        return real(data)
    monkeypatch.setattr(server.service, "check_image", slow)
    up = Client.connect(*server.address, server.token)
    lat, stop = [], threading.Event()
    th = threading.Thread(target=_pings, args=(client, stop, lat))
    th.start()
    a = time.perf_counter()
    assert up.upload(image)["accepted"]
    assert time.perf_counter() - a >= 1.5
    stop.set()
    th.join()
    up.close()
    assert len(lat) > 20 and max(lat) < 0.25 and _p99(lat) < 0.1, (max(lat), len(lat))


def test_pipelined_requests_do_not_hold_up_another_client(server, client):
    s = raw_connect(server.address)
    hello(s, server.token)
    burst = msg_frame({"type": "ping", "id": 1}) * 20000

    def reader():
        dec, n = protocol.FrameDecoder(), 0
        while n < 20000:
            data = s.recv(1 << 16)
            if not data:
                return
            n += len(dec.feed(data))
    th = threading.Thread(target=reader)
    th.start()
    s.sendall(burst)
    lat = []
    for _ in range(20):
        a = time.perf_counter()
        client.ping()
        lat.append(time.perf_counter() - a)
    th.join(20)
    s.close()
    assert max(lat) < 0.25 and statistics.median(lat) < 0.05, lat


@pytest.fixture(scope="module")
def busy_image():
    r = api.compile_source("main(){ do{ var02++; a = a + 1; b = a * 3; }while(1); }", "S.plc",
                           api.CompileOptions(kind=Kind.SOFTWARE))
    progs = [dataclasses.replace(r.program, name=f"S{i:04d}") for i in range(1000)]
    return write_image([(p.name, Kind.SOFTWARE, p.to_bytes()) for p in progs]), \
        [p.name for p in progs]


def test_state_and_stop_answer_quickly_with_a_thousand_busy_procedures(busy_image):
    """scripts/bench.py server prints the p99 (goal < 100 ms); a shared test machine
    is noisy, so this holds the 90th percentile to it."""
    img, names = busy_image
    with ControllerServer(port=0, speed="max", image=img) as srv:
        c = Client.connect(*srv.address, srv.token)
        for n in names:
            c.start(n)
        state, stop = [], []
        for _ in range(40):
            a = time.perf_counter()
            assert len(c.state().software) == 1000
            b = time.perf_counter()
            c.stop()
            stop.append(time.perf_counter() - b)
            state.append(b - a)
        c.close()
    for lat in (state, stop):
        lat.sort()
        assert lat[int(0.9 * len(lat))] < 0.1, lat[-5:]
