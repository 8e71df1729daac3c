"""The analysis of a session takes each channel's zero uncertainty from its zero events."""

from __future__ import annotations

from station.session.header import analysis_config, zero_uncertainties


def test_the_last_zero_of_a_channel_is_the_one_in_force() -> None:
    zeroes = [
        {"channels": {"x": {"uncertainty": 0.0003}, "y": {"uncertainty": 0.0002}}},
        {"channels": {"x": {"uncertainty": 0.00004}}},
        {"channels": {"y": {"method": "software", "offset": 0.001}}},  # an old one-reading zero
    ]
    assert zero_uncertainties(zeroes) == {"x": 0.00004}
    header = {"unit": "in", "resolution": 0.0001}
    assert analysis_config(header, zeroes).zero_uncertainty == {"x": 0.00004}
    assert analysis_config(header).zero_uncertainty == {}
