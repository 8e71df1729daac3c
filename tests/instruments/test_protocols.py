"""Gauge wire protocols: golden frames from gauges.md, every rejection kind, encode -> parse.

Golden frames are the examples quoted in ../shared/reference/gauges.md (Mitutoyo manuals,
U-WAVE captures, the CDI and ID-H manuals, the Sylvac Opto-RS manual).
"""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from station.errors import StationError
from station.instruments.base import Rejected, SerialSettings, Value
from station.instruments.framing import FrameSplitter
from station.instruments.protocols import PROTOCOLS, as_bytes, get_protocol, protocol_names
from tests.properties import examples

# (protocol, frame without terminator, expected device channel, value, unit)
GOLDEN_READINGS = [
    # Mitutoyo 01A: QM-Height manual §6.3 examples and the MUX-10 format example.
    ("mitutoyo", b"01A+0000.123", "1", 0.123, None),
    ("mitutoyo", b"01A+0000.125", "1", 0.125, None),
    ("mitutoyo", b"01A+00.12345", "1", 0.12345, None),
    ("mitutoyo", b"01A+000.1234", "1", 0.1234, None),
    ("mitutoyo", b"01A-001.2340", "1", -1.234, None),
    ("mitutoyo", b"03A-0012.345", "3", -12.345, None),
    # Digimatic nibbles as text: QM-Height, LSM-6200 and measuring projector manuals.
    ("digimatic", b"FFFF000012330", "1", 0.123, "mm"),
    ("digimatic", b"FFFF021076540", "1", 21.0765, "mm"),
    ("digimatic", b"FFFF801234530", "1", -12.345, "mm"),
    ("digimatic", b"F F F F 0 0 0 0 1 2 3 3 0", "1", 0.123, "mm"),
    ("digimatic", b"FFFF000123441", "1", 0.1234, "in"),
    ("digimatic", b"FFFF000012333", "1", 0.123, "mm"),  # LSM-6200: mm, GO
    ("digimatic", b"FFFF800012337", "1", -0.123, "in"),  # LSM-6200: inch, -NG
    ("digimatic", b"ffff000012330", "1", 0.123, "mm"),
    ("digimatic", b"FFFF000012338", "1", 0.123, "in"),  # Mahr Maxum III: 8 = inch
    # U-WAVE-R captures.
    ("uwave", b"DT10000+00000011.88M", "0", 11.88, "mm"),
    ("uwave", b"DT10002-0000000.001M", "2", -0.001, "mm"),
    ("uwave", b"DT10005+00000020.06M", "5", 20.06, "mm"),
    ("uwave", b"DT10102+000000.1234I", "1/2", 0.1234, "in"),
    # Sylvac Opto-RS: sign +, - or space.
    ("sylvac", b"+012.345", "1", 12.345, None),
    ("sylvac", b"-000.120", "1", -0.12, None),
    ("sylvac", b" 012.345", "1", 12.345, None),
    ("sylvac", b"012.345", "1", 12.345, None),
    # Chicago Dial Indicator (15 characters with CR LF) and the reference's spacing.
    ("cdi", b"+0012.345, MM", "1", 12.345, "mm"),
    ("cdi", b"-000.0450, IN", "1", -0.045, "in"),
    ("cdi", b"+0012.345 , MM", "1", 12.345, "mm"),
    ("cdi", b"+ 2.1380, MM", "1", 2.138, "mm"),  # Starrett IQ
    # Mitutoyo ID-H: GN normal, GX max, GM min, GW TIR.
    ("idh", b"GN01,+0016.2345", "1", 16.2345, None),
    ("idh", b"GX01,+0016.2345", "1", 16.2345, None),
    ("idh", b"GM12,-0000.0010", "12", -0.001, None),
    ("idh", b"GW00,+0000.0150", "0", 0.015, None),
    # One number per line.
    ("ascii", b"x: 0.0012", "x", 0.0012, None),
    ("ascii", b"2,+0.0012", "2", 0.0012, None),
    ("ascii", b"0.0012", "1", 0.0012, None),
    ("ascii", b"-.5 mm", "1", -0.5, "mm"),
    ("ascii", b"ch3=-1.25 in", "ch3", -1.25, "in"),
    ("ascii", b"4:+0.001000", "4", 0.001, None),  # lsst-ts hub reply
]


@pytest.mark.parametrize(("name", "frame", "channel", "value", "unit"), GOLDEN_READINGS)
def test_golden_reading(name, frame, channel, value, unit):
    parsed = get_protocol(name).parse(frame)
    assert isinstance(parsed, Value), parsed
    assert parsed.device_channel == channel
    assert parsed.value == pytest.approx(value, abs=1e-12)
    assert parsed.unit == unit


# (protocol, frame, reason, words the operator's sentence must contain)
GOLDEN_REJECTIONS = [
    ("mitutoyo", b"911", "error", "no data"),
    ("mitutoyo", b"922", "error", "format error"),
    ("mitutoyo", b"919", "error", "system error"),
    ("mitutoyo", b"1MITUTOYO", "status", "information"),
    ("mitutoyo", b"01A+0000.12", "malformed", "01A"),  # torn short
    ("mitutoyo", b"01A+0000.1234", "malformed", "01A"),
    ("mitutoyo", b"01B+0000.123", "malformed", "01A"),
    ("mitutoyo", b"01A+00.00.12", "malformed", "01A"),
    ("digimatic", b"FFFE000012330", "malformed", "header"),
    ("digimatic", b"FFFF00001A330", "malformed", "BCD"),
    ("digimatic", b"FFFF400012330", "malformed", "sign"),
    ("digimatic", b"FFFF000012360", "malformed", "point"),
    ("digimatic", b"FFFF000012339", "malformed", "unit"),
    ("digimatic", b"FFFF00001233", "malformed", "13 digits"),
    ("uwave", b"ST10001FFFFFFFFFF00", "status", "battery low"),
    ("uwave", b"ST10002FFFFFFFFFF01", "status", "instrument not responding"),
    ("uwave", b"ST10002123456789004", "status", "transmitter disconnected"),
    ("uwave", b"TI1120000009241511", "status", "transmitter information"),
    ("uwave", b"RI1000000", "status", "receiver information"),
    ("uwave", b"DT10000+00000011.88", "malformed", "DT1"),  # torn before the unit
    ("uwave", b"DT1000+00000011.88M", "malformed", "DT1"),
    ("sylvac", b"ERR0", "error", "sensor error"),
    ("sylvac", b"ERR1", "error", "incorrect command"),
    ("sylvac", b"ERR2", "error", "parity"),
    ("sylvac", b"ERR3", "out_of_range", "range exceeded"),
    ("sylvac", b"SY203.1", "status", "identification"),
    ("sylvac", b"SY235.2.1", "status", "identification"),
    ("sylvac", b"BAT0", "status", "battery low"),
    ("sylvac", b"+012.3.45", "malformed", "Sylvac"),
    ("cdi", b"+0012.345", "malformed", "Chicago"),  # torn before the unit
    ("cdi", b"0012.345, MM", "malformed", "Chicago"),
    ("cdi", b"+0012.345, UM", "malformed", "Chicago"),
    ("idh", b"CH01", "status", "acknowledged"),
    ("idh", b"DH01,+NG", "status", "+NG"),
    ("idh", b"GN1,+0016.2345", "malformed", "ID-H"),
    ("idh", b"GA01", "malformed", "ID-H"),
    ("ascii", b"# timeout waiting for clock", "error", "timeout waiting for clock"),
    ("ascii", b"#", "error", "no message"),
    ("ascii", b"nan", "malformed", "number"),
    ("ascii", b"inf", "malformed", "number"),
    ("ascii", b"1e5", "malformed", "number"),
    ("ascii", b"1_000", "malformed", "number"),
    ("ascii", b"12.5 um", "malformed", "number"),
]


@pytest.mark.parametrize(("name", "frame", "reason", "words"), GOLDEN_REJECTIONS)
def test_golden_rejection(name, frame, reason, words):
    parsed = get_protocol(name).parse(frame)
    assert isinstance(parsed, Rejected), parsed
    assert parsed.reason == reason
    assert words in parsed.detail


@pytest.mark.parametrize("name", protocol_names())
def test_empty_and_binary_frames_are_malformed(name):
    protocol = get_protocol(name)
    for frame in (b"", b"\xff\xfe\x00", b"01A+0000,123", b"+\xb2.5"):
        parsed = protocol.parse(frame)
        assert isinstance(parsed, Rejected), (frame, parsed)
        assert parsed.reason == "malformed"


@pytest.mark.parametrize("name", protocol_names())
def test_fault_frames_are_rejected_with_their_reason(name):
    protocol = get_protocol(name, channels="1,2")
    faults = protocol.fault_frames("2")
    for reason, frame in faults.items():
        assert frame.endswith(protocol.terminator)
        [stripped] = FrameSplitter(protocol.terminator).feed(frame)
        parsed = protocol.parse(stripped)
        assert isinstance(parsed, Rejected), (reason, frame)
        assert parsed.reason == reason, frame


def test_every_device_error_kind_has_an_example_frame():
    reasons = {name: set(get_protocol(name).fault_frames("1")) for name in protocol_names()}
    assert reasons["mitutoyo"] == {"error", "status"}
    assert reasons["uwave"] == {"status"}
    assert reasons["sylvac"] == {"error", "status", "out_of_range"}
    assert reasons["idh"] == {"status"}
    assert reasons["ascii"] == {"error"}
    assert reasons["cdi"] == reasons["digimatic"] == set()  # they send no such frames


@pytest.mark.parametrize("name", protocol_names())
def test_a_value_outside_the_gauge_range_is_out_of_range(name):
    protocol = get_protocol(name, gauge_range=(-5, 5))
    [inside] = FrameSplitter(protocol.terminator).feed(protocol.encode("1", 4.5, 0.001, "mm"))
    [outside] = FrameSplitter(protocol.terminator).feed(protocol.encode("1", -5.5, 0.001, "mm"))
    assert isinstance(protocol.parse(inside), Value)
    rejected = protocol.parse(outside)
    assert isinstance(rejected, Rejected)
    assert rejected.reason == "out_of_range"
    assert "-5.5 is outside the gauge range -5 to 5" in rejected.detail


# Encoding: the exact frames the real devices send.
GOLDEN_ENCODINGS = [
    ("mitutoyo", "1", 0.123, 0.001, "mm", b"01A+0000.123\r"),
    ("mitutoyo", "1", 0.125, 0.005, "mm", b"01A+0000.125\r"),
    ("mitutoyo", "1", 0.12345, 0.00001, "in", b"01A+00.12345\r"),
    ("mitutoyo", "1", 0.1234, 0.0001, "in", b"01A+000.1234\r"),
    ("mitutoyo", "1", -1.234, 0.0001, "mm", b"01A-001.2340\r"),
    ("mitutoyo", "2", -0.0004, 0.001, "mm", b"02A+0000.000\r"),  # rounds to zero: no minus
    ("digimatic", "1", 0.123, 0.001, "mm", b"FFFF000012330\r"),
    ("digimatic", "1", 21.0765, 0.0001, "mm", b"FFFF021076540\r"),
    ("digimatic", "1", -12.345, 0.001, "mm", b"FFFF801234530\r"),
    ("digimatic", "1", 0.1234, 0.0001, "in", b"FFFF000123441\r"),
    ("uwave", "0", 11.88, 0.01, "mm", b"DT10000+00000011.88M\r"),
    ("uwave", "2", -0.001, 0.001, "mm", b"DT10002-0000000.001M\r"),
    ("uwave", "1/2", 0.1234, 0.0001, "in", b"DT10102+000000.1234I\r"),
    ("sylvac", "1", 12.345, 0.001, "mm", b"+012.345\r"),
    ("sylvac", "1", -0.4861, 0.0001, "in", b"-00.4861\r"),
    ("cdi", "1", 12.345, 0.001, "mm", b"+0012.345, MM\r\n"),
    ("cdi", "1", -0.045, 0.0001, "in", b"-000.0450, IN\r\n"),
    ("idh", "1", 16.2345, 0.0001, "mm", b"GN01,+0016.2345\r\n"),
    ("ascii", "x", -0.0012, 0.0001, "mm", b"x,-0.0012\n"),
]


@pytest.mark.parametrize(
    ("name", "channel", "value", "resolution", "unit", "frame"), GOLDEN_ENCODINGS
)
def test_golden_encoding(name, channel, value, resolution, unit, frame):
    assert get_protocol(name).encode(channel, value, resolution, unit) == frame


def test_a_cdi_reply_is_15_characters():
    assert len(get_protocol("cdi").encode("1", -1.5, 0.001, "mm")) == 15


def test_untagged_ascii_and_other_idh_modes():
    assert get_protocol("ascii", tag_channel=False).encode("1", 0.5, 0.01, "mm") == b"+0.50\n"
    assert get_protocol("idh", mode="X").encode("7", 1, 0.001, "mm") == b"GX07,+00001.000\r\n"
    with pytest.raises(ValueError):
        get_protocol("idh", mode="Q").encode("7", 1, 0.001, "mm")


def test_values_that_do_not_fit_the_frame_raise():
    with pytest.raises(ValueError):
        get_protocol("mitutoyo").encode("1", 12345.678, 0.001, "mm")
    with pytest.raises(ValueError):
        get_protocol("digimatic").encode("1", 1000.0, 0.001, "mm")
    with pytest.raises(ValueError):
        get_protocol("digimatic").encode("1", 0.1, 0.000001, "mm")
    with pytest.raises(ValueError):
        get_protocol("mitutoyo").encode("1", 0.1, 0.0, "mm")


# Round trips: every value on the resolution grid that fits comes back as itself.
CHANNELS = {
    "mitutoyo": ["1", "2", "9", "A"],
    "uwave": ["0", "1", "12", "3/4"],
    "idh": ["0", "1", "42", "99"],
    "ascii": ["1", "x", "z2"],
}
RESOLUTIONS = [0.01, 0.005, 0.002, 0.001, 0.0005, 0.0001, 0.00005, 0.00001]
UNIT_IN_FRAME = {"uwave", "cdi", "digimatic"}


@settings(max_examples=examples(400), derandomize=True, deadline=None)
@given(
    name=st.sampled_from(protocol_names()),
    counts=st.integers(-99_999, 99_999),
    resolution=st.sampled_from(RESOLUTIONS),
    unit=st.sampled_from(["mm", "in"]),
    pick=st.integers(0, 3),
)
def test_encode_then_parse_round_trips(name, counts, resolution, unit, pick):
    protocol = get_protocol(name)
    channels = CHANNELS.get(name, ["1"])
    channel = channels[pick % len(channels)]
    value = counts * resolution
    wire = protocol.encode(channel, value, resolution, unit)
    frames = FrameSplitter(protocol.terminator).feed(wire)
    assert len(frames) == 1, wire
    parsed = protocol.parse(frames[0])
    assert isinstance(parsed, Value), (wire, parsed)
    assert parsed.device_channel == channel
    assert round(parsed.value / resolution) == counts
    assert parsed.value == pytest.approx(value, abs=resolution * 1e-6)
    assert parsed.unit == (unit if name in UNIT_IN_FRAME else None)


# Bytes that reach deep into the parsers: digits, signs, points, letters of the formats.
_frame_bytes = st.lists(
    st.one_of(
        st.sampled_from(list(b"0123456789+-. ,:=#FMIANGDTSRYEBCHXW\xff\x00")).map(
            lambda b: bytes([b])
        ),
        st.sampled_from([b"01A", b"DT1", b"ST1", b"FFFF", b"GN", b"ERR", b"SY", b", MM", b"0000"]),
    ),
    max_size=24,
).map(b"".join)


@settings(max_examples=examples(500), derandomize=True, deadline=None)
@given(
    name=st.sampled_from(protocol_names()), frame=st.one_of(st.binary(max_size=40), _frame_bytes)
)
def test_parse_never_raises(name, frame):
    parsed = get_protocol(name, gauge_range=(-100, 100)).parse(frame)
    assert isinstance(parsed, Value | Rejected)
    if isinstance(parsed, Value):
        assert -100 <= parsed.value <= 100
    else:
        assert parsed.reason in ("error", "status", "malformed", "out_of_range")
        assert parsed.detail


# Serial settings: a pty cannot tell 7E2 from 8N1 (gauges.md §10 pitfall 1), so check them here.
DEFAULT_SETTINGS = {
    "mitutoyo": ("9600 8N1", b"\r", True),
    "uwave": ("57600 8N1", b"\r", False),
    "sylvac": ("4800 7E2", b"\r", True),
    "cdi": ("9600 8N1", b"\r\n", True),
    "idh": ("9600 8N1", b"\r\n", True),
    "ascii": ("9600 8N1", b"\n", False),
    "digimatic": ("9600 8N1", b"\r", False),
}


@pytest.mark.parametrize("name", protocol_names())
def test_default_settings_terminator_and_polling(name):
    protocol = get_protocol(name)
    described, terminator, polled = DEFAULT_SETTINGS[name]
    assert protocol.settings.describe() == described
    assert protocol.terminator == terminator
    assert protocol.polled is polled
    assert (protocol.request("1") is not None) is polled


def test_sylvac_settings_are_seven_data_bits_even_parity_two_stop_bits():
    assert get_protocol("sylvac").settings.as_kwargs() == {
        "baudrate": 4800,
        "bytesize": 7,
        "parity": "E",
        "stopbits": 2,
    }


def test_requests_and_zero_commands():
    assert get_protocol("mitutoyo").request("3") == b"1\r"
    assert get_protocol("mitutoyo").zero_command("1") is None
    assert get_protocol("sylvac").request("1") == b"?\r"
    assert get_protocol("cdi").request("1") == b"R\r"
    assert get_protocol("cdi").zero_command("1") == b"C\r"
    assert get_protocol("idh").request("7") == b"GA07\r\n"
    assert get_protocol("idh").zero_command("12") == b"CR12\r\n"
    assert get_protocol("uwave").request("1") is None


def test_the_registry():
    assert protocol_names() == ["mitutoyo", "uwave", "sylvac", "cdi", "idh", "ascii", "digimatic"]
    assert all(PROTOCOLS[name].name == name for name in protocol_names())
    assert all(PROTOCOLS[name].description for name in protocol_names())


def test_an_unknown_protocol_names_the_known_ones():
    with pytest.raises(StationError) as error:
        get_protocol("mitutoyo2")
    assert "unknown gauge protocol 'mitutoyo2'" in error.value.message
    assert "mitutoyo, uwave, sylvac, cdi, idh, ascii, digimatic" in error.value.message


def test_options_override_what_is_unconfirmed():
    mux = get_protocol(
        "mitutoyo", request="{channel}\\r", channels="1,2,3", baudrate="19200", parity="e"
    )
    assert mux.request("2") == b"2\r"
    assert mux.channels == ("1", "2", "3")
    assert mux.settings == SerialSettings(19200, 8, "E", 1)
    pico = get_protocol("ascii", request="r", terminator="\\r\\n", stopbits="2")
    assert pico.polled and pico.request("1") == b"r"
    assert pico.terminator == b"\r\n"
    assert pico.settings.describe() == "9600 8N2"
    assert get_protocol("mitutoyo", request="").polled is False
    assert get_protocol("cdi", zero="").zero_command("1") is None
    assert get_protocol("idh", baudrate=None).settings.baudrate == 9600  # None = not given
    assert get_protocol("digimatic", stopbits=1.5).settings.describe() == "9600 8N1.5"
    assert get_protocol("uwave", request=b"IR1000000\r").request("1") == b"IR1000000\r"


@pytest.mark.parametrize(
    ("options", "words"),
    [
        ({"speed": 9600}, "no option speed"),
        ({"baudrate": "fast"}, "bad serial settings"),
        ({"baudrate": 0}, "baud rate 0"),
        ({"bytesize": 9}, "data bits 9"),
        ({"parity": "X"}, "parity X"),
        ({"stopbits": 3}, "stop bits 3"),
        ({"terminator": ""}, "terminator cannot be empty"),
        ({"channels": ""}, "at least one device channel"),
        ({"channels": "1,,2"}, "at least one device channel"),
        ({"gauge_range": (5, 1)}, "is empty"),
        ({"gauge_range": "wide"}, "two numbers"),
        ({"request": "\\x4"}, "not valid text"),
    ],
)
def test_bad_options_are_sentences(options, words):
    with pytest.raises(StationError) as error:
        get_protocol("mitutoyo", **options)
    assert words in error.value.message


def test_as_bytes():
    assert as_bytes("GA{channel}\\r\\n") == b"GA{channel}\r\n"
    assert as_bytes(b"\x03") == b"\x03"
    assert as_bytes("\\x03") == b"\x03"


@pytest.mark.parametrize(
    ("name", "channels", "words"),
    [
        ("mitutoyo", "1,10", "one digit or letter"),
        ("idh", "x", "no device channel 'x'"),
        ("idh", "100", "0 to 99"),
        ("uwave", "1/100", "0 to 99"),
        ("ascii", "x y", "letters, digits or _"),
    ],
)
def test_channels_a_device_cannot_address_are_refused(name, channels, words):
    with pytest.raises(StationError) as error:
        get_protocol(name, channels=channels)
    assert words in error.value.message
    with pytest.raises(ValueError):
        get_protocol(name).encode(channels.split(",")[-1], 0.1, 0.001, "mm")


def test_digimatic_values_are_the_exact_decimal_on_the_display():
    protocol = get_protocol("digimatic")
    assert protocol.parse(b"FFFF801248230").value == -12.482
    assert protocol.parse(b"FFFF000000150").value == 0.00001
