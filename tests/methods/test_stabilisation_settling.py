"""Stabilisation time and overshoot (ISO 9283 §7.4, §7.5) on hand-checked traces."""

from __future__ import annotations

import math

import numpy as np
import pytest

from station.errors import StationError
from station.methods.stabilisation.settling import (
    final_position,
    lines,
    noise_band,
    return_settling,
    stabilisation,
    stated_band,
)

T = [0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8]
BOUNCING = [
    (-0.050, -0.030, 0.0),  # approaching: 0.058 from the final position
    (-0.020, 0.000, 0.0),  # 0.020: still outside the band of 0.01
    (0.000, 0.000, 0.0),  # in: the line from -0.02 crossed -0.01 halfway, the entry at 0.15 s
    (0.012, 0.009, 0.0),  # 0.015: out again, past the final position in x and y: the overshoot
    (0.004, 0.003, 0.0),  # 0.005: in
    (-0.012, 0.000, 0.0),  # 0.012: out, the last time (short of the final position: not past)
    (-0.008, 0.000, 0.0),  # in from here on: back across -0.01 halfway, it stays from 0.55 s
    (0.000, 0.001, 0.0),
    (0.000, 0.000, 0.0),
]
FINAL = (0.0, 0.0, 0.0)


def test_a_bouncing_return_stays_from_its_last_exit_and_overshoots_at_its_farthest():
    found = return_settling(7, T, BOUNCING, 0.01, final=FINAL)
    # First entry 0.15 s, stays from 0.55 s: 0.4 s, each end known to one sampling interval.
    assert found.time == pytest.approx(0.4)
    assert found.interval == pytest.approx(0.1)
    assert found.overshoot == pytest.approx(0.015)
    # x came from -0.05 and went 0.012 past (its -0.012 is short of the final position, not
    # past it); y from -0.03, 0.009 past; z never moved.
    assert found.overshoot_axes == pytest.approx((0.012, 0.009, 0.0))
    assert found.settled and found.problem == "" and found.cycle == 7 and found.points == 9


def test_a_return_that_never_settles_has_no_time_and_says_so():
    hunting = [*BOUNCING[:7], (0.0, 0.02, 0.0), (0.0, -0.02, 0.0)]
    found = return_settling(2, T, hunting, 0.01, final=FINAL)
    assert found.time is None and not found.settled
    assert "never settled" in found.problem
    # It entered the band, so its largest excursion since is still a figure.
    assert found.overshoot == pytest.approx(0.02)


def test_a_return_that_enters_and_stays_took_no_time_to_stabilise():
    straight = [(-0.05, 0.0, 0.0), (-0.02, 0.0, 0.0), (-0.004, 0.0, 0.0), (-0.001, 0.0, 0.0)]
    found = return_settling(1, T[:4], straight, 0.01, final=FINAL)
    assert found.time == 0.0
    # It never went past the final position: no overshoot along x, and the largest distance
    # after its entry is the entry point's own.
    assert found.overshoot_axes == (0.0, 0.0, 0.0)
    assert found.overshoot == pytest.approx(0.004)


def test_a_trace_that_starts_inside_or_never_enters_has_no_time():
    starts_in = [(0.001, 0.0, 0.0), (0.02, 0.0, 0.0), (0.0, 0.0, 0.0)]
    inside = return_settling(1, T[:3], starts_in, 0.01, final=FINAL)
    assert inside.time is None and "entry was not seen" in inside.problem
    far = [(0.05, 0.0, 0.0), (0.04, 0.0, 0.0), (0.03, 0.0, 0.0)]
    outside = return_settling(1, T[:3], far, 0.01, final=FINAL)
    assert outside.time is None and outside.overshoot is None
    assert "never came within the band" in outside.problem


def test_a_swing_through_the_final_position_between_two_points_entered_the_band():
    # Neither of the points at 0.1 and 0.2 s is inside, but the line between them crosses
    # -0.01 a quarter of the way: the entry at 0.125 s; back in at 0.01, halfway to 0.3 s.
    swing = [(-0.05, 0.0, 0.0), (-0.02, 0.0, 0.0), (0.02, 0.0, 0.0), (0.0, 0.0, 0.0)]
    found = return_settling(1, T[:4], swing, 0.01, final=FINAL)
    assert found.time == pytest.approx(0.25 - 0.125)
    assert found.overshoot == pytest.approx(0.02) and found.overshoot_axes[0] == pytest.approx(0.02)


def test_the_final_position_is_the_mean_of_the_still_tail():
    # The last 0.25 s: the points at 0.6, 0.7 and 0.8 s.
    assert final_position(T, BOUNCING, 0.25) == pytest.approx([-0.008 / 3, 0.001 / 3, 0.0])
    found = return_settling(1, T, BOUNCING, 0.01, tail=0.25)
    assert found.final == pytest.approx((-0.008 / 3, 0.001 / 3, 0.0))


def test_the_statistics_need_every_return_to_have_settled():
    # Cycle 2's points from 0.5 s on came 0.1 s later: it stays from 0.65 s, 0.5 s; cycle 3
    # never leaves again after 0.3 s (its 0.5 s point is in): back in at 0.35 s, 0.2 s.
    late = [t + (0.1 if t >= 0.5 else 0.0) for t in T]
    early = [*BOUNCING[:5], (0.0, -0.001, 0.0), *BOUNCING[6:]]
    returns = [
        return_settling(1, T, BOUNCING, 0.01, final=FINAL),
        return_settling(2, late, BOUNCING, 0.01, final=FINAL),
        return_settling(3, T, early, 0.01, final=FINAL),
    ]
    assert [r.time for r in returns] == pytest.approx([0.4, 0.5, 0.2])
    band = stated_band(0.01)
    result = stabilisation(returns, band, axes="xyz", unit="mm", resolution=0.001)
    times = [0.4, 0.5, 0.2]
    assert result.mean_time == pytest.approx(np.mean(times))
    assert result.max_time == pytest.approx(0.5)
    # Student's t with 2 degrees of freedom: 4.303 × s/√3.
    half = 4.302653 * np.std(times, ddof=1) / math.sqrt(3)
    assert result.mean_time_ci == pytest.approx(
        (np.mean(times) - half, np.mean(times) + half), abs=1e-6
    )
    assert result.max_overshoot == pytest.approx(0.015)
    # The coarsest trace's interval: cycle 2's points are 0.1 s apart at the median too.
    assert result.interval == pytest.approx(0.1)
    data = result.as_json()
    assert data["band"] == 0.01 and data["band_basis"] == "a stated limit"
    assert [r["cycle"] for r in data["returns"]] == [1, 2, 3]

    hunting = [*BOUNCING[:7], (0.0, 0.02, 0.0), (0.0, -0.02, 0.0)]
    returns[2] = return_settling(3, T, hunting, 0.01, final=FINAL)
    result = stabilisation(returns, band, axes="xyz", unit="mm", resolution=0.001)
    assert result.mean_time is None and result.max_time is None and result.mean_time_ci is None
    assert result.max_overshoot == pytest.approx(0.02)
    text = "\n".join(lines(result))
    assert "no time: it was outside the band at the end of its trace: it never settled" in text
    assert "none over the returns: 1 of 3 have no time" in text
    assert "0.4 ± 0.2" in text  # each time with two sampling intervals, at its decimals
    assert "fewer than" not in text


def test_the_band_from_the_noise_at_rest_is_five_sigma_pooled_over_the_tails():
    t = [0.0, 1.0, 1.1]
    a = [(0.5, 0.5, 0.5), (0.001, 0.0, 0.0), (-0.001, 0.0, 0.0)]
    b = [(0.5, 0.5, 0.5), (0.0, 0.101, 0.0), (0.0, 0.099, 0.0)]
    band = noise_band([(t, a), (t, b)], tail=0.5, resolution=0.0001)
    # Each tail: two points, 2e-6 of squares over 3 degrees of freedom (one per axis).
    sigma = math.sqrt(4e-6 / 6)
    assert band.noise == pytest.approx(sigma)
    assert band.radius == pytest.approx(5 * sigma)
    assert "5 × the indicators' noise at rest" in band.basis and not band.stated
    # Coarse gauges: never narrower than two of their steps.
    coarse = noise_band([(t, a)], tail=0.5, resolution=0.01)
    assert coarse.radius == pytest.approx(0.02) and "2 gauge steps" in coarse.basis


def test_a_band_must_be_a_size():
    with pytest.raises(StationError, match="over 0"):
        stated_band(0.0)
    with pytest.raises(StationError, match="at least two"):
        return_settling(1, [0.0], [(0.0, 0.0, 0.0)], 0.01, final=FINAL)


def test_a_move_past_the_band_between_two_points_may_hide_an_earlier_entry():
    # From (-0.03, 0) to (0.012, 0.012) the straight line passes 0.0082 from the final
    # position, outside the band of 0.005, but the robot moved 0.044 between the two points:
    # a path that bends may have entered there. The entry seen is on the way back in from
    # (0.004, -0.008), 0.0089 away, at 0.1 × (1 - 0.005 / 0.0089) = 0.0441 s past 0.3 s.
    rows = [
        (-0.035, 0.0, 0.0),
        (-0.03, 0.0, 0.0),
        (0.012, 0.012, 0.0),
        (0.004, -0.008, 0.0),
        (0.0, 0.0, 0.0),
        (0.0, 0.0, 0.0),
    ]
    found = return_settling(1, T[:6], rows, 0.005, final=FINAL)
    entry = 0.3 + 0.1 * (1 - 0.005 / math.hypot(0.004, 0.008))
    assert found.time == 0.0
    # Had it entered at the start of that move (0.1 s), it would have taken until the entry
    # seen to stay.
    assert found.time_max == pytest.approx(entry - 0.1)
    result = stabilisation([found], stated_band(0.005), axes="xyz", unit="mm", resolution=0.001)
    text = " ".join(" ".join(lines(result)).split())
    assert "or up to 0.2 s: before its entry the trace moved more than the band" in text
    assert "cycles 1 may have entered the band unseen" in text
    # The bouncing trace moves less than the band near the final position: no doubt.
    assert return_settling(1, T, BOUNCING, 0.01, final=FINAL).time_max is None
