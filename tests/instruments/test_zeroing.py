"""A zero from several readings: mean, spread, method; refused while a gauge moves."""

from __future__ import annotations

import math

import pytest

from station.errors import StationError
from station.instruments.zeroing import ChannelZero, zero_from_readings


def test_the_zero_is_the_mean_of_the_readings_with_n_spread_and_method() -> None:
    zeros = zero_from_readings(
        {"x": [0.0003, 0.0004, 0.0003, 0.0004], "y": [-0.001] * 4},
        0.0001,
        methods={"y": "device"},
        min_readings=4,
    )
    x, y = zeros
    assert (x.channel, x.method, x.n) == ("x", "software", 4)
    assert x.mean == 0.00035 and x.offset == 0.00035
    assert x.spread == 0.0001
    assert (y.method, y.offset, y.mean, y.spread) == ("device", 0.0, -0.001, 0.0)
    assert x.record() == {
        "method": "software",
        "offset": 0.00035,
        "n": 4,
        "mean": 0.00035,
        "spread": 0.0001,
        "values": [0.0003, 0.0004, 0.0003, 0.0004],
    }


def test_the_offset_keeps_one_decimal_more_than_the_gauge_shows() -> None:
    (x,) = zero_from_readings({"x": [0.001, 0.002, 0.002]}, 0.001, min_readings=3)
    assert x.mean == pytest.approx(0.0016666667)
    assert x.offset == 0.0017


def test_one_noisy_reading_no_longer_makes_the_zero() -> None:
    # The session: a robot centred on 0 whose single zero reading was -0.0010.
    values = [0.0, 0.0001, -0.0001, 0.0, -0.0001, 0.0001, 0.0, 0.0, -0.0001, 0.0001]
    (x,) = zero_from_readings({"x": values}, 0.0001, still=3)
    assert abs(x.offset) < 0.0001


def test_a_moving_channel_is_refused_by_name() -> None:
    readings = {"x": [0.0] * 10, "y": [0.0, 0.002, 0.004, 0.006] + [0.008] * 6, "z": [0.0] * 10}
    with pytest.raises(StationError) as caught:
        zero_from_readings(readings, 0.001, window=1.0, unit="mm")
    message = caught.value.message
    # The spread and the step in the one number format: one decimal beyond the 0.001 mm step.
    assert "y moves" in message and "0.0080 mm over 1.0 s" in message
    assert "more than 3 × 0.0010)" in message
    assert "x moves" not in message and "z moves" not in message
    assert "zero again" in message


def test_spread_up_to_still_resolutions_is_still() -> None:
    (x,) = zero_from_readings({"x": [0.0, 0.003] * 5}, 0.001, still=3)
    assert x.spread == 0.003
    with pytest.raises(StationError, match="x moves"):
        zero_from_readings({"x": [0.0, 0.004] * 5}, 0.001, still=3)


def test_too_few_readings_are_refused() -> None:
    with pytest.raises(StationError, match=r"Could not zero y: too few readings .*y 2; 10 wanted"):
        zero_from_readings({"x": [0.0] * 10, "y": [0.0] * 2}, 0.001)


def test_the_uncertainty_combines_the_scatter_and_the_gauge_rounding() -> None:
    still = ChannelZero("x", "software", 0.0, 10, 0.0, 0.0, (0.0,) * 10, 0.001)
    assert still.uncertainty == pytest.approx(0.001 / math.sqrt(12))
    values = (0.0, 0.002) * 5
    noisy = ChannelZero("x", "software", 0.001, 10, 0.001, 0.002, values, 0.001)
    sd = math.sqrt(sum((v - 0.001) ** 2 for v in values) / 9)
    assert noisy.uncertainty == pytest.approx(math.sqrt(sd**2 / 10 + 0.001**2 / 12))
