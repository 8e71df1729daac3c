"""The aggregate analysis and its JSON document."""

from __future__ import annotations

import json

import numpy as np
import pytest

from station.analysis.capability import SpecLimits
from station.analysis.document import to_json
from station.analysis.summary import AnalysisConfig, analyze
from station.errors import StationError

REPORT_LIMITS = SpecLimits(lsl=-0.001, usl=0.001, nominal=0.0)
CHANNEL_KEYS = {"n", "mean", "sd", "skewness", "mode", "min", "max", "range", "capability"}
CAPABILITY_KEYS = {
    "lsl",
    "usl",
    "cp",
    "cpu",
    "cpl",
    "cpk",
    "cpk_lower",
    "cp_within",
    "cpk_within",
    "threshold",
    "capable",
}
CHART_KEYS = {"type", "subgroup", "center", "ucl", "lcl", "sigma_within", "dispersion"}


def report_config(**changes) -> AnalysisConfig:
    settings = dict(default_limits=REPORT_LIMITS, resolution=0.0001, unit="in")
    settings.update(changes)
    return AnalysisConfig(**settings)


def test_table_2_1_gives_the_reports_figures(table_2_1):
    analysis = analyze({"x": np.array(table_2_1)}, report_config())
    x = analysis.channels["x"]
    assert x.descriptive.n == 30
    assert x.descriptive.mean == pytest.approx(7.67e-5, abs=5e-8)
    assert x.descriptive.sd == pytest.approx(2.64e-4, abs=5e-7)
    assert round(x.descriptive.skewness, 3) == -0.356
    assert x.descriptive.modes == (0.0002,)
    cap = x.capability
    assert (round(cap.cp, 2), round(cap.cpu, 2), round(cap.cpl, 2)) == (1.26, 1.17, 1.36)
    assert cap.capable is True
    assert x.chart.type == "I-MR"
    assert x.alarms == ()  # the report: "no patterns or signs of out of control"
    assert analysis.spatial is None
    assert analysis.hints == ()
    assert x.readings == tuple(table_2_1)


def test_json_document_has_every_documented_key_and_no_nan(table_2_1):
    document = to_json(analyze({"x": np.array(table_2_1)}, report_config()))
    text = json.dumps(document, allow_nan=False)  # raises on NaN or inf
    channel = json.loads(text)["channels"]["x"]
    assert CHANNEL_KEYS | {"chart", "alarms"} <= channel.keys()
    assert channel["capability"].keys() >= CAPABILITY_KEYS
    assert channel["chart"].keys() >= CHART_KEYS
    assert channel["chart"]["dispersion"].keys() >= {"center", "ucl", "lcl"}
    assert channel["mode"] == [0.0002]
    assert document["spatial"] is None
    assert document["hints"] == []
    assert document["excluded_cycles"] == []


def test_without_limits_statistics_and_chart_remain_and_capability_says_why(table_2_1):
    analysis = analyze({"x": np.array(table_2_1)}, AnalysisConfig(resolution=0.0001))
    x = analysis.channels["x"]
    assert x.capability.capable is None
    assert x.capability.cp is None and x.capability.cpk is None
    assert "no specification limits" in x.capability.message
    assert x.capability.sigma == pytest.approx(x.descriptive.sd)
    assert x.chart.ucl is not None
    capability = to_json(analysis)["channels"]["x"]["capability"]
    assert capability["cp"] is None and capability["capable"] is None


def test_per_channel_limits_override_the_default_and_one_sided_limits_work():
    rng = np.random.default_rng(7)
    channels = {"x": rng.normal(0, 1e-4, 30), "y": rng.normal(0, 1e-4, 30)}
    config = AnalysisConfig(
        limits={"y": SpecLimits(usl=0.001)}, default_limits=SpecLimits(-0.002, 0.002)
    )
    analysis = analyze(channels, config)
    assert analysis.channels["x"].capability.usl == 0.002
    y = analysis.channels["y"].capability
    assert (y.lsl, y.usl, y.cp) == (None, 0.001, None)
    assert y.cpk == pytest.approx(y.cpu)


def test_limits_for_a_channel_not_in_the_data_are_an_error():
    with pytest.raises(StationError, match="'q'"):
        analyze({"x": np.zeros(3) + [0, 1, 2]}, AnalysisConfig(limits={"q": REPORT_LIMITS}))


@pytest.mark.parametrize(
    "changes, words",
    [
        ({"subgroup": 0}, "subgroup"),
        ({"rule_set": "acme"}, "rule set"),
        ({"resolution": -1.0}, "resolution"),
        ({"threshold": 0.0}, "threshold"),
    ],
)
def test_bad_configuration_is_a_sentence(changes, words):
    with pytest.raises(StationError, match=words):
        AnalysisConfig(**changes)


def test_xyz_channels_give_the_spatial_figures_in_the_json():
    rng = np.random.default_rng(11)
    channels = {axis.upper(): rng.normal(0, 2e-4, 30) for axis in "xyz"}
    document = to_json(analyze(channels, report_config()))
    spatial = document["spatial"]
    assert spatial is not None
    assert set(spatial["offset"]) == {"x", "y", "z"}
    assert spatial["ap"]["p"] == pytest.approx(spatial["total_offset"])
    assert spatial["rp"] == pytest.approx(spatial["l_mean"] + 3 * spatial["l_sd"])


def test_subgroups_pick_the_xbar_chart_and_excluded_cycles_are_kept():
    rng = np.random.default_rng(5)
    analysis = analyze(
        {"x": rng.normal(0, 1e-4, 30)}, report_config(subgroup=5), excluded_cycles=[4, 9]
    )
    assert analysis.channels["x"].chart.type == "Xbar-R"
    assert len(analysis.channels["x"].chart.points) == 6
    assert to_json(analysis)["excluded_cycles"] == [4, 9]


def test_incapable_channels_are_listed():
    rng = np.random.default_rng(2)
    channels = {"x": rng.normal(0, 1e-4, 30), "y": rng.normal(0, 1e-3, 30)}
    analysis = analyze(channels, report_config())
    assert analysis.incapable_channels == ["y"]
