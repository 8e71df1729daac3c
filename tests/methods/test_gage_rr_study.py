"""The crossed Gage R&R's figures (AIAG MSA 4th ed.): AIAG's constants, AIAG's own worked example
(the average and range worksheet's published figures), a small study worked by hand, the sums
of squares against an independent ANOVA (statsmodels' ``anova_lm``), a simulated study whose
injected appraiser bias, part spread and repeatability it must recover, the verdict's bands and
the designs it refuses."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from station.analysis.constants import d2
from station.errors import StationError
from station.methods.gage_rr.study import (
    ACCEPTABLE,
    CONDITIONAL,
    INCONCLUSIVE,
    NOT_ACCEPTABLE,
    AnovaStudy,
    _verdict,
    gage_rr_study,
    k1,
    k2,
    k3,
)

# AIAG MSA 4th ed., the Gage R&R example: 3 appraisers x 10 parts x 3 trials; per (appraiser,
# trial) the readings of parts 1 to 10.
AIAG = {
    ("A", 1): [0.29, -0.56, 1.34, 0.47, -0.80, 0.02, 0.59, -0.31, 2.26, -1.36],
    ("A", 2): [0.41, -0.68, 1.17, 0.50, -0.92, -0.11, 0.75, -0.20, 1.99, -1.25],
    ("A", 3): [0.64, -0.58, 1.27, 0.64, -0.84, -0.21, 0.66, -0.17, 2.01, -1.31],
    ("B", 1): [0.08, -0.47, 1.19, 0.01, -0.56, -0.20, 0.47, -0.63, 1.80, -1.68],
    ("B", 2): [0.25, -1.22, 0.94, 1.03, -1.20, 0.22, 0.55, 0.08, 2.12, -1.62],
    ("B", 3): [0.07, -0.68, 1.34, 0.20, -1.28, 0.06, 0.83, -0.34, 2.19, -1.50],
    ("C", 1): [0.04, -1.38, 0.88, 0.14, -1.46, -0.29, 0.02, -0.46, 1.77, -1.49],
    ("C", 2): [-0.11, -1.13, 1.09, 0.20, -1.07, -0.67, 0.01, -0.56, 1.45, -1.77],
    ("C", 3): [-0.15, -0.96, 0.67, 0.11, -1.45, -0.49, 0.21, -0.49, 1.87, -2.16],
}


def rows(table: dict) -> tuple[list, list, list, list]:
    """(parts, appraisers, trials, values), one entry per reading."""
    parts, appraisers, trials, values = [], [], [], []
    for (appraiser, trial), readings in table.items():
        for part, value in enumerate(readings, start=1):
            parts.append(part)
            appraisers.append(appraiser)
            trials.append(trial)
            values.append(value)
    return parts, appraisers, trials, values


def test_the_constants_are_aiags():
    """K1 by trials, K2 by appraisers, K3 by parts, as AIAG's worksheet tables print them."""
    assert [round(k1(r), 4) for r in (2, 3)] == [0.8862, 0.5908]
    assert [round(k2(k), 4) for k in (2, 3)] == [0.7071, 0.5231]
    published = [0.7071, 0.5231, 0.4467, 0.4030, 0.3742, 0.3534, 0.3375, 0.3249, 0.3146]
    assert [round(k3(n), 4) for n in range(2, 11)] == published


def test_aiag_example_gives_the_published_average_and_range_figures():
    study = gage_rr_study(*rows(AIAG))
    xr = study.xbar_r
    # Published (AIAG MSA 4th ed., the GRR report of this example): R̄̄ 0.3417, X̄diff 0.4447,
    # R_p 3.511; EV 0.20188, AV 0.22963, GRR 0.30575, PV 1.10456, TV 1.14610; %EV 17.62,
    # %AV 20.04, %GRR 26.68, %PV 96.38; ndc 5. AIAG multiplies by its 4-decimal K1, K3 and
    # R̄̄ rounded to 4 decimals: the last digit may differ by that rounding.
    assert xr.rbarbar == pytest.approx(0.34167, abs=1e-5)
    assert xr.xdiff == pytest.approx(0.44467, abs=1e-5)
    assert xr.part_range == pytest.approx(3.5111, abs=1e-4)
    assert xr.ev == pytest.approx(0.20188, abs=5e-5)
    assert xr.av == pytest.approx(0.22963, abs=1e-4)
    assert xr.grr == pytest.approx(0.30575, abs=1e-4)
    assert xr.pv == pytest.approx(1.10456, abs=2e-4)
    assert xr.tv == pytest.approx(1.14610, abs=2e-4)
    pct = {name: xr.pct(getattr(xr, name)) for name in ("ev", "av", "grr", "pv")}
    assert pct == pytest.approx({"ev": 17.62, "av": 20.04, "grr": 26.68, "pv": 96.38}, abs=0.02)
    assert xr.ndc == 5
    # AIAG's own remark on the example: appraiser B's range on part 4 (1.02) is beyond UCL_R.
    assert [(p, a) for p, a, _ in xr.ranges_out] == [("4", "B")]
    assert xr.ucl_r == pytest.approx(2.574591 * 0.341667, abs=1e-5)


def test_the_anova_agrees_with_statsmodels_and_the_expected_mean_squares():
    """Sums of squares, degrees of freedom and the interaction's F and p against statsmodels'
    two-way ANOVA of the same readings; the components from the expected mean squares written
    out here; the interaction (p 0.974) is pooled, as AIAG does."""
    pd = pytest.importorskip("pandas")
    ols = pytest.importorskip("statsmodels.formula.api").ols
    anova_lm = pytest.importorskip("statsmodels.stats.anova").anova_lm
    parts, appraisers, trials, values = rows(AIAG)
    frame = pd.DataFrame({"part": parts, "appraiser": appraisers, "value": values})
    fitted = ols("value ~ C(part) * C(appraiser)", data=frame).fit()
    reference = anova_lm(fitted, typ=2)
    study = gage_rr_study(parts, appraisers, trials, values)
    table = {row.source: row for row in study.anova.table}
    for ours, theirs in (
        ("part", "C(part)"),
        ("appraiser", "C(appraiser)"),
        ("part x appraiser", "C(part):C(appraiser)"),
        ("repeatability", "Residual"),
    ):
        assert table[ours].ss == pytest.approx(reference.loc[theirs, "sum_sq"], rel=1e-10)
        assert table[ours].df == reference.loc[theirs, "df"]
    # The interaction is tested against repeatability in both models.
    interaction = table["part x appraiser"]
    assert interaction.f == pytest.approx(reference.loc["C(part):C(appraiser)", "F"], rel=1e-9)
    assert interaction.p == pytest.approx(0.9741, abs=1e-4)
    assert study.anova.pooled
    # Pooled: MS_E' = (SS_PA + SS_E) / (df_PA + df_E); the components from it.
    ms = (table["part x appraiser"].ss + table["repeatability"].ss) / (18 + 60)
    assert study.anova.var_repeatability == pytest.approx(ms, rel=1e-12)
    assert study.anova.var_appraiser == pytest.approx((table["appraiser"].ms - ms) / 30)
    assert study.anova.var_part == pytest.approx((table["part"].ms - ms) / 9)
    assert study.anova.var_interaction == 0
    # Minitab's Gage R&R (ANOVA) of this example: repeatability 0.03997, reproducibility
    # 0.05146, part 1.08645; %study variation of GRR 27.86; ndc 4.
    assert study.anova.var_repeatability == pytest.approx(0.039973, abs=1e-6)
    assert study.anova.var_reproducibility == pytest.approx(0.051455, abs=1e-6)
    assert study.anova.var_part == pytest.approx(1.086447, abs=1e-6)
    assert study.anova.pct_grr == pytest.approx(27.86, abs=0.01)
    assert study.anova.ndc == 4
    # 6σ spreads: GRR = 6·√(σ²_E + σ²_A).
    assert study.anova.grr == pytest.approx(6 * math.sqrt(0.039973 + 0.051455), abs=1e-5)
    # Pooled, parts and appraisers are tested against MS_E' with 78 degrees of freedom.
    pooled = {row.source: row for row in study.anova.pooled_table}
    assert pooled["appraiser"].f == pytest.approx(table["appraiser"].ms / ms)
    assert pooled["appraiser"].p == pytest.approx(stats.f.sf(table["appraiser"].ms / ms, 2, 78))


# A small study worked by hand: 3 parts x 2 appraisers x 2 trials.
HAND = {
    ("A", 1): [1.0, 5.0, 9.0],
    ("A", 2): [3.0, 7.0, 9.0],
    ("B", 1): [4.0, 6.0, 12.0],
    ("B", 2): [4.0, 10.0, 14.0],
}


def test_a_small_study_worked_by_hand():
    """Cell means P1: A 2, B 4; P2: A 6, B 8; P3: A 9, B 13. Part means 3, 7, 11; appraiser
    means 17/3 and 25/3; grand mean 7.

    SS_P = 2·2·(16 + 0 + 16) = 128 (df 2); SS_A = 3·2·(2·(4/3)²) = 64/3 (df 1);
    interaction residuals ±1/3 (four cells) and ±2/3 (two): SS_PA = 2·(4/9 + 8/9) = 8/3 (df 2);
    within the cells 2 + 0 + 2 + 8 + 0 + 2 = 14 (df 6); total 166.
    F_PA = (4/3)/(14/6) = 4/7, p = (1 + 2F/6)^-3 = (21/25)³ = 0.5927 > 0.25: pooled,
    MS_E' = (8/3 + 14)/8 = 25/12. σ²_A = (64/3 − 25/12)/6 = 231/72, σ²_P = (64 − 25/12)/4 =
    743/48."""
    study = gage_rr_study(*rows(HAND))
    table = {row.source: row for row in study.anova.table}
    assert [table[s].ss for s in ("part", "appraiser", "part x appraiser", "repeatability")] == (
        pytest.approx([128.0, 64 / 3, 8 / 3, 14.0], rel=1e-12)
    )
    assert [table[s].df for s in ("part", "appraiser", "part x appraiser", "repeatability")] == [
        2, 1, 2, 6,
    ]  # fmt: skip
    assert table["total"].ss == pytest.approx(166.0)
    assert table["part x appraiser"].f == pytest.approx(4 / 7)
    assert study.anova.interaction_p == pytest.approx((21 / 25) ** 3, rel=1e-9)
    assert study.anova.pooled
    anova = study.anova
    assert anova.var_repeatability == pytest.approx(25 / 12)
    assert anova.var_appraiser == pytest.approx(231 / 72)
    assert anova.var_part == pytest.approx(743 / 48)
    grr = 25 / 12 + 231 / 72
    assert anova.grr == pytest.approx(6 * math.sqrt(grr))
    assert anova.tv == pytest.approx(6 * math.sqrt(grr + 743 / 48))
    assert anova.pct_grr == pytest.approx(100 * math.sqrt(grr / (grr + 743 / 48)))  # 50.5 %
    assert anova.ndc == math.floor(1.41 * math.sqrt((743 / 48) / grr)) == 2
    # Average and range: ranges A 2, 2, 0 and B 0, 4, 2: R̄̄ = 5/3; X̄diff = 8/3; R_p = 8.
    xr = study.xbar_r
    assert (xr.rbarbar, xr.xdiff, xr.part_range) == pytest.approx((5 / 3, 8 / 3, 8.0))
    ev = (5 / 3) / d2(2)  # K1 = 1/d2(2) = √π/2
    assert xr.ev == pytest.approx(ev)
    assert xr.av == pytest.approx(math.sqrt((8 / 3 / math.sqrt(2)) ** 2 - ev**2 / 6))
    assert xr.pv == pytest.approx(8 * 0.52314, abs=1e-4)  # K3(3) = 1/1.91155
    assert study.verdict == NOT_ACCEPTABLE and study.acceptable is False
    assert study.parts == ("1", "2", "3") and study.appraisers == ("A", "B")


def test_an_interaction_that_stays_is_tested_and_counted():
    """Appraiser B reads parts 1 and 2 swapped against A: a strong interaction (p < 0.25) stays
    in the model, parts and appraisers are tested against it, and it counts in reproducibility."""
    table = {
        ("A", 1): [1.0, 2.0, 3.0], ("A", 2): [1.1, 2.1, 3.1],
        ("B", 1): [2.0, 1.0, 3.0], ("B", 2): [2.1, 1.1, 3.1],
    }  # fmt: skip
    study = gage_rr_study(*rows(table))
    anova = study.anova
    rows_by = {row.source: row for row in anova.table}
    assert anova.interaction_p < 0.25 and not anova.pooled and anova.pooled_table is None
    ms_e, ms_pa = rows_by["repeatability"].ms, rows_by["part x appraiser"].ms
    assert ms_e == pytest.approx(0.005)  # two readings 0.1 apart: SS 0.005 a cell, 6 cells, 6 df
    assert anova.var_interaction == pytest.approx((ms_pa - ms_e) / 2)
    assert rows_by["part"].f == pytest.approx(rows_by["part"].ms / ms_pa)
    assert anova.var_reproducibility == pytest.approx(anova.var_appraiser + anova.var_interaction)
    # The appraisers' means are equal: their component is negative, taken as 0, and said.
    assert anova.var_appraiser == 0 and "appraiser" in anova.zeroed
    assert any("negative" in note for note in study.notes())


def test_a_simulated_study_recovers_the_injected_components():
    """10 parts of spread 1.0, appraisers reading 0.15 low, right and 0.15 high, the gauge's
    repeatability σ 0.05, 3 trials. In a crossed study the parts cancel out of the appraisers'
    means, so the components come back within their sampling error: repeatability within its
    χ² interval (78 degrees of freedom, 99.9 %), the appraiser component within what the noise
    of their means allows, the part component within the noise about the parts' own spread."""
    rng = np.random.default_rng(25)
    sizes = rng.normal(0.0, 1.0, 10)
    offsets = {"A": -0.15, "B": 0.0, "C": 0.15}
    sigma = 0.05
    parts, appraisers, trials, values = [], [], [], []
    for trial in (1, 2, 3):
        for appraiser, offset in offsets.items():
            for part in rng.permutation(10):
                parts.append(int(part) + 1)
                appraisers.append(appraiser)
                trials.append(trial)
                values.append(sizes[part] + offset + rng.normal(0.0, sigma))
    study = gage_rr_study(parts, appraisers, trials, values, tolerance=3.0)
    anova = study.anova
    assert anova.pooled  # no interaction was injected
    df = 78
    low, high = stats.chi2.ppf([0.0005, 0.9995], df) / df
    assert low * sigma**2 <= anova.var_repeatability <= high * sigma**2
    # σ²_A estimates the offsets' variance (0.0225); each appraiser mean carries noise of
    # σ/√30, so the estimate is off by about 2·0.15·σ/√30·√2 ≈ 0.004 at most 4 of those.
    assert anova.var_appraiser == pytest.approx(np.var(list(offsets.values()), ddof=1), abs=0.016)
    assert anova.var_part == pytest.approx(np.var(sizes, ddof=1), rel=0.05)
    # Average and range: EV estimates σ, and the appraisers' averages the offsets.
    assert study.xbar_r.ev == pytest.approx(sigma, rel=0.25)
    means = dict(zip(study.appraisers, study.xbar_r.appraiser_means, strict=True))
    assert means["C"] - means["A"] == pytest.approx(0.30, abs=4 * sigma * math.sqrt(2 / 30))


def anova_of(var_repeatability: float, var_part: float, tolerance: float | None = None):
    """An ANOVA result holding only the variances the verdict reads."""
    return AnovaStudy(
        table=(), pooled_table=None, interaction_p=1.0, pooled=True, pool_above=0.25,
        var_repeatability=var_repeatability, var_appraiser=0.0, var_interaction=0.0,
        var_part=var_part, zeroed=(), tolerance=tolerance,
    )  # fmt: skip


def test_the_verdict_takes_aiags_bands():
    # %GRR = 100·√(GRR/TV) in variances: 9.9 % / 10.0 % / 30.0 % / 31 %.
    assert _verdict(anova_of(0.0098, 0.9902))[0] == ACCEPTABLE
    assert _verdict(anova_of(0.01, 0.99))[0] == CONDITIONAL  # 10 % is no longer under 10 %
    assert _verdict(anova_of(0.0961, 0.9039))[0] == NOT_ACCEPTABLE
    # 28 %: within the conditional band, but ndc = floor(1.41·√(0.9216/0.0784)) = 4 < 5.
    word, sentence, accepted = _verdict(anova_of(0.0784, 0.9216))
    assert word == NOT_ACCEPTABLE and "fewer than 5 distinct categories" in sentence
    assert accepted is False
    # With a tolerance the worse of the two is judged: 9.9 % of TV but 6·√0.0098/4 = 14.8 %.
    word, sentence, accepted = _verdict(anova_of(0.0098, 0.9902, tolerance=4.0))
    assert word == CONDITIONAL and "14.8 % of the tolerance" in sentence and accepted is None
    # Readings that never vary between trials or appraisers cannot judge the gauge.
    assert _verdict(anova_of(0.0, 1.0))[0] == INCONCLUSIVE


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (lambda r: r[:-1], "part 3 by appraiser B has no trial 2"),
        (lambda r: [x for x in r if x[1] == "A"], "2 or more appraisers; the readings name 1 (A)"),
        (lambda r: [x for x in r if x[0] == 1], "2 or more parts; the readings name 1 (1)"),
        (lambda r: [x for x in r if not (x[0] == 2 and x[1] == "B")], "part 2 was not measured"),
        (lambda r: [*r, (1, "A", 1, 2.0)], "part 1 by appraiser A has trial 1 twice"),
        (lambda r: [x for x in r if x[2] == 1], "repeatability needs 2 or more trials"),
        (lambda r: [(1, "A", 1, math.nan), *r[1:]], "part 1 by appraiser A, trial 1 is not a"),
    ],
)
def test_a_design_it_cannot_analyse_is_one_sentence_naming_what_is_missing(change, message):
    readings = list(zip(*rows(HAND), strict=True))
    changed = change(readings)
    with pytest.raises(StationError) as refused:
        gage_rr_study(*zip(*changed, strict=True))
    assert message in refused.value.message and "\n" not in refused.value.message


def test_the_report_labels_both_methods():
    text = "\n".join(gage_rr_study(*rows(AIAG), tolerance=6.0, unit="mm").lines())
    assert text.startswith("GAGE R&R (CROSSED): NOT ACCEPTABLE")
    assert "ANOVA METHOD (two-way crossed" in text
    assert "The interaction (p = 0.974 > 0.25) is pooled into repeatability:" in text
    assert "6·SD is the study variation (mm); ndc = 1.41·PV/GRR = 4 (truncated)" in text
    assert "AVERAGE AND RANGE METHOD (AIAG MSA 4th ed. worksheet; figures are 1 SD)" in text
    assert "%GRR 26.7" in text and "ndc = 5 (truncated)" in text
    # Its tables fit the TUI summary's 74 columns unwrapped; the sentences wrap to it.
    tables = [line for line in text.splitlines() if "6·SD" in line or "  part" in line]
    assert tables and all(len(line) <= 74 for line in tables)


class Kit:
    """The chart kit a report gives a method (station.record.charts), in its simplest form."""

    point, centre, limit, alarm = "C0", "black", "red", "magenta"

    def figure(self, width: float = 7.0, height: float = 3.2):
        from matplotlib.figure import Figure

        return Figure(figsize=(width, height))

    def label(self, text: object) -> str:
        return str(text)


def test_the_charts_draw_the_studys_figures():
    from station.methods.gage_rr import charts

    study = gage_rr_study(*rows(AIAG), names={"A": "Ann"})
    cells = study.data.mean(axis=2)
    interaction = charts.interaction_chart(study, Kit()).axes[0]
    lines = {line.get_label(): line.get_ydata() for line in interaction.get_lines()}
    assert set(lines) == {"A (Ann)", "B", "C"}
    for j, label in enumerate(("A (Ann)", "B", "C")):
        assert np.allclose(lines[label], cells[:, j])
    assert "p = 0.974, pooled" in interaction.get_title()
    ranges = charts.range_chart(study, Kit()).axes[0]
    levels = {line.get_label(): line.get_ydata()[0] for line in ranges.get_lines()[-2:]}
    assert levels == pytest.approx({"R̄̄ 0.3417": 0.341667, "UCL 0.8797": 0.879652}, abs=1e-6)
    # Appraiser B's range on part 4, beyond UCL_R, is flagged where B's ranges run (10 + 4).
    (flagged,) = ranges.collections
    assert flagged.get_offsets().tolist() == [[14.0, pytest.approx(1.02)]]
    by_part = charts.by_part_chart(study, Kit()).axes[0]
    means = next(line for line in by_part.get_lines() if line.get_label() == "part mean")
    assert np.allclose(means.get_ydata(), study.data.mean(axis=(1, 2)))
    by_appraiser = charts.by_appraiser_chart(study, Kit()).axes[0]
    tick_labels = [tick.get_text() for tick in by_appraiser.get_xticklabels()]
    assert tick_labels == ["A (Ann)", "B", "C"]


def test_the_procedure_counts_trials_and_asks_for_two_at_least():
    """The built-in procedure: a trial block holding a parts step per appraiser (A, B, C) of
    ten parts; the set-up counts trials, 3 by default and never fewer than 2."""
    from station.methods import method_of
    from station.procedures import discover_procedures

    procedure = discover_procedures(use_env=False).get("gage_rr")
    assert procedure.analysis == "gage_rr"
    (block,) = [step for step in procedure.steps if step.kind == "repeat"]
    parts = [step for step in block.steps if step.kind == "parts"]
    assert [(s.id, s.count_target) for s in parts] == [("A", 10), ("B", 10), ("C", 10)]
    count = method_of("gage_rr").count_field(procedure)
    assert (count.label, count.setup_key, count.target, count.minimum) == (
        "Trials", "placements", 3, 2,
    )  # fmt: skip
    assert "AIAG asks for 3 with 3 appraisers" in count.hint
