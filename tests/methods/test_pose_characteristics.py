"""The ISO 9283 pose characteristics, checked by hand on small point sets: AP and RP per pose,
vAP, AD and RD, the conditions the report departs from, and the per-pose live analysis."""

from __future__ import annotations

import math

import numpy as np
import pytest

from station.analysis.summary import AnalysisConfig
from station.errors import StationError
from station.methods.pose_characteristics.iso9283 import (
    Conditions,
    DistanceSpec,
    departures,
    parse_distance,
    pose_characteristics,
    report_lines,
)
from station.methods.pose_characteristics.live import LivePerPose

# P1 from direction 1: four points about the barycentre (3, 4, 12), at 1, 1, 2 and 2 from it.
# l-bar = 1.5, S_l = sqrt(4 * 0.5^2 / 3) = sqrt(1/3), RP = 1.5 + 3 sqrt(1/3) = 1.5 + sqrt(3).
P1 = [(4, 4, 12), (2, 4, 12), (3, 6, 12), (3, 2, 12)]
RP_P1 = 1.5 + math.sqrt(3)


def test_ap_relative_to_the_zero_and_rp_of_one_pose():
    result = pose_characteristics(P1, [1] * 4)
    (pose,) = result.poses
    assert pose.name == "P1" and pose.n == 4
    assert pose.barycentre == pytest.approx((3, 4, 12))
    # No command pose: the command is the zero, AP the barycentre's distance from it (3-4-12-13).
    assert pose.ap_relative is True
    assert pose.ap == pytest.approx(13.0)
    assert pose.ap_axes == pytest.approx((3, 4, 12))
    assert pose.spatial.l_mean == pytest.approx(1.5)
    assert pose.spatial.l_sd == pytest.approx(math.sqrt(1 / 3))  # n - 1, not n (that is 0.5)
    assert pose.spatial.rp == pytest.approx(RP_P1)
    assert result.vap is None and result.distance is None


def test_ap_against_the_command_pose():
    result = pose_characteristics(P1, [1] * 4, commands={1: (0, 0, 12)})
    pose = result.pose(1)
    assert pose.ap_relative is False
    assert pose.ap_axes == pytest.approx((3, 4, 0))
    assert pose.ap == pytest.approx(5.0)
    assert pose.spatial.rp == pytest.approx(RP_P1)  # RP does not depend on the command


def test_vap_is_the_largest_distance_between_the_directions_barycentres():
    # Direction 2's barycentre is (6, 4, 12), direction 3's (3, 8, 12): 3, 4 and 5 apart.
    points = P1 + [(6, 4, 11), (6, 4, 13)] + [(3, 8, 12), (3, 8, 12)]
    directions = [1] * 4 + [2, 2] + [3, 3]
    result = pose_characteristics(points, [1] * 8, directions=directions)
    assert result.vap == pytest.approx({"P1": 5.0})
    (multi,) = result.multidirectional
    assert multi.counts == {1: 4, 2: 2, 3: 2}
    assert multi.barycentres[2] == pytest.approx((6, 4, 12))
    # AP and RP are the standard cycle's: direction 1 alone.
    assert result.pose(1).n == 4 and result.pose(1).spatial.rp == pytest.approx(RP_P1)


def distance_rows() -> tuple[list, list, list]:
    """P2 at the origin in cycles 1-4; P4 at 10, 11 and 12 from it in cycles 3, 1, 2 (the
    rows out of order, and cycle 4 measured at P2 only): D = 10, 11, 12."""
    points = [(0, 0, 0)] * 4 + [(0, 0, 11), (12, 0, 0), (6, 8, 0)]
    poses = [2] * 4 + [4, 4, 4]
    cycles = [1, 2, 3, 4, 1, 2, 3]
    return points, poses, cycles


def test_ad_and_rd_with_the_command_distance_given():
    points, poses, cycles = distance_rows()
    result = pose_characteristics(points, poses, cycles=cycles, distance=DistanceSpec(2, 4, 10.5))
    d = result.distance
    assert d is not None and d.n == 3  # cycle 4 has no P4 to pair with
    assert d.d_mean == pytest.approx(11.0)
    assert d.s_d == pytest.approx(1.0)
    assert d.rd == pytest.approx(3.0)
    assert d.dc == 10.5 and d.command_source == "given"
    assert d.ad == pytest.approx(0.5)
    assert d.ad_axes is None  # per axis needs both command poses


def test_ad_per_axis_from_the_command_poses():
    points = [(0, 0, 0)] * 3 + [(10, 0, 0), (11, 0, 0), (12, 0, 0)]
    result = pose_characteristics(
        points,
        [2] * 3 + [4] * 3,
        commands={2: (0, 0, 0), 4: (10, 0, 0)},
        distance=parse_distance("P2:P4"),
    )
    d = result.distance
    assert d is not None and d.dc == pytest.approx(10.0) and d.command_source == "command poses"
    assert d.ad == pytest.approx(1.0) and d.rd == pytest.approx(3.0)
    # D_x,j = x_2j - x_4j = -10, -11, -12; D_cx = 0 - 10: AD_x = -11 - (-10).
    assert d.ad_axes == pytest.approx((-1.0, 0.0, 0.0))


def test_the_distance_is_written_pose_colon_pose_equals_length():
    assert parse_distance("P2:P4=27.71") == DistanceSpec(2, 4, 27.71)
    assert parse_distance(" p1 : 3 ") == DistanceSpec(1, 3, None)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("P1-P2=3", "is not POSE:POSE=D; write e.g. P2:P4=27.71"),
        ("P2:P2=3", "needs two different poses"),
        ("P1:P2=abc", "'abc' is not a length greater than 0"),
        ("P1:P2=-1", "'-1' is not a length greater than 0"),
        ("P1:P2=inf", "'inf' is not a length greater than 0"),
    ],
)
def test_a_bad_distance_is_one_sentence(text: str, message: str):
    with pytest.raises(StationError, match=message) as raised:
        parse_distance(text)
    assert "\n" not in str(raised.value)


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda: pose_characteristics([], []), "there are no readings to analyse"),
        (lambda: pose_characteristics([(0, 0)], [1]), "need x, y and z in every row"),
        (
            lambda: pose_characteristics([(0, 0, 0)], [1.5]),
            r"the pose column must hold whole numbers 1, 2, ... \(P1, P2, ...\)",
        ),
        (
            lambda: pose_characteristics([(0, 0, 0)] * 2, [1, 1], directions=[1, 0]),
            "the direction column must hold whole numbers 1, 2, 3",
        ),
        (
            lambda: pose_characteristics([(0, 0, 0)] * 2, [1, 1], cycles=[2, 2]),
            "cycle 2 appears twice at P1 from direction 1",
        ),
        (
            lambda: pose_characteristics(
                [(0, 0, 0)] * 4, [1, 1, 2, 2], distance=DistanceSpec(1, 7, 5.0)
            ),
            r"the readings have no pose P7 \(they have P1, P2\)",
        ),
        (
            lambda: pose_characteristics(
                [(0, 0, 0)] * 4, [1, 1, 2, 2], distance=DistanceSpec(1, 2)
            ),
            "the distance P1:P2 needs its command length: give it",
        ),
        (
            lambda: pose_characteristics(
                [(0, 0, 0)] * 3, [1, 1, 2], distance=DistanceSpec(1, 2, 5.0)
            ),
            "the distance P1:P2 needs 2 or more cycles measured at both poses; 1 is",
        ),
        (
            lambda: pose_characteristics([(0, 0, 0)], [1], commands={1: (0, math.nan, 0)}),
            "the command pose of P1 must be three finite numbers",
        ),
    ],
)
def test_bad_readings_are_one_sentence(call, message: str):
    with pytest.raises(StationError, match=message) as raised:
        call()
    assert "\n" not in str(raised.value)


def full_run() -> tuple[list, list]:
    """P1 to P5, 30 cycles each (the points do not matter for the conditions)."""
    return [(0, 0, k % 3) for k in range(150)], [1 + k // 30 for k in range(150)]


def test_a_run_under_the_standards_conditions_departs_in_nothing():
    result = pose_characteristics(*full_run())
    standard = Conditions(100, 50, 30, 20.0, 20.4)
    assert departures(result, standard) == []
    lines = report_lines(result, standard, unit="mm", resolution=0.001)
    assert "  Departures from the standard's conditions: none." in lines
    assert any("load 100 % of rated, speed 50 % of rated, warm-up 30 min" in s for s in lines)
    assert any("(change +0.4 °C)" in s for s in lines)


def test_the_departures_from_the_standards_conditions_are_named():
    points, poses = full_run()
    # P5 left out, P4 with 29 cycles.
    result = pose_characteristics(points[:119], poses[:119])
    found = departures(result, Conditions(load=80, speed=75, warm_up=0, temperature_start=21))
    assert found == [
        "P5 not measured: the standard measures P1 to P5.",
        "fewer than 30 cycles at P4.",
        "load 80 % of rated: the standard tests at 100 %.",
        "speed 75 % of rated: the standard tests at 100, 50 and 10 %.",
        "no warm-up: the standard tests a warmed-up robot.",
        "the ambient temperature at the start and the end was not both recorded.",
    ]
    assert departures(result, None)[-1] == (
        "the conditions (load, speed, warm-up, temperature) were not recorded."
    )


def test_the_report_says_which_clauses_were_measured_and_what_ap_is_relative_to():
    points = P1 + [(0, 0, 0)] * 4
    result = pose_characteristics(points, [1] * 4 + [2] * 4, commands={2: (0, 0, 0)})
    text = "\n".join(report_lines(result, None))
    assert "Measured: pose accuracy AP and pose repeatability RP (ISO 9283 §7.2) at P1, P2." in (
        text
    )
    assert "Not measured: AD and RD (no distance between two poses was asked for); vAP" in text
    assert "drift of pose characteristics (§7.6" in text and "weaving" in text
    assert "AP at P1 is relative to the zero (no command pose)" in text
    # No gauge step given: the one number format's six decimals, positions signed.
    assert (
        "\n  P1*   4  +3.000000  +4.000000  +12.000000  +3.000000  +4.000000  +12.000000  "
        "13.000000\n" in text
    )
    assert "  * relative to the zero" in text


def test_the_live_analysis_charts_each_pose_on_its_own():
    live = LivePerPose(AnalysisConfig(unit="in"), ("x", "y", "z"), {})
    with pytest.raises(StationError, match="no cycle at a pose yet"):
        live.snapshot()
    rng = np.random.default_rng(1)
    fed = []
    for number in range(1, 11):
        # Pose 1 about +0.001 in, pose 2 about -0.002 in: one chart would step between them.
        placement = 1 if number <= 6 else 2
        centre = 0.001 if placement == 1 else -0.002
        values = {a: centre + 1e-5 * rng.standard_normal() for a in ("x", "y", "z")}
        live.add_cycle(values, number, None, placement)
        fed.append((values, number, None, placement))
    shown = live.copy().snapshot().channels["x"].descriptive
    assert shown.n == 4 and shown.mean == pytest.approx(-0.002, abs=1e-4)
    # Cycle 3 (pose 1) rejected: pose 1 keeps five, and pose 2, measured last, is shown.
    again = live.rebuilt([row for row in fed if row[1] != 3], None)
    assert again.poses[1].snapshot().channels["x"].descriptive.n == 5
    assert again.snapshot().channels["x"].descriptive.n == 4
