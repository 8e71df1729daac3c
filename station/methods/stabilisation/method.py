"""Position stabilisation time and overshoot (ISO 9283 §7.4, §7.5) as a method.

A session of it runs under the ``arrival`` trigger with ``[arrival] trace = N``: every return
to the fixture is a cycle, and its ``trace`` event holds the indicators from a few rows before
the robot came back into the working band until the set was taken (the approach, the ringing,
the rest). Each accepted cycle's trace gives one return's figures
(:mod:`~station.methods.stabilisation.settling`); the final position is the mean of the trace's
last settle time (the stillness the trigger waited for, from the header's arrival table).

The band is the command line's (``station analyze --band R``, e.g. the manufacturer's stated
limit), else 5 × the indicators' noise at rest pooled over the traces' still tails, never
narrower than two gauge steps: the report says which. The method gives figures, not a verdict
(the standard states figures; a limit on them is the buyer's), and judges no capability.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Mapping
from typing import TYPE_CHECKING, Any

import numpy as np

from station.errors import StationError
from station.methods.contract import Chart, ChartKit, Judgement, Method, MethodInputs
from station.methods.stabilisation.settling import (
    Stabilisation,
    lines,
    noise_band,
    return_settling,
    stabilisation,
    stated_band,
)
from station.methods.text import fitted
from station.plain import plain
from station.procedures import AnalysisNeeds

if TYPE_CHECKING:
    from station.session.model import Session
    from station.session.replay import Trace

NAME = "stabilisation"
DEFAULT_TAIL = 0.5
"""Seconds of still tail the final position is the mean of, when the header has no settle."""


def session_traces(session: Session) -> list[Trace]:
    """The traces of the accepted cycles, in cycle order (the last one written of a cycle);
    StationError when there are none."""
    accepted = set(session.accepted_cycles)
    found: dict[int, Trace] = {}
    for trace in session.traces:
        if trace.cycle in accepted:
            found[trace.cycle] = trace
    if not found:
        raise StationError(
            f"{plain(session.path)}: no return's trace is recorded: a stabilisation session "
            "takes its cycles under the arrival trigger with [arrival] trace = N in its "
            "procedure; capture a cycle."
        )
    return [found[c] for c in sorted(found)]


def settle_time(header: Mapping[str, Any] | None) -> float:
    """The arrival trigger's settle time the session recorded (the still tail), else 0.5 s."""
    arrival = ((header or {}).get("instruments") or {}).get("arrival") or {}
    settle = arrival.get("settle")
    return float(settle) if isinstance(settle, int | float) and settle > 0 else DEFAULT_TAIL


def settling_chart(result: Stabilisation, traces: list[Trace], kit: ChartKit) -> Any:
    """Each return's distance from its final position against the time since its first entry
    into the band, with the band."""
    unit = kit.label(result.unit)
    suffix = f" ({unit})" if unit else ""
    figure = kit.figure()
    axes = figure.add_subplot()
    for trace, figures in zip(traces, result.returns, strict=True):
        t, rows = trace.as_arrays()
        distance = np.sqrt(np.sum((rows - np.asarray(figures.final)) ** 2, axis=1))
        inside = np.flatnonzero(distance <= result.band.radius)
        start = t[inside[0]] if inside.size else t[0]
        axes.plot(t - start, distance, marker=".", markersize=3, label=f"cycle {trace.cycle}")
    axes.axhline(result.band.radius, color=kit.limit, linestyle="--", label="band")
    axes.set_ylim(0.0, max(4 * result.band.radius, (result.max_overshoot or 0.0) * 1.2))
    axes.set_xlabel("seconds since the first entry into the band")
    axes.set_ylabel("distance from the final position" + suffix)
    axes.set_title(f"Settling at each return (sampled every {result.interval:.3g} s)")
    kit.legend(axes)
    return figure


class StabilisationMethod(Method):
    """Position stabilisation time and overshoot, ISO 9283 §7.4–7.5 (see the module)."""

    name = NAME
    title = "POSITION STABILISATION REPORT (ISO 9283 §7.4, §7.5)"
    needs = AnalysisNeeds(
        facet="counts",
        facet_words="a cycles step (the returns, under the arrival trigger with [arrival] trace)",
        limits=False,
    )
    json_key = "stabilisation"
    options = ("band",)
    drift_chart = False

    def judge(self, inputs: MethodInputs) -> tuple[Stabilisation, list[Trace]]:
        """The figures of a session's traces, and the traces."""
        if inputs.session is None:
            raise StationError(
                "the stabilisation time needs a session file: a table of readings holds no "
                "trace of each return."
            )
        traces = session_traces(inputs.session)
        tail = settle_time(inputs.header)
        resolution = float(inputs.config.resolution or 0.0)
        stated = inputs.option("band")
        if stated is not None:
            band = stated_band(float(stated))
        else:
            band = noise_band([t.as_arrays() for t in traces], tail, resolution)
        returns = []
        for trace in traces:
            t, rows = trace.as_arrays()
            if rows.shape[0] < 2:
                continue
            returns.append(return_settling(trace.cycle, t, rows, band.radius, tail=tail))
        result = stabilisation(
            returns,
            band,
            axes=traces[0].channels,
            unit=inputs.config.unit,
            resolution=resolution,
        )
        return result, traces

    def batch(self, inputs: MethodInputs) -> Judgement:
        """The stabilisation time and overshoot of each return and over them (no capability
        verdict: the standard states figures)."""
        result, _ = self.judge(inputs)
        return Judgement(None, result, (fitted(lines(result), inputs.width),))

    def json(self, result: Any) -> dict[str, Any]:
        """``band``, ``sampling_interval``, ``returns`` and the means and largest figures."""
        data: dict[str, Any] = result.as_json()
        return data

    def count(self, result: Any) -> str:
        """``3 returns``."""
        n = len(result.returns)
        return f"{n} return" + ("" if n == 1 else "s")

    def charts(self, inputs: MethodInputs, judgement: Judgement, kit: ChartKit) -> Iterator[Chart]:
        """The distance from the final position over time at each return, with the band."""
        result, traces = self.judge(inputs)
        if not math.isfinite(result.interval):
            return
        kept = [t for t in traces if any(r.cycle == t.cycle for r in result.returns)]
        yield (
            "settling",
            "Distance from the final position at each return",
            settling_chart(result, kept, kit),
        )


METHOD = StabilisationMethod()
"""Position stabilisation time and overshoot, ISO 9283 §7.4–7.5: from the indicators' trace of
each return, the time from the first entry into a band around the final position until the
robot stays in it, and the largest excursion after that entry; the standard measures 3
cycles."""
