"""The simulated ISO 9283 test cube: where its poses are, and what the fixture reads there."""

from __future__ import annotations

import math

import pytest

from station.errors import StationError
from station.instruments.simulator import GaugeSpec
from station.instruments.simulator.cube import CubePosesModel


def test_the_poses_lie_on_the_diagonals_ten_percent_from_the_corners():
    model = CubePosesModel(centre=(40.0, 0.0, 30.0), edge=20.0)
    assert model.placement_of(1).pendant == (40.0, 0.0, 30.0)
    # A half-diagonal is 10 sqrt 3; 10 % of the diagonal (2 sqrt 3) from the corner leaves
    # 8 sqrt 3 from the centre: 8 in along each axis.
    assert model.placement_of(2).pendant == (48.0, 8.0, 38.0)
    assert model.placement_of(4).pendant == (32.0, -8.0, 22.0)
    corner = (50.0, 10.0, 40.0)
    diagonal = 20.0 * math.sqrt(3)
    assert math.dist(model.placement_of(2).pendant, corner) == pytest.approx(0.1 * diagonal)
    # Every pose lies on the plane x - 40 = y through the centre (a diagonal plane).
    for pose in range(1, 6):
        x, y, _ = model.placement_of(pose).pendant
        assert x - 40.0 == pytest.approx(y)
    with pytest.raises(StationError, match="poses are numbered from 1"):
        model.placement_of(0)


def test_the_zero_rest_is_the_taught_pose_and_a_return_its_bias_plus_noise():
    gauge = GaugeSpec(0.0001, -0.5, 0.5, "in")
    model = CubePosesModel(
        biases=[(0.001, 0.0, 0.0), (0.0, -0.002, 0.0)], noises=[0.0, 0.0], captures=2, gauge=gauge
    )
    assert model.rest_of(2) == 3  # P1's zero, two returns, then P2's zero
    assert [model.value("x", rest, 0) for rest in range(3)] == [0.0, 0.001, 0.001]
    assert [model.value("y", rest, 0) for rest in range(3, 6)] == [0.0, -0.002, -0.002]
    noisy = CubePosesModel(biases=[(0.0, 0.0, 0.0)], noises=[0.0003], captures=200, gauge=gauge)
    returns = [noisy.true_value("z", rest, 7) for rest in range(1, 201)]
    mean = sum(returns) / len(returns)
    spread = math.sqrt(sum((v - mean) ** 2 for v in returns) / (len(returns) - 1))
    assert spread == pytest.approx(0.0003, rel=0.15)


def test_a_cube_needs_a_bias_and_a_noise_per_pose():
    with pytest.raises(StationError, match="one bias and one noise per pose"):
        CubePosesModel(biases=[(0.0, 0.0, 0.0)], noises=[])
    with pytest.raises(StationError, match="edge must be greater than 0"):
        CubePosesModel(edge=0)
