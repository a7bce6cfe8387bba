"""The one character <-> UTF-8 byte conversion (plcbuilder.ide.offsets)."""

from hypothesis import given, settings
from hypothesis import strategies as st

from plcbuilder.ide.offsets import byte_to_char, char_to_byte, utf8_len

SAMPLES = ["", "abc", "héllo", "€uro", "x𝄞y", "日本語のテキスト", "tab\tand é\n", "\ud800lone"]


def test_ascii_is_identity():
    for i in range(0, 8):
        assert char_to_byte("abcdef", i) == min(i, 6)
        assert byte_to_char("abcdef", i) == min(i, 6)


def test_non_ascii_examples():
    s = "aé€𝄞b"                     # 1 + 2 + 3 + 4 + 1 bytes
    assert [char_to_byte(s, i) for i in range(6)] == [0, 1, 3, 6, 10, 11]
    assert [byte_to_char(s, b) for b in (0, 1, 3, 6, 10, 11)] == [0, 1, 2, 3, 4, 5]
    assert utf8_len(s) == 11


def test_offsets_inside_a_character_map_to_it():
    s = "a€b"                          # € is bytes 1..3
    assert byte_to_char(s, 2) == 1
    assert byte_to_char(s, 3) == 1
    assert byte_to_char(s, 4) == 2


def test_clamping():
    for s in SAMPLES:
        assert char_to_byte(s, -5) == 0
        assert char_to_byte(s, len(s) + 10) == utf8_len(s)
        assert byte_to_char(s, -1) == 0
        assert byte_to_char(s, utf8_len(s) + 10) == len(s)


def test_lone_surrogate_counts_three_bytes():
    s = "\ud800x"
    assert utf8_len(s) == 4
    assert char_to_byte(s, 1) == 3
    assert byte_to_char(s, 3) == 1


@settings(max_examples=300, deadline=None)
@given(st.text(), st.integers(min_value=-3, max_value=60))
def test_round_trip(text, i):
    b = char_to_byte(text, i)
    assert b == len(text[:max(i, 0)].encode("utf-8", "surrogatepass"))
    assert byte_to_char(text, b) == min(max(i, 0), len(text))


@settings(max_examples=200, deadline=None)
@given(st.text(min_size=1))
def test_monotonic(text):
    prev = -1
    for i in range(len(text) + 1):
        b = char_to_byte(text, i)
        assert b > prev
        prev = b
