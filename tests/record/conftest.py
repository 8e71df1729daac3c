"""Session files for the calibration-record tests, written through the real SessionWriter with
the header production writes (``SessionSetup.header_fields``) and seeded readings."""

from __future__ import annotations

from datetime import UTC, datetime
from pathlib import Path

import numpy as np
import pytest

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


@pytest.fixture
def sessions(tmp_path: Path) -> Path:
    """An empty sessions folder."""
    folder = tmp_path / "sessions"
    folder.mkdir()
    return folder
