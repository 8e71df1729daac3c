"""The set-up form's rows and defaults: which fields a procedure's set-up has, what they are
filled with (a resumed file's record, the demo's simulated line, the last set-up remembered),
and the count field (cycles, placements or strokes) its method asks for.

Nothing here reads what was typed (``setup_checks``) or talks to the gauges
(``setup_connection``); :class:`~station.tui.screens.setup.SetupScreen` puts the rows in its
scrolling form.
"""

from __future__ import annotations

import getpass
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rich.text import Text
from textual.app import ComposeResult
from textual.containers import Horizontal
from textual.widgets import Label, Select, Static

from station.errors import StationError
from station.instruments.protocols import protocol_names
from station.instruments.transport import list_ports
from station.plain import plain
from station.session.model import load_session
from station.text import LIMIT_HELP, channel_map_text, limits_text, parse_channel_map
from station.tui.text import shown
from station.tui.widgets.fields import FieldInput

if TYPE_CHECKING:
    from station.methods.contract import CountField
    from station.procedures import Procedure
    from station.tui.app import DemoPort

TRIGGER_CHOICES = (
    ("poll: the station asks the gauges at each capture", "poll"),
    ("push: the gauges send (DATA button, foot switch)", "push"),
    ("stable: take the set once the readings settle", "stable"),
    ("arrival: a set each time the robot returns and is still", "arrival"),
)
TYPED_PORT = "__typed__"
DEMO_LIMITS = "±0.001"
"""The report's example tolerance, offered in the demo when a procedure has no default limits."""
KEPT_ON_PROCEDURE_CHANGE = ("robot", "operator", "port", "protocol", "map", "trigger")

SelectMaker = Callable[..., Select]
"""Makes a drop-down: ``(field_id, options, value, **options)`` (the screen keeps its value)."""


def field_row(label: str, widget: Any, field_id: str, hint: str = "") -> ComposeResult:
    """One labelled row, an optional hint, and the error line under it."""
    with Horizontal(classes="field-row"):
        yield Label(shown(label), classes="field-label")
        yield widget
    if hint:
        yield Static(shown(hint), classes="field-hint")
    yield Static("", classes="field-error", id=f"{field_id}-error")


@dataclass(frozen=True)
class FormStart:
    """What the form opens with: the procedure, a resumed file's header (empty for a new
    session), the demo's simulated line (or None) and the last set-up remembered (empty when
    resuming or in the demo)."""

    procedure: Procedure
    procedures: tuple[Procedure, ...]
    header: Mapping[str, Any]
    demo: DemoPort | None
    last: Mapping[str, str]
    resuming: bool = False


def form_rows(start: FormStart, select: SelectMaker) -> ComposeResult:
    """The rows of the form, robot to trigger, filled as ``start`` says (a resumed session's
    fields disabled but for the instrument line)."""
    procedure, header, demo = start.procedure, start.header, start.demo
    last = fits_procedure(start.last, procedure)
    resuming = start.resuming
    catalog_procedures = start.procedures
    count = count_field(procedure)
    recorded_port = (header.get("instruments", {}).get("ports") or [{}])[0]
    if demo is not None:
        # The demo's line is its own running simulator, also for a resumed session: the one
        # the file recorded stopped with the demo that ran it, and its pseudo-terminal number
        # may now be another program's.
        recorded_port = {}
    if resuming:
        yield Static(recorded_summary(header), id="setup-recorded")
    yield from field_row(
        "Robot",
        FieldInput(
            compact=True,
            value=plain(header.get("robot") or (demo.robot if demo else last.get("robot", ""))),
            placeholder="name or asset number of the robot under test",
            id="robot",
            disabled=resuming,
        ),
        "robot",
    )
    yield from field_row(
        "Operator",
        FieldInput(
            compact=True,
            value=plain(header.get("operator") or last.get("operator") or login_name()),
            id="operator",
            disabled=resuming,
        ),
        "operator",
    )
    yield from field_row(
        "Procedure",
        select(
            "procedure",
            [(shown(f"{p.title} ({p.id})", limit=120), p.id) for p in catalog_procedures],
            procedure.id,
            disabled=resuming,
        ),
        "procedure",
    )
    yield from field_row(
        "Unit",
        select(
            "unit",
            [("inch (in)", "in"), ("millimetre (mm)", "mm")],
            header.get("unit") or procedure.unit,
            disabled=resuming,
        ),
        "unit",
    )
    yield from field_row(
        "Resolution",
        FieldInput(
            compact=True,
            value=f"{header.get('resolution') or procedure.resolution:g}",
            id="resolution",
            disabled=resuming,
        ),
        "resolution",
        "the gauge's smallest step, in the unit above",
    )
    recorded_limits = header.get("limits") or {}
    for channel in judged_channels(procedure):
        limit = recorded_limits.get(channel) or procedure.limits.get(channel)
        value = DEMO_LIMITS if demo is not None and limit is None else ""
        if isinstance(limit, dict):
            value = limits_text(limit.get("lsl"), limit.get("usl"), limit.get("nominal"))
        elif limit is not None:
            value = limits_text(limit.lsl, limit.usl, limit.nominal)
        yield from field_row(
            f"Limits {channel}",
            FieldInput(
                compact=True,
                value=value,
                placeholder=LIMIT_HELP,
                id=f"limits-{channel}",
                disabled=resuming,
            ),
            f"limits-{channel}",
        )
    if judged_channels(procedure):
        # How to write limits, under the limits fields (a gauge study has none to write).
        yield Static(LIMIT_HELP, classes="field-hint")
    limits_help = _method(procedure).limits_help
    if limits_help:
        # How the method judges these limits (linearity: by each stroke's straightness), said
        # here and not only in the procedure file.
        yield Static(limits_help, classes="field-hint")
    yield from field_row(
        count.label,
        FieldInput(
            compact=True,
            value=str(
                header.get(count.header_key) or (demo.count if demo else None) or count.target
            ),
            id="cycles",
            disabled=resuming,
        ),
        "cycles",
        count.hint,
    )
    detected = [(f"{p.device}  {p.description}", p.device) for p in list_ports()]
    port_value = recorded_port.get("url") or (demo.url if demo else last.get("port", ""))
    yield from field_row(
        "Detected",
        select("detected", [*detected, ("(type the port below)", TYPED_PORT)], TYPED_PORT),
        "detected",
        "serial ports this computer lists"
        + ("" if detected else ": none found (network and /dev/pts ports are not listed)"),
    )
    yield from field_row(
        "Port",
        FieldInput(
            compact=True,
            value=port_value,
            placeholder="/dev/ttyUSB0, /dev/pts/N, rfc2217://host:port, socket://host:port",
            id="port",
        ),
        "port",
    )
    protocols = protocol_names()
    protocol = recorded_port.get("protocol") or (
        demo.protocol if demo else last.get("protocol", protocols[0])
    )
    if protocol not in protocols:
        protocol = protocols[0]
    yield from field_row(
        "Protocol",
        select("protocol", [(name, name) for name in protocols], protocol),
        "protocol",
    )
    channel_map = recorded_port.get("map") or (
        demo.channel_map if demo else {str(i + 1): ch for i, ch in enumerate(procedure.channels)}
    )
    map_text = channel_map_text(channel_map)
    if last.get("channel_map") and not recorded_port.get("map"):
        map_text = last["channel_map"]
    yield from field_row(
        "Channel map",
        FieldInput(compact=True, value=map_text, id="map"),
        "map",
        "device channel = axis, e.g. 1=x,2=y,3=z",
    )
    # The procedure's own trigger (repeatability: arrival, the robot paces the cycles)
    # unless the demo's simulated set-up or the resumed session says otherwise.
    trigger = header.get("instruments", {}).get("trigger") or (
        demo.trigger if demo else last.get("trigger") or procedure.trigger or "poll"
    )
    if trigger not in {value for _, value in TRIGGER_CHOICES}:
        trigger = "poll"
    yield from field_row(
        "Trigger",
        select("trigger", TRIGGER_CHOICES, trigger, disabled=resuming),
        "trigger",
    )


def fits_procedure(values: Mapping[str, str], procedure: Procedure) -> dict[str, str]:
    """``values`` (a remembered set-up, or what was typed for another procedure) without the
    channel map and trigger that do not fit ``procedure``: a map naming channels it does not
    have (a repeatability's x, y, z on a gauge check's x), the arrival trigger where the
    procedure does not pace its cycles by a robot's returns (a gauge on a bench)."""
    kept = dict(values)
    try:
        mapped = set(parse_channel_map(kept.get("map") or kept.get("channel_map")).values())
    except StationError:
        mapped = set()  # the operator's own text: F2 says what is wrong with it
    if not mapped <= set(procedure.channels):
        kept.pop("map", None)
        kept.pop("channel_map", None)
    if kept.get("trigger") == "arrival" and procedure.trigger != "arrival":
        kept.pop("trigger")
    return kept


def _method(procedure: Procedure) -> Any:
    """The method that judges ``procedure``'s sessions."""
    from station.methods import method_of  # deferred: the methods load numpy

    return method_of(procedure.analysis)


def count_field(procedure: Procedure) -> CountField:
    """What ``procedure``'s set-up counts (cycles, its block's placements, strokes), in its
    method's words."""
    return _method(procedure).count_field(procedure)


def judged_channels(procedure: Procedure) -> list[str]:
    """The channels that take limits (none when the method judges no spec limits)."""
    return list(_method(procedure).judged_channels(procedure))


def login_name() -> str:
    """The operator's login name, or '' when the system cannot say."""
    try:
        return getpass.getuser()
    except (KeyError, OSError):
        return ""


def read_header(path: Path) -> dict[str, Any]:
    """The recorded set-up of a session file (read-only)."""
    session = load_session(path, recover=False)
    header = getattr(session, "header", {})
    return dict(header) if isinstance(header, dict) else dict(vars(header))


def recorded_summary(header: Mapping[str, Any]) -> Text:
    """What the file recorded, for the operator to check before resuming."""
    procedure = header.get("procedure", {})
    text = Text("Recorded set-up (kept as it was):\n", style="bold")
    text.append(
        f"robot {plain(header.get('robot'), limit=80)}, operator "
        f"{plain(header.get('operator'), limit=80)}, procedure "
        f"{procedure.get('id')} {procedure.get('version')}, unit {header.get('unit')}, "
        f"resolution {header.get('resolution')}, {_asked_for(header)}.\n"
        "Check the instrument line below (the port may have changed), then press F2."
    )
    return text


def _asked_for(header: Mapping[str, Any]) -> str:
    """``30 cycles``, ``3 placements`` or ``25 strokes``: what the set-up asked for."""
    for key, word in (
        ("strokes_target", "strokes"),
        ("placements_target", "placements"),
        ("cycles_target", "cycles"),
    ):
        if isinstance(header.get(key), int):
            return f"{header[key]} {word}"
    return "no count recorded"
