"""Session files for the calibration-record tests, written through the real SessionWriter with
the header production writes (``SessionSetup.header_fields``) and seeded readings."""

from __future__ import annotations

from datetime import UTC, datetime
from pathlib import Path

import numpy as np
import pytest

from station.analysis.capability import SpecLimits
from station.instruments.simulator import FixtureModel
from station.instruments.zeroing import zero_from_readings
from station.procedures import discover_procedures
from station.run import PortSetup, SessionSetup
from station.session.journal import SessionWriter

AXES = ("x", "y", "z")
WHEN = datetime(2026, 11, 23, 12, 0, 0, tzinfo=UTC)


def header_fields(procedure_id: str, *, robot: str, operator: str = "ana", **setup) -> dict:
    """The header fields of a session of a built-in procedure on one simulated port."""
    procedure = discover_procedures(use_env=False).get(procedure_id)
    port = PortSetup(
        url="socket://127.0.0.1:7001",
        protocol="mitutoyo",
        channel_map={str(n): ch for n, ch in enumerate(procedure.channels, start=1)},
    )
    return SessionSetup(
        procedure=procedure, robot=robot, operator=operator, ports=(port,), **setup
    ).header_fields()


def _reading(values: dict[str, float], unit: str, zero: float = 0.375) -> dict:
    return {
        channel: {
            "value": value,
            "raw_value": round(zero + value, 6),
            "zero": zero,
            "unit": unit,
            "raw": f"01A+{zero + value:.4f}",
        }
        for channel, value in values.items()
    }


def write_repeatability(
    folder: Path,
    *,
    robot: str = "KSC-7",
    seed: int = 1,
    cycles: int = 30,
    bias: dict[str, float] | None = None,
    noise: dict[str, float] | None = None,
    created: datetime = WHEN,
    reject: tuple[int, str] | None = (2, "bumped the fixture"),
    note: str | None = "warm-up done at 11:40",
    alarm: bool = True,
    operator: str = "ana",
    resolution: float = 0.0001,
    unit: str | None = None,
) -> Path:
    """A finished repeatability session of ``cycles`` reading sets of x, y, z (rounded to the
    resolution), with a reject, a note and a recorded alarm."""
    rng = np.random.default_rng(seed)
    bias = {axis: 0.0 for axis in AXES} | (bias or {})
    noise = {axis: 0.0002 for axis in AXES} | (noise or {})
    header = header_fields("repeatability", robot=robot, operator=operator, unit=unit)
    with SessionWriter.create(folder, header, now=created) as writer:
        writer.append("instrument", port="socket://127.0.0.1:7001", state="connected")
        writer.append("step", step="fixture", action="confirmed", by="operator")
        writer.append(
            "zero",
            step="zero",
            channels={a: {"method": "software", "offset": 0.375} for a in AXES},
            by="operator",
        )
        for cycle in range(1, cycles + 1):
            values = {
                a: round(round((bias[a] + rng.normal(0, noise[a])) / resolution) * resolution, 6)
                for a in AXES
            }
            writer.append(
                "reading", cycle=cycle, step="cycles", channels=_reading(values, "in"), by="op"
            )
        if reject is not None and reject[0] <= cycles:
            writer.append("reject", cycle=reject[0], reason=reject[1], by="operator")
        if note:
            writer.append("note", text=note, by="operator")
        if alarm:
            writer.append(
                "alarm",
                channel="x",
                rule="report-1",
                points=[4],
                cycles=[5],
                text="cycle 5 beyond the control limits",
            )
        writer.append("finish", by="operator", complete=True, accepted=cycles, rejected=[])
    return writer.path


def simulated_session(
    model: FixtureModel, seed: int, *, cycles: int = 30, zero_readings: int = 5
) -> tuple[list[dict], list[dict]]:
    """A repeatability session of the simulator's ``model`` as the runner takes it: the zero
    step reads every gauge ``zero_readings`` times at the robot's first rest and records the
    mean (:func:`~station.instruments.zeroing.zero_from_readings`, the record and uncertainty
    the zero step writes); each cycle then reads the gauges once at the next rest, less the
    zero. Returns the ``zero`` event's fields and the ``reading`` events' fields."""
    channels = model.channels
    resolution = {c: model.gauge(c).resolution for c in channels}
    zeros = zero_from_readings(
        {c: [model.reading(c, 0, k, seed) for k in range(zero_readings)] for c in channels},
        resolution,
        min_readings=zero_readings,
    )
    offsets = {z.channel: z.offset for z in zeros}
    zero = {
        "step": "zero",
        "channels": {z.channel: {**z.record(), "uncertainty": z.uncertainty} for z in zeros},
        "by": "operator",
    }
    readings = []
    for cycle in range(1, cycles + 1):
        shown = {c: model.reading(c, cycle, zero_readings + cycle - 1, seed) for c in channels}
        readings.append(
            {
                "cycle": cycle,
                "step": "cycles",
                "channels": {
                    c: {
                        "value": round(value - offsets[c], 6),
                        "raw_value": value,
                        "zero": offsets[c],
                        "unit": model.gauge(c).unit,
                        "raw": f"01A{value:+.4f}",
                    }
                    for c, value in shown.items()
                },
                "by": "operator",
            }
        )
    return [zero], readings


def write_simulated(
    folder: Path, model: FixtureModel, seed: int, *, robot: str = "KSC-7", cycles: int = 30
) -> Path:
    """A finished repeatability session file of :func:`simulated_session`, written through the
    real SessionWriter."""
    zeros, readings = simulated_session(model, seed, cycles=cycles)
    header = header_fields("repeatability", robot=robot)
    with SessionWriter.create(folder, header, now=WHEN) as writer:
        writer.append("step", step="fixture", action="confirmed", by="operator")
        for zero in zeros:
            writer.append("zero", **zero)
        for reading in readings:
            writer.append("reading", **reading)
        writer.append("finish", by="operator", complete=True, accepted=cycles, rejected=[])
    return writer.path


def write_accuracy(
    folder: Path, *, robot: str = "KSC-7", seed: int = 2, placements: int = 5, per: int = 6
) -> Path:
    """A finished relative-accuracy session: ``per`` captures at each of ``placements``
    fixture placements, with the pendant coordinates of each."""
    rng = np.random.default_rng(seed)
    header = header_fields("relative_accuracy", robot=robot, placements=placements)
    cycle = 0
    with SessionWriter.create(folder, header, now=WHEN) as writer:
        for placement in range(1, placements + 1):
            pendant = {"x": 10.0 * placement, "y": -4.0 + placement, "z": 2.5 * (placement % 3)}
            writer.append(
                "zero",
                step="zero-first",
                placement=placement,
                channels={a: {"method": "software", "offset": 0.25} for a in AXES},
            )
            writer.append("input", step="pendant", placement=placement, values=pendant)
            for _ in range(per):
                cycle += 1
                values = {a: round(pendant[a] * 1e-5 + rng.normal(0, 0.0002), 4) for a in AXES}
                writer.append(
                    "reading",
                    cycle=cycle,
                    step="return",
                    placement=placement,
                    channels=_reading(values, "in", 0.25),
                )
        writer.append("reject", cycle=3, reason="fixture not seated")
        writer.append("finish", by="operator", complete=True)
    return writer.path


def write_linearity(
    folder: Path, *, robot: str = "KSC-7", seed: int = 3, strokes: int = 8, points: int = 60
) -> Path:
    """A finished linearity session: ``strokes`` strokes along a 10 in bar, back and forth,
    h with a bow and v with a sag, each stroke's last samples event marked ``end``."""
    rng = np.random.default_rng(seed)
    header = header_fields("linearity", robot=robot, strokes=strokes)
    with SessionWriter.create(folder, header, now=WHEN) as writer:
        writer.append(
            "zero", step="zero", channels={c: {"method": "software", "offset": 0.1} for c in "hv"}
        )
        for stroke in range(1, strokes + 1):
            s = np.linspace(0.0, 10.0, points)
            if stroke % 2 == 0:
                s = s[::-1]
            h = 0.0006 * (1 - ((s - 5) / 5) ** 2) + rng.normal(0, 0.00003, points)
            v = -0.0004 * (s / 10) ** 2 + rng.normal(0, 0.00003, points)
            rows = [
                [round(a, 6), round(b, 6), round(c, 4)] for a, b, c in zip(h, v, s, strict=True)
            ]
            for start in range(0, points, 20):
                writer.append(
                    "samples",
                    step="strokes",
                    stroke=stroke,
                    channels=["h", "v", "s"],
                    values=rows[start : start + 20],
                    end=True if start + 20 >= points else None,
                )
        writer.append("note", text="bar cleaned before stroke 1")
        writer.append("finish", by="operator", complete=True)
    return writer.path


def write_gauge_check(
    folder: Path, *, robot: str = "bench", seed: int = 4, cycles: int = 30, bias: float = 0.00005
) -> Path:
    """A finished gauge check (Type-1 study) of one indicator on a 0.25 in gauge block: the
    gauge id, reference and tolerance typed, the zero on the plate, ``cycles`` readings."""
    rng = np.random.default_rng(seed)
    header = header_fields("gauge_check", robot=robot)
    with SessionWriter.create(folder, header, now=WHEN) as writer:
        writer.append("step", step="stand", action="confirmed", by="operator")
        writer.append(
            "input",
            step="reference",
            values={"gauge": "DI-7", "reference": 0.25, "tolerance": 0.002},
        )
        writer.append(
            "zero", step="zero-plate", channels={"x": {"method": "software", "offset": 0.1}}
        )
        for cycle in range(1, cycles + 1):
            value = round(round((0.25 + bias + rng.normal(0, 0.00006)) / 0.0001) * 0.0001, 6)
            writer.append(
                "reading",
                cycle=cycle,
                step="readings",
                channels=_reading({"x": value}, "in", 0.1),
            )
        writer.append("finish", by="operator", complete=True)
    return writer.path


def write_joints(
    folder: Path, *, robot: str = "KSC-7", seed: int = 5, joints: int = 3, per: int = 10
) -> Path:
    """A finished per-joint troubleshooting session: ``per`` returns of each of ``joints``
    joints, its lever arm typed, joint 2 twice as loose as the others."""
    rng = np.random.default_rng(seed)
    limits = {a: SpecLimits(lsl=-0.001, usl=0.001) for a in AXES}
    header = header_fields("joint_troubleshooting", robot=robot, placements=joints, limits=limits)
    cycle = 0
    with SessionWriter.create(folder, header, now=WHEN) as writer:
        for joint in range(1, joints + 1):
            writer.append("input", step="lever", placement=joint, values={"lever": 10.0 * joint})
            writer.append(
                "zero",
                step="zero",
                placement=joint,
                channels={a: {"method": "software", "offset": 0.25} for a in AXES},
            )
            spread = 0.0004 if joint == 2 else 0.0002
            for _ in range(per):
                cycle += 1
                values = {a: round(float(rng.normal(0, spread)), 4) for a in AXES}
                writer.append(
                    "reading",
                    cycle=cycle,
                    step="returns",
                    placement=joint,
                    channels=_reading(values, "in", 0.25),
                )
        writer.append("finish", by="operator", complete=True)
    return writer.path


@pytest.fixture
def sessions(tmp_path: Path) -> Path:
    """An empty sessions folder."""
    folder = tmp_path / "sessions"
    folder.mkdir()
    return folder
