"""The TUI's side of the instruments: the demo's simulated fixture and the "test connection".

Both use the instruments package as it is (the simulator, the protocol registry, the gauge
reader); nothing here parses a frame or writes a file.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from typing import Any

from station.errors import StationError
from station.text import format_figure

DEMO_PROTOCOL = "mitutoyo"
TEST_CAPTURES = 5
DEMO_GAUGE_NOISE = 0.3
"""The demo indicators' own reading noise, in resolutions (σ): a robot at rest looks at rest."""


def demo_methods() -> dict[str, str]:
    """The methods ``station demo`` simulates, with the set-up each one's simulator models in
    words (:attr:`Method.demo_words <station.methods.contract.Method.demo_words>`)."""
    from station.methods import methods  # deferred: the methods load numpy

    return {name: m.demo_words for name, m in methods().items() if m.demo_words}


@dataclass
class DemoFixture:
    """A running simulated set-up: its URL, how to talk to it, and the simulator to stop."""

    url: str
    protocol: str
    channel_map: dict[str, str]
    simulator: Any
    method: str = ""
    """The method whose simulated set-up this is ("" for one a test started itself)."""
    trigger: str = "poll"
    description: str = "simulated dial indicators (seeded)"
    display: Callable[[Any, int | None, str], Any] | None = None
    """What the set-up shows at an input step (the method's ``DemoRig.display``)."""

    def shows(self, placement: int | None, unit: str) -> Any:
        """What the simulated set-up shows the operator at ``placement`` for an input step (a
        ``DemoDisplay``: the teach pendant's X, Y, Z, a master's size), or None."""
        if self.display is None:
            return None
        return self.display(self.simulator.model, placement, unit)

    def follow(self, state: Any) -> None:
        """Put the still simulated robot where the procedure's state says the operator has
        brought it (a moving robot follows its own clock): for two fixtures, home at the
        placement's first fixture until its return is to be captured; for one fixture, the
        taught position (rest 0) for the zero, then a new return for every cycle; on the bar,
        still at its end for the zeros, shuttling for the strokes; on a Gage R&R bench, the part
        the step asks for as its appraiser seats it. However many
        sets the station reads at one of these rests, they all read that rest."""
        simulator = self.simulator
        if simulator.motion is not None:
            return
        model = simulator.model
        capturing = state.action.kind == "capture"
        part = getattr(state.action, "part", None)
        if hasattr(model, "rest_of_part"):
            # A Gage R&R bench: the plate, or the part asked for as its appraiser (the step)
            # seats it, a new seating per cycle.
            if not capturing or part is None or state.current is None:
                rest = 0
            else:
                rest = model.rest_of_part(part, state.current.step.id, state.next_cycle)
        elif model.moves_per_set:
            # The bar's robot stands at its end for the zeros and shuttles for the strokes.
            rest = 1 if state.action.kind == "stream" else 0
        elif hasattr(model, "rest_of"):
            # Blocks of a rest where the station zeroes, then returns (two fixtures: one).
            done = state.progress.done if state.progress is not None else 0
            # Returns per block: the model's cycles (None: no end, one block), else one.
            cap = getattr(model, "cycles", 1)
            returned = (done + 1 if cap is None else min(done + 1, cap)) if capturing else 0
            rest = model.rest_of(state.placement or 1, returned)
        elif isinstance(state.next_cycle, int) and capturing:
            rest = state.next_cycle
        elif state.action.kind in ("zero", "confirm", "input"):
            rest = 0
        else:
            return
        if rest != simulator.rest:
            simulator.move_to_rest(rest)

    def stop(self) -> None:
        """Close the pseudo-terminal and stop the simulator's thread."""
        # Only this fixture's own entry: the kernel gives a closed /dev/pts/N to the next
        # pseudo-terminal opened, and a second stop of a stale fixture would otherwise untrack
        # the new set-up that now serves that path.
        if _RUNNING.get(self.url) is self:
            del _RUNNING[self.url]
        self.simulator.stop()


_RUNNING: dict[str, DemoFixture] = {}
"""The simulated set-ups started in this process, by URL: a session on one of them moves its
robot where the steps say (:meth:`DemoFixture.follow`)."""


def track(fixture: DemoFixture) -> DemoFixture:
    """Follow ``fixture`` (a simulated set-up started in this process) in the sessions that
    use its URL, until it stops: from now on the procedure's steps play its robot."""
    # ``station simulate``'s still robot moves to its next rest after a pause in the polls
    # (``return_gap``), standing in for an operator nobody plays. Followed, it must not move
    # as well: a slow screen between the frames check and the zero (a loaded machine) would
    # move it off the plate, and the zero would be taken on the block.
    fixture.simulator.return_gap = None
    _RUNNING[fixture.url] = fixture
    return fixture


def running_fixture(url: str) -> DemoFixture | None:
    """The simulated set-up started in this process that serves ``url``, if any."""
    return _RUNNING.get(url)


def start_demo_fixture(
    seed: int = 1990,
    *,
    method: str = "",
    unit: str = "in",
    resolution: float = 0.0001,
    link: str | None = None,
    stroke_points: int = 400,
    cycle_period: float | None = None,
) -> DemoFixture:
    """Start the simulator of ``method``'s set-up (its :meth:`demo_rig
    <station.methods.contract.Method.demo_rig>`; the default method's for one without, or for
    "") on a pseudo-terminal, seeded; ``stroke_points`` points per streamed stroke.

    ``link``: a fixed path for the pty (a symlink), instead of ``/dev/pts/N``.
    ``cycle_period``: a robot that can run a playback loop leaves the fixture and comes back
    every so many seconds (its indicators at free travel while away, a short overshoot on
    return), and the set-up takes the ``arrival`` trigger: the station counts the robot's
    round trips. Without it every poll is a new rest position (Space per cycle).
    """
    # Deferred: the gauge layer (about 80 ms) loads when a line is opened, off the start path.
    from station.instruments.motion import CycleMotion, default_free_travel
    from station.instruments.protocols import get_protocol
    from station.instruments.simulator import GaugeSpec, Simulator
    from station.methods import BUILT_IN, methods

    protocol = get_protocol(DEMO_PROTOCOL)
    # The indicators' own noise: readings at rest scatter by about a third of a resolution.
    gauge = GaugeSpec(
        resolution=resolution, low=-0.5, high=0.5, unit=unit, noise=DEMO_GAUGE_NOISE * resolution
    )
    chosen = methods().get(method)
    rig = chosen.demo_rig(gauge, seed, stroke_points=stroke_points) if chosen else None
    if chosen is None or rig is None:
        chosen = BUILT_IN[0]
        rig = chosen.demo_rig(gauge, seed, stroke_points=stroke_points)
        assert rig is not None, "the default method has a simulated set-up"
    trigger, description, motion = rig.trigger, rig.description, None
    if cycle_period is not None and rig.loops:
        motion = CycleMotion(cycle_period, default_free_travel(unit), 20 * resolution)
        trigger = "arrival"
        description = f"simulated dial indicators, the robot back every {cycle_period:g} s (seeded)"
    simulator = Simulator(
        protocol,
        rig.model,
        seed=seed,
        channel_map=dict(rig.channel_map),
        push_rate=rig.push_rate,
        motion=motion,
    )
    url = simulator.start_pty(link=link)
    fixture = DemoFixture(
        url=url,
        protocol=DEMO_PROTOCOL,
        channel_map=dict(rig.channel_map),
        simulator=simulator,
        method=chosen.name,
        trigger=trigger,
        description=description,
        display=rig.display,
    )
    return track(fixture)


class DemoLab:
    """The demo's simulators, one per method, each started the first time it is asked for
    (so the set-up's procedure picker switches the simulated set-up with the procedure)."""

    def __init__(
        self,
        seed: int = 1990,
        *,
        stroke_points: int = 400,
        cycle_period: float | None = None,
        link_prefix: str | None = None,
    ) -> None:
        self.seed = seed
        self.stroke_points = stroke_points
        self.cycle_period = cycle_period
        """The repeatability robot's round trip in seconds (None: it does not move)."""
        self.link_prefix = link_prefix
        """When set, each simulator's port is also a link named ``<prefix>-<method>`` (a name
        that does not change from run to run, for the screen snapshots)."""
        self._fixtures: dict[str, DemoFixture] = {}

    def fixture(self, method: str) -> DemoFixture:
        """The running simulator for ``method``'s set-up (the default method's for a method
        without one)."""
        from station.methods import BUILT_IN  # deferred: the methods load numpy

        key = method if method in demo_methods() else BUILT_IN[0].name
        if key not in self._fixtures:
            link = f"{self.link_prefix}-{key}" if self.link_prefix else None
            self._fixtures[key] = start_demo_fixture(
                self.seed,
                method=key,
                stroke_points=self.stroke_points,
                cycle_period=self.cycle_period,
                link=link,
            )
        return self._fixtures[key]

    def by_url(self, url: str) -> DemoFixture | None:
        """The running simulator on ``url``, if it is one of the demo's."""
        return next((f for f in self._fixtures.values() if f.url == url), None)

    def stop(self) -> None:
        """Stop every simulator started."""
        fixtures, self._fixtures = list(self._fixtures.values()), {}
        for fixture in fixtures:
            fixture.stop()


def gauge_set(ports: Sequence[Any], trigger: str, **options: Any) -> Any:
    """A started-not GaugeSet over the runner's ``PortSetup``s (protocols from the registry)."""
    from station.instruments.gauge import GaugeSet, PortSpec  # deferred: as above
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
    ports: Sequence[Any],
    trigger: str,
    captures: int = TEST_CAPTURES,
    timeout: float = 3.0,
    *,
    unit: str | None = None,
    resolution: float | None = None,
) -> Iterator[list[str]]:
    """Open the line, take a few reading sets and yield the lines to show after each one: the
    values at the gauge's ``resolution`` (as the dashboard shows them) with their unit (the
    frame's own, else ``unit``); with ``unit`` and ``resolution``, then judge the frames
    against them.

    Nothing is recorded. Raises StationError when the port cannot be opened or stays silent,
    or when the frames disagree with the unit and resolution (naming both).
    """
    from station.instruments.units import describe_inference  # deferred: as above

    # Arrival waits for the robot: the test polls (a push device is polled too, where it can).
    gauges = gauge_set(ports, "poll" if trigger in ("push", "arrival") else trigger)
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
                f"{channel}={format_figure(reading.value, resolution)}"
                for channel, reading in result.readings.items()
            )
            # The frame's own unit when it states one, else the set-up's (``unit`` of a
            # reading without one is only the reader's default).
            units = {
                str(r.frame_unit)
                for r in result.readings.values()
                if getattr(r, "frame_unit", None)
            }
            shown_unit = units.pop() if len(units) == 1 else ("" if units else unit)
            if values and shown_unit:
                values += f" {shown_unit}"
            note = f"  ({result.message})" if result.message else ""
            lines = [*lines, f"  {number}: {values or 'no reading'}{note}"]
            yield lines
        if unit is not None and resolution is not None:
            # The frames of the sets just shown (no more readings are taken).
            problem = gauges.check_frames(unit, resolution, readings=0, timeout=timeout)
            if problem:
                raise StationError(
                    f"The line works, but {problem}: set the unit and resolution to the "
                    "gauges' (or the gauges to the session's) before starting"
                )
            inferred = describe_inference(gauges.infer_frames())
            lines = [*lines, f"The frames agree with {unit} at {resolution:g} ({inferred})."]
        yield [*lines, "The line works. Press F2 to start."]
    finally:
        gauges.stop()
