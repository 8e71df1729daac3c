"""`station analyze FILE --procedure gage_rr` on a CSV of ``part,appraiser,trial,value`` rows
(AIAG's own example): the JSON document, the text report with both methods labelled, the
options, and the tables it refuses in one line naming what is missing."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from helpers import run_station

from tests.methods.test_gage_rr_study import AIAG


def write(path: Path, rows: list[tuple], header: str = "part,appraiser,trial,value") -> Path:
    path.write_text(header + "\n" + "\n".join(",".join(map(str, row)) for row in rows) + "\n")
    return path


def aiag_rows() -> list[tuple]:
    return [
        (part, appraiser, trial, value)
        for (appraiser, trial), values in AIAG.items()
        for part, value in enumerate(values, start=1)
    ]


@pytest.fixture
def aiag_csv(tmp_path: Path) -> Path:
    return write(tmp_path / "grr.csv", aiag_rows())


def test_the_json_document_holds_both_methods_and_the_verdict(aiag_csv: Path):
    done = run_station("analyze", aiag_csv, "--procedure", "gage_rr", "--tolerance", "8", "--json")
    assert done.returncode == 0, done.stderr
    document = json.loads(done.stdout)
    assert document["procedure"] == "gage_rr" and "channels" not in document
    study = document["gage_rr"]
    assert {
        "var_repeatability", "var_reproducibility", "var_part", "var_interaction",
        "interaction_p", "pooled", "ev", "av", "grr", "pv", "tv", "pct_grr", "pct_tolerance",
        "ndc",
    } <= set(study["anova"])  # fmt: skip
    assert {
        "rbarbar", "xdiff", "ev", "av", "grr", "pv", "tv", "pct_ev", "pct_av", "pct_grr",
        "pct_pv", "ndc",
    } <= set(study["xbar_r"])  # fmt: skip
    anova, xr = study["anova"], study["xbar_r"]
    assert anova["pooled"] is True and anova["interaction_p"] == pytest.approx(0.9741, abs=1e-4)
    assert anova["pct_grr"] == pytest.approx(27.86, abs=0.01) and anova["ndc"] == 4
    assert anova["spread_sigmas"] == 6 and xr["spread_sigmas"] == 1
    # %tolerance = 100·6σ_GRR/T = 100·6·√0.091429/8.
    assert anova["pct_tolerance"] == pytest.approx(100 * 6 * 0.091429**0.5 / 8, abs=0.01)
    assert xr["pct_grr"] == pytest.approx(26.68, abs=0.02) and xr["ndc"] == 5
    assert study["verdict"] == "NOT ACCEPTABLE" and study["acceptable"] is False
    assert study["appraisers"] == ["A", "B", "C"] and study["parts"][-1] == "10"


def test_the_text_report_labels_both_methods_and_fails_a_script(aiag_csv: Path):
    done = run_station("analyze", aiag_csv, "--procedure", "gage_rr", "--fail-if-incapable")
    assert done.returncode == 1
    assert done.stdout.startswith("GAGE R&R (CROSSED) REPORT ON grr.csv")
    assert "ANOVA METHOD (two-way crossed" in done.stdout
    assert "AVERAGE AND RANGE METHOD (AIAG MSA 4th ed. worksheet; figures are 1 SD)" in done.stdout
    assert "gage_rr (NOT ACCEPTABLE)" in done.stderr


def test_operator_for_appraiser_and_the_pooling_level(tmp_path: Path):
    path = write(tmp_path / "op.csv", aiag_rows(), header="part,operator,trial,value")
    done = run_station("analyze", path, "--procedure", "gage_rr", "--json", "--pool-above", "0.99")
    assert done.returncode == 0, done.stderr
    anova = json.loads(done.stdout)["gage_rr"]["anova"]
    # p 0.974 is not above 0.99: the interaction stays (its estimate is negative: 0).
    assert anova["pooled"] is False and anova["var_interaction"] == 0
    assert "part x appraiser" in anova["zeroed"]
    refused = run_station("analyze", path, "--procedure", "gage_rr", "--pool-above", "1.5")
    assert refused.returncode == 2 and "between 0 and 1" in refused.stderr


@pytest.mark.parametrize(
    ("change", "header", "message"),
    [
        (lambda r: r[:-1], None, "part 10 by appraiser C has no trial 3"),
        (lambda r: [x for x in r if x[1] == "A"], None, "2 or more appraisers"),
        (lambda r: [x for x in r if x[0] == 1], None, "2 or more parts"),
        (lambda r: [x for x in r if (x[0], x[1]) != (7, "C")], None,
         "part 7 was not measured by appraiser C"),
        (lambda r: [(1, "A", 1, "n/a"), *r[1:]], None,
         "line 2, column 'value': 'n/a' is not a number"),
        (lambda r: r, "part,appraiser,value", "trial missing"),
        (lambda r: [(1, "A", 1.5, 0.3), *r[1:]], None, "trial 1.5 of part 1 is not a trial"),
        (lambda r: [(1, " ", 1, 0.3), *r[1:]], None, "column 'appraiser': the cell is empty"),
    ],
)  # fmt: skip
def test_a_table_it_cannot_analyse_is_one_line_naming_what_is_missing(
    tmp_path: Path, change, header, message
):
    rows = change(aiag_rows())
    if header == "part,appraiser,value":
        rows = [(p, a, v) for p, a, _, v in rows]
    path = write(tmp_path / "bad.csv", rows, header=header or "part,appraiser,trial,value")
    done = run_station("analyze", path, "--procedure", "gage_rr")
    assert done.returncode == 2, done.stdout
    assert message in done.stderr
    assert done.stderr.count("\n") == 1 and "Traceback" not in done.stderr


def test_names_from_the_table_are_text(tmp_path: Path):
    """An appraiser's name with control characters reaches the terminal made visible."""
    rows = [
        (part, "A" if appraiser == "A" else "B\x1b]0;pwned\x07", trial, value)
        for part, appraiser, trial, value in aiag_rows()
        if appraiser != "C"
    ]
    path = write(tmp_path / "names.csv", rows)
    done = run_station("analyze", path, "--procedure", "gage_rr")
    assert done.returncode == 0, done.stderr
    assert "\x1b" not in done.stdout and "\x07" not in done.stdout
    assert "B\\x1b]0;pwned\\x07" in done.stdout
    missing = write(tmp_path / "missing.csv", rows[:-1])
    refused = run_station("analyze", missing, "--procedure", "gage_rr")
    assert refused.returncode == 2 and "\x1b" not in refused.stderr
    assert "part 10 by appraiser B\\x1b]0;pwned\\x07 has no trial 3" in refused.stderr
