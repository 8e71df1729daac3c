"""The pose characteristics of ISO 9283:1998 that three indicators at a fixture can measure:
pose accuracy AP and pose repeatability RP per pose, the multi-directional pose accuracy
variation vAP, and the distance accuracy AD and repeatability RD between two poses.

Definitions (reference/standards.md §1.2–1.5; the formulas several independent implementations
agree on, the ISO text itself was not retrievable). Each pose P_k is visited once per cycle of
the standard's test (P1 → P5 → P4 → P3 → P2 → P1, 30 cycles); its n attained positions
(x_j, y_j, z_j), in the frame its command pose (x_c, y_c, z_c) is given in:

* barycentre (x̄, ȳ, z̄), AP_x = x̄ − x_c (likewise y, z), AP = √(AP_x² + AP_y² + AP_z²); without
  a command pose the command is the zero, and AP is said to be relative to it;
* RP = l̄ + 3·S_l, l_j the distance of point j from the barycentre, S_l its sample (n − 1) SD.
  AP and RP come from :func:`station.analysis.spatial.spatial_figures`, the station's one
  place for them, and of the first approach direction a pose was measured from (the
  standard's cycle);
* vAP: the same pose approached from several directions (the standard asks three), the
  largest distance between two directions' barycentres;
* distance, between poses A and B measured in the same cycles: D_j = ‖P_A,j − P_B,j‖, D̄ their
  mean, AD = D̄ − D_c with D_c the command distance (given, else ‖C_A − C_B‖), RD = ±3·S_D
  (S_D with n − 1); per axis, with both command poses, AD_x = D̄_x − D_cx, D_x,j = x_A,j − x_B,j.

The run's conditions (load and speed as a percentage of rated, warm-up, ambient temperature
at the start and the end) are reported with how the run departs from the standard's: every
pose P1 to P5, 30 cycles, 100 % of the rated load, the rated speed (and 50 % and 10 % of it),
a warm-up, three approach directions for vAP.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from itertools import combinations
from typing import Any

import numpy as np

from station.analysis.spatial import AXES, Spatial, spatial_figures
from station.errors import StationError
from station.plain import plain
from station.text import format_figure, format_spread

Point = tuple[float, float, float]

POSES = 5
"""The test cube's poses the standard measures: P1 (its centre) to P5."""
CYCLES = 30
"""The cycles the standard asks for pose accuracy, repeatability, vAP and distance."""
DIRECTIONS = 3
"""The approach directions the standard asks for vAP."""
SPEEDS = (100.0, 50.0, 10.0)
"""The speeds (percent of rated) the standard tests at."""

# Clause numbers as the 1998 table of contents gives them (reference/standards.md §1.1); the
# subclause of vAP is unconfirmed against the ISO text, so it is named, not numbered.
MEASURED = {
    "pose": "pose accuracy AP and pose repeatability RP (ISO 9283 §7.2)",
    "vap": "multi-directional pose accuracy variation vAP",
    "distance": "distance accuracy AD and repeatability RD (§7.3)",
}
NOT_MEASURED = (
    "orientation parts of AP and RP (three indicators read a position only)",
    "position stabilisation time and overshoot (§7.4, §7.5: they need the approach in time)",
    "drift of pose characteristics (§7.6: an 8 h run from cold)",
    "path, cornering, velocity and weaving characteristics (§8, §11: a moving tool)",
    "exchangeability, minimum posing time, static compliance (§7.7, §9, §10)",
)

_DISTANCE = re.compile(
    r"^\s*P?(\d+)\s*:\s*P?(\d+)\s*(?:=\s*([^=\s][^=]*?))?\s*$", re.IGNORECASE | re.ASCII
)


def pose_name(number: int) -> str:
    """``P3`` for pose 3."""
    return f"P{number}"


@dataclass(frozen=True)
class DistanceSpec:
    """Which two poses the distance is measured between, and the command distance D_c
    (None: from their command poses)."""

    pose_a: int
    pose_b: int
    command: float | None = None


def parse_distance(text: str) -> DistanceSpec:
    """``P2:P4=27.71`` (or ``P2:P4``, the distance then from the two command poses) as a
    :class:`DistanceSpec`; StationError saying how to write it."""
    match = _DISTANCE.match(str(text))
    shown = repr(plain(text, limit=40))
    example = "write e.g. P2:P4=27.71 (the known distance between P2 and P4)"
    if match is None:
        raise StationError(f"the distance {shown} is not POSE:POSE=D; {example}.")
    a, b = int(match.group(1)), int(match.group(2))
    if a == b or a < 1 or b < 1:
        raise StationError(f"the distance {shown} needs two different poses; {example}.")
    command = None
    if match.group(3) is not None:
        try:
            command = float(match.group(3))
        except ValueError:
            command = math.nan
        if not (math.isfinite(command) and command > 0):
            raise StationError(
                f"the distance {shown}: {plain(match.group(3), limit=20)!r} is not a length "
                f"greater than 0; {example}."
            )
    return DistanceSpec(a, b, command)


# -- the figures ---------------------------------------------------------------------------------


@dataclass(frozen=True)
class PoseResult:
    """One pose: the attained points of its first approach direction, its command pose (None:
    the zero), its barycentre, AP and RP."""

    number: int
    direction: int
    """The approach direction AP and RP are of (the lowest measured: the standard's cycle)."""
    command: Point | None
    spatial: Spatial

    @property
    def name(self) -> str:
        """``P1`` ..."""
        return pose_name(self.number)

    @property
    def n(self) -> int:
        """The cycles measured at the pose (from that direction)."""
        return self.spatial.n

    @property
    def barycentre(self) -> Point:
        """(x̄, ȳ, z̄)."""
        x, y, z = (self.spatial.nominal[a] + self.spatial.offset[a] for a in AXES)
        return x, y, z

    @property
    def ap(self) -> float:
        """AP: the distance from the command pose (or the zero) to the barycentre."""
        return self.spatial.total_offset

    @property
    def ap_axes(self) -> Point:
        """AP_x, AP_y, AP_z (signed)."""
        x, y, z = (self.spatial.offset[a] for a in AXES)
        return x, y, z

    @property
    def ap_relative(self) -> bool:
        """True when there is no command pose: AP is relative to the zero."""
        return self.command is None


@dataclass(frozen=True)
class Multidirectional:
    """One pose approached from several directions: each direction's count and barycentre,
    and vAP, the largest distance between two of them."""

    number: int
    counts: Mapping[int, int]
    barycentres: Mapping[int, Point]
    vap: float


@dataclass(frozen=True)
class DistanceResult:
    """The distance between poses A and B over the ``n`` cycles measured at both: D̄, the
    command distance D_c (``command_source``: ``given`` or ``command poses``), AD, S_D and RD
    (= 3·S_D, reported ±), and per axis (None without both command poses) AD_x, AD_y, AD_z."""

    pose_a: int
    pose_b: int
    n: int
    d_mean: float
    dc: float
    command_source: str
    ad: float
    s_d: float | None
    ad_axes: Point | None

    @property
    def rd(self) -> float | None:
        """RD = 3·S_D (the standard writes ±3·S_D); None below two cycles."""
        return None if self.s_d is None else 3.0 * self.s_d


@dataclass(frozen=True)
class PoseCharacteristics:
    """Every pose's AP and RP, the multi-directional variation of the poses measured from
    more than one direction, and the distance (None when none was asked for)."""

    poses: tuple[PoseResult, ...]
    multidirectional: tuple[Multidirectional, ...]
    distance: DistanceResult | None

    @property
    def vap(self) -> dict[str, float] | None:
        """vAP by pose name; None when no pose was approached from two directions or more."""
        if not self.multidirectional:
            return None
        return {pose_name(m.number): m.vap for m in self.multidirectional}

    def pose(self, number: int) -> PoseResult:
        """The pose ``number``; StationError naming the poses there are."""
        for pose in self.poses:
            if pose.number == number:
                return pose
        raise StationError(
            f"the readings have no pose {pose_name(number)} (they have "
            f"{', '.join(p.name for p in self.poses)})."
        )


def _whole(values: np.ndarray, what: str, example: str) -> np.ndarray:
    """``values`` as whole numbers 1 or more; StationError naming the column otherwise."""
    if values.size and (np.any(values != np.round(values)) or np.any(values < 1)):
        raise StationError(f"the {what} column must hold whole numbers {example}.")
    return values.astype(np.int64)


def pose_characteristics(
    points: Any,
    poses: Any,
    *,
    directions: Any = None,
    cycles: Any = None,
    commands: Mapping[int, Sequence[float]] | None = None,
    distance: DistanceSpec | None = None,
) -> PoseCharacteristics:
    """The ISO 9283 pose characteristics (see the module) of ``points`` (n × 3: x, y, z per
    row), each row measured at pose ``poses[i]`` (1 = P1 ...) from approach direction
    ``directions[i]`` (None: all from one) in the standard's cycle ``cycles[i]`` (None: the
    rows of each pose and direction in order are cycles 1, 2, 3 ...: how the distance pairs
    them). ``commands`` maps a pose to its command pose (a pose without one: the zero).
    ``distance``: the two poses to measure the distance between, and its command length."""
    table = np.asarray(points, dtype=float)
    if table.size == 0:
        raise StationError("there are no readings to analyse.")
    if table.ndim != 2 or table.shape[1] != 3:
        raise StationError("the pose characteristics need x, y and z in every row.")
    rows = table.shape[0]
    if not np.all(np.isfinite(table)):
        raise StationError("a reading is not a finite number.")
    pose_of = _whole(np.asarray(poses, dtype=float).ravel(), "pose", "1, 2, ... (P1, P2, ...)")
    direction_of = (
        np.ones(rows, dtype=np.int64)
        if directions is None
        else _whole(np.asarray(directions, dtype=float).ravel(), "direction", "1, 2, 3")
    )
    for name, column in (("pose", pose_of), ("direction", direction_of)):
        if column.size != rows:
            raise StationError(f"the {name} column has {column.size} rows, the readings {rows}.")
    cycle_of = _cycles(cycles, pose_of, direction_of)
    command_at = {int(k): _point(v, pose_name(int(k))) for k, v in (commands or {}).items()}

    results = []
    multidirectional = []
    for number in sorted(set(pose_of.tolist())):
        at_pose = pose_of == number
        measured = sorted(set(direction_of[at_pose].tolist()))
        first = at_pose & (direction_of == measured[0])
        command = command_at.get(number)
        x, y, z = (table[first, i] for i in range(3))
        spatial = spatial_figures(x, y, z, (0.0, 0.0, 0.0) if command is None else command)
        results.append(PoseResult(number, measured[0], command, spatial))
        if len(measured) > 1:
            barycentres: dict[int, Point] = {}
            counts: dict[int, int] = {}
            for direction in measured:
                chosen = at_pose & (direction_of == direction)
                mean = table[chosen].mean(axis=0)
                barycentres[direction] = (float(mean[0]), float(mean[1]), float(mean[2]))
                counts[direction] = int(chosen.sum())
            vap = max(
                math.dist(barycentres[h], barycentres[k]) for h, k in combinations(measured, 2)
            )
            multidirectional.append(Multidirectional(number, counts, barycentres, vap))
    found = PoseCharacteristics(tuple(results), tuple(multidirectional), None)
    if distance is None:
        return found
    between = _distance(table, pose_of, direction_of, cycle_of, found, distance)
    return PoseCharacteristics(found.poses, found.multidirectional, between)


def _point(value: Sequence[float], pose: str) -> Point:
    coordinates = tuple(float(v) for v in value)
    if len(coordinates) != 3 or not all(math.isfinite(v) for v in coordinates):
        raise StationError(f"the command pose of {pose} must be three finite numbers x, y, z.")
    return coordinates[0], coordinates[1], coordinates[2]


def _cycles(cycles: Any, pose_of: np.ndarray, direction_of: np.ndarray) -> np.ndarray:
    """The standard's cycle of each row: given (each at most once per pose and direction), or
    the rows of each pose and direction counted 1, 2, 3 ... in order."""
    rows = pose_of.size
    if cycles is None:
        numbered = np.zeros(rows, dtype=np.int64)
        seen: dict[tuple[int, int], int] = {}
        for i, key in enumerate(zip(pose_of.tolist(), direction_of.tolist(), strict=True)):
            seen[key] = seen.get(key, 0) + 1
            numbered[i] = seen[key]
        return numbered
    given = _whole(np.asarray(cycles, dtype=float).ravel(), "cycle", "1, 2, 3 ...")
    if given.size != rows:
        raise StationError(f"the cycle column has {given.size} rows, the readings {rows}.")
    keys = set()
    rows_of = zip(given.tolist(), pose_of.tolist(), direction_of.tolist(), strict=True)
    for cycle, pose, direction in rows_of:
        if (cycle, pose, direction) in keys:
            raise StationError(
                f"cycle {cycle} appears twice at {pose_name(pose)} from direction {direction}: "
                "number each cycle of the test once per pose."
            )
        keys.add((cycle, pose, direction))
    return given


def _distance(
    table: np.ndarray,
    pose_of: np.ndarray,
    direction_of: np.ndarray,
    cycle_of: np.ndarray,
    found: PoseCharacteristics,
    spec: DistanceSpec,
) -> DistanceResult:
    """D̄, AD and RD between the two poses of ``spec`` over the cycles measured at both (from
    the direction their AP is of)."""
    a, b = found.pose(spec.pose_a), found.pose(spec.pose_b)
    pair = f"{a.name}:{b.name}"
    rows_a = {
        int(c): i
        for i, c in enumerate(cycle_of)
        if pose_of[i] == a.number and direction_of[i] == a.direction
    }
    rows_b = {
        int(c): i
        for i, c in enumerate(cycle_of)
        if pose_of[i] == b.number and direction_of[i] == b.direction
    }
    shared = sorted(set(rows_a) & set(rows_b))
    if len(shared) < 2:
        raise StationError(
            f"the distance {pair} needs 2 or more cycles measured at both poses; "
            f"{len(shared)} {'is' if len(shared) == 1 else 'are'}."
        )
    differences = table[[rows_a[c] for c in shared]] - table[[rows_b[c] for c in shared]]
    lengths = np.linalg.norm(differences, axis=1)
    both = a.command is not None and b.command is not None
    commanded = np.subtract(a.command, b.command) if both else None  # type: ignore[arg-type]
    if spec.command is not None:
        dc, source = spec.command, "given"
    elif commanded is not None:
        dc, source = float(np.linalg.norm(commanded)), "command poses"
    else:
        raise StationError(
            f"the distance {pair} needs its command length: give it ({pair}=D) or the "
            "command poses of both."
        )
    d_mean = float(lengths.mean())
    ad_axes: Point | None = None
    if commanded is not None:
        mean = differences.mean(axis=0) - commanded
        ad_axes = (float(mean[0]), float(mean[1]), float(mean[2]))
    return DistanceResult(
        pose_a=a.number,
        pose_b=b.number,
        n=len(shared),
        d_mean=d_mean,
        dc=float(dc),
        command_source=source,
        ad=d_mean - float(dc),
        s_d=float(lengths.std(ddof=1)),
        ad_axes=ad_axes,
    )


# -- the conditions ------------------------------------------------------------------------------


@dataclass(frozen=True)
class Conditions:
    """The run's conditions as recorded (None: not recorded): load and speed in percent of
    the rated ones, the warm-up in minutes, the ambient temperature (°C) at start and end."""

    load: float | None = None
    speed: float | None = None
    warm_up: float | None = None
    temperature_start: float | None = None
    temperature_end: float | None = None

    @property
    def recorded(self) -> bool:
        """True when any condition was recorded."""
        return any(v is not None for v in self.as_json().values())

    def as_json(self) -> dict[str, float | None]:
        """The conditions by name."""
        return {
            "load": self.load,
            "speed": self.speed,
            "warm_up": self.warm_up,
            "temperature_start": self.temperature_start,
            "temperature_end": self.temperature_end,
        }


def departures(result: PoseCharacteristics, conditions: Conditions | None) -> list[str]:
    """How the run departs from the standard's test, one sentence each (none: it does not)."""
    found: list[str] = []
    numbers = [p.number for p in result.poses]
    missing = [pose_name(k) for k in range(1, POSES + 1) if k not in numbers]
    if missing:
        found.append(f"{', '.join(missing)} not measured: the standard measures P1 to P5.")
    few = [p.name for p in result.poses if p.n < CYCLES]
    if few:
        found.append(f"fewer than {CYCLES} cycles at {', '.join(few)}.")
    short = [pose_name(m.number) for m in result.multidirectional if len(m.counts) < DIRECTIONS]
    if short:
        found.append(f"vAP from fewer than {DIRECTIONS} directions at {', '.join(short)}.")
    if conditions is None or not conditions.recorded:
        found.append("the conditions (load, speed, warm-up, temperature) were not recorded.")
        return found
    c = conditions
    if c.load is None:
        found.append("the load was not recorded: the standard tests at 100 % of the rated load.")
    elif c.load != 100:
        found.append(f"load {c.load:g} % of rated: the standard tests at 100 %.")
    if c.speed is None:
        found.append("the speed was not recorded: the standard tests at 100, 50 and 10 %.")
    elif c.speed not in SPEEDS:
        found.append(f"speed {c.speed:g} % of rated: the standard tests at 100, 50 and 10 %.")
    if c.warm_up is None:
        found.append("the warm-up was not recorded: the standard tests a warmed-up robot.")
    elif c.warm_up <= 0:
        found.append("no warm-up: the standard tests a warmed-up robot.")
    if c.temperature_start is None or c.temperature_end is None:
        found.append("the ambient temperature at the start and the end was not both recorded.")
    return found


# -- the report ----------------------------------------------------------------------------------


def clause_lines(result: PoseCharacteristics) -> list[str]:
    """Which of the standard's characteristics the run measured, and which it did not."""
    names = ", ".join(p.name for p in result.poses)
    measured = [f"{MEASURED['pose']} at {names}"]
    if result.multidirectional:
        at = ", ".join(pose_name(m.number) for m in result.multidirectional)
        measured.append(f"{MEASURED['vap']} at {at}")
    if result.distance is not None:
        d = result.distance
        measured.append(f"{MEASURED['distance']} {pose_name(d.pose_a)} to {pose_name(d.pose_b)}")
    lines = [f"  Measured: {'; '.join(measured)}."]
    unmeasured = list(NOT_MEASURED)
    if not result.multidirectional:
        unmeasured.insert(0, "vAP (each pose was approached from one direction)")
    if result.distance is None:
        unmeasured.insert(0, "AD and RD (no distance between two poses was asked for)")
    lines.append(f"  Not measured: {'; '.join(unmeasured)}.")
    relative = [p.name for p in result.poses if p.ap_relative]
    if relative:
        lines.append(
            f"  AP at {', '.join(relative)} is relative to the zero (no command pose): the "
            "distance of the barycentre from where the indicators read 0."
        )
    return lines


def report_lines(
    result: PoseCharacteristics,
    conditions: Conditions | None,
    *,
    unit: str = "",
    resolution: float | None = None,
) -> list[str]:
    """The report block: the clauses measured, per pose the barycentre, AP and RP, vAP, the
    distance, the conditions and how the run departs from the standard's."""
    shown = f" ({unit})" if unit else ""
    lines = [
        f"ISO 9283 POSE CHARACTERISTICS ({len(result.poses)} poses)",
        *clause_lines(result),
        "",
        f"  BARYCENTRE AND POSE ACCURACY{shown}",
    ]
    header = ["POSE", "N", "x", "y", "z", "APx", "APy", "APz", "AP"]
    rows = [
        [
            p.name + ("*" if p.ap_relative else ""),
            str(p.n),
            *(format_figure(v, resolution) for v in p.barycentre),
            *(format_figure(v, resolution) for v in p.ap_axes),
            format_spread(p.ap, resolution),
        ]
        for p in result.poses
    ]
    lines += _table(header, rows)
    if any(p.ap_relative for p in result.poses):
        lines.append("  * relative to the zero")
    lines += ["", f"  POSE REPEATABILITY RP = l-bar + 3 S_l{shown}"]
    rows = [
        [
            p.name,
            str(p.n),
            format_spread(p.spatial.l_mean, resolution),
            format_spread(p.spatial.l_sd, resolution),
            format_spread(p.spatial.rp, resolution),
        ]
        for p in result.poses
    ]
    lines += _table(["POSE", "N", "l-bar", "S_l", "RP"], rows)
    for pose in result.poses:
        if pose.spatial.message:
            lines.append(f"  {pose.name}: {pose.spatial.message}.")
    if result.multidirectional or result.distance is not None:
        lines.append("")
    for m in result.multidirectional:
        counts = ", ".join(f"{m.counts[d]} from direction {d}" for d in m.counts)
        lines.append(
            f"  vAP at {pose_name(m.number)}: "
            f"{format_spread(m.vap, resolution)}{unit and ' ' + unit} "
            f"(largest distance between the directions' barycentres; {counts})"
        )
    d = result.distance
    if d is not None:
        pair = f"{pose_name(d.pose_a)} to {pose_name(d.pose_b)}"
        rd = "-" if d.rd is None else "±" + format_spread(d.rd, resolution)
        lines.append(
            f"  Distance {pair} over {d.n} cycles: D-bar {format_spread(d.d_mean, resolution)}, "
            f"D_c {format_spread(d.dc, resolution)} ({d.command_source}), "
            f"AD {format_figure(d.ad, resolution)},"
            f" RD {rd}{unit and ' ' + unit}"
        )
        if d.ad_axes is not None:
            axes = ", ".join(format_figure(v, resolution) for v in d.ad_axes)
            lines.append(f"    AD per axis x, y, z: {axes}")
    lines += ["", *condition_lines(conditions)]
    gaps = departures(result, conditions)
    lines.append("  Departures from the standard's conditions:" + ("" if gaps else " none."))
    lines += [f"    - {gap}" for gap in gaps]
    return lines


def condition_lines(conditions: Conditions | None) -> list[str]:
    """The run's conditions in one line."""
    if conditions is None or not conditions.recorded:
        return ["  Conditions: not recorded."]
    c = conditions

    def shown(value: float | None, suffix: str) -> str:
        return "not recorded" if value is None else f"{value:g}{suffix}"

    temperature = (
        f"{shown(c.temperature_start, ' °C')} at the start, {shown(c.temperature_end, ' °C')} "
        "at the end"
    )
    if c.temperature_start is not None and c.temperature_end is not None:
        temperature += f" (change {c.temperature_end - c.temperature_start:+.1f} °C)"
    return [
        f"  Conditions: load {shown(c.load, ' %')} of rated, speed {shown(c.speed, ' %')} of "
        f"rated, warm-up {shown(c.warm_up, ' min')}, temperature {temperature}."
    ]


def _table(header: Sequence[str], rows: Sequence[Sequence[str]]) -> list[str]:
    """Columns as wide as their widest cell: the pose name to the left, figures to the right."""
    widths = [max(len(row[j]) for row in [header, *rows]) for j in range(len(header))]
    return [
        "  "
        + "  ".join(
            cell.ljust(widths[j]) if j == 0 else cell.rjust(widths[j]) for j, cell in enumerate(row)
        ).rstrip()
        for row in [header, *rows]
    ]


def as_json(result: PoseCharacteristics, conditions: Conditions | None) -> dict[str, Any]:
    """``station analyze --json``'s ``iso9283``: per pose the barycentre, AP and RP; vAP by
    pose (None: no pose from two directions); the distance (None: none asked for); the
    conditions and the departures from the standard's."""
    d = result.distance
    return {
        "poses": {
            p.name: {
                "n": p.n,
                "barycentre": list(p.barycentre),
                "ap": p.ap,
                "ap_axes": list(p.ap_axes),
                "ap_relative": p.ap_relative,
                "rp": p.spatial.rp,
                "l_bar": p.spatial.l_mean,
                "s_l": p.spatial.l_sd,
                "command": None if p.command is None else list(p.command),
                "direction": p.direction,
            }
            for p in result.poses
        },
        "vap": result.vap,
        "distance": None
        if d is None
        else {
            "d_mean": d.d_mean,
            "dc": d.dc,
            "ad": d.ad,
            "rd": d.rd,
            "poses": [pose_name(d.pose_a), pose_name(d.pose_b)],
            "n": d.n,
            "s_d": d.s_d,
            "dc_from": d.command_source,
            "ad_axes": None if d.ad_axes is None else list(d.ad_axes),
        },
        "conditions": None if conditions is None else conditions.as_json(),
        "departures": departures(result, conditions),
    }
