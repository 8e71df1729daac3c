"""The analysis engine: pure functions over arrays of readings, small frozen dataclasses out.

No I/O and no UI here. numpy and scipy are imported inside the functions, so importing this
package stays cheap for ``station --help`` and the TUI's start.
"""

from station.analysis.capability import (
    Capability,
    SpecLimits,
    bissell_interval,
    capability,
    cp_interval,
    cpk_lower_bound,
    cpk_upper_bound,
    readings_needed,
)
from station.analysis.charts import (
    CHART_TYPES,
    ControlChart,
    Limits,
    chart_type,
    control_chart,
    moving_ranges,
    pooled_sigma,
    sigma_within,
    subgroups,
)
from station.analysis.constants import ChartFactors, c4, chart_factors, d2, d3
from station.analysis.descriptive import (
    Descriptive,
    Histogram,
    as_readings,
    describe,
    histogram,
    mean_and_sd,
    modes_at_resolution,
)
from station.analysis.rules import RULE_SETS, Alarm, check_rules, rule_descriptions

__all__ = [
    "CHART_TYPES",
    "RULE_SETS",
    "Alarm",
    "Capability",
    "ChartFactors",
    "ControlChart",
    "Descriptive",
    "Histogram",
    "Limits",
    "SpecLimits",
    "as_readings",
    "bissell_interval",
    "c4",
    "capability",
    "chart_factors",
    "chart_type",
    "check_rules",
    "control_chart",
    "cp_interval",
    "cpk_lower_bound",
    "cpk_upper_bound",
    "d2",
    "d3",
    "describe",
    "histogram",
    "mean_and_sd",
    "modes_at_resolution",
    "moving_ranges",
    "pooled_sigma",
    "readings_needed",
    "rule_descriptions",
    "sigma_within",
    "subgroups",
]
