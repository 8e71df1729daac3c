"""The text report: the report's figures and layout, plain text, at most 80 columns."""

from __future__ import annotations

import re

import numpy as np
import pytest

from station.analysis.capability import SpecLimits
from station.analysis.report import format_histogram, format_report
from station.analysis.summary import AnalysisConfig, analyze
from station.text import verdict_word

LIMITS = SpecLimits(lsl=-0.001, usl=0.001, nominal=0.0)


def report_of(channels, width: int = 80, **config) -> str:
    settings = dict(default_limits=LIMITS, resolution=0.0001, unit="in")
    settings.update(config)
    analysis = analyze(
        {k: np.asarray(v, float) for k, v in channels.items()}, AnalysisConfig(**settings)
    )
    return format_report(
        analysis, title="BASIC STATISTICS COMPREHENSIVE REPORT ON hht1", width=width
    )


def assert_fits(text: str, width: int) -> None:
    longest = max(text.splitlines(), key=len)
    assert len(longest) <= width, longest
    assert "\x1b" not in text  # no colour codes: the report is filed and printed


def test_table_2_1_report_shows_the_reports_figures(table_2_1):
    text = report_of({"x": table_2_1})
    for figure in [
        "MAXIMUM: +0.00070",
        "AVERAGE: +0.00008",
        "MINIMUM: -0.00050",
        "UPPER SPEC: +0.00100",
        "NOMINAL: +0.00000",
        "LOWER SPEC: -0.00100",
        "TOTAL NUMBER OF PIECES: 30",
        "SIGMA: 0.00026",  # a spread has no sign
        "RANGE: 0.00120",
        "MODE: +0.00020",
        "SKEWNESS a1: -0.356",
        "PIECES ABOVE UPPER SPEC: 0   PERCENT ABOVE UPPER SPEC: 0.00",
        "PIECES BELOW LOWER SPEC: 0   PERCENT BELOW LOWER SPEC: 0.00",
        "Cp 1.26   Cpu 1.17   Cpl 1.36   Cpk 1.17",
        "VERDICT: INCONCLUSIVE (Cpk 1.17; Bissell 95% bounds 0.90 to 1.44 straddle 1: 77",
        "by the report's rule: capable, Cpk 1.17",
        "CAPABILITY (overall sigma 0.00026: report §2.7.3's Cp/Cpk, ISO 22514-2's Pp/Ppk)",
        "Cp (Pp)   95% interval 0.94 to 1.59 (chi-square)",
        "Cpk (Ppk) 95% interval 0.84 to 1.49, one-sided bounds 0.90 and 1.44 (Bissell)",
        "Cp within",
        "CONTROL CHART: I-MR",
        "ALARMS (rules: report): none",
    ]:
        assert figure in text, figure
    assert_fits(text, 80)


def test_readings_are_numbered_down_three_columns_like_the_report(table_2_1):
    lines = report_of({"x": table_2_1}).splitlines()
    header = next(i for i, line in enumerate(lines) if line.split()[:1] == ["PIECE"])
    assert lines[header].split() == ["PIECE", "MEASUREMENT"] * 3
    assert lines[header + 1].split() == ["1", "+0.00020", "11", "+0.00030", "21", "+0.00040"]
    assert lines[header + 10].split() == ["10", "+0.00010", "20", "-0.00010", "30", "+0.00000"]


def test_histogram_bars_count_the_readings_and_mark_the_limits(table_2_1):
    text = report_of({"x": table_2_1})
    rows = {line.split()[0]: line for line in text.splitlines() if " |" in line}
    assert rows["+0.00020"].count("#") > rows["+0.00010"].count("#") > 0
    assert rows["+0.00020"].split()[-1] == "7"  # the mode, 7 times
    assert rows["-0.00100"].endswith("<LSL") and rows["+0.00100"].endswith("<USL")
    assert rows["+0.00000"].endswith("<NOM")


def test_histogram_without_limits_has_no_marks():
    from station.analysis.descriptive import histogram

    lines = format_histogram(histogram([1.0, 2.0, 2.0], 1.0), None, 1)
    assert [line.split()[-1] for line in lines] == ["1", "2"]


def test_no_limits_is_undefined_with_the_reason(table_2_1):
    text = report_of({"x": table_2_1}, default_limits=None)
    assert re.search(r"VERDICT: UNDEFINED \(no specification limits", text)
    assert "UPPER SPEC: -" in text and "Cp undefined" in text
    assert "CONTROL CHART: I-MR" in text


def test_incapable_alarms_3d_and_hints_are_reported():
    rng = np.random.default_rng(6)
    x = np.round(rng.normal(0.0006, 0.0002, 30), 4)
    x[25] = 0.004
    channels = {"x": x, "y": np.round(rng.normal(0, 1e-4, 30), 4), "z": np.zeros(30) + 1e-4}
    text = report_of(channels, rule_set="nelson")
    assert "VERDICT: NOT CAPABLE (Cpk" in text
    # Rules are named in words, and each alarm says whether the live analysis raised it.
    assert "ALARMS (rules: nelson; retrospective chart):" in text
    assert "Nelson rule 1 (a point beyond the control limits) [" in text
    assert "]: Cycle 26 is above" in text
    assert "PIECES ABOVE UPPER SPEC: 1   PERCENT ABOVE UPPER SPEC: 3.33" in text
    assert "3-D FIGURES (x, y, z; 30 cycles)" in text
    assert "ISO 9283 pose repeatability RP = l-bar + 3 S_l:" in text
    hints = " ".join(text.split("HINTS", 1)[1].split())
    assert "- x: the control chart shows a pattern (" in hints
    assert "Nelson rule 1 (a point beyond the control limits) at cycle 26" in " ".join(
        hints.split()
    )
    assert_fits(text, 80)


@pytest.mark.parametrize("width", [72, 80, 100])
def test_no_line_is_longer_than_the_width(width):
    rng = np.random.default_rng(1)
    channels = {name: rng.normal(0, 3e-4, 40) for name in ("x", "y", "z", "a_long_channel_name")}
    text = report_of(channels, width=width, subgroup=4, rule_set="western-electric")
    assert_fits(text, width)
    assert "CONTROL CHART: Xbar-R, subgroup 4" in text and "R chart:" in text


def test_verdict_words():
    from station.analysis.capability import capability

    values = [0.0, 0.0001, -0.0001, 0.0002]
    assert verdict_word(capability(values, LIMITS)) == "CAPABLE"
    assert verdict_word(capability(values, SpecLimits(-0.0001, 0.0001))) == "NOT CAPABLE"
    assert verdict_word(capability([0.0], LIMITS)) == "UNDEFINED"


def test_notes_and_excluded_cycles_appear_under_the_title(table_2_1):
    analysis = analyze(
        {"x": np.array(table_2_1)}, AnalysisConfig(default_limits=LIMITS), excluded_cycles=[3]
    )
    text = format_report(analysis, notes=["Robot: r1, operator: ann"])
    head = text.split("FEATURE:", 1)[0]
    assert "Robot: r1, operator: ann" in head and "Excluded (rejected) cycles: 3" in head
