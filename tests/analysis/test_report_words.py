"""Issue 26, item 6: the words say what happened. A verdict on 30 readings said "final from 25
readings", which reads as 25 judged; the report and the summary say how many were judged and
the minimum as a minimum."""

from __future__ import annotations

import numpy as np

from station.analysis.capability import SpecLimits
from station.analysis.report import format_report
from station.analysis.summary import AnalysisConfig, analyze


def _analysis(n: int):
    rng = np.random.default_rng(3)
    readings = {name: rng.normal(0, 0.0002, n).round(5) for name in ("x", "y", "z")}
    config = AnalysisConfig(
        default_limits=SpecLimits(-0.001, 0.001), resolution=0.00001, unit="in", min_n=25
    )
    return analyze(readings, config)


def test_the_report_says_how_many_readings_were_judged_and_the_minimum() -> None:
    text = " ".join(format_report(_analysis(30)).split())
    assert "Judged on 30 readings (a verdict needs 25)" in text
    assert "from 25 readings" not in text
