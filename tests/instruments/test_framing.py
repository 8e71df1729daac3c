"""The frame splitter: terminators, torn frames, line noise, the bounded buffer, reset."""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from station.instruments.framing import FrameSplitter, Overflow
from tests.properties import examples


def feed_all(splitter: FrameSplitter, *chunks: bytes) -> list[bytes | Overflow]:
    out: list[bytes | Overflow] = []
    for chunk in chunks:
        out.extend(splitter.feed(chunk))
    return out


def test_cr_frames_in_one_read():
    splitter = FrameSplitter(b"\r")
    assert splitter.feed(b"01A+0000.123\r02A-0000.456\r") == [b"01A+0000.123", b"02A-0000.456"]
    assert splitter.pending == 0


def test_a_frame_torn_at_every_position_is_joined():
    stream = b"GN01,+0016.2345\r\n"
    for cut in range(len(stream) + 1):
        splitter = FrameSplitter(b"\r\n")
        assert feed_all(splitter, stream[:cut], stream[cut:]) == [b"GN01,+0016.2345"], cut


def test_crlf_torn_between_reads_gives_no_empty_frame_and_no_leading_lf():
    splitter = FrameSplitter(b"\r\n")
    assert splitter.feed(b"+0012.345, MM\r") == [b"+0012.345, MM"]
    assert splitter.feed(b"\n+0012.346, MM\r\n") == [b"+0012.346, MM"]


def test_a_lone_cr_ends_a_frame_of_a_crlf_protocol():
    splitter = FrameSplitter(b"\r\n")
    assert splitter.feed(b"GN01,+0000.1000\rGN01,+0000.2000\r\n") == [
        b"GN01,+0000.1000",
        b"GN01,+0000.2000",
    ]


def test_stray_lf_before_a_cr_frame_is_dropped():
    splitter = FrameSplitter(b"\r")
    assert splitter.feed(b"\n01A+0000.123\r\n\n01A+0000.124\r") == [
        b"01A+0000.123",
        b"01A+0000.124",
    ]


def test_surrounding_noise_is_stripped_and_blank_lines_are_not_frames():
    splitter = FrameSplitter(b"\r")
    assert splitter.feed(b"\x00\x00 01A+0000.123 \t\r \r\x00\r\r") == [b"01A+0000.123"]


def test_inner_spaces_are_kept():
    assert FrameSplitter(b"\r\n").feed(b"+ 2.1380, MM\r\n") == [b"+ 2.1380, MM"]


def test_a_frame_of_exactly_max_frame_bytes_passes():
    splitter = FrameSplitter(b"\r", max_frame=8)
    assert splitter.feed(b"12345678\r") == [b"12345678"]


def test_an_overlong_run_is_reported_once_and_framing_resumes_after_the_next_terminator():
    splitter = FrameSplitter(b"\r", max_frame=8)
    out = feed_all(splitter, b"0123456789", b"abcdefghij", b"xyz\r01A+0.1\r")
    assert out == [Overflow(b"01234567"), b"01A+0.1"]
    assert "8 bytes" in out[0].detail


def test_an_overlong_terminated_run_in_one_read_is_an_overflow():
    splitter = FrameSplitter(b"\r", max_frame=4)
    assert splitter.feed(b"123456\rabc\r") == [Overflow(b"1234"), b"abc"]


def test_the_buffer_stays_bounded_while_discarding():
    splitter = FrameSplitter(b"\r", max_frame=16)
    for _ in range(1000):
        splitter.feed(b"x" * 100)
        assert splitter.pending <= 16
    assert splitter.feed(b"\rok\r") == [b"ok"]


def test_reset_drops_a_partial_frame_and_an_overflow_in_progress():
    splitter = FrameSplitter(b"\r", max_frame=4)
    splitter.feed(b"01A+00")
    splitter.reset()
    assert splitter.pending == 0
    assert splitter.feed(b"abc\r") == [b"abc"]
    splitter.feed(b"123456")
    splitter.reset()
    assert splitter.feed(b"abc\r") == [b"abc"]


def test_a_single_byte_non_line_terminator_keeps_cr_lf_inside_frames():
    splitter = FrameSplitter(b";")
    assert splitter.feed(b"1\r2;\n3 ;") == [b"1\r2", b"3"]


def test_a_multi_byte_terminator_torn_between_reads():
    splitter = FrameSplitter(b"\x03\x04")
    assert splitter.feed(b"12.5\x03") == []
    assert splitter.feed(b"\x0413\x03x\x04") == [b"12.5"]
    assert splitter.feed(b"\x03\x04") == [b"13\x03x\x04"]


def test_a_torn_multi_byte_terminator_ends_an_overflow():
    splitter = FrameSplitter(b"\x03\x04", max_frame=4)
    out = feed_all(splitter, b"abcdefgh\x03", b"\x04ok\x03\x04")
    assert out == [Overflow(b"abcd"), b"ok"]


def test_a_torn_multi_byte_terminator_does_not_count_towards_max_frame():
    splitter = FrameSplitter(b"\x03\x04", max_frame=4)
    assert feed_all(splitter, b"abcd\x03", b"\x04") == [b"abcd"]


def test_bad_arguments():
    with pytest.raises(ValueError):
        FrameSplitter(b"")
    with pytest.raises(ValueError):
        FrameSplitter(b"\r", max_frame=0)


# Bytes that matter to the splitter (terminators, noise) are over-represented.
_stream_bytes = st.lists(
    st.one_of(
        st.sampled_from([b"\r", b"\n", b"\x00", b" ", b";", b"\x03", b"\x04"]),
        st.binary(max_size=12),
    ),
    max_size=20,
).map(b"".join)


@settings(max_examples=examples(300), derandomize=True, deadline=None)
@given(
    stream=_stream_bytes,
    terminator=st.sampled_from([b"\r", b"\n", b"\r\n", b";", b"\x03\x04"]),
    max_frame=st.integers(1, 24),
    cuts=st.lists(st.integers(0, 200), max_size=8),
)
def test_the_frames_do_not_depend_on_how_reads_cut_the_stream(stream, terminator, max_frame, cuts):
    whole = FrameSplitter(terminator, max_frame).feed(stream)
    pieces = [
        stream[a:b] for a, b in zip([0, *sorted(cuts)], [*sorted(cuts), len(stream)], strict=True)
    ]
    cut = feed_all(FrameSplitter(terminator, max_frame), *pieces)
    assert cut == whole
    for item in cut:
        if isinstance(item, Overflow):
            assert len(item.head) == max_frame
        else:
            assert 0 < len(item) <= max_frame
