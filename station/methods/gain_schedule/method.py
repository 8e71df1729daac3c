"""The gain-schedule method: the position ``q`` and the gains typed at each position (or the
columns of a CSV), fitted against the position. It judges no readings: its report is the fit
alone (no capability analysis)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

from station.analysis.gain_schedule import GainSchedule, fit_schedule
from station.errors import StationError
from station.methods.contract import (
    DemoDisplay,
    DemoRig,
    Judgement,
    Method,
    MethodInputs,
    PlacementWords,
)
from station.methods.sessions import is_number
from station.methods.text import fitted
from station.procedures import AnalysisNeeds
from station.session.tables import require_columns

if TYPE_CHECKING:
    from station.instruments.simulator import GaugeSpec

DEMO_STEP = 50.0
"""mm between two of the demo joint's positions (the first at 0)."""
DEMO_GAINS = {"kp": (2.0, -3e-3, 4e-6), "ki": (0.4, 2e-4, 0.0), "kd": (0.07, 0.0, 1e-7)}
"""The demo's tuned gains as polynomials of the position q (a0, a1, a2): what the tuning at
each position comes out at."""


def gain_inputs(
    events: Sequence[Mapping[str, Any]],
) -> tuple[list[float], dict[str, list[float]]]:
    """Positions and gains typed in a gain-schedule session: its input ``events`` with a
    number ``q`` and other numbers (a position typed again replaces the earlier one)."""
    by_position: dict[float, dict[str, float]] = {}
    for event in events:
        values = event.get("values") or {}
        q = values.get("q")
        gains = {k: float(v) for k, v in values.items() if k != "q" and is_number(v)}
        if is_number(q) and gains:
            by_position[float(q)] = gains
    if not by_position:
        raise StationError("the session has no tuned gains typed in yet.")
    # The gains in the order they were first typed (the procedure's field order).
    names = list(dict.fromkeys(name for gains in by_position.values() for name in gains))
    positions = sorted(by_position)
    missing = [(q, n) for q in positions for n in names if n not in by_position[q]]
    if missing:
        q, name = missing[0]
        raise StationError(f"position {q:g} has no {name} typed in.")
    return positions, {n: [by_position[q][n] for q in positions] for n in names}


def gain_schedule_lines(schedule: GainSchedule) -> list[str]:
    """The schedule's report section (without plots: those are ``station gains``')."""
    lines = [f"GAIN SCHEDULE: {len(schedule.positions)} positions"]
    for name, fit in schedule.fits.items():
        loo = "n/a" if fit.loo_rmse is None else f"{fit.loo_rmse:.4g}"
        shown = "".join(ch if ch.isprintable() else "?" for ch in name)
        lines.append(f"  {shown}: order {fit.order} ({fit.chosen_by}), leave-one-out RMSE {loo}")
        terms = [f"a{i} = {c:+.6g}" for i, c in enumerate(fit.coefficients)]
        lines.extend("    " + "   ".join(terms[i : i + 4]) for i in range(0, len(terms), 4))
        lines.extend(f"    WARNING: {warning}" for warning in fit.warnings)
    return lines


class GainScheduleMethod(Method):
    """Gains tuned per position, fitted against the position."""

    name = "gain_schedule"
    title = "GAIN SCHEDULE REPORT"
    reads_columns_by_name = True
    needs = AnalysisNeeds(
        numbers=("q",),
        more_numbers=1,
        numbers_words="an input step with a number field 'q' (the position) and one number "
        "field per gain",
        limits=False,
    )
    options = ("order",)
    placement_words = PlacementWords(
        label="Positions",
        noun="positions",
        hint="positions along the joint's path where the gains are tuned ({low} to {target})",
        too_few="Give at least 3 positions: the fit chooses its order from 3 or more.",
        fewest=3,
    )
    demo_words = "one joint with a position readout q, the gains tuned at each position"

    def batch(self, inputs: MethodInputs) -> Judgement:
        """The fit of each gain against q (``order``: a fixed order, else chosen)."""
        positions: Any
        gains: Mapping[str, Any]
        if inputs.table is not None:
            table = inputs.table
            q = require_columns(table, ("q",), "a gains table")["q"]
            gains = {n: v for n, v in table.channels.items() if n.lower() != "q"}
            if not gains:
                raise StationError(f"{table.path}: no gain columns beside q; add one per gain.")
            positions = q
        else:
            positions, gains = gain_inputs(inputs.input_events)
        schedule = fit_schedule(positions, gains, inputs.option("order") or "auto")
        return Judgement(None, schedule, (fitted(gain_schedule_lines(schedule), inputs.width),))

    def json(self, result: Any) -> dict[str, Any]:
        """The fit of each gain (at the document's top level)."""
        return result.as_json()

    def count(self, result: Any) -> str:
        """``5 positions``."""
        return f"{len(result.positions)} positions"

    def demo_rig(self, gauge: GaugeSpec, seed: int, *, stroke_points: int) -> DemoRig:
        """One joint's position readout q (the study takes no readings: the line is there as
        at the robot), and at each position the gains its tuning comes out at."""
        from station.instruments.simulator import AxisModel, FixtureModel
        from station.instruments.simulator import GaugeSpec as Spec

        readout = Spec(0.001, -500.0, 500.0, "mm", 0.0)
        model = FixtureModel({"q": AxisModel(noise=0.0)}, readout)
        return DemoRig(
            model,
            "a simulated joint with a position readout q and its tuned gains (seeded)",
            channel_map={"1": "q"},
            display=_gains_display,
        )


def _gains_display(model: Any, placement: int | None, unit: str) -> DemoDisplay | None:
    """What the tuning tool shows at ``placement``: the position and the tuned gains."""
    if placement is None:
        return None
    q = DEMO_STEP * (placement - 1)
    values: dict[str, float] = {"q": q}
    for name, (a0, a1, a2) in DEMO_GAINS.items():
        values[name] = float(f"{a0 + a1 * q + a2 * q * q:.6g}")
    return DemoDisplay(
        label=f"Tuning tool at position {placement} (simulated)",
        text="  ".join(f"{name} {value:g}" for name, value in values.items()),
        values=values,
        hint="type the position and the gains shown above",
    )


METHOD = GainScheduleMethod()
