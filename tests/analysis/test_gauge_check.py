"""Type-1 gauge study: Cg, Cgk, the bias t-test, resolution against tolerance, the verdict."""

from __future__ import annotations

import math

import numpy as np
import pytest

from station.analysis.gauge_check import gauge_check
from station.errors import StationError


def test_hand_checked_example():
    # Three readings 10.0005, 10.0010, 10.0015 of a 10.0000 reference: mean 10.001, s 0.0005.
    # T = 0.03: Cg = 0.2*0.03 / (6*0.0005) = 0.006/0.003 = 2.0;
    # Cgk = (0.1*0.03 - 0.001) / (3*0.0005) = 0.002/0.0015 = 1.333...
    # t = 0.001 / (0.0005/sqrt 3) = 2 sqrt 3; with 2 df, P(|T| > t) = 1 - t/sqrt(2 + t^2)
    # = 1 - sqrt(12/14) = 0.0742.
    study = gauge_check([10.0005, 10.0010, 10.0015], 10.0, 0.03, resolution=0.0005)
    assert study.mean == pytest.approx(10.001)
    assert study.sd == pytest.approx(0.0005)
    assert study.bias == pytest.approx(0.001)
    assert study.cg == pytest.approx(2.0)
    assert study.cgk == pytest.approx(4.0 / 3.0)
    assert study.bias_t == pytest.approx(2 * math.sqrt(3))
    assert study.bias_p == pytest.approx(1 - math.sqrt(12 / 14))
    assert study.resolution_ratio == pytest.approx(0.0005 / 0.03)
    assert study.resolution_ok is True
    assert study.capable is True  # 1.3333 >= 1.33
    document = study.as_json()
    assert list(document)[:6] == ["cg", "cgk", "bias", "bias_p", "resolution_ratio", "capable"]
    assert study.percent_repeatability == pytest.approx(10.0)


def test_injected_bias_fails_cgk_but_not_cg():
    rng = np.random.default_rng(5)
    readings = 25.4 + 0.0008 + rng.normal(0, 0.0001, 50)  # σ 0.0001, bias 0.0008
    study = gauge_check(readings, 25.4, tolerance=0.01, resolution=0.0001)
    assert study.cg is not None and study.cg > 1.33  # the gauge repeats ...
    assert study.cgk is not None and study.cgk < 1.33  # ... but reads off the reference
    assert study.capable is False
    assert study.bias_significant is True
    assert any("Cgk fails" in line for line in study.lines())
    centred = readings - (readings.mean() - 25.4)
    unbiased = gauge_check(centred, 25.4, tolerance=0.01, resolution=0.0001)
    assert unbiased.capable is True
    assert unbiased.bias_significant is False


def test_coarse_resolution_is_said():
    study = gauge_check([0.001, 0.002, 0.001, 0.002] * 7, 0.0015, 0.01, resolution=0.001)
    assert study.resolution_ratio == pytest.approx(0.1)
    assert study.resolution_ok is False
    assert any("TOO COARSE" in line for line in study.lines())


def test_no_spread_gives_no_verdict():
    study = gauge_check([1.0] * 30, 1.0, 0.01, resolution=0.001)
    assert study.cg is None and study.cgk is None and study.capable is None
    assert study.verdict == "no verdict"
    assert study.as_json()["capable"] is None


@pytest.mark.parametrize(
    ("values", "tolerance", "fragment"),
    [([1.0], 0.01, "at least 2 readings"), ([1.0, 2.0], 0.0, "tolerance must be more than 0")],
)
def test_bad_input_is_a_sentence(values, tolerance, fragment):
    with pytest.raises(StationError, match=fragment):
        gauge_check(values, 1.0, tolerance)


def test_readings_that_differ_by_float_rounding_only_have_no_spread():
    """A software zero leaves 0.1 as 0.30000000000000004 − 0.2 in some readings: the study
    must see one display value (no index), not an s of 1e-17 and a Cg of 1e13 (found on a
    simulated bench whose indicator repeated to its last digit)."""
    readings = [0.1, 0.30000000000000004 - 0.2] * 13
    study = gauge_check(readings, 0.1, 0.004, resolution=0.0001)
    assert study.cg is None and study.cgk is None and study.capable is None
    assert study.verdict == "no verdict"
