"""Framing, message checks and the telemetry encoding."""

import base64
import json
import random
import struct

import pytest
from hypothesis import given, settings, strategies as st

from plcbuilder.controller.events import Ended, Note, Sample
from plcbuilder.link import protocol
from plcbuilder.link.protocol import (MAX_FRAME, BadRequest, ErrorCode, FrameDecoder,
                                      ProtocolError, decode_payload, encode_frame)


def test_frame_is_u32_big_endian_length_then_utf8_json():
    f = encode_frame({"type": "ping", "id": 7, "text": "é"})
    n = struct.unpack(">I", f[:4])[0]
    assert n == len(f) - 4
    assert json.loads(f[4:].decode("utf-8")) == {"type": "ping", "id": 7, "text": "é"}


def test_decoder_reassembles_frames_fed_byte_by_byte():
    msgs = [{"type": "ping", "id": i, "pad": "x" * i} for i in range(20)]
    stream = b"".join(encode_frame(m) for m in msgs)
    dec = FrameDecoder()
    got = []
    for i in range(len(stream)):
        got += dec.feed(stream[i:i + 1])
        assert dec.mid_frame == (i + 1 < len(stream)) or got
    assert [decode_payload(p) for p in got] == msgs
    assert not dec.mid_frame


def test_decoder_refuses_an_oversize_prefix_before_buffering():
    dec = FrameDecoder(max_frame=100)
    with pytest.raises(ProtocolError, match="more than the 100-byte limit"):
        dec.feed(struct.pack(">I", 101))
    with pytest.raises(ProtocolError):
        FrameDecoder().feed(b"\xff\xff\xff\xff")
    assert FrameDecoder().feed(struct.pack(">I", MAX_FRAME))  == []


@pytest.mark.parametrize("payload, why", [
    (b"\xff\xfe", "not UTF-8"),
    (b"{", "not valid JSON"),
    (b"[1,2]", "must be a JSON object"),
    (b'"hello"', "must be a JSON object"),
    (b"{}", "needs a 'type'"),
    (b'{"type": 3}', "needs a 'type'"),
    (b'{"type": "Hello"}', "needs a 'type'"),
    (b'{"type": "a b"}', "needs a 'type'"),
    (b'{"type": "ping", "id": [1]}', "'id' must be"),
    (b'{"type": "ping", "id": 1.5}', "'id' must be"),
    (b'{"type": "ping", "type": "ping"}', "appears twice"),
    (b'{"type": "ping", "x": NaN}', "not valid JSON"),
    (b'{"type": "ping", "x": Infinity}', "not valid JSON"),
    (b"[" * 100000 + b"]" * 100000, "JSON"),
])
def test_bad_payloads_are_protocol_errors(payload, why):
    with pytest.raises(ProtocolError, match=why) as e:
        decode_payload(payload)
    assert e.value.code is ErrorCode.BAD_FRAME


def test_unknown_type_is_its_own_error_code():
    with pytest.raises(ProtocolError) as e:
        decode_payload(b'{"type": "eval", "id": 1}', protocol.REQUESTS)
    assert e.value.code is ErrorCode.UNKNOWN_TYPE


def test_encoder_refuses_nan_and_oversize():
    with pytest.raises(ValueError):
        encode_frame({"type": "x", "v": float("nan")})
    with pytest.raises(ProtocolError, match="larger than"):
        encode_frame({"type": "x", "v": "a" * 200}, max_frame=100)


def test_field_checks():
    m = {"type": "input", "pin": 3, "value": True, "name": "x" * 10, "f": 2.5}
    assert protocol.field_int(m, "pin", lo=0, hi=63) == 3
    with pytest.raises(BadRequest, match="must be an integer"):
        protocol.field_int(m, "value")                # a bool is not an integer
    with pytest.raises(BadRequest, match="missing field 'x'"):
        protocol.field_int(m, "x")
    assert protocol.field_int(m, "x", 9) == 9
    with pytest.raises(BadRequest, match="from 0 to 2"):
        protocol.field_int(m, "pin", lo=0, hi=2)
    with pytest.raises(BadRequest, match="longer than"):
        protocol.field_str(m, "name", max_len=5)
    assert protocol.field_number(m, "f", 0, 10) == 2.5
    with pytest.raises(BadRequest):
        protocol.field_number({"type": "s", "f": float("inf")}, "f", 0, 10)


def test_image_base64_is_strict_and_bounded():
    data = bytes(range(256)) * 3
    assert protocol.decode_image({"image": protocol.encode_image(data)}) == data
    for bad in ({"image": "@@@@"}, {"image": "QUJD\nRA=="}, {"image": 5}, {},
                {"image": "QUJ"}, {"image": "é"}):
        with pytest.raises(BadRequest):
            protocol.decode_image(bad)
    with pytest.raises(BadRequest, match="larger than 10"):
        protocol.decode_image({"image": base64.b64encode(b"x" * 30).decode()}, max_image=10)


def test_samples_and_events_round_trip_through_json():
    s = Sample(5, "M03", 2, 0, (1,) * 8, (8,) * 8, (0,) * 8, (0,) * 8, (1200,) * 8, (1,) * 9,
               (0,) * 9)
    row = json.loads(json.dumps(protocol.sample_row(s)))
    assert protocol.sample_from_row(row) == s
    # a newer server's extra field is ignored
    fields = list(protocol.SAMPLE_FIELDS) + ["future"]
    assert protocol.sample_from_row(row + [1], fields) == s
    for e in (Ended(3, "M03", "hardware", 99, "plc_exit_normal", 0), Note(4, "hi")):
        assert protocol.event_from_dict(json.loads(json.dumps(protocol.event_dict(e)))) == e
    assert protocol.event_from_dict({"type": "brand_new", "x": 1}) == {"type": "brand_new", "x": 1}


@settings(max_examples=300, deadline=None)
@given(st.binary(max_size=300))
def test_decoder_only_ever_raises_protocol_errors(data):
    dec = FrameDecoder(max_frame=1000)
    try:
        for p in dec.feed(data):
            decode_payload(p, protocol.REQUESTS)
    except ProtocolError:
        pass


def test_random_json_values_never_escape_as_other_errors():
    rng = random.Random(9)
    atoms = [None, True, 1, -1, 2 ** 70, 1.5, "x", "", [], {}]
    for _ in range(500):
        obj = {rng.choice(["type", "id", "token", "x"]): rng.choice(atoms) for _ in range(3)}
        try:
            decode_payload(json.dumps(obj).encode(), protocol.REQUESTS)
        except ProtocolError:
            pass


def test_one_reading_of_a_speed_for_the_command_line_and_the_ide():
    """`controller --speed` and the IDE's Speed box read a speed the same way
    (issue 28: speed parsing lived in two places that disagreed: the IDE took
    "1x" and "fast", the command line did not)."""
    import argparse

    from plcbuilder.cli.cmd_controller import parse_speed as cli_speed
    from plcbuilder.link.protocol import parse_speed

    assert parse_speed("realtime") == ("realtime", None)
    assert parse_speed("1x") == parse_speed(1) == parse_speed("1") == ("realtime", None)
    assert parse_speed("10") == parse_speed(10) == ("factor", 10.0)
    assert parse_speed("2.5x") == parse_speed("2.5×") == ("factor", 2.5)
    assert parse_speed("max") == parse_speed("fast") == ("max", None)
    assert parse_speed("pause") == parse_speed("Paused") == ("pause", None)
    for bad in ("warp", "1e9", "nan", "0", "-3", True):
        with pytest.raises(ValueError, match="speed"):
            parse_speed(bad)
    assert cli_speed("1x") == ("realtime", 1.0) and cli_speed("fast") == ("max", 1.0)
    assert cli_speed("10") == ("factor", 10.0)
    with pytest.raises(argparse.ArgumentTypeError, match="out of range"):
        cli_speed("1e9")
