"""The summary's verdict states its confidence (issue 20): the bounds beside each Cpk, the
readings that would settle an INCONCLUSIVE word and the report's own rule beside it."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from rich.cells import cell_len

from station.analysis.capability import SpecLimits
from station.analysis.summary import AnalysisConfig, analyze
from station.tui.screens.summary import SummaryView, verdict_text

TABLE_2_1 = Path(__file__).resolve().parents[2] / "sessions" / "examples" / "table-2-1.csv"


def table_2_1() -> list[float]:
    lines = TABLE_2_1.read_text().splitlines()
    return [float(line.split(",")[1]) for line in lines if line[:1].isdigit()]


def test_table_2_1_summary_is_inconclusive_with_bounds_and_the_reports_rule():
    config = AnalysisConfig(default_limits=SpecLimits(-0.001, 0.001), resolution=0.0001)
    analysis = analyze({"x": np.array(table_2_1())}, config)
    view = SummaryView(
        path=Path("t.jsonl"), header={"unit": "in"}, analysis=analysis, last_hash="", status="x"
    )
    text = verdict_text(view).plain
    assert text.startswith("Verdict: INCONCLUSIVE")
    assert "capable when Cpk's 95% lower bound ≥ 1" in text
    assert "(lower–upper) its one-sided 95% bounds, Bissell" in text
    assert "x  INCONCLUSIVE Cp 1.26  Cpk 1.17 (0.90–1.44)" in text
    assert "77 readings settle it; by the report's rule: capable, Cpk 1.17 >= 1" in text
    # The U the readings were decided with (the gauge step alone: r/√12 at k = 2; the view
    # has no resolution, so six decimals).
    assert "measurement U 0.000058 in, k = 2: 30 PASS 0 FAIL 0 INDETERMINATE" in text
    # Each axis line fits the summary at 80 columns (the header wraps as the widget does).
    assert all(cell_len(line) <= 74 for line in text.splitlines()[1:]), text
