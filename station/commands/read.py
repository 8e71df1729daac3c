"""``station read``: a miniterm for gauges: readings as they arrive, and every rejected frame."""

from __future__ import annotations

import argparse
import json
import queue
import sys
import threading
import time

from station.commands._args import positive_number
from station.errors import StationError
from station.instruments.triggers import TRIGGERS
from station.text import parse_channel_map

DESCRIPTION = """\
Open a gauge port and print each reading as it arrives (station channel, value,
unit and the raw frame) and one line per rejected frame (error, status,
malformed, out of range). A polled protocol is polled continuously
(--interval); a push protocol waits for the device (DATA button, foot switch,
data logger); --trigger stable prints a set once every channel has stayed
within 2 x resolution for 0.5 s; --trigger arrival reads continuously and
prints a set each time the robot has left the fixture (a channel beyond 100
resolutions from zero) and come back to rest (2 resolutions for --settle
seconds, default 0.5), with
"left", "back" and "did not settle" lines on stderr. Connection changes go to
stderr; the reader reconnects by itself after an unplug. Ctrl-C stops.

What the frames say is printed on stderr as soon as it is known, and again when
it changes: "station: x, y, z send steps of 0.001, which is mm on this
protocol" (the decimals in the frames, the step between values, and the unit
where the frames state it or the protocol's gauges usually show it).

--jsonl prints one JSON object per line instead: {"channel", "value", "unit",
"raw"} for a reading, {"rejected", "raw"} for a rejected frame (rejected = the
reason).

exit codes: 0 done (or --count reached); 2 bad port, protocol or option; 130
interrupted.
"""


POLL_PATIENCE = 1.0
"""Seconds a poll waits for its answers before the next poll is sent anyway."""


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    """Register ``station read``."""
    from station.instruments.protocols import protocol_names

    parser = subparsers.add_parser(
        "read",
        help="print readings and rejected frames from a gauge port",
        description=DESCRIPTION,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument(
        "--port",
        required=True,
        metavar="URL",
        help="device path, /dev/serial/by-id/..., rfc2217://HOST:PORT, socket://HOST:PORT "
        "or hwgrep://VID:PID",
    )
    parser.add_argument(
        "--protocol",
        required=True,
        metavar="NAME",
        help="gauge protocol: " + ", ".join(protocol_names()),
    )
    parser.add_argument(
        "--map",
        metavar="DEV=CH,...",
        help="device channel to station channel, e.g. 1=x,2=y,3=z (the device channels "
        "polled are the map's)",
    )
    parser.add_argument(
        "--trigger",
        choices=TRIGGERS,
        help="poll (default for a polled protocol), push (default otherwise), stable or arrival",
    )
    parser.add_argument("--count", metavar="N", help="stop after N readings")
    parser.add_argument("--jsonl", action="store_true", help="one JSON object per line")
    parser.add_argument("--baud", metavar="BAUD", help="baud rate (default: the protocol's)")
    parser.add_argument("--bytesize", metavar="BITS", help="data bits, 5..8")
    parser.add_argument("--parity", metavar="P", help="parity N, E, O, M or S")
    parser.add_argument("--stopbits", metavar="S", help="stop bits 1, 1.5 or 2")
    parser.add_argument("--unit", default="mm", help="unit when frames carry none (mm)")
    parser.add_argument(
        "--interval",
        default="0.2",
        metavar="S",
        help="seconds between polls of a polled device (default 0.2)",
    )
    parser.add_argument(
        "--resolution",
        default="0.001",
        metavar="R",
        help="gauge resolution: the decimals shown, and the band of --trigger stable "
        "(default 0.001)",
    )
    parser.add_argument(
        "--settle",
        default="0.5",
        metavar="S",
        help="--trigger arrival: seconds the gauges must be still before a set (default 0.5)",
    )
    parser.set_defaults(func=run)


def value_text(value: float, resolution: float) -> str:
    """A reading with its sign at the decimals a gauge of ``resolution`` shows (``+0.000``
    beside ``-0.001``); a value with finer digits than that keeps them (up to 6)."""
    from station.instruments.protocols.common import decimals_for

    decimals = decimals_for(resolution)
    while decimals < 6 and round(value, decimals) != value:
        decimals += 1
    return f"{value:+.{decimals}f}"


def _print_item(item: object, jsonl: bool, resolution: float) -> bool:
    """Print a reading or a rejection; True when it was a reading."""
    from station.instruments.base import Reading

    if isinstance(item, Reading):
        if jsonl:
            line = json.dumps(
                {"channel": item.channel, "value": item.value, "unit": item.unit, "raw": item.raw}
            )
        else:
            line = (
                f"{item.channel:>4}  {value_text(item.value, resolution)} {item.unit}  {item.raw}"
            )
        print(line, flush=True)
        return True
    if jsonl:
        line = json.dumps({"rejected": item.reason, "raw": item.raw})
    else:
        line = f"rejected ({item.reason}): {item.detail}  [{item.raw}]"
    print(line, flush=True)
    return False


def run(args: argparse.Namespace) -> int:
    """Read until --count readings arrived or Ctrl-C."""
    from station.instruments.arrival import DEFAULT_TIMEOUT, ArrivalConfig
    from station.instruments.gauge import GaugeSet, PortSpec
    from station.instruments.protocols import get_protocol
    from station.instruments.reader import GaugeReader

    count = positive_number(args.count, "--count", int)
    interval = positive_number(args.interval, "--interval")
    resolution = positive_number(args.resolution, "--resolution")
    settle = positive_number(args.settle, "--settle")
    channel_map = parse_channel_map(args.map)
    protocol = get_protocol(
        args.protocol,
        baudrate=args.baud,
        bytesize=args.bytesize,
        parity=args.parity,
        stopbits=args.stopbits,
        channels=tuple(channel_map) or None,
    )
    from station.procedures import UNITS

    if args.unit not in UNITS:
        raise StationError(f"--unit {args.unit!r} is not a gauge unit; use {' or '.join(UNITS)}.")
    trigger = args.trigger or ("poll" if protocol.polled else "push")
    if trigger == "poll" and not protocol.polled:
        raise StationError(
            f"The {protocol.name} protocol has no request to poll with: use --trigger push."
        )
    events: queue.Queue = queue.Queue(maxsize=10_000)

    opened = threading.Event()

    def on_status(status) -> None:
        # The first failed open is the command's own error (exit 2), not a status line.
        if status.state == "connected":
            opened.set()
        if not opened.is_set():
            return
        if status.state in ("disconnected", "connected") or "failed" in status.message:
            print(f"station: {status.state}: {status.message}", file=sys.stderr, flush=True)

    gauges = None
    if trigger in ("stable", "arrival"):
        gauges = GaugeSet(
            [PortSpec(args.port, protocol, channel_map)],
            trigger=trigger,
            unit=args.unit,
            resolution=resolution,
            poll_interval=interval,
            on_rejection=events.put_nowait,
            on_status=on_status,
            on_arrival=_print_arrival,
            arrival=ArrivalConfig(settle=settle, timeout=max(DEFAULT_TIMEOUT, 4 * settle)),
        )
        reader = gauges.readers[0]
    else:
        reader = GaugeReader(
            args.port, protocol, channel_map, unit=args.unit, events=events, on_status=on_status
        )
    if gauges is not None:
        gauges.start()
    else:
        reader.start()
    try:
        _wait_first_open(reader)
        if not args.jsonl:
            print(
                f"station: reading {args.port} ({protocol.name}, {reader.settings.describe()}, "
                f"trigger {trigger}); Ctrl-C stops",
                file=sys.stderr,
                flush=True,
            )
        return _loop(reader, gauges, events, trigger, count, interval, args.jsonl, resolution)
    except KeyboardInterrupt:
        return 130
    finally:
        if gauges is not None:
            gauges.stop()
        else:
            reader.stop()


def _wait_first_open(reader) -> None:
    """Fail at once (exit 2) when the port cannot be opened the first time."""
    deadline = time.monotonic() + 15.0
    while reader.state in ("stopped", "connecting") and time.monotonic() < deadline:
        time.sleep(0.01)
    if reader.state != "connected":
        message = reader.last_message or f"Could not open {reader.url}."
        raise StationError(message)


def _print_arrival(event) -> None:
    """The arrival trigger's news, on stderr (the sets themselves go to stdout)."""
    if event.kind == "departed":
        line = f"the robot left the fixture ({', '.join(event.channels)} out of the band)"
    elif event.kind == "returned":
        line = "the robot is back at the fixture; waiting for it to be still"
    else:
        line = f"warning: {event.message}"
    print(f"station: {line}", file=sys.stderr, flush=True)


class FrameWatch:
    """What the frames read so far say (decimals, steps, unit), printed when it changes."""

    def __init__(self, protocol, channels=(), keep: int = 256) -> None:
        self.protocol = protocol
        self.channels = tuple(channels)
        self.keep = keep
        self.samples: dict[str, list] = {}
        self.said = ""

    def add(self, reading) -> str:
        """Note ``reading``'s frame; the new line to print, or '' when nothing changed."""
        from station.instruments.units import FrameSample, describe_inference, infer_channel

        frame = reading.raw.encode("ascii", "backslashreplace")
        sample = FrameSample(
            getattr(reading, "device_value", reading.value),
            self.protocol.frame_decimals(frame),
            getattr(reading, "frame_unit", None),
        )
        kept = self.samples.setdefault(reading.channel, [])
        kept.append(sample)
        del kept[: -self.keep]
        if any(channel not in self.samples for channel in self.channels):
            return ""  # one line for the whole set, once every channel has spoken
        text = describe_inference(
            {
                channel: infer_channel(channel, values, self.protocol.units_by_decimals)
                for channel, values in sorted(self.samples.items())
            }
        )
        if text == self.said:
            return ""
        self.said = text
        return text


def _loop(reader, gauges, events, trigger, count, interval, jsonl, resolution) -> int:
    from station.instruments.base import Reading

    watch = FrameWatch(reader.protocol, reader.channels)

    def note(item) -> None:
        if isinstance(item, Reading):
            line = watch.add(item)
            if line:
                print(f"station: {line}", file=sys.stderr, flush=True)

    readings = 0
    # A poll waits for its answers (or POLL_PATIENCE) before the next one: a new poll flushes
    # the input, so polling faster than the device answers would starve the reader.
    expected = max(1, len(reader.device_channels))
    answered = expected
    polled_at = -1e9
    while count is None or readings < count:
        if gauges is not None:
            if trigger == "arrival":
                result = gauges.wait_set(0.25)
                if result is None:
                    continue
            else:
                result = gauges.capture(timeout=max(2.0, 4 * interval))
            while not events.empty():
                _print_item(events.get_nowait(), jsonl, resolution)
            for channel in result.channels:
                if channel in result.readings and (count is None or readings < count):
                    note(result.readings[channel])
                    readings += _print_item(result.readings[channel], jsonl, resolution)
            continue
        now = time.monotonic()
        if (
            trigger == "poll"
            and now - polled_at >= interval
            and (answered >= expected or now - polled_at >= POLL_PATIENCE)
        ):
            reader.trigger(True)
            polled_at, answered = now, 0
        try:
            item = events.get(timeout=0.02)
        except queue.Empty:
            continue
        note(item)
        is_reading = _print_item(item, jsonl, resolution)
        readings += is_reading
        answered += 1  # a rejected frame is an answer too
    return 0
