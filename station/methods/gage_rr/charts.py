"""The Gage R&R report's charts (drawn with the record's kit, so they look like every other
chart of a report): the readings by part, the readings by appraiser, the part × appraiser
interaction, and the range chart by appraiser with its limits."""

from __future__ import annotations

from typing import Any

import numpy as np

from station.analysis.constants import chart_factors
from station.methods.contract import ChartKit
from station.methods.gage_rr.study import GageRRStudy

MARKERS = ("o", "s", "^", "D", "v", "P", "X", "*")
"""One marker per appraiser (cycled), so the lines part without colour too."""


def _unit(study: GageRRStudy, kit: ChartKit) -> str:
    unit = kit.label(study.unit)
    return f" ({unit})" if unit else ""


def _part_ticks(axes: Any, study: GageRRStudy, kit: ChartKit) -> None:
    positions = np.arange(1, len(study.parts) + 1)
    axes.set_xticks(positions)
    axes.set_xticklabels([kit.label(part) for part in study.parts], fontsize=7)
    axes.set_xlabel("part")


def by_part_chart(study: GageRRStudy, kit: ChartKit) -> Any:
    """Every reading of each part (all appraisers and trials), and each part's mean: the
    parts should spread far more than any part's own readings."""
    figure = kit.figure()
    axes = figure.add_subplot()
    n, k, r = study.data.shape
    positions = np.repeat(np.arange(1, n + 1), k * r)
    axes.scatter(positions, study.data.reshape(-1), s=10, color=kit.point, alpha=0.5,
                 label="a reading")  # fmt: skip
    means = study.data.mean(axis=(1, 2))
    axes.plot(np.arange(1, n + 1), means, color=kit.centre, marker="D", label="part mean")
    _part_ticks(axes, study, kit)
    axes.set_ylabel("reading" + _unit(study, kit))
    axes.set_title("Readings by part")
    axes.legend(loc="best", fontsize=7)
    return figure


def by_appraiser_chart(study: GageRRStudy, kit: ChartKit) -> Any:
    """Each appraiser's readings (a box of all parts and trials) and their mean: an appraiser
    whose mean stands off reads with a bias of their own (reproducibility)."""
    figure = kit.figure()
    axes = figure.add_subplot()
    columns = [study.data[:, j, :].reshape(-1) for j in range(len(study.appraisers))]
    positions = np.arange(1, len(columns) + 1)
    axes.boxplot(columns, positions=positions, widths=0.5)
    axes.plot(positions, [c.mean() for c in columns], color=kit.centre, marker="D",
              label="appraiser mean")  # fmt: skip
    axes.set_xticks(positions)
    axes.set_xticklabels([kit.label(study.appraiser_label(a)) for a in study.appraisers])
    axes.set_xlabel("appraiser")
    axes.set_ylabel("reading" + _unit(study, kit))
    axes.set_title("Readings by appraiser")
    axes.legend(loc="best", fontsize=7)
    return figure


def interaction_chart(study: GageRRStudy, kit: ChartKit) -> Any:
    """Each appraiser's mean of each part, a line per appraiser: lines that run parallel (or
    on top of each other) show no interaction; lines that cross show appraisers who read some
    parts differently from others."""
    figure = kit.figure()
    axes = figure.add_subplot()
    cells = study.data.mean(axis=2)
    positions = np.arange(1, len(study.parts) + 1)
    for j, appraiser in enumerate(study.appraisers):
        axes.plot(positions, cells[:, j], marker=MARKERS[j % len(MARKERS)], linewidth=1,
                  label=kit.label(study.appraiser_label(appraiser)))  # fmt: skip
    _part_ticks(axes, study, kit)
    axes.set_ylabel("mean reading" + _unit(study, kit))
    anova = study.anova
    state = "pooled" if anova.pooled else "kept"
    axes.set_title(f"Part x appraiser interaction (p = {anova.interaction_p:.3f}, {state})")
    axes.legend(loc="best", fontsize=7, title="appraiser", title_fontsize=7)
    return figure


def range_chart(study: GageRRStudy, kit: ChartKit) -> Any:
    """The range of each part's trials, appraiser by appraiser, against R̄̄ and the R chart's
    limits (D3·R̄̄, D4·R̄̄): a range beyond the upper limit is a reading to repeat (AIAG); an
    appraiser whose ranges run high is less consistent than the others."""
    figure = kit.figure()
    axes = figure.add_subplot()
    n, k, r = study.data.shape
    ranges = np.ptp(study.data, axis=2)  # [part, appraiser]
    xr = study.xbar_r
    factors = chart_factors(r)
    flagged = False
    for j in range(k):
        positions = j * n + np.arange(1, n + 1)
        values = ranges[:, j]
        axes.plot(positions, values, marker="o", markersize=3, linewidth=1, color=kit.point)
        out = values > xr.ucl_r * (1 + 1e-12)
        if out.any():
            label = None if flagged else "beyond UCL: measure again"
            axes.scatter(positions[out], values[out], s=40, color=kit.alarm, zorder=3,
                         label=label)  # fmt: skip
            flagged = True
        if j:
            axes.axvline(j * n + 0.5, color="grey", linewidth=0.6)
    axes.axhline(xr.rbarbar, color=kit.centre, label=f"R̄̄ {xr.rbarbar:.4g}")
    axes.axhline(xr.ucl_r, color=kit.limit, linestyle="--", label=f"UCL {xr.ucl_r:.4g}")
    lcl = factors.D3 * xr.rbarbar
    if lcl > 0:
        axes.axhline(lcl, color=kit.limit, linestyle="--", label=f"LCL {lcl:.4g}")
    axes.set_xticks([j * n + (n + 1) / 2 for j in range(k)])
    axes.set_xticklabels([kit.label(study.appraiser_label(a)) for a in study.appraisers])
    axes.set_xlabel(f"appraiser (parts 1 to {n} each)")
    axes.set_ylabel(f"range of {r} trials" + _unit(study, kit))
    axes.set_title("Range chart by appraiser")
    axes.legend(loc="best", fontsize=7)
    return figure
