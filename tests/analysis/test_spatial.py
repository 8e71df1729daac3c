"""3-D figures: the report's offsets and total, ISO 9283 AP and RP."""

from __future__ import annotations

import math

import numpy as np
import pytest

from station.analysis.spatial import find_axes, spatial_figures
from station.errors import StationError


def test_a_hand_computed_cloud():
    # Four points at distance 1 from their barycentre (0.5, 0, 0): l = 1 each, S_l = 0.
    x = np.array([1.5, -0.5, 0.5, 0.5])
    y = np.array([0.0, 0.0, 1.0, -1.0])
    z = np.zeros(4)
    spatial = spatial_figures(x, y, z)
    assert spatial.offset == {"x": 0.5, "y": 0.0, "z": 0.0}
    assert spatial.total_offset == 0.5
    assert spatial.ap == {"x": 0.5, "y": 0.0, "z": 0.0, "p": 0.5}
    assert (spatial.l_mean, spatial.l_sd, spatial.rp) == (1.0, 0.0, 1.0)


def test_offsets_follow_the_nominal_and_rp_does_not():
    rng = np.random.default_rng(3)
    x, y, z = rng.normal([1e-4, -2e-4, 3e-4], 2e-4, size=(30, 3)).T
    zeroed = spatial_figures(x, y, z)
    shifted = spatial_figures(x, y, z, nominal=(1e-4, -2e-4, 3e-4))
    assert zeroed.offset["x"] == pytest.approx(np.mean(x))
    assert shifted.offset["y"] == pytest.approx(np.mean(y) + 2e-4)
    assert zeroed.total_offset == pytest.approx(
        math.dist((0, 0, 0), (x.mean(), y.mean(), z.mean()))
    )
    assert shifted.rp == zeroed.rp


def test_rp_matches_the_iso_formula_written_out():
    rng = np.random.default_rng(8)
    x, y, z = rng.normal(0, 1e-3, size=(3, 25))
    centre = (sum(x) / 25, sum(y) / 25, sum(z) / 25)
    distances = [math.dist(p, centre) for p in zip(x, y, z, strict=True)]
    l_bar = sum(distances) / 25
    s_l = math.sqrt(sum((d - l_bar) ** 2 for d in distances) / 24)
    assert spatial_figures(x, y, z).rp == pytest.approx(l_bar + 3 * s_l, rel=1e-12)


def test_one_cycle_has_offsets_but_no_repeatability():
    spatial = spatial_figures(np.array([1.0]), np.array([2.0]), np.array([2.0]))
    assert spatial.total_offset == 3.0
    assert spatial.rp is None and "at least 2" in spatial.message


def test_unequal_counts_are_an_error_naming_them():
    with pytest.raises(StationError, match="x 3, y 2, z 3"):
        spatial_figures(np.zeros(3), np.zeros(2), np.zeros(3))


def test_axes_are_found_case_insensitively_and_only_all_three():
    assert find_axes(["cycle", "X", "Y", "z"]) == {"x": "X", "y": "Y", "z": "z"}
    assert find_axes(["x", "y"]) is None
