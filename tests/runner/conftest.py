"""Real instruments for the runner tests: a seeded simulator on a pseudo-terminal and the real
gauge set reading it, both in this process."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from pathlib import Path

import pytest
from helpers import CYCLES_ONLY

from station.instruments.protocols import get_protocol
from station.instruments.simulator import AxisModel, Faults, GaugeSpec, Simulator, fixture_model
from station.procedures import Procedure, discover_procedures, parse_procedure
from station.run import PortSetup, SessionSetup, open_gauges

CHANNELS = ("x", "y", "z")
DEVICE_MAP = {"1": "x", "2": "y", "3": "z"}


def make_simulator(seed: int = 7, faults: Faults | None = None, push_rate: float = 0.0):
    """A Mitutoyo-speaking fixture in inches at 0.0001 in (the report's gauges)."""
    model = fixture_model(
        CHANNELS,
        axis=AxisModel(noise=0.0003),
        gauge=GaugeSpec(resolution=0.0001, unit="in", low=-1.0, high=1.0),
    )
    return Simulator(get_protocol("mitutoyo"), model, faults, seed=seed, push_rate=push_rate)


def repeatability() -> Procedure:
    """The built-in repeatability procedure."""
    return discover_procedures(use_env=False).get("repeatability")


@pytest.fixture
def simulator() -> Iterator[Simulator]:
    """A started simulator on a pty (polled)."""
    sim = make_simulator()
    sim.start_pty()
    yield sim
    sim.stop()


@pytest.fixture
def gauges_for() -> Iterator[Callable[..., object]]:
    """``gauges_for(setup)``: the started gauge set of a set-up; stopped after the test."""
    started = []

    def build(setup: SessionSetup):
        gauges = open_gauges(setup, backoff=(0.05, 0.2))
        started.append(gauges)
        assert gauges.wait_connected(5.0), "the simulator's pty did not open"
        return gauges

    yield build
    for gauges in started:
        gauges.stop()


@pytest.fixture
def warming_robot() -> Iterator[Simulator]:
    """A robot that warms up (x drifts over the whole run) and throws outliers (y): live
    alarms are sure to come (polled, on a pty)."""
    model = fixture_model(
        CHANNELS,
        axis={
            "x": AxisModel(noise=0.0002, drift=0.004, drift_tau=60.0),
            "y": AxisModel(noise=0.0002, outlier_rate=0.12, outlier_size=8.0),
            "z": AxisModel(noise=0.0002),
        },
        gauge=GaugeSpec(resolution=0.0001, unit="in", low=-1.0, high=1.0),
    )
    sim = Simulator(get_protocol("mitutoyo"), model, None, seed=11)
    sim.start_pty()
    yield sim
    sim.stop()


def setup_for(
    url: str,
    procedure: Procedure | None = None,
    *,
    cycles: int | None = None,
    trigger: str = "poll",
    channel_map: dict[str, str] | None = None,
) -> SessionSetup:
    """A set-up reading the simulator at ``url``."""
    return SessionSetup(
        procedure=procedure or repeatability(),
        robot="KSC-7",
        operator="tester",
        ports=(PortSetup(url, "mitutoyo", channel_map or DEVICE_MAP),),
        trigger=trigger,
        cycles=cycles,
    )


EVERY_KIND = b"""
id = "every-kind"
title = "Every step kind the runner drives"
version = "1"
report_section = "2.8.2"
channels = ["x", "y", "z"]
unit = "in"
resolution = 0.0001
# The placements capture x and y only: judged as repeatability, not relative accuracy.
analysis = "repeatability"
[cycles]
min = 2
target = 3
[limits]
tolerance = 0.002
[[steps]]
id = "fixture"
kind = "check"
title = "Fix the fixture"
[[steps]]
id = "pendant"
kind = "input"
title = "Read the pendant"
fields = [
    { name = "x", label = "Pendant X", unit = "in" },
    { name = "remark", type = "text", required = false },
]
[[steps]]
id = "zero"
kind = "zero"
title = "Zero"
[[steps]]
id = "placements"
kind = "repeat"
title = "Each placement"
target = 2
[[steps.steps]]
id = "place"
kind = "check"
title = "Place the fixture"
[[steps.steps]]
id = "inverse"
kind = "capture"
title = "Capture after the inverse move"
channels = ["x", "y"]
[[steps]]
id = "cycles"
kind = "cycles"
title = "Cycles"
"""


def written_procedure(path: Path, data: bytes) -> Procedure:
    """``data`` written as the procedure file ``path`` (a session records the file it ran) and
    that procedure."""
    path.write_bytes(data)
    return parse_procedure(data, path)


def every_kind_procedure(folder: Path) -> Procedure:
    """A procedure with check, input, zero, repeat (check + capture) and cycles steps."""
    return written_procedure(folder / "every-kind.toml", EVERY_KIND)


def cycles_only_procedure(folder: Path) -> Procedure:
    """A procedure that is one cycles step (for tests about reading sets alone)."""
    return written_procedure(folder / "cycles-only.toml", CYCLES_ONLY)


STROKES = b"""
id = "strokes"
title = "Straightness along a bar"
version = "1"
report_section = "2.9.3"
channels = ["h", "v", "s"]
unit = "mm"
resolution = 0.001
[[steps]]
id = "along"
kind = "stroke"
title = "Move along the bar"
channels = ["h", "v", "s"]
direction_channel = "s"
min = 2
target = 2
"""


def strokes_procedure(folder: Path) -> Procedure:
    """A procedure that is one stroke step over channels h, v and s (linearity's shape)."""
    return written_procedure(folder / "strokes.toml", STROKES)
