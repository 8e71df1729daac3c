"""A session's measurement budget: built from what its header recorded of the gauge register
(certificate, latest Type-1 check) and its zero, shown in every output, and the very U its
readings are decided with."""

from __future__ import annotations

import datetime as dt
import json
import math
from datetime import UTC, datetime
from pathlib import Path

import numpy as np
import pytest

from station.analysis.gauge_check import gauge_check
from station.errors import StationError
from station.session.gauge_register import (
    check_repeatability,
    gauge_status,
    load_register,
    record_certificate,
    record_check,
)
from station.session.header import analysis_config
from station.session.journal import SessionWriter
from tests.helpers import run_station
from tests.session.conftest import session_header_fields

CHECK = gauge_check(
    1.0 + np.random.default_rng(0).normal(0, 0.00005, 30).round(5), 1.0, 0.01, resolution=0.00001
)
TODAY = dt.date.today()


def test_a_type1_check_files_its_sd_and_an_older_entry_gives_it_back_from_cg(tmp_path: Path):
    register = tmp_path / "gauges.json"
    entry = record_check(register, "G-1", CHECK, when=TODAY)
    assert check_repeatability(entry) == (CHECK.sd, CHECK.n)
    older = {k: v for k, v in entry.items() if k != "sd"}  # a register from before
    sd, n = check_repeatability(older)
    assert n == CHECK.n and sd == pytest.approx(CHECK.sd, rel=1e-12)
    assert check_repeatability({"cg": 2.0}) == (None, None)


def test_a_certificate_is_recorded_and_seen_in_the_gauges_status(tmp_path: Path):
    register = tmp_path / "gauges.json"
    record_check(register, "G-1", CHECK, when=TODAY)
    record_certificate(register, "G-1", expanded=0.00004, k=2, date="2026-10-01")
    status = gauge_status(load_register(register), "G-1", TODAY).as_json()
    assert status["certificate"] == {"U": 0.00004, "k": 2.0, "date": "2026-10-01", "id": None}
    assert (status["sd"], status["n"]) == (CHECK.sd, CHECK.n)
    for bad, words in (
        ({"expanded": -1.0, "k": 2}, "finite number 0 or more"),
        ({"expanded": math.nan, "k": 2}, "finite number 0 or more"),
        ({"expanded": 1.0, "k": 0}, "the certificate's k must be a finite number above 0"),
    ):
        with pytest.raises(StationError) as caught:
            record_certificate(register, "G-1", **bad)
        assert words in caught.value.message


def test_the_gauges_certificate_command_records_it(tmp_path: Path):
    register = tmp_path / "gauges.json"
    done = run_station(
        "gauges",
        "certificate",
        "G-7",
        "--U",
        "0.00004",
        "--k",
        "2",
        "--number",
        "C-12",
        "--register",
        str(register),
    )
    assert done.returncode == 0, done.stderr
    assert "u = U/k = 2e-05" in done.stdout
    kept = load_register(register)["gauges"]["G-7"]["certificate"]
    assert kept == {"U": 0.00004, "k": 2.0, "date": None, "id": "C-12"}
    refused = run_station(
        "gauges", "certificate", "G-7", "--U", "-1", "--k", "2", "--register", str(register)
    )
    assert refused.returncode == 2 and "0 or more" in refused.stderr


def _session(folder: Path, register: Path, monkeypatch, values: list[float]) -> Path:
    """A repeatability session on gauge G-1 (its check and certificate in ``register`` when it
    began), zeroed from 5 readings, with ``values`` on x (y and z at 0)."""
    monkeypatch.setenv("STATION_GAUGES", str(register))
    header = session_header_fields(gauges={"x": "G-1", "y": "G-1", "z": "G-1"})
    zero = {"method": "software", "offset": 0.375, "n": 5, "uncertainty": 0.00003}
    moment = datetime(2026, 11, 23, 12, 0, 0, tzinfo=UTC)
    with SessionWriter.create(folder, header, now=moment) as writer:
        writer.append("zero", step="zero", channels={c: dict(zero) for c in "xyz"})
        for cycle, value in enumerate(values, start=1):
            channels = {
                c: {"value": value if c == "x" else 0.0, "unit": "in", "raw": "-"} for c in "xyz"
            }
            writer.append("reading", cycle=cycle, step="cycles", channels=channels)
        writer.append("finish", by="operator", complete=True)
    return writer.path


def test_the_session_budget_is_in_analyze_json_and_decides_its_readings(
    tmp_path: Path, monkeypatch
):
    register = tmp_path / "gauges.json"
    record_check(register, "G-1", CHECK, when=TODAY)
    record_certificate(register, "G-1", expanded=0.00004, k=2)
    # ±0.001 in limits; 0.00096 in is inside them but within U of the USL.
    values = [0.0001 * ((i * 7) % 5 - 2) for i in range(29)] + [0.00096]
    path = _session(tmp_path / "sessions", register, monkeypatch, values)
    register.unlink()  # the budget rests on the header's snapshot, not today's register

    done = run_station("analyze", str(path), "--json")
    assert done.returncode == 0, done.stderr
    budget = json.loads(done.stdout)["channels"]["x"]["budget"]
    parts = [0.0001 / math.sqrt(12), 0.00002, CHECK.sd, 0.00003]
    u_c = math.sqrt(sum(p * p for p in parts))
    assert [c["name"] for c in budget["contributions"]] == [
        "gauge step (r/2 rectangular)",
        "certificate (U at k = 2)",
        f"repeatability (Type-1, n = {CHECK.n})",
        "zero",
    ]
    assert budget["u_c"] == pytest.approx(u_c, rel=1e-9)
    assert (budget["k"], budget["U"]) == (2.0, pytest.approx(2 * u_c, rel=1e-9))
    assert budget["U"] > 0.001 - 0.00096  # so the last reading cannot be called in
    readings = budget["readings"]
    assert readings["rule"] == "guarded" and readings["U"] == budget["U"]
    assert readings["acceptance_zone"] == pytest.approx([-0.001 + budget["U"], 0.001 - budget["U"]])
    assert (readings["pass"], readings["fail"], readings["indeterminate"]) == (29, 0, 1)
    assert readings["cycles_indeterminate"] == [30]

    text = " ".join(run_station("analyze", str(path)).stdout.split())  # wrapped at 80
    assert "MEASUREMENT BUDGET (GUM; one reading)" in text
    assert "29 PASS, 0 FAIL, 1 INDETERMINATE" in text
    assert "INDETERMINATE (neither in nor out is proven) at cycles 30" in text
    for fmt in ("txt", "md", "html"):
        report = run_station("report", str(path), "--format", fmt).stdout
        assert "certificate (U at k = 2)" in report, fmt
        assert "29 PASS, 0 FAIL, 1 INDETERMINATE" in report, fmt


def test_a_header_without_a_register_snapshot_still_has_the_gauge_steps_budget():
    header = {k: v for k, v in session_header_fields().items() if not k.startswith("gauge")}
    config = analysis_config(header)
    budget = config.budget_for("x")
    assert budget is not None
    assert [c.name for c in budget.contributions] == ["gauge step (r/2 rectangular)"]
    assert config.decision_rule == "guarded"
    assert analysis_config(header | {"decision_rule": "simple"}).decision_rule == "simple"
