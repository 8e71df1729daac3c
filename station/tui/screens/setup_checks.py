"""Reading the set-up form: the typed text turned into the engine's ``PortSetup`` and
``SessionSetup``, each refused value as a sentence for the row it belongs to.

The rules are :mod:`station.text`'s (limits, channel maps), the engine's and the analysis'
(``SessionSetup``, ``SpecLimits``), the same the command line uses: this module only says
which field a refusal belongs under. ``value`` is the form's reader, field id -> typed text.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from station.analysis.capability import SpecLimits
from station.analysis.tolerance import implausible_tolerance
from station.errors import StationError
from station.instruments.protocols import get_protocol
from station.instruments.transport import refuse_own_terminal, url_scheme
from station.text import LIMIT_HELP, parse_channel_map, parse_limits_text
from station.tui.remedies import explained
from station.tui.screens.setup_form import count_field, judged_channels

if TYPE_CHECKING:
    from station.procedures import Procedure
    from station.run import PortSetup, SessionSetup

Value = Callable[[str], str]
"""The form's reader: a field id -> the text in it, stripped."""


def read_ports(value: Value, errors: dict[str, str]) -> tuple[PortSetup, ...]:
    """The instrument line as the engine's ``PortSetup`` (empty when a field is refused);
    each fault goes into ``errors`` under its field id."""
    # Deferred: the engine loads numpy, which the set-up loads on a worker meanwhile.
    from station.run import PortSetup

    url = value("port")
    if not url:
        errors["port"] = "Name the port of the indicators (or pick a detected one above)."
    elif url_scheme(url) is None:
        try:
            refuse_own_terminal(url)
        except StationError as error:
            errors["port"] = explained(error)
    try:
        protocol = get_protocol(value("protocol"))
    except StationError as error:
        errors["protocol"] = explained(error)
        protocol = None
    try:
        channel_map = parse_channel_map(value("map"))
        if not channel_map:
            raise StationError("say which device channel feeds which axis, e.g. 1=x,2=y,3=z")
    except StationError as error:
        errors["map"] = explained(error)
        channel_map = {}
    if errors.keys() & {"port", "protocol", "map"} or protocol is None:
        return ()
    return (
        PortSetup(
            url=url,
            protocol=value("protocol"),
            channel_map=channel_map,
            settings=protocol.settings,
        ),
    )


def read_resolution(value: Value) -> float | None:
    """The resolution typed, or None while it is not a positive number."""
    try:
        resolution = float(value("resolution"))
    except ValueError:
        return None
    return resolution if math.isfinite(resolution) and resolution > 0 else None


def read_limits(value: Value, procedure: Procedure, errors: dict[str, str]) -> dict[str, Any]:
    """Each judged channel's limits as ``SpecLimits``; a refusal under ``limits-<channel>``."""
    limits: dict[str, Any] = {}
    for channel in judged_channels(procedure):
        try:
            typed = parse_limits_text(value(f"limits-{channel}"))
            if typed is None:
                raise StationError(
                    f"Give the limits of {channel}: {LIMIT_HELP}. The verdict needs them."
                )
            limits[channel] = SpecLimits(lsl=typed.lsl, usl=typed.usl, nominal=typed.nominal)
        except StationError as error:
            errors[f"limits-{channel}"] = explained(error)
    return limits


def read_count(value: Value, procedure: Procedure, errors: dict[str, str]) -> int:
    """The cycles, placements or strokes asked for (a refusal under ``cycles``). Fewer than the
    report asks for are a short trial run (``station demo --count 5``): its verdict comes with
    the wide confidence bound on Cpk that so few readings give. Fewer than the method can
    judge (a gain schedule's fit from 2 positions) are refused, in the demo too."""
    count = count_field(procedure)
    try:
        asked = int(value("cycles"))
    except ValueError:
        errors["cycles"] = f"Give a whole number of {count.noun}, e.g. {count.target}."
        return 0
    if asked < count.minimum:
        errors["cycles"] = count.too_few
    return asked


def read_setup(
    value: Value, procedure: Procedure, *, operator: str, errors: dict[str, str]
) -> SessionSetup | None:
    """A validated ``SessionSetup``, or None with each fault in ``errors`` under its field id.
    A fault of the whole (``SessionSetup`` refusing the combination) is raised as
    StationError."""
    from station.record.baseline import header_baseline  # deferred: loads numpy
    from station.run import SessionSetup  # deferred: the engine loads numpy

    robot = value("robot")
    if not robot:
        errors["robot"] = "Name the robot under test (its name or asset number)."
    resolution = read_resolution(value)
    if resolution is None:
        errors["resolution"] = (
            f"The resolution must be a positive number such as {procedure.resolution:g}."
        )
    limits = read_limits(value, procedure, errors)
    asked = read_count(value, procedure, errors)
    ports = read_ports(value, errors)
    if errors:
        return None
    unit = value("unit")
    # The method names the count's argument (cycles, placements or strokes).
    count: dict[str, Any] = {count_field(procedure).setup_key: asked}
    return SessionSetup(
        procedure=procedure,
        robot=robot,
        operator=value("operator") or operator,
        ports=ports,
        trigger=value("trigger"),  # type: ignore[arg-type]
        unit=unit,
        resolution=resolution,
        limits=limits,
        **count,
        # Live alarms test against the robot's baseline for this procedure and unit.
        baseline=header_baseline(robot, procedure.id, unit or procedure.unit),
    )


def limits_key(setup: Any) -> tuple[Any, ...]:
    """What a confirmation of implausible limits holds for: the resolution and every limit."""
    return (
        setup.resolution,
        tuple(sorted((c, lim.lsl, lim.usl, lim.nominal) for c, lim in setup.limits.items())),
    )


def implausible(setup: Any) -> dict[str, str]:
    """Channel -> a sentence for each tolerance under 10 or over 100,000 gauge steps."""
    doubts: dict[str, str] = {}
    for channel, limits in setup.limits.items():
        sentence = implausible_tolerance(
            channel, limits.lsl, limits.usl, limits.nominal, setup.resolution, setup.unit
        )
        if sentence:
            doubts[channel] = sentence
    return doubts
