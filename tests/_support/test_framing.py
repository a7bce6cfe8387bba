"""Content-Length framing: whatever arrives, frames or errors come out, and the
reader holds no more than a header and a body."""

from plcbuilder._support.framing import Frame, FrameError, FrameReader, encode_frame


def test_frames_split_anywhere_come_out_whole():
    data = encode_frame(b'{"a": 1}') + encode_frame("{\"é\": 2}".encode()) + b"\r\n"
    for cut in range(len(data)):
        r = FrameReader()
        got = r.feed(data[:cut]) + r.feed(data[cut:])
        assert got == [Frame(b'{"a": 1}'), Frame("{\"é\": 2}".encode())]


def test_other_headers_and_case_are_accepted():
    r = FrameReader()
    got = r.feed(b"content-type: x\r\nCONTENT-LENGTH:  2\r\n\r\n{}")
    assert got == [Frame(b"{}")]


def test_a_body_over_the_limit_is_skipped_and_the_next_frame_read():
    r = FrameReader(max_body=10)
    got = r.feed(b"Content-Length: 20\r\n\r\n" + b"x" * 15)
    assert isinstance(got[0], FrameError) and got[0].skipped == 20
    assert r.pending == 0
    got = r.feed(b"y" * 5 + encode_frame(b"{}"))
    assert got == [Frame(b"{}")]


def test_bad_headers_are_reported_and_reading_resynchronises():
    r = FrameReader(max_header=64)
    got = r.feed(b"Nonsense\r\n\r\n{garbage}" + encode_frame(b"[1]"))
    assert isinstance(got[0], FrameError) and "without a Content-Length" in got[0].reason
    assert got[1:] == [Frame(b"[1]")]
    got = r.feed(b"Content-Length: -5\r\n\r\n" + encode_frame(b"[2]"))
    assert "not a number" in got[0].reason and got[1:] == [Frame(b"[2]")]
    got = r.feed(b"z" * 1000)
    assert len(got) == 1 and "without the blank line" in got[0].reason
    assert r.pending < 64
    assert r.feed(b"z" * 100000) == [] and r.pending < 64
    assert r.feed(encode_frame(b"[3]")) == [Frame(b"[3]")]


def test_two_different_content_lengths_refuse_that_frame_only():
    r = FrameReader()
    got = r.feed(b"Content-Length: 2\r\nContent-Length: 40\r\n\r\n{}" + encode_frame(b"[4]"))
    assert isinstance(got[0], FrameError) and "different Content-Length" in got[0].reason
    assert got[1:] == [Frame(b"[4]")]
    got = r.feed(b"Content-Length: 2\r\ncontent-length: 2\r\n\r\n{}" + encode_frame(b"[5]"))
    assert got == [Frame(b"{}"), Frame(b"[5]")]


def test_a_short_content_length_loses_no_next_frame():
    """The rest of a body whose length was given too short is skipped, and the
    header that follows it is the next frame's."""
    for tail in (b'"}', b'1}\n  ', b'\n}'):
        r = FrameReader()
        body = b'{"a": "b' + tail
        got = r.feed(b"Content-Length: 6\r\n\r\n" + body + encode_frame(b"[6]") + encode_frame(b"[7]"))
        assert got == [Frame(body[:6]), Frame(b"[6]"), Frame(b"[7]")], (tail, got)
