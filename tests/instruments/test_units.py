"""The unit and resolution the frames say, against the session's: the sentence naming both."""

from __future__ import annotations

import pytest

from station.instruments.protocols import get_protocol
from station.instruments.units import (
    FrameSample,
    describe_inference,
    frames_disagree,
    infer_channel,
)

MITUTOYO = get_protocol("mitutoyo")


def samples_of(protocol, values, resolution, unit):
    """What ``protocol``'s frames of ``values`` show, as the reader sees them."""
    out = []
    for value in values:
        frame = protocol.encode(protocol.channels[0], value, resolution, unit).rstrip(b"\r\n")
        parsed = protocol.parse(frame)
        out.append(FrameSample(parsed.value, protocol.frame_decimals(frame), parsed.unit))
    return out


def test_mitutoyo_mm_at_0_001_against_an_inch_session_at_0_0001() -> None:
    samples = samples_of(MITUTOYO, [0.001, -0.002, 0.0, 0.003], 0.001, "mm")
    inferred = infer_channel("x", samples, MITUTOYO.units_by_decimals)
    assert (inferred.decimals, inferred.step, inferred.unit) == (3, 0.001, None)
    assert inferred.protocol_unit == "mm"
    sentence = frames_disagree({"x": inferred}, "in", 0.0001, {"x": samples})
    assert sentence == (
        "the gauges send steps of 0.001, which is mm on this protocol; "
        "the session is in inches at 0.0001"
    )


def test_matching_frames_say_nothing() -> None:
    samples = samples_of(MITUTOYO, [0.0001, -0.0012, 0.0], 0.0001, "in")
    inferred = infer_channel("x", samples, MITUTOYO.units_by_decimals)
    assert frames_disagree({"x": inferred}, "in", 0.0001, {"x": samples}) == ""


def test_a_gauge_finer_than_declared_is_found_by_its_values() -> None:
    samples = samples_of(MITUTOYO, [0.001, 0.002, 0.013], 0.001, "mm")
    inferred = infer_channel("y", samples, MITUTOYO.units_by_decimals)
    sentence = frames_disagree({"y": inferred}, "mm", 0.005, {"y": samples})
    assert sentence.startswith("the gauges send steps of 0.001")
    assert sentence.endswith("the session is in mm at 0.005")


def test_the_step_between_values_shows_a_coarser_gauge_with_the_same_decimals() -> None:
    values = [0.005, 0.010, -0.015, 0.020, 0.0, 0.035]
    samples = samples_of(MITUTOYO, values, 0.005, "mm")
    inferred = infer_channel("x", samples, MITUTOYO.units_by_decimals)
    assert inferred.step == 0.005
    assert frames_disagree({"x": inferred}, "mm", 0.005, {"x": samples}) == ""
    # A 0.001 gauge may show only multiples of 0.005 by chance: that alone refuses nothing.
    assert frames_disagree({"x": inferred}, "mm", 0.001, {"x": samples}) == ""
    assert (
        describe_inference({"x": inferred})
        == "x sends steps of 0.005, which is mm on this protocol"
    )


@pytest.mark.parametrize("name", ["uwave", "cdi", "digimatic"])
def test_a_unit_the_frames_state_refuses_a_session_in_the_other(name: str) -> None:
    protocol = get_protocol(name)
    assert protocol.carries_unit
    samples = samples_of(protocol, [0.0012, 0.0], 0.0001, "in")
    inferred = infer_channel("x", samples, protocol.units_by_decimals)
    assert inferred.unit == "in" and inferred.decimals == 4
    assert frames_disagree({"x": inferred}, "mm", 0.0001, {"x": samples}) == (
        "the gauges send steps of 0.0001 in; the session is in mm at 0.0001"
    )


def test_protocols_without_a_unit_say_so() -> None:
    for name in ("mitutoyo", "sylvac", "idh", "ascii"):
        assert not get_protocol(name).carries_unit


def test_only_the_channels_that_disagree_are_named() -> None:
    good = samples_of(MITUTOYO, [0.0001, 0.0], 0.0001, "in")
    bad = samples_of(MITUTOYO, [0.001, 0.0], 0.001, "mm")
    inferred = {
        "x": infer_channel("x", good, MITUTOYO.units_by_decimals),
        "y": infer_channel("y", bad, MITUTOYO.units_by_decimals),
    }
    sentence = frames_disagree(inferred, "in", 0.0001, {"x": good, "y": bad})
    assert sentence == (
        "y sends steps of 0.001, which is mm on this protocol; the session is in inches at 0.0001"
    )
    assert describe_inference(inferred) == (
        "x sends steps of 0.0001, which is in on this protocol; "
        "y sends steps of 0.001, which is mm on this protocol"
    )


def test_no_frames_say_nothing() -> None:
    inferred = {"x": infer_channel("x", [], MITUTOYO.units_by_decimals)}
    assert frames_disagree(inferred, "in", 0.0001) == ""
    assert describe_inference(inferred) == "x: nothing yet"


def test_an_adaptor_that_drops_trailing_zeros_still_shows_its_decimals() -> None:
    ascii_lines = get_protocol("ascii")
    frames = [b"0.1", b"0.123", b"-0.02", b"0.101"]
    samples = [
        FrameSample(ascii_lines.parse(f).value, ascii_lines.frame_decimals(f)) for f in frames
    ]
    inferred = infer_channel("x", samples, ascii_lines.units_by_decimals)
    assert (inferred.decimals, inferred.step, inferred.protocol_unit) == (3, 0.001, None)
    assert inferred.describe() == "steps of 0.001 (the frames carry no unit)"
