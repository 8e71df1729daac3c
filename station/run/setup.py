"""What a session is set up with, before the engine runs it: the ports, the set-up the set-up
screen or the ``station capture`` flags collect, the plan of steps, and the gauges it opens.
"""

from __future__ import annotations

import math
import socket
from collections.abc import Callable, Collection, Mapping, Sequence
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from station.analysis.capability import SpecLimits
from station.errors import StationError
from station.instruments.base import SerialSettings
from station.instruments.gauge import GaugeSet, PortSpec
from station.instruments.protocols import get_protocol
from station.instruments.reader import DEFAULT_BACKOFF
from station.instruments.transport import pseudo_terminal_opened
from station.instruments.triggers import TRIGGERS, Trigger
from station.methods import method_of
from station.procedures import Procedure, Step, discover_procedures
from station.run.steps import handler_for
from station.run.steps.base import PlanItem
from station.session.header import header_limits
from station.session.model import Session, load_session


@dataclass(frozen=True)
class PortSetup:
    """One serial line: where it is, what it speaks, and which station channel each device
    channel feeds (``{"1": "x", "2": "y", "3": "z"}``). ``settings`` ``None`` means the
    protocol's own line settings."""

    url: str
    protocol: str
    channel_map: Mapping[str, str]
    settings: SerialSettings | None = None

    def resolved_settings(self) -> SerialSettings:
        """The line settings in force: the given ones, else the protocol's."""
        return self.settings or get_protocol(self.protocol).settings

    def header(self) -> dict[str, Any]:
        """The port as it is recorded in the session header's ``instruments``."""
        return {
            "url": self.url,
            "protocol": self.protocol,
            "map": dict(self.channel_map),
            "settings": self.resolved_settings().as_kwargs(),
        }

    @classmethod
    def from_header(cls, recorded: Mapping[str, Any]) -> PortSetup:
        """The port a session header recorded (for resuming on the same line)."""
        settings = recorded.get("settings")
        return cls(
            url=str(recorded["url"]),
            protocol=str(recorded["protocol"]),
            channel_map={str(k): str(v) for k, v in dict(recorded.get("map") or {}).items()},
            settings=SerialSettings(**settings) if settings else None,
        )


@dataclass(frozen=True)
class SessionSetup:
    """What the set-up screen or the ``station capture`` flags collect before a session starts.

    ``None`` for ``unit``, ``resolution``, ``limits`` or ``cycles`` means the procedure's own
    value. Construction validates and raises :class:`StationError` with a sentence naming the
    field (``error.field``), so a set-up screen can show it next to the field.
    """

    procedure: Procedure
    robot: str
    operator: str
    ports: tuple[PortSetup, ...]
    trigger: Trigger = "poll"
    unit: str | None = None
    resolution: float | None = None
    limits: Mapping[str, Any] | None = None
    """Per channel a :class:`station.analysis.capability.SpecLimits` (or anything with ``lsl``,
    ``usl`` and ``nominal``)."""
    cycles: int | None = None
    rule_set: str = "report"
    threshold: float = 1.0
    placements: int | None = None
    """How many times each ``repeat`` block runs (fixture placements); ``None``: its target."""
    strokes: int | None = None
    """How many whole strokes each ``stroke`` step asks for; ``None``: its target."""
    baseline: Mapping[str, Any] | None = None
    """The robot's baseline (phase II limits and where they came from, as the header records
    it), which the live alarms test against; ``None``: the limits freeze after phase I."""
    gauges: Mapping[str, str] | None = None
    """The gauge id or serial on each channel (for the gauge register); ``None``: none named."""

    def __post_init__(self) -> None:
        if not self.robot.strip():
            raise StationError("the robot name is empty: name the robot under test", field="robot")
        if self.trigger not in TRIGGERS:
            raise StationError(
                f"unknown trigger {self.trigger!r}: use one of {', '.join(TRIGGERS)}",
                field="trigger",
            )
        for name, value in (
            ("cycles", self.cycles),
            ("placements", self.placements),
            ("strokes", self.strokes),
        ):
            if value is not None and value < 1:
                raise StationError(f"{name} must be at least 1, not {value}", field=name)
        if self.resolution is not None and not (
            math.isfinite(self.resolution) and self.resolution > 0
        ):
            raise StationError(
                f"the gauge resolution must be positive, not {self.resolution}",
                field="resolution",
            )
        if not math.isfinite(self.threshold) or self.threshold <= 0:
            raise StationError(
                f"the capability threshold must be positive, not {self.threshold}",
                field="threshold",
            )
        unknown = sorted(set(self.limits or {}) - set(self.channels))
        if unknown:
            raise StationError(
                f"limits given for {', '.join(unknown)}, which procedure "
                f"{self.procedure.id!r} does not measure (its channels: "
                f"{', '.join(self.channels)})",
                field="limits",
            )
        if not self.ports:
            raise StationError(
                "no port given: name the serial port of the indicators", field="port"
            )
        mapped = {ch for port in self.ports for ch in port.channel_map.values()}
        missing = [ch for ch in self.channels if ch not in mapped]
        if missing:
            raise StationError(
                f"no device channel feeds {', '.join(missing)}",
                field="map",
                remedy="map_channel",
                subject=", ".join(missing),
            )

    @property
    def channels(self) -> tuple[str, ...]:
        """The station channels the procedure measures, in its order."""
        return tuple(self.procedure.channels)

    @property
    def resolved_unit(self) -> str:
        """The session's unit: the set-up's, else the procedure's."""
        return self.unit or self.procedure.unit

    @property
    def resolved_resolution(self) -> float:
        """The gauge resolution: the set-up's, else the procedure's."""
        return float(self.resolution if self.resolution is not None else self.procedure.resolution)

    @property
    def resolved_cycles(self) -> int:
        """The number of cycles a ``cycles`` step asks for: the set-up's, else the procedure's
        target."""
        return int(self.cycles if self.cycles is not None else self.procedure.cycles_target)

    def resolved_limits(self) -> dict[str, Any]:
        """Spec limits per channel: the procedure's defaults overridden by the set-up's."""
        return procedure_limits(self.procedure) | dict(self.limits or {})

    def arrival_header(self) -> dict[str, Any]:
        """The arrival trigger's parameters as the session header records them (the band in
        the session's unit, resolved from the resolution when the procedure gives none)."""
        arrival = self.procedure.arrival
        return {
            "band": arrival.band_of(self.resolved_resolution),
            "still": arrival.still,
            "settle": arrival.settle,
            "timeout": arrival.timeout,
            "stop": arrival.stop,
            **({"free_travel": dict(arrival.free_travel)} if arrival.free_travel else {}),
            **({"trace": arrival.trace} if arrival.trace else {}),
        }

    def header_fields(self) -> dict[str, Any]:
        """The session header's fields (the journal adds format, session id, created, prev).
        Each step kind in the plan may add fields of its own (a stroke step records the
        deadband its split uses), and so may the method."""
        fields: dict[str, Any] = {
            "procedure": {
                "id": self.procedure.id,
                "version": self.procedure.version,
                "sha256": self.procedure.sha256,
                "analysis": self.procedure.analysis,
            },
            "robot": self.robot,
            "operator": self.operator,
            "host": socket.gethostname(),
            "unit": self.resolved_unit,
            "resolution": self.resolved_resolution,
            "limits": {
                channel: {"lsl": limits.lsl, "usl": limits.usl, "nominal": limits.nominal}
                for channel, limits in self.resolved_limits().items()
            },
            "channels": list(self.channels),
            "instruments": {
                "trigger": self.trigger,
                "ports": [port.header() for port in self.ports],
                **({"arrival": self.arrival_header()} if self.trigger == "arrival" else {}),
            },
            "cycles_target": self.resolved_cycles,
            # The count below which a verdict is provisional, and when the live limits freeze.
            "cycles_min": self.procedure.cycles_min,
            "freeze_after": self.procedure.cycles_min,
            **({"placements_target": self.placements} if self.placements else {}),
            **({"strokes_target": self.strokes} if self.strokes else {}),
            "rules": self.rule_set,
            "threshold": self.threshold,
            # How a reading is judged against its limits with the measurement budget's U
            # (ISO 14253-1 guarded acceptance); kept so a later station judges it alike.
            "decision_rule": "guarded",
            **({"baseline": dict(self.baseline)} if self.baseline else {}),
            **({"gauges": dict(self.gauges)} if self.gauges else {}),
        }
        for step in self.procedure.all_steps():
            fields.update(handler_for(step.kind).header_fields(self, step))
        # And the method's (a repeatability session: the gauge checks covering its gauges).
        fields.update(method_of(self.procedure.analysis).header_fields(fields))
        return fields


def procedure_limits(procedure: Procedure) -> dict[str, SpecLimits]:
    """The procedure file's default limits, per channel."""
    return {
        channel: SpecLimits(lsl=limit.lsl, usl=limit.usl, nominal=limit.nominal)
        for channel, limit in procedure.limits.items()
    }


def setup_from_header(
    header: Mapping[str, Any],
    procedure: Procedure,
    *,
    ports: Sequence[PortSetup] | None = None,
) -> SessionSetup:
    """The set-up a session header records, to resume it. ``ports`` replaces the recorded
    ports (a USB adapter that came back under another name)."""
    instruments = dict(header.get("instruments") or {})
    recorded_ports = tuple(PortSetup.from_header(p) for p in instruments.get("ports") or ())
    cycles = header.get("cycles_target")
    placements, strokes = header.get("placements_target"), header.get("strokes_target")
    return SessionSetup(
        procedure=procedure,
        robot=str(header["robot"]),
        operator=str(header.get("operator") or ""),
        ports=tuple(ports) if ports else recorded_ports,
        trigger=instruments.get("trigger", "poll"),
        unit=str(header["unit"]),
        resolution=float(header["resolution"]) if header.get("resolution") else None,
        limits=header_limits(header),
        cycles=int(cycles) if isinstance(cycles, int) else None,
        rule_set=str(header.get("rules") or "report"),
        threshold=float(header.get("threshold") or 1.0),
        placements=placements if isinstance(placements, int) else None,
        strokes=strokes if isinstance(strokes, int) else None,
        baseline=header.get("baseline") if isinstance(header.get("baseline"), Mapping) else None,
        gauges={str(c): str(g) for c, g in dict(header.get("gauges") or {}).items()} or None,
    )


def recorded_setup(
    path: str | Path,
    *,
    procedures_dirs: Sequence[str | Path] = (),
    ports: Sequence[PortSetup] | None = None,
) -> SessionSetup:
    """The set-up the unfinished session in ``path`` records (its procedure found by id;
    ``ports`` replaces its line), not checked against the devices as they are now: to compare
    what a command line gives with the session's. To resume, take :func:`resume_setup`."""
    return _recorded(path, procedures_dirs, ports)[0]


def resume_setup(
    path: str | Path,
    *,
    procedures_dirs: Sequence[str | Path] = (),
    ports: Sequence[PortSetup] | None = None,
    own_simulators: Collection[str] = (),
) -> SessionSetup:
    """The set-up to resume the session in ``path`` with (its procedure found by id; ``ports``
    replaces the recorded line: a USB adapter that came back under another name).

    A port at a pseudo-terminal path the session used (``/dev/pts/5``) that was opened after
    the session last used it is refused (StationError naming the port field): the kernel gives
    a closed pseudo-terminal's number to the next program, and opened as the gauges' line it
    would be someone's terminal or another program's. ``own_simulators``: the URLs of
    simulators this process started to stand in for the instruments (the demo's), which are
    the line whatever their number."""
    setup, session = _recorded(path, procedures_dirs, ports)
    for port in setup.ports:
        if port.url not in own_simulators:
            _refuse_another_pseudo_terminal(port.url, _last_used(session))
    return setup


def _recorded(
    path: str | Path,
    procedures_dirs: Sequence[str | Path],
    ports: Sequence[PortSetup] | None,
) -> tuple[SessionSetup, Session]:
    session = load_session(path, recover=False)
    if session.finished:
        raise StationError(f"session {path} is finished; start a new session instead")
    procedure = discover_procedures(procedures_dirs).get(session.procedure_id)
    return setup_from_header(session.header, procedure, ports=ports), session


def _last_used(session: Session) -> dict[str, str]:
    """When the session last wrote while each of its lines was in use, by URL (an event's
    ``t``): the header's ports from its creation, a resume's ports from that resume on."""

    def urls(instruments: Any) -> list[str]:
        ports = dict(instruments or {}).get("ports") or ()
        return [str(port.get("url")) for port in ports if isinstance(port, Mapping)]

    in_use = urls(session.header.get("instruments"))
    last = {url: str(session.header.get("created") or "") for url in in_use}
    for event in session.events:
        if event.get("type") == "resume" and event.get("instruments"):
            in_use = urls(event["instruments"])
        for url in in_use:
            last[url] = str(event.get("t") or "")
    return last


def _refuse_another_pseudo_terminal(url: str, last_used: Mapping[str, str]) -> None:
    """StationError when ``url`` is a pseudo-terminal opened after the session last used it."""
    used_at = _moment(last_used.get(url))
    opened = pseudo_terminal_opened(url)
    if used_at is None or opened is None:
        return
    opened_at = datetime.fromtimestamp(opened, UTC)
    if opened_at <= used_at:
        return
    raise StationError(
        f"{url} is not the pseudo-terminal this session recorded: the session last used "
        f"{url} at {_local(used_at)}, and the one there now was opened at {_local(opened_at)}, "
        "by another program (the number of a closed pseudo-terminal is given to the next "
        "one); name the port of the running simulator or bridge. Nothing was written",
        field="port",
    )


def _moment(text: str | None) -> datetime | None:
    try:
        return datetime.fromisoformat(text) if text else None
    except ValueError:
        return None


def _local(moment: datetime) -> str:
    """A time as the operator's clock shows it, to the second (with the date when not today)."""
    local = moment.astimezone()
    if local.date() == datetime.now().astimezone().date():
        return f"{local:%H:%M:%S}"
    return f"{local:%Y-%m-%d %H:%M:%S}"


def open_gauges(
    setup: SessionSetup,
    *,
    backoff: tuple[float, float] | None = None,
    on_reading: Callable[[Any], object] | None = None,
    poll_interval: float | None = None,
) -> GaugeSet:
    """Build and start the :class:`~station.instruments.gauge.GaugeSet` the set-up describes.

    The engine subscribes to its sets, port changes and arrival news; ``on_reading`` (every
    accepted frame, on a reader thread) is for a live display. The caller stops the set when
    done. The ``arrival`` trigger takes the procedure's ``[arrival]`` table (its band, by
    default 100 resolutions of the session's gauges); ``poll_interval`` (how often a polled
    device is asked while the gauges are read continuously) is by default 0.1 s, or a quarter
    of the arrival settle time when that is shorter, so stillness is judged on several
    readings.
    """
    arrival = setup.procedure.arrival
    if poll_interval is None:
        poll_interval = min(0.1, arrival.settle / 4) if setup.trigger == "arrival" else 0.1
    specs = [
        PortSpec(
            url=port.url,
            protocol=get_protocol(port.protocol),
            channel_map=dict(port.channel_map),
            settings=port.settings,
        )
        for port in setup.ports
    ]
    gauges = GaugeSet(
        specs,
        trigger=setup.trigger,
        unit=setup.resolved_unit,
        resolution=setup.resolved_resolution,
        poll_interval=poll_interval,
        on_reading=on_reading,
        backoff=backoff or DEFAULT_BACKOFF,
        arrival=arrival,
    )
    gauges.start()
    return gauges


def unroll(procedure: Procedure, placements: int | None = None) -> tuple[PlanItem, ...]:
    """The procedure's steps in the order a session walks them (each step kind's handler says
    whether it is a block to repeat)."""
    items: list[PlanItem] = []
    for step in procedure.steps:
        items.extend(handler_for(step.kind).unroll(step, placements))
    return tuple(items)


def plan_steps(setup: SessionSetup) -> tuple[tuple[Step, int | None], ...]:
    """The steps a session of ``setup`` walks, in order, each with its placement (a repeat
    block's steps once per placement; ``None`` outside one)."""
    return tuple((item.step, item.placement) for item in unroll(setup.procedure, setup.placements))
