"""The ISO 9283 pose test end to end: ``station capture`` of the shipped procedure against the
simulated test cube (each pose with a bias and a spread of its own, a real pty), the robot
played between cycles; the session analysed recovers each pose's bias, the distance between
two poses, and the conditions typed."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest
from helpers import STATION, run_station

from station.instruments.protocols import get_protocol
from station.instruments.simulator import GaugeSpec, Simulator
from station.instruments.simulator.cube import POSE_BIAS, POSE_NOISE, CubePosesModel

from .playing import play_capture

CYCLES = 30
"""The procedure's cycles per pose (its block's target)."""
POSES = 3
RESOLUTION = 0.0001


def analyze_json(*args: str | Path) -> dict:
    done = run_station("analyze", *map(str, args), "--json")
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout)


@pytest.fixture(scope="module")
def session(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, str, CubePosesModel]:
    """A pose test of P1 to P3 (30 cycles each), the pendant and the conditions typed."""
    folder = tmp_path_factory.mktemp("sessions")
    gauge = GaugeSpec(RESOLUTION, -0.5, 0.5, "in", noise=0.00002)
    model = CubePosesModel(captures=CYCLES, gauge=gauge, seed=3)
    simulator = Simulator(get_protocol("idh"), model, seed=3)
    pendant = [
        f"{pose}:{axis}={value}"
        for pose in range(1, POSES + 1)
        for axis, value in zip("xyz", model.placement_of(pose).pendant, strict=True)
    ]
    conditions = ("load=100", "speed=50", "warm_up=0", "temperature_start=20.5")
    url = simulator.start_pty()
    try:
        done, _ = play_capture(
            simulator,
            CYCLES,
            [
                *STATION,
                "capture",
                *("--trigger", "poll", "--every", "0.15", "--procedure", "pose_characteristics"),
                *("--port", url, "--protocol", "idh", "--robot", "KSC-7"),
                *("--sessions", str(folder), "--placements", str(POSES)),
                *(arg for item in (*pendant, *conditions) for arg in ("--input", item)),
                *("--input", "temperature_end=21.7"),
            ],
        )
    finally:
        simulator.stop()
    assert done.returncode == 0, done.stderr
    return next(folder.glob("*.jsonl")), done.stdout, model


def test_each_poses_bias_is_recovered_within_its_uncertainty(session):
    path, summary, model = session
    iso = analyze_json(path)["iso9283"]
    assert list(iso["poses"]) == ["P1", "P2", "P3"]
    for number, pose in enumerate(iso["poses"].values(), start=1):
        sigma = POSE_NOISE[number - 1]
        # The barycentre's own uncertainty, 3 sigma / sqrt(n), and half a step each of the
        # readings' and the zero's rounding.
        allowed = 3 * sigma / math.sqrt(CYCLES) + RESOLUTION
        assert pose["n"] == CYCLES and pose["ap_relative"] is False
        assert pose["command"] == pytest.approx(list(model.placement_of(number).pendant))
        assert pose["ap_axes"] == pytest.approx(list(POSE_BIAS[number - 1]), abs=allowed)
        assert pose["ap"] == pytest.approx(math.hypot(*POSE_BIAS[number - 1]), abs=2 * allowed)
        # RP of an isotropic normal cloud is about 3.6 sigma (Maxwell: l-bar 1.60, S_l 0.67).
        assert 2.5 * sigma < pose["rp"] < 5 * sigma
    assert iso["vap"] is None and iso["distance"] is None
    assert iso["conditions"] == {
        "load": 100,
        "speed": 50,
        "warm_up": 0,
        "temperature_start": 20.5,
        "temperature_end": 21.7,
    }
    assert iso["departures"] == [
        "P4, P5 not measured: the standard measures P1 to P5.",
        "no warm-up: the standard tests a warmed-up robot.",
    ]
    text = " ".join(summary.split())
    assert "ISO 9283 POSE CHARACTERISTICS (3 poses)" in text
    assert "temperature 20.5 °C at the start, 21.7 °C at the end (change +1.2 °C)" in text


def test_the_distance_between_two_poses_is_the_bias_along_their_line(session):
    path, _, model = session
    distance = analyze_json(path, "--distance", "P2:P3")["iso9283"]["distance"]
    c2, c3 = (model.placement_of(k).pendant for k in (2, 3))
    along = [a - b for a, b in zip(c2, c3, strict=True)]
    length = math.hypot(*along)
    # The attained distance moves by the pose biases' difference along the line P3 -> P2.
    shift = sum(u * (b2 - b3) for u, b2, b3 in zip(along, POSE_BIAS[1], POSE_BIAS[2], strict=True))
    allowed = 3 * math.hypot(POSE_NOISE[1], POSE_NOISE[2]) / math.sqrt(CYCLES) + 2 * RESOLUTION
    assert distance["dc"] == pytest.approx(length) and distance["n"] == CYCLES
    assert distance["ad"] == pytest.approx(shift / length, abs=allowed)
    assert 0 < distance["rd"] < 6 * math.hypot(POSE_NOISE[1], POSE_NOISE[2])


def test_the_wide_export_reads_back_to_the_same_figures(session, tmp_path: Path):
    path, _, _ = session
    table = tmp_path / "poses.csv"
    exported = run_station("export", str(path), "--csv", "-o", str(table))  # fmt: skip
    assert exported.returncode == 0, exported.stderr
    header = next(line for line in table.read_text().splitlines() if not line.startswith("#"))
    assert header == "cycle,pose,direction,x,y,z,cx,cy,cz"
    again = analyze_json(table, "--procedure", "pose_characteristics", "--distance", "P2:P3")
    first = analyze_json(path, "--distance", "P2:P3")
    for name, pose in first["iso9283"]["poses"].items():
        read = again["iso9283"]["poses"][name]
        assert read["ap_axes"] == pytest.approx(pose["ap_axes"], abs=1e-12)
        assert read["rp"] == pytest.approx(pose["rp"], rel=1e-9)
    assert again["iso9283"]["distance"]["ad"] == pytest.approx(
        first["iso9283"]["distance"]["ad"], abs=1e-12
    )
