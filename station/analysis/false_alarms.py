"""How often a rule set cries wolf: the chance that a stable process raises some alarm on a
chart of this many points.

Every report states it beside its alarms, because the figure is larger than people expect: the
more rules and the more points, the likelier one fires by chance (Western Electric quote one
false alarm in about 92 points for their four rules on known limits; with limits estimated from
the same 30 readings the chance per session is higher still).

The chance is **simulated**, not taken from a table, because the chart's limits are estimated
from the very readings they judge (phase I: MR-bar/d2, R-bar/d2 or S-bar/c4), which no closed
form covers for run rules: ``SESSIONS`` charts of independent normal readings (a fixed seed, so
the figure is the same on every run and machine), each charted and judged exactly as
:func:`station.analysis.summary.chart_alarms` judges a session (:func:`control_chart`, then
:func:`check_rules` on its own centre and sigma). The figure is given with its binomial standard
error. Results are cached per (rule set, points, subgroup). Above ``MAX_POINTS`` points the
chance is simulated at ``MAX_POINTS`` and stated as a lower bound (it only grows with the points).

Readings rounded by a coarse gauge are judged with the limits' floor and the rounding margin of
:mod:`station.analysis.discrimination`, which keep their false-alarm chance at or below this
figure (``tests/analysis/test_discrimination.py`` checks it at 0.35 and 0.5 step of spread).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from station.analysis.charts import check_subgroup, control_chart
from station.analysis.rules import RULE_SETS, check_rules
from station.errors import StationError

#: Simulated charts per figure: a standard error of about 1 percentage point at 12 %.
SESSIONS = 1000
#: The seed of the simulation: the same figure on every run.
SEED = 20_240_901
#: Charts longer than this are simulated at this length (the figure is then a lower bound).
MAX_POINTS = 1000


@dataclass(frozen=True)
class FalseAlarmChance:
    """The simulated chance that a stable process raises at least one alarm of ``rule_set`` on
    a chart of ``points`` points (subgroups of ``subgroup``), with its standard error.
    ``at_least`` is True when the chart was longer than the simulated ``simulated_points``."""

    rule_set: str
    points: int
    subgroup: int
    chance: float
    standard_error: float
    sessions: int
    simulated_points: int
    seed: int = SEED

    @property
    def at_least(self) -> bool:
        """True when the figure is a lower bound (the chart is longer than simulated)."""
        return self.points > self.simulated_points

    def text(self) -> str:
        """The sentence a report prints beside its alarms."""
        what = "points" if self.subgroup == 1 else f"subgroups of {self.subgroup}"
        if self.at_least and self.chance >= 0.995:
            share = "nearly every chart"
        else:
            bound = "at least " if self.at_least else ""
            share = (
                f"{bound}{100 * self.chance:.1f} % (± {100 * self.standard_error:.1f} %) of charts"
            )
        return (
            f"False-alarm chance: a stable process raises some alarm of the {self.rule_set} "
            f"rules on {share} of {self.points} {what} (simulated: {self.sessions} charts of "
            f"{self.simulated_points} normal {what}, limits from each chart's own readings, "
            f"seed {self.seed}): an alarm is a reason to look, not proof of a cause."
        )


def false_alarm_chance(
    rule_set: str, points: int, subgroup: int = 1, sessions: int = SESSIONS
) -> FalseAlarmChance | None:
    """The false-alarm chance of ``rule_set`` on a chart of ``points`` points (subgroup size
    ``subgroup``), simulated once and cached (see the module docstring). None for a chart too
    short to have limits (fewer than 2 individuals or 1 subgroup)."""
    if rule_set not in RULE_SETS:
        raise StationError(f"unknown rule set {rule_set!r}: use one of {', '.join(RULE_SETS)}")
    size = check_subgroup(subgroup)
    if points < (2 if size == 1 else 1) or sessions < 1:
        return None
    simulated = min(points, MAX_POINTS)
    return _simulate(rule_set, points, simulated, size, sessions)


@lru_cache(maxsize=128)
def _simulate(
    rule_set: str, points: int, simulated: int, subgroup: int, sessions: int
) -> FalseAlarmChance:
    rng = np.random.default_rng(SEED)
    raised = 0
    for _ in range(sessions):
        chart = control_chart(rng.standard_normal(simulated * subgroup), subgroup)
        sigma = chart.point_sigma
        if chart.center is None or sigma is None or not sigma > 0:
            continue
        if check_rules(chart.points.array, chart.center, sigma, rule_set):
            raised += 1
    chance = raised / sessions
    return FalseAlarmChance(
        rule_set=rule_set,
        points=points,
        subgroup=subgroup,
        chance=chance,
        standard_error=math.sqrt(chance * (1 - chance) / sessions),
        sessions=sessions,
        simulated_points=simulated,
    )
