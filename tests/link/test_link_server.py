"""The server over real sockets (127.0.0.1, port 0): hello and tokens, several
clients, telemetry, and more than a thousand garbage or hostile frames that
close only their own connection."""

import random
import socket
import struct
import threading
import time

import pytest

from plcbuilder.bytecode.program import Kind
from plcbuilder.controller.events import Ended, Sample, Started
from plcbuilder.link import protocol
from plcbuilder.link.client import AuthError, Client, ConnectionLost, RefusedError
from plcbuilder.link.server import ControllerServer, Server
from tests.link.linkkit import (SOURCES, TOGGLE, compile_programs, frame, hello, image_of, msg_frame,
                                raw_connect, read_until_closed, wait_for)


# ------------------------------------------------------------------ basics

def test_default_bind_is_loopback_and_a_token_is_always_made():
    srv = ControllerServer(port=0)
    try:
        assert srv.address[0] == "127.0.0.1" and srv.address[1] > 0
        assert len(srv.token) >= 40
    finally:
        srv.close(shutdown=False)
    import inspect
    assert inspect.signature(Server).parameters["host"].default == "127.0.0.1"
    assert inspect.signature(ControllerServer).parameters["host"].default == "127.0.0.1"


def test_hello_welcome_and_requests(server):
    s = raw_connect(server.address)
    w = hello(s, server.token)
    assert w["type"] == "welcome" and w["id"] == 0 and w["version"] == protocol.PROTOCOL_VERSION
    s.sendall(msg_frame({"type": "ping", "id": "abc"}))
    assert protocol.recv_msg(s) == {"type": "result", "id": "abc", "result": {"pong": True}}
    s.sendall(msg_frame({"type": "frobnicate", "id": 9}))       # unknown: answered, kept open
    r = protocol.recv_msg(s)
    assert r["type"] == "error" and r["code"] == "unknown_type" and r["id"] == 9
    s.sendall(msg_frame({"type": "input", "id": 10, "pin": "x", "value": 1}))
    r = protocol.recv_msg(s)
    assert r["code"] == "bad_request" and r["id"] == 10
    s.sendall(msg_frame({"type": "start", "id": 11, "name": "NOPE"}))
    r = protocol.recv_msg(s)
    assert r["code"] == "refused" and "NOPE" in r["reason"]
    s.sendall(msg_frame({"type": "ping", "id": 12}))
    assert protocol.recv_msg(s)["type"] == "result"
    s.close()


@pytest.mark.parametrize("hello_msg, code", [
    ({"type": "hello", "id": 0, "version": 1}, "unauthorized"),
    ({"type": "hello", "id": 0, "version": 1, "token": "wrong"}, "unauthorized"),
    ({"type": "hello", "id": 0, "version": 1, "token": ""}, "unauthorized"),
    ({"type": "hello", "id": 0, "version": 1, "token": 12345}, "unauthorized"),
    ({"type": "hello", "id": 0, "version": 1, "token": None}, "unauthorized"),
    ({"type": "state", "id": 0}, "unauthorized"),
    ({"type": "upload", "id": 0, "image": ""}, "unauthorized"),
])
def test_missing_or_wrong_token_is_refused_and_closed(server, hello_msg, code):
    s = raw_connect(server.address)
    s.sendall(msg_frame(hello_msg))
    msgs, closed = read_until_closed(s)
    assert closed and [m["code"] for m in msgs] == [code]
    s.close()


def test_token_with_a_suffix_or_prefix_is_wrong(server):
    for token in (server.token + "x", server.token[:-1], "x" + server.token, server.token.upper()):
        with pytest.raises(AuthError, match="wrong or missing token"):
            Client.connect(*server.address, token)


@pytest.mark.parametrize("version", [1, protocol.PROTOCOL_VERSION + 1])
def test_other_protocol_version_is_refused(server, version):
    s = raw_connect(server.address)
    r = hello(s, server.token, version=version)
    assert r["code"] == "version"
    assert f"speaks version {protocol.PROTOCOL_VERSION}" in r["reason"]
    msgs, closed = read_until_closed(s)
    assert closed
    s.close()


def test_no_hello_within_the_timeout_closes(server):
    s = raw_connect(server.address)
    msgs, closed = read_until_closed(s, timeout=5)
    assert closed and msgs[0]["code"] == "unauthorized" and "no hello" in msgs[0]["reason"]


def test_several_clients_at_once(server):
    clients = [Client.connect(*server.address, server.token) for _ in range(8)]
    errors = []

    def work(c, i):
        try:
            for _ in range(25):
                assert isinstance(c.state().t_ms, int)
                c.set_input(10 + i, 1)
        except Exception as exc:  # noqa: BLE001
            errors.append(exc)

    threads = [threading.Thread(target=work, args=(c, i)) for i, c in enumerate(clients)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(30)
    assert not errors
    inputs = clients[0].state().inputs
    assert all(10 + i in inputs for i in range(8))
    assert clients[0].state().server["clients"] == 8
    for c in clients:
        c.close()
    wait_for(lambda: server.server.clients == 0)


def test_one_client_used_from_many_threads(client):
    results = []

    def work():
        for _ in range(30):
            results.append(client.ping()["pong"])

    threads = [threading.Thread(target=work) for _ in range(6)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(30)
    assert results == [True] * 180


# ------------------------------------------------------------------ telemetry

def test_subscribe_delivers_samples_and_events(client):
    client.speed("pause")
    client.subscribe()
    client.start("M03")
    client.step(300)
    samples, events = [], []
    for batch in client.telemetry(timeout=2):
        samples += batch.samples
        events += batch.events
        if any(isinstance(e, Ended) and e.name == "M03" for e in events):
            break
    assert all(isinstance(s, Sample) for s in samples)
    ts = [s.t_ms for s in samples]
    assert ts == sorted(set(ts)) and len(ts) < 300              # changes only, in order
    assert len(samples[0].outputs) == 8 and len(samples[0].axes) == 9   # the first is whole
    assert any(isinstance(e, Started) and e.name == "M03" for e in events)
    ended = next(e for e in events if isinstance(e, Ended) and e.name == "M03")
    assert ended.exit_code == 99 and ended.exit_name == "plc_exit_normal"
    assert any(s.running == "M03" and s.outputs[0] & 8 for s in samples)


def test_subscribe_with_a_callback(client):
    got = []
    done = threading.Event()

    def cb(batch):
        got.append(batch)
        if len(got) >= 5:
            done.set()

    client.subscribe(cb)
    assert done.wait(10)
    client.unsubscribe()
    assert len(got[0].samples) >= 1                 # where things stand
    assert got[-1].t_ms > got[0].t_ms               # time goes on without changes


def test_a_client_that_does_not_read_never_holds_up_the_simulation(server, client):
    s = raw_connect(server.address)
    hello(s, server.token)
    s.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
    s.sendall(msg_frame({"type": "subscribe", "id": 1, "queue": 16}))
    client.upload(image_of(compile_programs(overrides=TOGGLE)))
    client.start("TOGGLE")                          # a change every tick
    client.speed("max")
    t0 = client.state().t_ms
    wait_for(lambda: client.state().t_ms > t0 + 200_000, timeout=30)   # it keeps running
    client.speed("pause")
    # the sleeper now reads: it finds how many samples it missed
    total_missed = 0
    dec = protocol.FrameDecoder()
    s.settimeout(2)
    deadline = time.monotonic() + 10
    while total_missed == 0 and time.monotonic() < deadline:
        try:
            data = s.recv(1 << 16)
        except socket.timeout:
            continue
        assert data
        for p in dec.feed(data):
            m = protocol.decode_payload(p, binary=True)
            if m["type"] == "telemetry":
                total_missed += m["missed"]
                assert len(m["changes"]) <= 16
    assert total_missed > 1000
    s.close()


# ------------------------------------------------------------------ hostile frames

def _hostile_frames(rng: random.Random, token: str) -> list[tuple[str, bytes, bool]]:
    """(label, bytes, authenticate first). Each one must make the server close
    that connection (with an error frame where it could say why)."""
    out = []
    for _ in range(400):                                   # random bytes
        out.append(("random", bytes(rng.randrange(256) for _ in range(rng.randint(4, 200))),
                    rng.random() < 0.5))
    for n in (protocol.MAX_FRAME + 1, 0xFFFFFFFF, 0x80000000, 0x7FFFFFFF, 1 << 30) * 20:
        out.append(("huge prefix", struct.pack(">I", n) + b"{", rng.random() < 0.5))
    for _ in range(150):                                   # a whole frame of garbage
        body = bytes(rng.randrange(256) for _ in range(rng.randint(0, 100)))
        out.append(("garbage frame", frame(body), rng.random() < 0.5))
    bad_json = [b"", b"{", b"}", b"null", b"[]", b"1", b'"x"', b"{'type': 'ping'}",
                b'{"type": 1}', b'{"type": ""}', b'{"type": "ping", "id": {}}',
                b'{"type": "ping", "id": 1.5}', b'{"type": "ping"}{"type": "ping"}',
                b'{"type": "ping", "x": NaN}', b'{"type": "ping", "type": "ping"}',
                b"\xef\xbb\xbf{\"type\": \"ping\"}", b"\x00" * 8, "{\"type\": \"é\"}".encode(),
                b"[" * 5000, b'{"type": "PING"}', b'{"type": "ping", "id": 18446744073709551616}']
    for i in range(300):
        out.append(("bad json", frame(bad_json[i % len(bad_json)]), i % 2 == 0))
    for i in range(100):                                   # hello itself is broken
        variants = [{"type": "hello"}, {"type": "hello", "token": token},
                    {"type": "hello", "version": 1, "token": token[:-1]},
                    {"type": "hello", "version": "1", "token": token},
                    {"type": "hello", "version": 1, "token": [token]},
                    {"type": "state"}, {"type": "welcome"}]
        out.append(("bad hello", msg_frame(variants[i % len(variants)]), False))
    return out


def test_a_thousand_hostile_frames_close_only_their_connection(server, client):
    rng = random.Random(99)
    cases = _hostile_frames(rng, server.token)
    assert len(cases) >= 1000
    keeper = Client.connect(*server.address, server.token)      # an innocent bystander
    for i, (label, data, auth) in enumerate(cases):
        s = raw_connect(server.address)
        try:
            if auth:
                assert hello(s, server.token)["type"] == "welcome"
            s.sendall(data)
            msgs, closed = read_until_closed(s, timeout=5)
        finally:
            s.close()
        assert closed, (i, label, data[:40])
        assert all(m["type"] == "error" for m in msgs), (i, label)
        if i % 50 == 0:
            assert keeper.ping()["pong"] and isinstance(client.state().t_ms, int)
    assert keeper.ping()["pong"] and not keeper.closed
    t = client.state().t_ms
    wait_for(lambda: client.state().t_ms > t)
    assert server.server.stats["bad_frames"] >= 900
    keeper.close()


def test_half_frames_then_silence_time_out(server, client):
    """Many at once: a header only, half a payload, 3 bytes of a header."""
    socks = []
    for i in range(40):
        s = raw_connect(server.address)
        if i % 2:
            hello(s, server.token)
        kind = i % 4
        payload = protocol.encode_payload({"type": "ping", "id": 1})
        if kind == 0:
            s.sendall(struct.pack(">I", len(payload)))
        elif kind == 1:
            s.sendall(frame(payload)[: 4 + len(payload) // 2])
        elif kind == 2:
            s.sendall(struct.pack(">I", 100)[:3])
        else:
            s.sendall(struct.pack(">I", 1 << 20) + b"{" * 1000)   # big frame, trickled
        socks.append(s)
    assert client.ping()["pong"]                                  # not blocked meanwhile
    for s in socks:
        msgs, closed = read_until_closed(s, timeout=5)
        assert closed
        assert any("unfinished" in m.get("reason", "") or "hello" in m.get("reason", "")
                   for m in msgs)
        s.close()
    assert client.ping()["pong"]


def test_a_trickle_that_keeps_sending_still_hits_the_frame_deadline(server):
    s = raw_connect(server.address)
    hello(s, server.token)
    s.sendall(struct.pack(">I", 1 << 20))
    deadline = time.monotonic() + 10
    closed = False
    while time.monotonic() < deadline and not closed:
        try:
            s.sendall(b" ")
        except OSError:
            closed = True
            break
        time.sleep(0.05)                                          # < frame_timeout each time
        s.setblocking(False)
        try:
            data = s.recv(4096)
            closed = data == b"" or b"unfinished" in data
        except BlockingIOError:
            pass
        except OSError:
            closed = True
        s.setblocking(True)
    assert closed
    s.close()


def test_too_many_clients_are_told_so(image):
    srv = ControllerServer(port=0, max_clients=2, hello_timeout=5)
    srv.start()
    try:
        a = Client.connect(*srv.address, srv.token)
        b = Client.connect(*srv.address, srv.token)
        s = raw_connect(srv.address)
        msgs, closed = read_until_closed(s)
        assert closed and msgs[0]["code"] == "busy"
        a.close()
        wait_for(lambda: srv.server.clients == 1)
        c = Client.connect(*srv.address, srv.token)
        assert c.ping()["pong"]
        b.close()
        c.close()
    finally:
        srv.close()


def test_closing_the_server_says_bye_and_fails_waiting_requests(image):
    srv = ControllerServer(port=0, image=image)
    srv.start()
    c = Client.connect(*srv.address, srv.token)
    srv.close()
    wait_for(lambda: c.closed)
    assert "shutting down" in c.close_reason
    with pytest.raises(ConnectionLost):
        c.state()
    c.close()


def test_upload_of_a_good_image_over_the_socket(client, image):
    r = client.upload(image)
    assert r["accepted"] and r["image_crc32"] == client.state().image_crc32
    with pytest.raises(RefusedError, match="base64"):
        client.request("upload", image="not base64!")


def test_controller_process_for_the_ide(tmp_path, image):
    from plcbuilder.link.client import LinkError
    from plcbuilder.link.process import ControllerProcess
    img = tmp_path / "eeprom.rom"
    img.write_bytes(image)
    proc = ControllerProcess.start(image=img, speed="10")
    try:
        assert proc.address[0] == "127.0.0.1" and proc.running
        with proc.connect() as c:
            assert len(c.state().image) == len(SOURCES)
            assert c.welcome["pid"] == proc.popen.pid
    finally:
        assert proc.stop() == 0
    assert not proc.running
    with pytest.raises(LinkError, match="did not start: .*refused"):
        bad = tmp_path / "bad.rom"
        bad.write_bytes(b"junk")
        ControllerProcess.start(image=bad)


def test_a_big_burst_of_events_arrives_whole_in_several_frames(client):
    """10 000 print events in one step: split over frames under the size limit."""
    from plcbuilder.controller.events import Print
    client.speed("pause")
    chatter = "main(){ do{ gvarset(20000, n); n++; }while(1); }"     # a print every tick
    client.upload(image_of(compile_programs(["M77"], {"M77": (Kind.HARDWARE, chatter)})))
    client.subscribe(samples=False, queue=16)
    client.start("M77")
    client.step(10_000)
    prints, frames = 0, 0
    # (a gap of 2 s between two batches, on a loaded machine, once ended the
    # wait at 9,048: the wait ends at the 10,000th, so a long bound costs nothing)
    for batch in client.telemetry(timeout=15):
        frames += 1
        prints += sum(isinstance(e, Print) for e in batch.events)
        assert batch.missed_events == 0
        if prints >= 10_000:
            break
    assert prints == 10_000 and frames >= 3


def test_a_client_gone_is_an_error_not_sigpipe_even_where_sigpipe_kills():
    """The link sends with MSG_NOSIGNAL: a peer that went away mid-telemetry is
    an EPIPE the server handles, even in a process where SIGPIPE has its
    default action (an embedding program's, or one a library changed: the
    signal would end the process without a word)."""
    import subprocess
    import sys
    code = r'''
import signal, socket, struct, time
signal.signal(signal.SIGPIPE, signal.SIG_DFL)
from plcbuilder.link.client import Client
from plcbuilder.link.server import ControllerServer
from tests.link.linkkit import TOGGLE, compile_programs, image_of
srv = ControllerServer(port=0, speed="max", image=image_of(compile_programs(
    ["TOGGLE"], overrides=TOGGLE)), frame_timeout=0.2, hello_timeout=1.0)
srv.start()
c = Client.connect(*srv.address, srv.token, timeout=10.0)
c.subscribe(lambda batch: None)
c.start("TOGGLE")
time.sleep(0.2)
# the server's side of the connection can no longer write (as after a peer's
# reset): its next send is EPIPE, which without MSG_NOSIGNAL raises SIGPIPE
for conn in list(srv.server._conns.values()):
    conn.sock.shutdown(socket.SHUT_WR)
time.sleep(0.5)
c.close()
print("alive")
srv.close()
'''
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                       timeout=120, cwd=str(__import__("pathlib").Path(__file__).parents[2]))
    assert r.returncode == 0 and "alive" in r.stdout, (r.returncode, r.stderr[-2000:])
