"""Per-joint troubleshooting (report §1.2, §2.8): which joint spreads the tool centre point?

When a robot is out of control or not capable, the report traces the cause "by testing each
individual joint separately". With the other joints held, each joint in turn is moved away and
back for the same cycles at the same 3-D fixture; the indicators x, y, z read where the cube
returns. With the others held, joint j's readings spread along its Jacobian column J_j: the
spread at the fixture is the joint's angular repeatability times its lever arm.

Per joint this module gives the offset (mean) and spread (sample σ) per axis, the 3-D spread
(√ of the summed axis variances) and its share of all the joints' variance, and ranks the joints
by that share. Between the joints, the readings projected on each joint's own principal
direction (its line of motion, found by a singular value decomposition) are compared with
Levene's test (``center="median"``: Brown–Forsythe, robust to the non-normal spread of
backlash) and Bartlett's (exact for normal readings): :func:`scipy.stats.levene`,
:func:`scipy.stats.bartlett`.

The suspect joint is named with the report's reading of its pattern:

* **backlash** (§2.1 "backlash and wear in the joints"): the procedure leaves in alternate
  directions (odd cycles +, even −), so lost motion shows as a difference between the odd and
  even returns along the joint's line (Welch's t between them);
* **servo gains** (§2.7.3: a skewness a₁ near 1 or more "is usually attributed to an instability
  in the robot's control system"; §2.8.3: the error "could be accounted for ... in the control
  system gains"): a skewed spread, or a joint that simply does not settle at the same place;
* **encoder** (§2.1 "the zero of the encoder does not coincide with the zero of the joint"): no
  joint spreads more than the others, but one returns off the zero set before it moved (its
  offset is significant, one-sample t along its line, Bonferroni over the joints).

Definitions: ``reference/spc-extensions.md`` §8.
"""

from __future__ import annotations

import math
import textwrap
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from station.errors import StationError

AXES = ("x", "y", "z")
#: The level at which the joints' spreads are called different.
SPREAD_ALPHA = 0.05
#: The level (before Bonferroni over the joints) for an alternation or an offset.
PATTERN_ALPHA = 0.01
#: |a₁| at or above which the report reads control-system instability.
SKEW_LIMIT = 1.0

READINGS: Mapping[str, str] = {
    "backlash": "backlash: the returns alternate with the direction the joint left in (lost "
    "motion or wear in the joint, report 2.1); check the gear train and its preload.",
    "servo gains (skew)": "servo gains: the spread is skewed (a1 near 1 or more: instability "
    "in the control system, report 2.7.3); retune the joint's PID gains.",
    "servo gains": "servo gains: the joint does not settle at the same place (no direction "
    "pattern); check its PID gains, then its encoder's resolution and coupling.",
    "encoder": "encoder: the joint returns off the zero set before it moved (the encoder's "
    "zero does not coincide with the joint's, report 2.1); re-reference the encoder.",
}


@dataclass(frozen=True)
class JointResult:
    """One joint's returns. ``offset``/``sd`` per axis; ``spread`` the 3-D σ; ``share`` its
    part of the summed variance of all joints; ``skewness`` a₁ along its line of motion
    (sign as the principal direction falls); ``alternation`` the odd-minus-even mean along
    its line over the within σ, with Welch's p; ``offset_p`` the one-sample t-test of its
    mean along its line."""

    joint: int
    n: int
    offset: Mapping[str, float]
    sd: Mapping[str, float]
    spread: float
    share: float
    rank: int
    direction: tuple[float, float, float]
    skewness: float | None
    alternation: float | None
    alternation_p: float | None
    offset_3d: float
    offset_p: float | None
    lever_arm: float | None = None
    """|J_j|, the distance from the joint's axis to the cube, when given."""
    angular_spread: float | None = None
    """``spread`` / ``lever_arm`` (radians when both are in the same unit), when given."""

    def as_json(self) -> dict[str, Any]:
        """The joint's figures for ``joints: [...]``."""
        return {
            "joint": self.joint,
            "lever_arm": self.lever_arm,
            "angular_spread": self.angular_spread,
            "n": self.n,
            "rank": self.rank,
            "share": self.share,
            "spread": self.spread,
            "offset": dict(self.offset),
            "sd": dict(self.sd),
            "offset_3d": self.offset_3d,
            "offset_p": self.offset_p,
            "skewness": self.skewness,
            "alternation": self.alternation,
            "alternation_p": self.alternation_p,
            "direction": list(self.direction),
        }


@dataclass(frozen=True)
class JointsAnalysis:
    """All joints, ranked by share of the spread (largest first), the tests between them,
    and the suspect joint with the report's reading (None when no joint stands out)."""

    joints: tuple[JointResult, ...]
    levene_statistic: float | None
    levene_p: float | None
    bartlett_statistic: float | None
    bartlett_p: float | None
    suspect: int | None
    cause: str | None
    """``backlash``, ``servo gains (skew)``, ``servo gains`` or ``encoder``; None without a
    suspect."""
    reason: str

    @property
    def angular(self) -> bool:
        """True when the joints were compared by angular spread (every lever arm known)."""
        return all(j.angular_spread is not None for j in self.joints)

    @property
    def reading(self) -> str | None:
        """The report's reading of the suspect's pattern, as a sentence."""
        return None if self.cause is None else READINGS[self.cause]

    def as_json(self) -> dict[str, Any]:
        """``{joints: [...], suspect, cause, reading, levene_p, bartlett_p, ...}``."""
        return {
            "joints": [joint.as_json() for joint in self.joints],
            "suspect": self.suspect,
            "cause": self.cause,
            "reading": self.reading,
            "reason": self.reason,
            "compared": "angular spread" if self.angular else "spread at the fixture",
            "levene_statistic": self.levene_statistic,
            "levene_p": self.levene_p,
            "bartlett_statistic": self.bartlett_statistic,
            "bartlett_p": self.bartlett_p,
        }

    def lines(self, unit: str = "") -> list[str]:
        """The report block: the ranking table, the tests and the verdict (at most 80
        columns)."""
        angular = self.angular
        lines = [
            "PER-JOINT TROUBLESHOOTING (each joint moved alone, the others held)",
            f"  ranked by share of the {'angular ' if angular else ''}variance; spread: 3-D σ"
            + (f" ({unit})" if unit else "")
            + ("; angular: µrad" if angular else ""),
            "  joint   n  share    spread"
            + (" angular" if angular else "")
            + "  offset x / y / z           a1  odd-even",
        ]
        for j in self.joints:
            offsets = "/".join(f"{j.offset[a]:+.5f}" for a in AXES)
            skew = "  n/a" if j.skewness is None else f"{j.skewness:+5.2f}"
            alt = "   n/a" if j.alternation is None else f"{j.alternation:+6.2f}"
            micro = f" {1e6 * j.angular_spread:7.2f}" if angular else ""  # type: ignore[operator]
            lines.append(
                f"  {j.joint:5d} {j.n:3d} {100 * j.share:5.1f} % {j.spread:9.6f}"
                f"{micro}  {offsets}  {skew}  {alt}"
            )
        if self.levene_p is not None:
            lines.append(
                f"  spreads between joints: Levene (median) p = {self.levene_p:.3g}, "
                f"Bartlett p = {self.bartlett_p:.3g}"
            )
        verdict = (
            f"SUSPECT: none. {self.reason}"
            if self.suspect is None
            else f"SUSPECT: joint {self.suspect}. {self.reason}"
        )
        wrap = {"width": 80, "initial_indent": "  ", "subsequent_indent": "    "}
        lines.extend(textwrap.wrap(verdict, **wrap))  # type: ignore[arg-type]
        if self.reading is not None:
            lines.extend(textwrap.wrap(f"Reading: {self.reading}", **wrap))  # type: ignore[arg-type]
        if not angular:
            note = (
                "Note: compared by the spread at the fixture; without the lever arms a joint far "
                "from the cube (the base) spreads it more for the same angular repeatability. "
                "Give each joint's lever arm to compare the joints themselves."
            )
            lines.extend(textwrap.wrap(note, **wrap))  # type: ignore[arg-type]
        return lines


def _joint_numbers(values: Any) -> Any:
    numbers = np.asarray(values, dtype=float).ravel()
    if numbers.size and (not np.all(np.isfinite(numbers)) or np.any(numbers != np.round(numbers))):
        raise StationError("the joint column must hold whole joint numbers (1, 2, 3, ...).")
    return numbers.astype(int)


def analyze_joints(
    joint: Sequence[int] | Any,
    readings: Mapping[str, Any],
    *,
    lever_arms: Mapping[int, float] | None = None,
) -> JointsAnalysis:
    """Analyse readings x, y, z (one row per return, in cycle order) labelled by the joint that
    moved (``joint``, one number per row). Needs 2 or more joints with 3 or more returns each;
    raises StationError otherwise or when the columns do not line up.

    ``lever_arms`` (joint → distance from its axis to the cube, in the readings' unit) turns
    each joint's spread into an angle before the joints are ranked and compared: a joint far
    from the cube (the base) spreads it more for the same angular repeatability, and without
    the lever arms the comparison is of what the fixture sees, which is what the verdict judges
    but not a fault of the joint."""
    from scipy import stats  # on first use: see station/README.md

    missing = [axis for axis in AXES if axis not in readings]
    if missing:
        raise StationError(
            f"per-joint troubleshooting needs the indicators x, y and z; {missing[0]!r} is missing."
        )
    labels = _joint_numbers(joint)
    points = np.column_stack([np.asarray(readings[a], dtype=float).ravel() for a in AXES])
    if len(points) != len(labels):
        raise StationError(
            f"{len(points)} readings but {len(labels)} joint labels: one label per row."
        )
    if not np.all(np.isfinite(points)):
        raise StationError("a reading is not a finite number; fix or drop it.")
    numbers = sorted(set(labels.tolist()))
    small = [n for n in numbers if np.sum(labels == n) < 3]
    if small:
        raise StationError(
            f"joint {small[0]} has fewer than 3 returns: move each joint 3 or more times "
            "(the procedure asks for 25)."
        )
    if len(numbers) < 2:
        raise StationError("per-joint troubleshooting compares 2 or more joints; one was given.")
    levers: dict[int, float] | None = None
    if lever_arms:
        absent = [n for n in numbers if n not in lever_arms]
        if absent:
            raise StationError(f"no lever arm for joint {absent[0]}: give one for every joint.")
        levers = {n: float(lever_arms[n]) for n in numbers}
        bad = [n for n, v in levers.items() if not (math.isfinite(v) and v > 0)]
        if bad:
            raise StationError(f"joint {bad[0]}'s lever arm must be more than 0.")

    projected: dict[int, Any] = {}
    partial: list[dict[str, Any]] = []
    for number in numbers:
        block = points[labels == number]
        n = len(block)
        mean = block.mean(axis=0)
        centred = block - mean
        # The joint's line of motion: the first right singular vector of its centred returns,
        # signed so that its largest component is positive (a stable, readable direction).
        _, _, rows = np.linalg.svd(centred, full_matrices=False)
        direction = rows[0] * (1.0 if rows[0][np.argmax(np.abs(rows[0]))] >= 0 else -1.0)
        along = block @ direction
        scale = 1.0 if levers is None else levers[number]
        projected[number] = (along - along.mean()) / scale
        variance = float(np.sum(block.var(axis=0, ddof=1)))
        sd_along = float(along.std(ddof=1))
        skewness = (
            float(np.mean((along - along.mean()) ** 3) / sd_along**3) if sd_along > 0 else None
        )
        odd, even = along[0::2], along[1::2]
        alternation = alternation_p = None
        if len(odd) >= 2 and len(even) >= 2:
            within = math.sqrt(
                ((len(odd) - 1) * odd.var(ddof=1) + (len(even) - 1) * even.var(ddof=1)) / (n - 2)
            )
            if within > 0:
                alternation = float((odd.mean() - even.mean()) / within)
                alternation_p = float(stats.ttest_ind(odd, even, equal_var=False).pvalue)
        offset_p = None
        if sd_along > 0:
            offset_p = float(stats.ttest_1samp(along, 0.0).pvalue)
        partial.append(
            {
                "joint": number,
                "n": n,
                "offset": dict(zip(AXES, map(float, mean), strict=True)),
                "sd": dict(zip(AXES, map(float, block.std(axis=0, ddof=1)), strict=True)),
                "variance": variance,
                "compared": variance / scale**2,
                "lever_arm": None if levers is None else scale,
                "direction": tuple(float(v) for v in direction),
                "skewness": skewness,
                "alternation": alternation,
                "alternation_p": alternation_p,
                "offset_3d": float(np.linalg.norm(mean)),
                "offset_p": offset_p,
            }
        )
    total = sum(p["compared"] for p in partial)
    ranked = sorted(partial, key=lambda p: -p["compared"])
    results = tuple(
        JointResult(
            joint=p["joint"],
            n=p["n"],
            offset=p["offset"],
            sd=p["sd"],
            spread=math.sqrt(p["variance"]),
            share=p["compared"] / total if total > 0 else 0.0,
            rank=rank,
            direction=p["direction"],
            skewness=p["skewness"],
            alternation=p["alternation"],
            alternation_p=p["alternation_p"],
            offset_3d=p["offset_3d"],
            offset_p=p["offset_p"],
            lever_arm=p["lever_arm"],
            angular_spread=None
            if p["lever_arm"] is None
            else math.sqrt(p["variance"]) / p["lever_arm"],
        )
        for rank, p in enumerate(ranked, start=1)
    )

    groups = [projected[number] for number in numbers]
    levene = bartlett = None
    if all(np.ptp(g) > 0 for g in groups):
        levene = stats.levene(*groups, center="median")
        bartlett = stats.bartlett(*groups)
    suspect, cause, reason = _suspect(results, None if levene is None else levene.pvalue)
    return JointsAnalysis(
        joints=results,
        levene_statistic=None if levene is None else float(levene.statistic),
        levene_p=None if levene is None else float(levene.pvalue),
        bartlett_statistic=None if bartlett is None else float(bartlett.statistic),
        bartlett_p=None if bartlett is None else float(bartlett.pvalue),
        suspect=suspect,
        cause=cause,
        reason=reason,
    )


def _suspect(
    ranked: Sequence[JointResult], levene_p: float | None
) -> tuple[int | None, str | None, str]:
    """The suspect joint, its cause and why (see the module).

    An offset comes first: a joint that returns off its zero by more than twice its own spread
    (and significantly, Bonferroni over the joints) has an encoder fault whatever the spreads.
    Then the spreads: when they differ, the joint with the largest share."""
    level = PATTERN_ALPHA / len(ranked)
    offsets = [
        j
        for j in ranked
        if j.offset_p is not None and j.offset_p < level and j.offset_3d > 2 * j.spread
    ]
    if offsets:
        worst = max(offsets, key=lambda j: j.offset_3d / j.spread)
        return (
            worst.joint,
            "encoder",
            f"It returns {worst.offset_3d:.5f} off its zero, {worst.offset_3d / worst.spread:.0f}"
            f" times its own spread (p = {worst.offset_p:.2g}).",
        )
    top = ranked[0]
    if levene_p is not None and levene_p < SPREAD_ALPHA:
        what = "angular spread" if top.lever_arm is not None else "spread at the fixture"
        why = (
            f"Its returns have the largest {what} ({100 * top.share:.0f} % of the variance), "
            f"and the joints' spreads differ (Levene p = {levene_p:.2g})."
        )
        if top.alternation_p is not None and top.alternation_p < PATTERN_ALPHA:
            return top.joint, "backlash", why
        if top.skewness is not None and abs(top.skewness) >= SKEW_LIMIT:
            return top.joint, "servo gains (skew)", why
        return top.joint, "servo gains", why
    if levene_p is None:
        return None, None, "A joint's returns do not vary at the gauge's resolution."
    return (
        None,
        None,
        f"The joints' spreads do not differ (Levene p = {levene_p:.2g}) and none returns off "
        "its zero: look beyond the joints (fixture, gauges, temperature).",
    )
