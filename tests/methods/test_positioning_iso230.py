"""The ISO 230-2 figures of one axis (station/methods/positioning/iso230.py) on hand-checked
sets: every figure worked out on paper below, including a set where R comes from a target's
2s↑ + 2s↓ + |B_i| (neither R↑ nor R↓), and where E's (and A's) extremes lie in different
directions (neither E↑ nor E↓); the refusals, the notes and the standard test cycle."""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from properties import examples

from station.analysis.summary import AnalysisConfig
from station.errors import StationError
from station.methods.positioning.iso230 import (
    axis_positioning,
    cycle_approach,
    direction_of,
    standard_cycle,
)
from station.methods.positioning.live import about_approaches, stops
from station.methods.positioning.method import typed_targets

PATTERN = (-1.0, -1.0, 0.0, 1.0, 1.0)
"""Five approaches about their mean: the sum of squares is 4, so s = √(4/4) = 1 exactly; scaled
by s it gives a standard deviation of s."""


def approaches(
    rows: list[tuple[float, float, float, float, float]],
) -> tuple[list[float], list[bool], list[float]]:
    """Targets, directions and deviations of ``rows`` (target, x̄↑, s↑, x̄↓, s↓): five approaches
    each way, ``mean + s·PATTERN``."""
    targets, up, deviations = [], [], []
    for target, mean_up, s_up, mean_down, s_down in rows:
        for rising, mean, s in ((True, mean_up, s_up), (False, mean_down, s_down)):
            for step in PATTERN:
                targets.append(target)
                up.append(rising)
                deviations.append(mean + s * step)
    return targets, up, deviations


# Set A, three targets.            x̄↑  s↑   x̄↓  s↓ |  B_i  2s↑+2s↓+|B_i|  4s↑  4s↓  R_i
SET_A = [
    (0.0, 2.0, 1.0, -1.0, 1.0),  #  +3   2+2+3 = 7       4    4    7
    (100.0, 5.0, 0.5, 4.0, 0.5),  # +1   1+1+1 = 3       2    2    3
    (200.0, 1.0, 1.5, 3.0, 0.0),  # -2   3+0+2 = 5       6    0    6  (from 4s↑)
]
# B = max|B_i| = 3; B̄ = (3 + 1 - 2)/3 = 2/3.
# R↑ = max(4, 2, 6) = 6; R↓ = max(4, 2, 0) = 4; R = max(7, 3, 6) = 7: target 0's
#   2s↑ + 2s↓ + |B_i|, above both R↑ and R↓.
# x̄↑ = 2, 5, 1: E↑ = 5 - 1 = 4; x̄↓ = -1, 4, 3: E↓ = 4 - (-1) = 5;
#   E = max(5, 4) - min(1, -1) = 5 - (-1) = 6: the largest mean is 100↑, the smallest 0↓,
#   so E exceeds both E↑ and E↓.
# x̄ = 0.5, 4.5, 2: M = 4.5 - 0.5 = 4.
# x̄↑ + 2s↑ = 4, 6, 4 and x̄↑ - 2s↑ = 0, 4, -2: A↑ = 6 - (-2) = 8;
# x̄↓ + 2s↓ = 1, 5, 3 and x̄↓ - 2s↓ = -3, 3, 3: A↓ = 5 - (-3) = 8;
# A = max(6, 5) - min(-2, -3) = 9: above both A↑ and A↓.

# Set B, five targets.             x̄↑  s↑   x̄↓  s↓ |  B_i  2s↑+2s↓+|B_i|  4s↑  4s↓  R_i
SET_B = [
    (10.0, 0.0, 0.0, 1.0, 2.0),  #   -1   0+4+1 = 5       0    8    8  (from 4s↓)
    (20.0, 3.0, 0.5, 2.0, 0.5),  #   +1   1+1+1 = 3       2    2    3
    (30.0, 6.0, 1.0, 5.0, 0.0),  #   +1   2+0+1 = 3       4    0    4  (from 4s↑)
    (40.0, 2.0, 0.0, 2.0, 0.0),  #    0   0               0    0    0
    (50.0, -1.0, 0.5, 0.0, 0.5),  #  -1   1+1+1 = 3       2    2    3
]
# B = 1; B̄ = (-1 + 1 + 1 + 0 - 1)/5 = 0.
# R↑ = 4, R↓ = 8, R = 8 (= R↓: target 10's 4s↓).
# x̄↑ = 0, 3, 6, 2, -1: E↑ = 7; x̄↓ = 1, 2, 5, 2, 0: E↓ = 5; E = 6 - (-1) = 7 = E↑ (both
#   extremes up: 30↑ and 50↑).
# x̄ = 0.5, 2.5, 5.5, 2, -0.5: M = 6.
# x̄↑ ± 2s↑: +: 0, 4, 8, 2, 0; -: 0, 2, 4, 2, -2 -> A↑ = 8 - (-2) = 10;
# x̄↓ ± 2s↓: +: 5, 3, 5, 2, 1; -: -3, 1, 5, 2, -1 -> A↓ = 5 - (-3) = 8;
# A = max(8, 5) - min(-2, -3) = 11.


def test_set_a_every_figure_by_hand():
    result = axis_positioning(*approaches(SET_A))
    figures = result.as_json()
    expected = {
        "B": 3.0, "B_mean": 2.0 / 3.0, "R": 7.0, "R_up": 6.0, "R_down": 4.0, "E": 6.0,
        "E_up": 4.0, "E_down": 5.0, "M": 4.0, "A": 9.0, "A_up": 8.0, "A_down": 8.0,
    }  # fmt: skip
    for name, value in expected.items():
        assert figures[name] == pytest.approx(value, abs=1e-12), name
    # R comes from R_i, not from R↑ or R↓; E and A from both directions together.
    assert figures["R"] > max(figures["R_up"], figures["R_down"])
    assert figures["E"] > max(figures["E_up"], figures["E_down"])
    assert figures["A"] > max(figures["A_up"], figures["A_down"])
    per_target = [
        (t["target"], t["mean_up"], t["mean_down"], t["s_up"], t["s_down"], t["reversal"], t["R"])
        for t in figures["targets"]
    ]
    assert per_target == pytest.approx(
        [
            (0.0, 2.0, -1.0, 1.0, 1.0, 3.0, 7.0),
            (100.0, 5.0, 4.0, 0.5, 0.5, 1.0, 3.0),
            (200.0, 1.0, 3.0, 1.5, 0.0, -2.0, 6.0),
        ]
    )
    assert [t["mean"] for t in figures["targets"]] == pytest.approx([0.5, 4.5, 2.0])
    assert [(t["R_up"], t["R_down"]) for t in figures["targets"]] == pytest.approx(
        [(4.0, 4.0), (2.0, 2.0), (6.0, 0.0)]
    )


def test_set_a_report_names_where_each_extreme_lies():
    text = "\n".join(axis_positioning(*approaches(SET_A), resolution=0.001, unit="mm").lines())
    assert "deviations (actual - target) in mm" in text
    assert "B = 3.0000  reversal, the largest |B_i| (at 0); mean B = +0.6667" in text
    assert "R = 7.0000  repeatability, the largest R_i (at 0: 2s↑ + 2s↓ + |B_i|)" in text
    assert "R↑ = 6.0000  R↓ = 4.0000" in text
    assert "E = 6.0000  systematic error (mean 100↑ - mean 0↓)" in text
    assert "E↑ = 4.0000  E↓ = 5.0000" in text
    assert "M = 4.0000  mean bidirectional error (mean at 100 - mean at 0)" in text
    assert "A = 9.0000  accuracy (mean+2s 100↑ - mean-2s 0↓)" in text
    assert "note: only 3 targets: ISO 230-2 asks for at least 5" in text
    # The figures fit the TUI summary's 74 columns (a note is wrapped, as every method's).
    assert all(len(line) <= 74 for line in text.splitlines() if "note:" not in line)


def test_set_b_every_figure_by_hand():
    result = axis_positioning(*approaches(SET_B))
    figures = result.as_json()
    expected = {
        "B": 1.0, "B_mean": 0.0, "R": 8.0, "R_up": 4.0, "R_down": 8.0, "E": 7.0,
        "E_up": 7.0, "E_down": 5.0, "M": 6.0, "A": 11.0, "A_up": 10.0, "A_down": 8.0,
    }  # fmt: skip
    for name, value in expected.items():
        assert figures[name] == pytest.approx(value, abs=1e-12), name
    assert [t["R"] for t in figures["targets"]] == pytest.approx([8.0, 3.0, 4.0, 0.0, 3.0])
    assert [t["reversal"] for t in figures["targets"]] == pytest.approx([-1, 1, 1, 0, -1])
    assert result.notes() == []  # five targets, five approaches each way
    text = "\n".join(result.lines())
    assert "(at 10: 4s↓)" in text and "systematic error (mean 30↑ - mean 50↑)" in text


def test_the_order_of_the_approaches_does_not_matter():
    targets, up, deviations = approaches(SET_A)
    order = list(reversed(range(len(targets))))
    shuffled = axis_positioning(
        [targets[i] for i in order], [up[i] for i in order], [deviations[i] for i in order]
    )
    assert shuffled.as_json() == pytest.approx(axis_positioning(targets, up, deviations).as_json())


def test_a_target_approached_one_way_only_is_refused_by_name():
    targets, up, deviations = approaches(SET_A)
    kept = [i for i in range(len(targets)) if not (targets[i] == 100.0 and not up[i])]
    with pytest.raises(StationError, match=r"^target 100 is approached up only, never down"):
        axis_positioning(
            [targets[i] for i in kept], [up[i] for i in kept], [deviations[i] for i in kept]
        )


def test_a_target_approached_once_in_a_direction_is_refused_by_name():
    targets, up, deviations = approaches(SET_A)
    drop = [i for i in range(len(targets)) if targets[i] == 200.0 and up[i]][1:]
    kept = [i for i in range(len(targets)) if i not in drop]
    with pytest.raises(StationError, match=r"^target 200 has 1 approach up: its standard devia"):
        axis_positioning(
            [targets[i] for i in kept], [up[i] for i in kept], [deviations[i] for i in kept]
        )
    with pytest.raises(StationError, match="no approach to a target yet"):
        axis_positioning([], [], [])


def test_fewer_approaches_than_the_standard_asks_are_analysed_with_a_note():
    targets, up, deviations = approaches(SET_B)
    drop = {i for i in range(len(targets)) if targets[i] == 20.0 and not up[i]}
    kept = [i for i in range(len(targets)) if i not in sorted(drop)[:2]]
    result = axis_positioning(
        [targets[i] for i in kept], [up[i] for i in kept], [deviations[i] for i in kept]
    )
    assert result.targets[1].n_down == 3
    assert result.notes() == [
        "1 target(s) approached fewer than 5 times in a direction (first: 20): ISO 230-2 asks "
        "for 5 each way."
    ]


def test_the_standard_test_cycle_goes_up_through_the_targets_then_down():
    assert standard_cycle(3) == [(0, "up"), (1, "up"), (2, "up"), (2, "down"), (1, "down"),
                                 (0, "down")]  # fmt: skip
    assert [cycle_approach(k, 3) for k in (0, 3, 5, 6)] == [
        (0, "up"), (2, "down"), (0, "down"), (0, "up"),
    ]  # fmt: skip
    assert [direction_of(w) for w in ("up", " Down ", "+", "-", "UP", "left")] == [
        "up", "down", "up", "down", "up", None,
    ]  # fmt: skip


@settings(max_examples=examples(500))
@given(
    st.lists(
        st.tuples(st.floats(-1, 1), st.floats(0, 1), st.floats(-1, 1), st.floats(0, 1)),
        min_size=2,
        max_size=6,
    )
)
def test_the_bidirectional_figures_cover_each_direction(rows):
    """R ≥ R↑, R↓; E ≥ E↑, E↓ ≥ 0; A ≥ A↑, A↓; M ≤ E; B ≤ R (each R_i holds |B_i|)."""
    result = axis_positioning(*approaches([(float(i), *row) for i, row in enumerate(rows)]))
    tiny = 1e-9
    assert result.r >= max(result.r_up, result.r_down) - tiny
    assert result.e >= max(result.e_up, result.e_down) - tiny
    assert result.a >= max(result.a_up, result.a_down) - tiny
    assert result.m <= result.e + tiny
    assert result.b <= result.r + tiny


# -- a session's targets and its live analysis ------------------------------------------------


def test_the_targets_typed_are_read_in_their_order_and_must_rise():
    events = [
        {"step": "targets", "values": {"target_2": 97.6, "target_10": 500.0, "target_1": 10.3}},
        {"step": "other", "values": {"note": "x"}},
    ]
    assert typed_targets(events) == [10.3, 97.6, 500.0]
    with pytest.raises(StationError, match=r"target_2 \(5\) is not beyond target_1 \(10.3\)"):
        typed_targets([{"values": {"target_1": 10.3, "target_2": 5.0}}])
    with pytest.raises(StationError, match="no targets are typed in yet"):
        typed_targets([{"values": {"reference": 1.0}}])


def test_the_live_analysis_is_each_stop_about_its_own_approach():
    """Two runs of a 2-target cycle (4 stops each): the k-th stop of each run is one approach,
    so the live readings are each stop less the mean of the two runs' same stop."""
    stops_taken = [(10.0, 20.0, 20.4, 10.4), (10.2, 20.2, 20.4, 10.8)]
    rows = [
        ({"s": value}, number, None, run)
        for number, (run, value) in enumerate(
            ((run, v) for run, values in enumerate(stops_taken, start=1) for v in values), start=1
        )
    ]
    residuals = about_approaches(rows, AnalysisConfig(), ("s",)).channels["s"].readings
    assert list(residuals) == pytest.approx([-0.1, -0.1, 0, -0.2, 0.1, 0.1, 0, 0.2])
    assert stops([1, 1, 2, 1, 2]) == [(1, 0), (1, 1), (2, 0), (1, 2), (2, 1)]
