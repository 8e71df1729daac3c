"""`station analyze --procedure gauge_check | joint_troubleshooting | gain_schedule` on CSV
tables: the real console script."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from helpers import run_station

from station.instruments.joint_model import faulty_arm

STATION = Path(sys.executable).parent / "station"


def analyze(*args: str | Path) -> subprocess.CompletedProcess[str]:
    """``station analyze ARGS``, in this process (test_analyze_honesty runs the real one)."""
    return run_station("analyze", *args)


@pytest.fixture()
def gauge_csv(tmp_path: Path) -> Path:
    readings = np.round(0.1 + np.random.default_rng(2).normal(0, 0.00003, 30), 4)
    path = tmp_path / "gauge.csv"
    path.write_text("# G-1 on a 0.1 in block\nx\n" + "\n".join(map(str, readings)) + "\n")
    return path


def test_gauge_check_json(gauge_csv: Path):
    result = analyze(
        gauge_csv,
        "--procedure",
        "gauge_check",
        "--reference",
        "0.1",
        "--tolerance",
        "0.002",
        "--resolution",
        "0.0001",
        "--json",
    )
    assert result.returncode == 0, result.stderr
    study = json.loads(result.stdout)["gauge_check"]
    assert {"cg", "cgk", "bias", "bias_p", "resolution_ratio", "capable"} <= set(study)
    assert study["resolution_ratio"] == pytest.approx(0.05)
    readings = np.loadtxt(gauge_csv, skiprows=2)
    assert study["cg"] == pytest.approx(0.0004 / (6 * readings.std(ddof=1)))
    # Through the registry: the verdict's capability is the study (Cp = Cg, Cpk = Cgk).
    capability = json.loads(result.stdout)["channels"]["x"]["capability"]
    assert capability["cp"] == pytest.approx(study["cg"])
    assert capability["cpk"] == pytest.approx(study["cgk"])
    text = analyze(
        gauge_csv, "--procedure", "gauge_check", "--reference", "0.1", "--tolerance", "0.002"
    ).stdout
    assert text.startswith("GAUGE CHECK REPORT ON gauge.csv")
    assert max(len(line) for line in text.splitlines()) <= 80


def test_gauge_check_with_a_bias_fails_and_exits_1_when_asked(gauge_csv: Path):
    common = ["--procedure", "gauge_check", "--tolerance", "0.002", "--fail-if-incapable"]
    result = analyze(gauge_csv, *common, "--reference", "0.0997")  # the gauge reads 0.0003 high
    assert result.returncode == 1
    assert "GAUGE CHECK (TYPE-1 STUDY): NOT CAPABLE" in result.stdout
    assert "failed the capability check: x (not capable)" in result.stderr


@pytest.mark.parametrize(
    ("args", "fragment"),
    [
        (("--tolerance", "0.002"), "needs --reference X_M"),
        (("--reference", "0.1", "--tolerance", "-1"), "must be greater than 0"),
    ],
)
def test_gauge_check_bad_options(gauge_csv: Path, args, fragment):
    result = analyze(gauge_csv, "--procedure", "gauge_check", *args)
    assert result.returncode == 2 and fragment in result.stderr


def test_joint_troubleshooting_json_names_the_suspect(tmp_path: Path):
    arm = faulty_arm(3, "backlash")
    path = tmp_path / "joints.csv"
    rows = [f"{j},{x},{y},{z}" for j, x, y, z in arm.table(seed=2)]
    path.write_text("joint,x,y,z\n" + "\n".join(rows) + "\n")
    result = analyze(path, "--procedure", "joint_troubleshooting", "--json")
    assert result.returncode == 0, result.stderr
    document = json.loads(result.stdout)
    assert document["suspect"] == 3 and document["cause"] == "backlash"
    assert [j["joint"] for j in document["joints"]][0] == 3
    assert len(document["joints"]) == 3 and document["levene_p"] < 0.05
    text = analyze(path, "--procedure", "joint_troubleshooting").stdout
    assert "SUSPECT: joint 3." in text
    assert max(len(line) for line in text.splitlines()[3:]) <= 80


def test_joint_troubleshooting_takes_lever_arms_from_a_column(tmp_path: Path):
    arm = faulty_arm(1, "noise", size=2e-5)
    levers = arm.lever_arms()
    rows = [f"{j},{x},{y},{z},{levers[j - 1]}" for j, x, y, z in arm.table(seed=1)]
    path = tmp_path / "joints.csv"
    path.write_text("joint,x,y,z,lever\n" + "\n".join(rows) + "\n")
    document = json.loads(analyze(path, "--procedure", "joint_troubleshooting", "--json").stdout)
    assert all(j["angular_spread"] is not None for j in document["joints"])
    assert document["suspect"] == 1
    rows[0] = rows[0].rsplit(",", 1)[0] + ",99"
    path.write_text("joint,x,y,z,lever\n" + "\n".join(rows) + "\n")
    result = analyze(path, "--procedure", "joint_troubleshooting")
    assert result.returncode == 2 and "has two lever arms" in result.stderr


def test_gain_schedule_through_analyze(tmp_path: Path):
    q = np.linspace(0, 90, 9)
    path = tmp_path / "gains.csv"
    rows = [f"{v},{1 + 0.01 * v - 1e-4 * v * v}" for v in q]
    path.write_text("q,kp\n" + "\n".join(rows) + "\n")
    document = json.loads(analyze(path, "--procedure", "gain_schedule", "--json").stdout)
    kp = document["gains"]["kp"]
    assert kp["order"] == 2
    assert kp["coefficients"] == pytest.approx([1, 0.01, -1e-4], abs=1e-10)


def test_reference_belongs_to_the_gauge_check(gauge_csv: Path):
    result = analyze(gauge_csv, "--reference", "0.1")
    assert result.returncode == 2
    assert "--reference is not an option of --procedure repeatability" in result.stderr
    assert "it belongs to --procedure gauge_check." in result.stderr
