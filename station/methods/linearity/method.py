"""The linearity method: per stroke the least-squares and minimum-zone straightness of h and v
against the scale s, per direction, the path repeatability along the bar, and Cp/Cpk of the
straightness against the tolerance; its charts are each indicator's profiles along the bar."""

from __future__ import annotations

import csv
from collections.abc import Iterator, Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from station.analysis.linearity import (
    analyze_linearity,
    linearity_json,
    linearity_summary,
    tolerance_from_limits,
)
from station.analysis.report import format_linearity
from station.methods.contract import Chart, ChartKit, DemoRig, Judgement, Method, MethodInputs
from station.methods.linearity.strokes import (
    TABLE_COLUMNS,
    LiveStrokes,
    session_stroke_profiles,
    table_stroke_profiles,
)
from station.methods.tables import export_comments, number
from station.procedures import AnalysisNeeds

if TYPE_CHECKING:
    from _typeshed import SupportsWrite

    from station.analysis.strokes import StrokeProfile
    from station.analysis.summary import AnalysisConfig
    from station.instruments.simulator import GaugeSpec
    from station.session.model import Session

BAR_CHANNEL_MAP = {"1": "h", "2": "v", "3": "s"}
BAR_PUSH_RATE = 200.0
"""Sets a second the simulated bar's indicators and scale send (a linear-scale counter's rate)."""
LIMITS_HELP = (
    "Strokes: the limits about the bar's line make a straightness tolerance of USL − LSL "
    "(±0.001 → 0.002); each stroke's straightness (never below 0) is judged one-sided "
    "against it: Cpk = (tolerance − X̄)/3σ, Cp is not defined."
)


def _profiles(inputs: MethodInputs) -> list[StrokeProfile]:
    if inputs.table is not None:
        return table_stroke_profiles(inputs.table)
    assert inputs.session is not None
    return session_stroke_profiles(inputs.session)


def profile_chart(
    channel: str, result: Any, profiles: Sequence[StrokeProfile], unit: str, kit: ChartKit
) -> Any:
    """Every stroke's deviation along the bar (grey), the widest stroke in colour with its
    least-squares line and its minimum zone (two parallel lines)."""
    by_number = {p.number: p for p in profiles}
    figure = kit.figure()
    axes = figure.add_subplot()
    for profile in profiles:
        axes.plot(profile.s, profile.channels[channel], color="lightgrey", linewidth=0.8)
    widest = max(result.strokes, key=lambda r: r.straightness[channel].mz, default=None)
    if widest is not None and widest.number in by_number:
        profile = by_number[widest.number]
        s = np.asarray(profile.s, dtype=float)
        d = np.asarray(profile.channels[channel], dtype=float)
        straight = widest.straightness[channel]
        axes.plot(s, d, color=kit.point, linewidth=1.2, label=f"stroke {widest.number}")
        a, b = straight.ls_line
        axes.plot(
            s,
            a + b * s,
            color=kit.centre,
            label=f"LS line (LS {kit.number(straight.ls, signed=False)})",
        )
        a, b = straight.mz_line
        for offset in (-straight.mz / 2, straight.mz / 2):
            axes.plot(
                s,
                a + b * s + offset,
                color=kit.limit,
                linestyle="--",
                label=f"minimum zone (MZ {kit.number(straight.mz, signed=False)})"
                if offset > 0
                else None,
            )
    suffix = f" ({kit.label(unit)})" if unit else ""
    axes.set_title(f"Straightness profiles of {kit.label(channel)} along the bar")
    axes.set_xlabel("position s" + suffix)
    axes.set_ylabel(f"deviation {kit.label(channel)}{suffix}")
    kit.legend(axes)
    return figure


class Linearity(Method):
    """Straightness along a parallel bar, stroke by stroke."""

    name = "linearity"
    title = "LINEARITY REPORT"
    reads_columns_by_name = True
    needs = AnalysisNeeds(
        facet="direction", facet_words="a stroke step (streamed strokes)", implied=True
    )
    json_key = "linearity"
    options = ("tolerance",)
    export_layout = "wide"
    drift_chart = False
    limits_help = LIMITS_HELP
    demo_words = "a bar, indicators h and v, a scale s"

    def live(
        self, config: AnalysisConfig, channels: Sequence[str], header: Mapping[str, Any]
    ) -> LiveStrokes:
        """Each whole stroke, judged as it comes."""
        return LiveStrokes(config, channels, header)

    def batch(self, inputs: MethodInputs) -> Judgement:
        """The straightness of every whole stroke (``tolerance``: the zone width per stroke,
        else the session's, from its h/v limits)."""
        tolerance = inputs.option("tolerance")
        if tolerance is None:
            tolerance = tolerance_from_limits(inputs.config)
        result = analyze_linearity(_profiles(inputs), tolerance=tolerance, config=inputs.config)
        analysis = linearity_summary(result)
        block = tuple(format_linearity(result, analysis.config, inputs.width))
        return Judgement(analysis, result, (block,))

    def json(self, result: Any) -> dict[str, Any]:
        """Straightness per stroke and direction, path repeatability, capability."""
        return linearity_json(result)

    def count(self, result: Any) -> str:
        """``7 strokes``."""
        return f"{len(result.strokes)} strokes"

    def recognises(self, session: Session) -> bool:
        """Streamed points (a file from before headers named the method)."""
        return bool(session.samples)

    def charts(self, inputs: MethodInputs, judgement: Judgement, kit: ChartKit) -> Iterator[Chart]:
        """Each indicator's profiles along the bar."""
        result = judgement.result
        profiles = _profiles(inputs)
        unit = inputs.config.unit
        for channel in result.channels:
            yield (
                f"profile-{channel}",
                f"Linearity profiles of {channel}",
                profile_chart(channel, result, profiles, unit, kit),
            )

    def write_wide(self, session: Session, out: SupportsWrite[str]) -> int:
        """The whole strokes as ``stroke,s,h,v``: one row per point, strokes numbered as the
        analysis numbers them (split and trimmed as it splits and trims them)."""
        export_comments(session, out)
        writer = csv.writer(out, lineterminator="\n")
        writer.writerow(TABLE_COLUMNS)
        rows = 0
        for profile in session_stroke_profiles(session):
            h, v = profile.channels["h"], profile.channels["v"]
            for s, dh, dv in zip(profile.s, h, v, strict=True):
                writer.writerow((profile.number, number(s), number(dh), number(dv)))
                rows += 1
        return rows

    def demo_rig(self, gauge: GaugeSpec, seed: int, *, stroke_points: int) -> DemoRig:
        """A bar with a bow, a sag and a linear scale, a robot path with a wobble, pushing
        ``BAR_PUSH_RATE`` sets a second; ``stroke_points`` points per stroke."""
        from station.instruments.simulator import BarModel

        return DemoRig(
            BarModel(points=stroke_points, indicator=gauge),
            "a simulated parallel bar with indicators h, v and a scale s (seeded)",
            channel_map=BAR_CHANNEL_MAP,
            trigger="push",
            push_rate=BAR_PUSH_RATE,
        )


METHOD = Linearity()
