"""Shared builders for the session tests: real session files written through the real writer."""

from __future__ import annotations

from collections.abc import Callable
from datetime import UTC, datetime
from pathlib import Path

import pytest

from station.procedures import discover_procedures
from station.run import PortSetup, SessionSetup
from station.session.journal import SessionWriter

CHANNELS = ("x", "y", "z")


def session_header_fields(
    procedure_id: str = "repeatability", *, robot: str = "r2", operator: str = "ana", **setup
) -> dict:
    """The header fields production writes: ``SessionSetup(...).header_fields()``, the one
    function the TUI and ``station capture`` use (review finding 16)."""
    procedure = discover_procedures(use_env=False).get(procedure_id)
    port = PortSetup(
        url="loop://",
        protocol="mitutoyo",
        channel_map={str(n): ch for n, ch in enumerate(procedure.channels, start=1)},
    )
    return SessionSetup(
        procedure=procedure, robot=robot, operator=operator, ports=(port,), **setup
    ).header_fields()


def reading_fields(cycle: int) -> dict:
    """A deterministic reading set for ``cycle`` (zeroed value = raw - zero)."""
    channels = {}
    for index, channel in enumerate(CHANNELS):
        value = round(((cycle * 7 + index * 3) % 11 - 5) * 0.0001, 4)
        channels[channel] = {
            "value": value,
            "raw_value": round(0.375 + value, 4),
            "zero": 0.375,
            "unit": "in",
            "raw": f"0{index + 1}A+{0.375 + value:.4f}",
            "t_mono": 1000.0 + cycle,
            "t_wall": 1.7e9 + cycle,
        }
    return {"cycle": cycle, "step": "cycles", "channels": channels}


def write_session(folder: Path, cycles: int = 5, *, finish: bool = True, robot: str = "r2") -> Path:
    """A session with one of every common event type; returns its path (writer closed)."""
    header = session_header_fields(robot=robot, operator="ana")
    moment = datetime(2026, 11, 23, 12, 0, 0, tzinfo=UTC)
    with SessionWriter.create(folder, header, now=moment) as writer:
        writer.append("instrument", action="connect", port="sim")
        writer.append("step", step="fixture", action="confirmed", by="operator")
        writer.append("input", step="teach", values={"x": 12.5, "label": "A"})
        writer.append("zero", step="zero", channels={c: {"method": "software"} for c in CHANNELS})
        for cycle in range(1, cycles + 1):
            writer.append("reading", **reading_fields(cycle))
        if cycles >= 2:
            writer.append("reject", cycle=2, reason="bumped the fixture")
        writer.append("note", text="coffee spilled, wiped")
        writer.append("alarm", rule="report-1", channel="x", points=[3], text="beyond 3 sigma")
        writer.append("samples", step="stroke", stroke=1, channels=["x", "y"], values=[[0.0, 1.0]])
        if finish:
            writer.append("finish", verdict="capable")
    return writer.path


@pytest.fixture
def session_factory(tmp_path: Path) -> Callable[..., Path]:
    """Build sessions in a fresh folder: ``session_factory(cycles=5, finish=True)``."""

    def build(**kwargs) -> Path:
        return write_session(tmp_path / "sessions", **kwargs)

    return build
