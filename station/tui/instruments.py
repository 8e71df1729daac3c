"""The TUI's side of the instruments: the demo's simulated fixture and the "test connection".

Both use the instruments package as it is (the simulator, the protocol registry, the gauge
reader); nothing here parses a frame or writes a file.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from typing import Any

from station.errors import StationError

DEMO_PROTOCOL = "mitutoyo"
DEMO_CHANNEL_MAP = {"1": "x", "2": "y", "3": "z"}
TEST_CAPTURES = 5


@dataclass
class DemoFixture:
    """A running simulated fixture: its URL and the simulator to stop."""

    url: str
    protocol: str
    channel_map: dict[str, str]
    simulator: Any

    def stop(self) -> None:
        """Close the pseudo-terminal and stop the simulator's thread."""
        self.simulator.stop()


def start_demo_fixture(
    seed: int = 1990, *, unit: str = "in", resolution: float = 0.0001, link: str | None = None
) -> DemoFixture:
    """Start the simulator on a pseudo-terminal: a robot that repeats well in x, sits a little
    off nominal in y, and warms up (drifts) in z, so the demo shows each kind of verdict and a
    control-chart alarm. Deterministic for a seed. ``link``: a fixed path for the pty (a
    symlink), instead of ``/dev/pts/N``."""
    from station.instruments.protocols import get_protocol
    from station.instruments.simulator import AxisModel, FixtureModel, GaugeSpec, Simulator

    model = FixtureModel(
        {
            "x": AxisModel(bias=0.0, noise=0.00022),
            "y": AxisModel(bias=0.00025, noise=0.00036, skew=2.0),
            "z": AxisModel(bias=-0.0002, noise=0.00012, drift=0.0005, drift_tau=6.0),
        },
        GaugeSpec(resolution=resolution, low=-0.5, high=0.5, unit=unit),
    )
    protocol = get_protocol(DEMO_PROTOCOL)
    simulator = Simulator(protocol, model, seed=seed, channel_map=DEMO_CHANNEL_MAP)
    url = simulator.start_pty(link=link)
    return DemoFixture(
        url=url, protocol=DEMO_PROTOCOL, channel_map=dict(DEMO_CHANNEL_MAP), simulator=simulator
    )


def gauge_set(ports: Sequence[Any], trigger: str, **options: Any) -> Any:
    """A started-not GaugeSet over the runner's ``PortSetup``s (protocols from the registry)."""
    from station.instruments.gauge import GaugeSet, PortSpec
    from station.instruments.protocols import get_protocol

    specs = [
        PortSpec(
            url=port.url,
            protocol=get_protocol(port.protocol),
            channel_map=dict(port.channel_map),
            settings=port.settings,
        )
        for port in ports
    ]
    return GaugeSet(specs, trigger=trigger, **options)  # type: ignore[arg-type]


def test_connection(
    ports: Sequence[Any], trigger: str, captures: int = TEST_CAPTURES, timeout: float = 3.0
) -> Iterator[list[str]]:
    """Open the line, take a few reading sets and yield the lines to show after each one.

    Nothing is recorded. Raises StationError when the port cannot be opened or stays silent.
    """
    gauges = gauge_set(ports, trigger if trigger != "push" else "poll")
    gauges.start()
    try:
        if not gauges.wait_connected(timeout):
            states = ", ".join(f"{url}: {state}" for url, state in gauges.status().items())
            raise StationError(
                f"the port did not open within {timeout:g} s ({states}): check the port name, "
                "the cable and that no other program holds the port"
            )
        lines = [f"Connected to {', '.join(p.url for p in ports)}; readings (not recorded):"]
        yield lines
        for number in range(1, captures + 1):
            result = gauges.capture(timeout)
            values = "  ".join(
                f"{channel}={reading.value:+.5f}" for channel, reading in result.readings.items()
            )
            note = f"  ({result.message})" if result.message else ""
            lines = [*lines, f"  {number}: {values or 'no reading'}{note}"]
            yield lines
        yield [*lines, "The line works. Press F2 to start."]
    finally:
        gauges.stop()
