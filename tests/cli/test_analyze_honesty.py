"""`station analyze`: provisional verdicts (--min-n), and the JSON fields of issue 11."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[2]
STATION = Path(sys.executable).parent / "station"


def station(*args: str | Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [str(STATION), "analyze", *map(str, args)],
        capture_output=True,
        text=True,
        timeout=60,
        cwd=REPO,
    )


def write_csv(folder: Path, name: str, text: str) -> Path:
    path = folder / name
    path.write_text(text)
    return path


def test_a_short_csv_is_provisional_and_min_n_sets_the_count(tmp_path):
    rng = np.random.default_rng(1)
    rows = ["x"] + [f"{v:.5f}" for v in rng.normal(0, 0.0002, 9)]
    path = write_csv(tmp_path, "short.csv", "\n".join(rows) + "\n")
    document = json.loads(station(path, "--lsl", "-0.001", "--usl", "0.001", "--json").stdout)
    x = document["channels"]["x"]
    assert x["capability"]["provisional"] is True
    assert x["capability"]["verdict"] == "PROVISIONAL: 9 of 25"
    for key in ("out_of_spec", "normality", "autocorrelation", "drift"):
        assert key in x
    assert x["capability"]["method"] in ("normal", "percentile")
    text = station(path, "--lsl", "-0.001", "--usl", "0.001").stdout
    assert "VERDICT: PROVISIONAL: 9 of 25 readings" in text
    failed = station(path, "--lsl", "-0.001", "--usl", "0.001", "--fail-if-incapable")
    assert failed.returncode == 1 and "provisional: 9 of 25 readings" in failed.stderr
    final = json.loads(
        station(path, "--lsl", "-0.001", "--usl", "0.001", "--min-n", "9", "--json").stdout
    )
    assert final["channels"]["x"]["capability"]["provisional"] is False
    bad = station(path, "--min-n", "many")
    assert bad.returncode == 2 and "--min-n 'many' is not a whole number" in bad.stderr
