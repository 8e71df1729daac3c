"""The Gage R&R bench (the gauge bench with parts and appraisers): each seating of a part by an
appraiser is a rest of its own, read as the part's size plus the appraiser's offset plus a fresh
noise draw; the plate is rest 0."""

from __future__ import annotations

import statistics

import pytest

from station.errors import StationError
from station.instruments.gauge_bench import GageRRBenchModel
from station.instruments.simulator import GaugeSpec

GAUGE = GaugeSpec(0.0001, -0.5, 1.0, "in")
PARTS = (0.1, 0.2, 0.3)
OFFSETS = {"A": 0.0, "B": 0.001}


def test_each_seating_is_a_rest_that_names_its_part_and_appraiser():
    bench = GageRRBenchModel(PARTS, OFFSETS, noise=0.0, gauge=GAUGE)
    rests = set()
    for seating in range(4):
        for appraiser in OFFSETS:
            for part in (1, 2, 3):
                rest = bench.rest_of_part(part, appraiser, seating)
                assert bench.seated(rest) == (part, appraiser)
                rests.add(rest)
    assert len(rests) == 4 * 2 * 3 and min(rests) >= 1
    assert bench.value("x", 0, seed=1) == 0.0  # the plate
    # Without noise: part 2 by B reads 0.2 + 0.001.
    assert bench.value("x", bench.rest_of_part(2, "B", 5), seed=1) == pytest.approx(0.201)


def test_the_noise_is_drawn_afresh_for_every_seating():
    bench = GageRRBenchModel(PARTS, OFFSETS, noise=0.0001, gauge=GAUGE)
    readings = [
        bench.rest_position("x", bench.rest_of_part(1, "A", seating), seed=3)
        for seating in range(200)
    ]
    assert len(set(readings)) == 200
    assert statistics.mean(readings) == pytest.approx(0.1, abs=4 * 0.0001 / 200**0.5)
    assert statistics.stdev(readings) == pytest.approx(0.0001, rel=0.2)


def test_a_part_or_an_appraiser_the_bench_does_not_have_is_refused():
    bench = GageRRBenchModel(PARTS, OFFSETS, gauge=GAUGE)
    with pytest.raises(StationError, match="parts 1 to 3, not part 4"):
        bench.rest_of_part(4, "A", 1)
    with pytest.raises(StationError, match="appraisers A, B, not 'C'"):
        bench.rest_of_part(1, "C", 1)
    with pytest.raises(StationError, match="at least one appraiser"):
        GageRRBenchModel(PARTS, {}, gauge=GAUGE)
