"""`station analyze FILE --procedure gauge_linearity` on a CSV of ``reference,value`` rows: the
real console script, on AIAG's own example."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

STATION = Path(sys.executable).parent / "station"

# AIAG MSA 4th ed., the linearity example: references 2 to 10, twelve readings each.
AIAG = {
    2: "2.7 2.5 2.4 2.5 2.7 2.3 2.5 2.5 2.4 2.4 2.6 2.4",
    4: "5.1 3.9 4.2 5.0 3.8 3.9 3.9 3.9 3.9 4.0 4.1 3.8",
    6: "5.8 5.7 5.9 5.9 6.0 6.1 6.0 6.1 6.4 6.3 6.0 6.1",
    8: "7.6 7.7 7.8 7.7 7.8 7.8 7.8 7.7 7.8 7.5 7.6 7.7",
    10: "9.1 9.3 9.5 9.3 9.4 9.5 9.5 9.5 9.6 9.2 9.3 9.4",
}


def analyze(*args: str | Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [str(STATION), "analyze", *map(str, args)], capture_output=True, text=True, timeout=60
    )


@pytest.fixture
def aiag_csv(tmp_path: Path) -> Path:
    lines = [f"{size},{value}" for size, values in AIAG.items() for value in values.split()]
    path = tmp_path / "linearity.csv"
    path.write_text("# AIAG MSA 4th ed. linearity example\nreference,value\n" + "\n".join(lines))
    return path


def test_the_json_document_holds_the_study(aiag_csv: Path):
    done = analyze(
        aiag_csv, "--procedure", "gauge_linearity", "--process-variation", "16.53",
        "--tolerance", "4", "--resolution", "0.1", "--json",
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    document = json.loads(done.stdout)
    assert document["procedure"] == "gauge_linearity" and "channels" not in document
    study = document["gauge_linearity"]
    assert {
        "slope", "intercept", "r2", "s", "slope_p", "intercept_p", "average_bias",
        "average_bias_p", "linearity", "pct_linearity", "biases", "acceptable",
    } <= set(study)  # fmt: skip
    assert study["slope"] == pytest.approx(-0.13167, abs=1e-5)
    assert study["intercept"] == pytest.approx(0.73667, abs=1e-5)
    assert study["r2"] == pytest.approx(0.7143, abs=1e-4)
    assert study["linearity"] == pytest.approx(2.1765, abs=1e-3)
    assert study["pct_linearity"] == pytest.approx(13.17, abs=0.01)
    assert study["average_bias"] == pytest.approx(-0.05333, abs=1e-5)
    assert study["average_bias_p"] == pytest.approx(0.089, abs=1e-3)
    assert [b["reference"] for b in study["biases"]] == [2, 4, 6, 8, 10]
    assert set(study["biases"][0]) >= {"reference", "n", "bias", "t", "p"}
    assert study["biases"][0]["n"] == 12 and study["biases"][0]["t"] == pytest.approx(13.73, 1e-3)
    # A bias of 0.47 is proven at 10, beyond 5 % of T = 0.2: not acceptable.
    assert study["acceptable"] is False and study["verdict"] == "NOT ACCEPTABLE"


def test_the_text_report_and_the_failing_exit(aiag_csv: Path):
    done = analyze(aiag_csv, "--procedure", "gauge_linearity", "--fail-if-incapable")
    assert done.returncode == 1
    assert done.stdout.startswith("GAUGE LINEARITY AND BIAS REPORT ON linearity.csv")
    assert "GAUGE LINEARITY AND BIAS STUDY: NOT ACCEPTABLE" in done.stdout
    # No gauge step given: the figures at six decimals (the one number format's rule).
    assert "bias = +0.736667 -0.13167·reference" in done.stdout
    assert "gauge_linearity (NOT ACCEPTABLE)" in done.stderr


def test_options_it_does_not_take_and_a_table_it_cannot_read_are_refused(
    aiag_csv: Path, tmp_path: Path
):
    done = analyze(aiag_csv, "--procedure", "gauge_linearity", "--reference", "2")
    assert done.returncode == 2
    assert "--reference is not an option of --procedure gauge_linearity" in done.stderr
    assert "(it takes --tolerance, --process-variation)" in done.stderr
    plain = tmp_path / "plain.csv"
    plain.write_text("x\n0.1\n0.2\n")
    done = analyze(plain, "--procedure", "gauge_linearity")
    assert done.returncode == 2
    assert "a gauge linearity table needs the columns reference, value" in done.stderr
