"""Relative accuracy: per placement and across placements, from a simulated two-fixture run."""

from __future__ import annotations

import numpy as np
import pytest

from station.analysis.accuracy import ERROR_3D, accuracy_json, analyze_accuracy
from station.analysis.capability import SpecLimits
from station.analysis.summary import AnalysisConfig
from station.errors import StationError
from station.instruments.simulator import TwoFixtureModel

CONFIG = AnalysisConfig(resolution=0.0001, unit="in", default_limits=SpecLimits(-0.002, 0.002))


def simulated_run(model: TwoFixtureModel, placements: int, seed: int = 0):
    """What the first fixture's indicators read, placement by placement (no runner)."""
    # The robot's rests after each return (rest 0 of each placement is home, the zero).
    rests = [
        model.rest_of(number, c)
        for number in range(1, placements + 1)
        for c in range(1, model.captures + 1)
    ]
    numbers = [model.current_placement(r) for r in rests]
    errors = {axis: [model.value(axis, r, seed) for r in rests] for axis in "xyz"}
    pendant = {p: model.placement_of(p).pendant for p in range(1, placements + 1)}
    return numbers, errors, pendant


def test_hand_checked_placements():
    numbers = [1, 1, 2, 2]
    errors = {
        "x": [0.001, 0.003, -0.001, -0.001],
        "y": [0.0, 0.0, 0.002, 0.002],
        "z": [0.0, 0.0, 0.0, 0.0],
    }
    result = analyze_accuracy(numbers, errors, CONFIG, pendant={1: (3.0, 4.0, 0.0)})
    first, second = result.placements
    assert (first.number, first.n, second.n) == (1, 2, 2)
    assert first.mean["x"] == pytest.approx(0.002)
    assert first.sd["x"] == pytest.approx(np.std([0.001, 0.003], ddof=1))
    assert first.pendant == (3.0, 4.0, 0.0)
    assert first.distance == pytest.approx(5.0)
    assert second.pendant is None and second.distance is None
    assert second.error_3d == pytest.approx(np.hypot(0.001, 0.002))
    # The overall average accuracy per axis is the mean of the placement means.
    assert result.average["x"] == pytest.approx(0.0005)
    assert result.span["x"] == pytest.approx(0.003)
    assert result.spread["y"] == pytest.approx(np.std([0.0, 0.002], ddof=1))
    assert result.per_unit is None and result.scale_error is None
    # Overall: the repeatability statistics of every reading, and the 3-D error channel.
    assert result.overall.channels["x"].descriptive.n == 4
    assert result.overall.spatial is not None
    assert result.error_3d.name == ERROR_3D
    assert result.error_3d.readings == pytest.approx(
        tuple(np.sqrt(np.add.reduce([np.square(errors[a]) for a in "xyz"])))
    )
    assert result.error_3d.limits is None
    assert first.analysis.channels["x"].descriptive.mean == pytest.approx(0.002)


def test_a_simulated_run_recovers_the_scale_error_of_each_axis():
    model = TwoFixtureModel(
        scale=(3.0e-5, -2.0e-5, 1.0e-5),
        rotation=(0.0, 0.0, 4.0e-6),
        noise=0.0001,
        captures=3,
        seed=11,
    )
    numbers, errors, pendant = simulated_run(model, placements=8)
    result = analyze_accuracy(numbers, errors, CONFIG, pendant=pendant)
    assert len(result.placements) == 8
    for axis, expected in zip("xyz", model.scale, strict=True):
        assert result.scale_error[axis] == pytest.approx(expected, abs=3e-6)
    # The rotation about z shows off the diagonal: e_x = -wz * Y, e_y = +wz * X.
    assert result.per_unit[0][1] == pytest.approx(-4.0e-6, abs=3e-6)
    assert result.per_unit[1][0] == pytest.approx(4.0e-6, abs=3e-6)
    # Per placement, the mean error is the systematic error within the noise of 3 readings.
    for placement in result.placements:
        truth = model.systematic_error(placement.number)
        for axis, value in zip("xyz", truth, strict=True):
            assert placement.mean[axis] == pytest.approx(value, abs=0.0003)
        assert placement.distance == pytest.approx(
            np.linalg.norm(model.placement_of(placement.number).pendant)
        )


def test_accuracy_json_keeps_pendant_and_statistics():
    model = TwoFixtureModel(captures=2, seed=3)
    numbers, errors, pendant = simulated_run(model, placements=4)
    document = accuracy_json(analyze_accuracy(numbers, errors, CONFIG, pendant=pendant))
    assert set(document["axes"]) == {"x", "y", "z"}
    assert {"average", "spread", "range", "scale_error"} <= document["axes"]["x"].keys()
    placement = document["placements"][0]
    assert placement["placement"] == 1
    assert placement["pendant"] == dict(zip("xyz", model.placement_of(1).pendant, strict=True))
    assert {"n", "distance", "mean", "sd", "error_3d"} <= placement.keys()
    assert document["error_3d"]["n"] == 8
    assert len(document["per_unit"]) == 3


@pytest.mark.parametrize(
    ("numbers", "errors", "fault"),
    [
        ([1], {"x": [0.0], "y": [0.0]}, "'z' is missing"),
        ([1, 2], {"x": [0.0], "y": [0.0, 0.0], "z": [0.0, 0.0]}, "'x' has 1 readings"),
        ([1.5], {"x": [0.0], "y": [0.0], "z": [0.0]}, "whole numbers"),
        ([], {"x": [], "y": [], "z": []}, "no readings"),
    ],
)
def test_bad_input_is_named(numbers, errors, fault):
    with pytest.raises(StationError, match=fault):
        analyze_accuracy(numbers, errors, CONFIG)
