"""`station analyze FILE --procedure pose_characteristics` on a CSV of ``cycle,x,y,z`` with the
optional ``pose``, ``direction`` and ``cx,cy,cz``: the real console script, figures checked by
hand (tests/methods/test_pose_characteristics.py has the same sets)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

STATION = Path(sys.executable).parent / "station"


def analyze(*args: str | Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [str(STATION), "analyze", *map(str, args)], capture_output=True, text=True, timeout=60
    )


# P1: barycentre (3, 4, 12), l = 1, 1, 2, 2 (RP = 1.5 + sqrt 3), command (0, 0, 12): AP 5.
# P1 from directions 2 and 3: barycentres (6, 4, 12) and (3, 8, 12): vAP 5.
# P2 at (0, 0, 0), command (0, 0, 0), cycles 1-4; P1 - P2 over cycles 1-4: D = 13, 12.6..,
# 14.4.., 12.6.. (not checked); P3 10, 11 and 12 from P2 along x in cycles 1-3: D-bar 11, RD 3.
ROWS = """\
# a hand-made pose test
cycle,pose,direction,x,y,z,cx,cy,cz
1,1,1,4,4,12,0,0,12
2,1,1,2,4,12,0,0,12
3,1,1,3,6,12,0,0,12
4,1,1,3,2,12,0,0,12
1,1,2,6,4,11,0,0,12
2,1,2,6,4,13,0,0,12
1,1,3,3,8,12,0,0,12
2,1,3,3,8,12,0,0,12
1,2,1,0,0,0,0,0,0
2,2,1,0,0,0,0,0,0
3,2,1,0,0,0,0,0,0
4,2,1,0,0,0,0,0,0
1,3,1,10,0,0,10,0,0
2,3,1,11,0,0,10,0,0
3,3,1,12,0,0,10,0,0
"""


@pytest.fixture
def poses_csv(tmp_path: Path) -> Path:
    path = tmp_path / "poses.csv"
    path.write_text(ROWS)
    return path


def test_the_json_document_holds_ap_rp_vap_and_the_distance(poses_csv: Path):
    done = analyze(
        poses_csv, "--procedure", "pose_characteristics", "--distance", "P2:P3=10.5", "--json"
    )
    assert done.returncode == 0, done.stderr
    document = json.loads(done.stdout)
    assert document["procedure"] == "pose_characteristics" and "channels" not in document
    iso = document["iso9283"]
    assert list(iso["poses"]) == ["P1", "P2", "P3"]
    p1 = iso["poses"]["P1"]
    assert {"n", "barycentre", "ap", "ap_axes", "ap_relative", "rp", "l_bar", "s_l"} <= set(p1)
    assert p1["n"] == 4 and p1["barycentre"] == pytest.approx([3, 4, 12])
    assert p1["ap"] == pytest.approx(5.0) and p1["ap_axes"] == pytest.approx([3, 4, 0])
    assert p1["ap_relative"] is False
    assert p1["l_bar"] == pytest.approx(1.5) and p1["s_l"] == pytest.approx(3**-0.5)
    assert p1["rp"] == pytest.approx(1.5 + 3**0.5)
    assert iso["poses"]["P3"]["ap"] == pytest.approx(1.0)
    assert iso["vap"] == pytest.approx({"P1": 5.0})
    distance = iso["distance"]
    assert distance["d_mean"] == pytest.approx(11.0) and distance["dc"] == 10.5
    assert distance["ad"] == pytest.approx(0.5) and distance["rd"] == pytest.approx(3.0)
    assert distance["n"] == 3 and distance["ad_axes"] == pytest.approx([-1.0, 0.0, 0.0])


def test_without_a_distance_or_a_command_pose(tmp_path: Path):
    table = tmp_path / "one.csv"
    table.write_text("cycle,x,y,z\n1,4,4,12\n2,2,4,12\n3,3,6,12\n4,3,2,12\n")
    done = analyze(table, "--procedure", "pose_characteristics", "--json")
    assert done.returncode == 0, done.stderr
    iso = json.loads(done.stdout)["iso9283"]
    (pose,) = iso["poses"].values()
    assert pose["ap_relative"] is True and pose["ap"] == pytest.approx(13.0)
    assert iso["vap"] is None and iso["distance"] is None


def test_the_text_report_says_what_was_measured(poses_csv: Path):
    done = analyze(
        poses_csv, "--procedure", "pose_characteristics", "--distance", "P2:P3", "--unit", "mm"
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.startswith("ISO 9283 POSE CHARACTERISTICS REPORT ON poses.csv")
    text = " ".join(done.stdout.split())  # the report wraps its long lines at 80 columns
    assert "Measured: pose accuracy AP and pose repeatability RP (ISO 9283 §7.2) at P1, P2," in text
    assert "multi-directional pose accuracy variation vAP at P1" in text
    assert "distance accuracy AD and repeatability RD (§7.3) P2 to P3" in text
    # No gauge step given: the one number format's six decimals.
    assert "vAP at P1: 5.000000 mm" in text
    # D_c from the two command poses, 10 apart: AD = 11 - 10.
    assert "D-bar 11.000000, D_c 10.000000 (command poses), AD +1.000000, RD ±3.000000 mm" in text
    assert "Conditions: not recorded." in text


@pytest.mark.parametrize(
    ("rows", "extra", "message"),
    [
        ("cycle,pose,x,y\n1,1,0,0\n", (), "needs the columns x, y, z; z missing"),
        ("pose,x,y,z,cx\n1,0,0,0,0\n", (), "needs all of cx, cy, cz, not only cx"),
        (
            "pose,x,y,z,cx,cy,cz\n1,0,0,0,0,0,0\n1,0,0,0,0,0,1\n",
            (),
            "pose P1 has two command poses (0, 0, 0 and 0, 0, 1); give one per pose",
        ),
        ("pose,x,y,z\n0,0,0,0\n", (), "the pose column must hold whole numbers 1, 2, ..."),
        ("pose,x,y,z\n1,0,0,0\n2,0,0,0\n", ("--distance", "P1+P2"), "is not POSE:POSE=D"),
        (
            "pose,x,y,z\n1,0,0,0\n1,0,0,0\n2,0,0,0\n2,0,0,0\n",
            ("--distance", "P1:P2"),
            "needs its command length: give it (P1:P2=D) or the command poses of both",
        ),
    ],
)
def test_bad_input_is_one_line(tmp_path: Path, rows: str, extra: tuple[str, ...], message: str):
    table = tmp_path / "bad.csv"
    table.write_text(rows)
    done = analyze(table, "--procedure", "pose_characteristics", *extra)
    assert done.returncode == 2, done.stdout
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("station: "), done.stderr
    assert message in lines[0]


def test_the_distance_belongs_to_the_pose_test_alone(poses_csv: Path):
    done = analyze(poses_csv, "--distance", "P1:P2=3")
    assert done.returncode == 2
    assert done.stderr.strip() == (
        "station: --distance is not an option of --procedure repeatability; it belongs to "
        "--procedure pose_characteristics."
    )
