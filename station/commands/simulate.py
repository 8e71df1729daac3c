"""``station simulate``: a virtual robot in a fixture, speaking a gauge protocol on a pty or TCP."""

from __future__ import annotations

import argparse
import math
import signal
import sys
import threading
from pathlib import Path

from station.commands._args import bounded_int, bounded_number, positive_number
from station.errors import StationError

DESCRIPTION = """\
Run a simulated fixture with one dial indicator per channel, speaking a gauge
protocol, so that `station read`, `station capture` and the TUI work with no
hardware. The first line on stdout is the URL to open (a pseudo-terminal path,
or socket://127.0.0.1:PORT with --tcp); it then runs until Ctrl-C or SIGTERM.
Seeded: the k-th reading of a channel depends only on --seed and k. With
--disconnect-every on a pty the URL is a symlink that follows the pty across
disconnects.

Model options take one value for every channel or CH=V pairs, e.g. --bias
x=0.002,y=-0.001. Fault rates are probabilities per frame sent.

--model chooses the set-up (channels and unit follow from it for the two
others):
  fixture      one fixture, indicators x, y, z (repeatability; the default).
  two-fixture  relative accuracy (report 2.8): x, y, z in inches. Each
               placement's second fixture is where the teach pendant says
               (printed on stderr as "placement P: the pendant reads X=...
               Y=... Z=... in" when the robot gets there); the indicators at
               the first fixture read the return's error: --scale per unit
               moved, --rotation (radians) about x, y, z, --noise. Each
               placement is a rest at home (the zero), then the return.
  bar          linearity (report 2.9): indicators h, v and the linear scale s
               in inches. The robot shuttles A-B-A... along the bar (--length,
               --points per stroke, --dwell readings at each end); h sees the
               bar's bow (--bow sagitta), v its sag (--sag), both the path's
               wobble (--wobble, --wobble-v, --period). The indicators and the
               scale's counter send every set by themselves at --push-rate sets
               per second (default 200, as a counter's continuous output does):
               capture with --trigger push. The robot stands still at A for
               --hold seconds (default 8) from the first frame it sends, where
               the station zeroes, then advances one point per set sent.
  joints       per-joint troubleshooting (report 1.2, 2.8): x, y, z in inches
               at the fixture of a 3-joint arm (base, shoulder, elbow), each
               joint moved alone for --cycles-per-joint returns in turn (joint
               1 first, leaving in alternate directions); its angular error
               reaches the fixture through the arm's Jacobian. --faulty-joint
               J with --joint-fault backlash|noise|servo|encoder of
               --fault-size radians; the healthy joints repeat to 5e-6 rad.
               Printed on stderr as "joint J: ..." when the next joint's turn
               comes, with its lever arm. Each joint's turn is a rest at the
               taught position (the zero), then its returns.
  gauge-bench  the gauge studies: one indicator x in inches over a surface
               plate (zeroing reads the plate), a gauge block of --reference
               size re-seated for every reading (the gauge check), or several
               (--reference 0.1,0.3,0.5,0.7,0.9: the linearity and bias study)
               in turn, --readings-per-block seatings each (12). It reads a
               block of size r as r + bias + slope*r: --bias, and --slope its
               linearity error (0), with --noise (default 0.00003). The first
               rest is the plate (the zero), every later one a seating.

The models follow the robot's state, not the readings: at each rest every
reading shows the same rest position plus the indicators' own noise
(--gauge-noise, in resolutions), however often the station reads it. Without
--cycle-period the robot moves to its next rest whenever the station has not
polled it for --return-gap seconds (1), as a technician moves the robot
while the station waits: pace `station capture --trigger poll` with --every
above the gap, and the readings of one zero stay at one rest. The next rest
is the next return at one fixture; with two-fixture, the placement's return
after its home, then the next home; with joints, the next return or the next
joint's taught position; with gauge-bench, the plate and then each seating
of the block. --cycle-period S makes the fixture model's robot leave the
fixture and come back every S seconds, as a playback loop does: at rest (the
model's bias, noise, drift and backlash for that cycle), then the indicators
run out to their free travel (--free-travel, default -3/8 in or -9.525 mm)
while the robot is away, then it returns with a short overshoot
(--overshoot, default 20 resolutions) and settles. The c-th rest position is
the model's c-th value; a reading shows where the robot is when it is sent.
--settling V (one value or CH=V) makes the arrival a second-order one
instead: the approach ends on the rest position and each axis rings about
it, its first swing V past it, --settling-period seconds per swing, the
envelope falling by e every --settling-decay seconds (a known overshoot and
stabilisation time, ISO 9283 7.4-7.5).
--hunt CH=V makes an axis hunt by +-V at rest on every --hunt-every N-th
return instead of settling (a return the station must report, not record).
"""


BAR_HOLD = 8.0
"""Seconds the bar model's robot stands at A (from the first reading) before it shuttles."""


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    """Register ``station simulate``."""
    from station.instruments.protocols import protocol_names

    parser = subparsers.add_parser(
        "simulate",
        help="a simulated robot and gauges on a pseudo-terminal or a TCP port",
        description=DESCRIPTION,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument(
        "--protocol",
        required=True,
        metavar="NAME",
        help="gauge protocol: " + ", ".join(protocol_names()),
    )
    where = parser.add_mutually_exclusive_group()
    where.add_argument("--pty", action="store_true", help="serve on a pseudo-terminal (default)")
    where.add_argument("--tcp", metavar="PORT", help="serve on TCP 127.0.0.1:PORT (0 = free)")
    parser.add_argument("--link", metavar="PATH", help="pty: also make PATH a symlink to it")
    parser.add_argument(
        "--model",
        choices=("fixture", "two-fixture", "bar", "joints", "gauge-bench"),
        default="fixture",
        help="the set-up: fixture (repeatability, default), two-fixture (relative accuracy), "
        "bar (linearity), joints (per-joint troubleshooting) or gauge-bench (gauge check)",
    )
    parser.add_argument("--channels", default="x,y,z", help="station channels (default x,y,z)")
    parser.add_argument("--seed", default="0", help="random seed (default 0)")
    model = parser.add_argument_group("model (one value, or CH=V,... per channel)")
    for flag, default, text in (
        ("--bias", "0", "offset from nominal"),
        ("--noise", None, "noise sigma (0.0005; two-fixture 0.0002, bar 0.00005)"),
        ("--skew", "0", "skew-normal shape alpha (0 = normal)"),
        ("--drift", "0", "warm-up drift approached exponentially"),
        ("--drift-tau", "10", "warm-up time constant, in readings"),
        ("--backlash", "0", "difference between the two approach directions"),
        ("--outlier-rate", "0", "probability of an outlier per reading"),
    ):
        model.add_argument(flag, default=default, metavar="V", help=f"{text} (default {default})")
    accuracy = parser.add_argument_group("two-fixture model (relative accuracy)")
    accuracy.add_argument(
        "--scale", default="x=2e-5,y=-1.5e-5,z=1e-5", metavar="V", help="scale error per unit moved"
    )
    accuracy.add_argument(
        "--rotation", default="z=5e-6", metavar="V", help="rotation error, radians about x, y, z"
    )
    accuracy.add_argument(
        "--reach", default="10,40", metavar="MIN,MAX", help="pendant coordinates' size (10,40)"
    )
    accuracy.add_argument(
        "--preload", default="0.05", metavar="V", help="indicator preload spread at home (0.05)"
    )
    bar = parser.add_argument_group("bar model (linearity)")
    for flag, default, text in (
        ("--length", "20", "bar length A-B"),
        ("--points", "400", "points per stroke while moving"),
        ("--dwell", "20", "points at rest at each end"),
        ("--bow", "0.0012", "bow of the bar (sagitta, seen by h)"),
        ("--sag", "0.0006", "sag of the bar (sagitta, seen by v)"),
        ("--wobble", "0.0004", "amplitude of the path's wobble on h"),
        ("--wobble-v", "0.0002", "amplitude of the path's wobble on v"),
        ("--period", "5", "period of the wobble along the bar"),
    ):
        bar.add_argument(flag, default=default, metavar="V", help=f"{text} (default {default})")
    joints = parser.add_argument_group("joints model (per-joint troubleshooting)")
    joints.add_argument("--faulty-joint", default="0", metavar="J", help="1, 2 or 3 (0 = none)")
    joints.add_argument(
        "--joint-fault",
        default="backlash",
        choices=("backlash", "noise", "servo", "encoder"),
        help="the faulty joint's fault (backlash)",
    )
    joints.add_argument("--fault-size", default="4e-5", metavar="RAD", help="radians (4e-5)")
    joints.add_argument(
        "--cycles-per-joint", default="25", metavar="N", help="returns per joint (25)"
    )
    bench = parser.add_argument_group("gauge-bench model (gauge check, linearity study)")
    bench.add_argument(
        "--reference",
        default="0.1",
        metavar="V[,V...]",
        help="gauge block size (0.1), or the sizes of several blocks read in turn",
    )
    bench.add_argument(
        "--slope",
        default="0",
        metavar="S",
        help="the indicator's linearity error: its bias grows by S per unit of size (0)",
    )
    bench.add_argument(
        "--readings-per-block", default="12", metavar="N", help="seatings of each block (12)"
    )
    gauge = parser.add_argument_group("gauge")
    gauge.add_argument(
        "--resolution", help="gauge resolution (0.001; two-fixture and bar 0.0001 in)"
    )
    gauge.add_argument("--unit", default="mm", choices=("mm", "in"), help="unit (mm)")
    gauge.add_argument("--range", default="-12.5,12.5", metavar="LOW,HIGH", help="gauge range")
    gauge.add_argument(
        "--gauge-noise",
        default="0.3",
        metavar="R",
        help="the indicators' own reading noise (sigma), in resolutions (0.3): readings at "
        "rest scatter by it",
    )
    motion = parser.add_argument_group("motion (fixture model)")
    motion.add_argument(
        "--cycle-period",
        metavar="S",
        help="the robot leaves the fixture and returns every S seconds (default: it never "
        "moves, each reading is a new rest position)",
    )
    motion.add_argument(
        "--free-travel", metavar="V", help="what the indicators show while the robot is away"
    )
    motion.add_argument(
        "--overshoot", metavar="V", help="how far past its rest position the robot returns"
    )
    motion.add_argument(
        "--settling",
        metavar="V",
        help="a second-order arrival instead of --overshoot: each axis rings about its rest "
        "position, its first swing V past it (one value, or CH=V,...)",
    )
    motion.add_argument(
        "--settling-period",
        default="0.1",
        metavar="S",
        help="with --settling: seconds per swing of the ringing (0.1)",
    )
    motion.add_argument(
        "--settling-decay",
        default="0.05",
        metavar="S",
        help="with --settling: the ringing's envelope falls by e every S seconds (0.05)",
    )
    motion.add_argument(
        "--return-gap",
        default="1",
        metavar="S",
        help="without --cycle-period: the robot moves to its next rest whenever the station "
        "has not polled for S seconds (1; 0 = never), so pace polls with --every above S",
    )
    motion.add_argument(
        "--hold", metavar="S", help="bar: seconds the robot stands at A before shuttling (8)"
    )
    motion.add_argument(
        "--hunt", default="0", metavar="V", help="amplitude of an axis that hunts at rest (0)"
    )
    motion.add_argument(
        "--hunt-every", default="1", metavar="N", help="the returns that hunt: every N-th (1)"
    )
    motion.add_argument(
        "--hunt-period",
        default="0.037",
        metavar="S",
        help="seconds per swing of a hunting axis (0.037; a gauge read less often than twice a "
        "swing cannot see it hunt)",
    )
    line = parser.add_argument_group("line and faults")
    line.add_argument(
        "--push-rate",
        metavar="HZ",
        help="sets pushed per second (default 1 for a push protocol, 0 = answer polls only)",
    )
    for flag, text in (
        ("--garbage-rate", "a line of noise bytes before a frame"),
        ("--torn-rate", "a frame written in two pieces"),
        ("--error-rate", "an error/status frame instead of a reading"),
        ("--silence-rate", "no answer to a request"),
        ("--stale-rate", "old frames delivered again after a frame"),
    ):
        line.add_argument(flag, default="0", metavar="P", help=f"{text} (probability)")
    line.add_argument("--disconnect-every", default="0", metavar="S", help="seconds (0 = never)")
    line.add_argument("--down-time", default="1", metavar="S", help="seconds a disconnect lasts")
    parser.set_defaults(func=run)


def per_channel(text: str, name: str, channels: list[str]) -> dict[str, float]:
    """``"0.1"`` or ``"x=0.1,y=0.2"`` -> a value per channel (0 where a pair is absent)."""
    try:
        if "=" not in text:
            return dict.fromkeys(channels, _finite(float(text), name, text))
        values = dict.fromkeys(channels, 0.0)
        for pair in text.split(","):
            channel, _, value = (part.strip() for part in pair.partition("="))
            if channel not in values:
                raise StationError(
                    f"{name} names channel {channel!r}; the channels are {', '.join(channels)}."
                )
            values[channel] = _finite(float(value), name, text)
        return values
    except ValueError:
        raise StationError(f"{name} {text!r}: give a number or CH=NUMBER pairs.") from None


def _float(text: str, name: str, low: float = -1e6, high: float = 1e6) -> float:
    value = bounded_number(text, name, low, high)
    if value is None:
        raise StationError(f"{name} {text!r} is not a number.")
    return value


def _rate(text: str, name: str) -> float:
    """A probability, 0 to 1."""
    return _float(text, name, 0.0, 1.0)


def _finite(value: float, name: str, text: str) -> float:
    if not math.isfinite(value) or abs(value) > 1e6:
        raise StationError(f"{name} {text!r}: give finite numbers (within ±1e6).")
    return value


def _pair(text: str, name: str) -> tuple[float, float]:
    try:
        low, high = (float(v) for v in text.split(","))
    except ValueError:
        raise StationError(f"{name} {text!r}: give two numbers, e.g. {name} 10,40.") from None
    if not (math.isfinite(low) and math.isfinite(high) and abs(low) <= 1e6 and abs(high) <= 1e6):
        raise StationError(f"{name} {text!r}: give two finite numbers.")
    if not low < high:
        raise StationError(f"{name} {text!r}: the first number must be below the second.")
    return low, high


def _procedure_model(args: argparse.Namespace, protocol, seed: int):
    """The two-fixture or bar model the options describe (None for the fixture model)."""
    from station.instruments.simulator import BarModel, GaugeSpec, TwoFixtureModel

    if args.model == "fixture":
        return None
    resolution = bounded_number(args.resolution, "--resolution", 1e-6, 1.0)
    gauge_noise = gauge_noise_of(args, resolution)
    if args.model == "gauge-bench":
        from station.instruments.gauge_bench import GaugeBenchModel

        bias = per_channel(args.bias, "--bias", ["x"])["x"]
        noise = per_channel(args.noise, "--noise", ["x"])["x"]
        references = [_float(part, "--reference") for part in args.reference.split(",")]
        return GaugeBenchModel(
            references,
            bias=bias,
            slope=_float(args.slope, "--slope", -1.0, 1.0),
            noise=noise,
            readings=positive_number(args.readings_per_block, "--readings-per-block", int),
            gauge=GaugeSpec(resolution, -0.5, 1.0, "in", gauge_noise),
        )
    if args.model == "joints":
        from station.instruments.joint_model import JointModel, faulty_arm

        cycles = positive_number(args.cycles_per_joint, "--cycles-per-joint", int)
        # Each joint's turn starts with a rest at the taught position, where the station zeroes.
        options = {
            "cycles": cycles,
            "gauge": GaugeSpec(resolution, -0.5, 0.5, "in", gauge_noise),
            "home_readings": 1,
        }
        try:
            joint = int(args.faulty_joint)
        except ValueError:
            raise StationError(f"--faulty-joint {args.faulty_joint!r} is 1, 2, 3 or 0.") from None
        if joint == 0:
            return JointModel(**options)
        size = _float(args.fault_size, "--fault-size")
        return faulty_arm(joint, args.joint_fault, size=size, **options)
    if args.model == "two-fixture":
        axes = ["x", "y", "z"]
        scale = per_channel(args.scale, "--scale", axes)
        rotation = per_channel(args.rotation, "--rotation", axes)
        noise = per_channel(args.noise, "--noise", axes)
        if len(set(noise.values())) != 1:
            raise StationError("--noise: the two-fixture model takes one noise sigma for x, y, z.")
        reach_min, reach_max = _pair(args.reach, "--reach")
        return TwoFixtureModel(
            scale=tuple(scale[a] for a in axes),
            rotation=tuple(rotation[a] for a in axes),
            noise=noise["x"],
            reach_min=reach_min,
            reach_max=reach_max,
            preload=_float(args.preload, "--preload"),
            gauge=GaugeSpec(resolution, -0.5, 0.5, "in", gauge_noise),
            seed=seed,
        )
    noise = per_channel(args.noise, "--noise", ["h", "v", "s"])
    try:
        points, dwell = int(args.points), int(args.dwell)
    except ValueError:
        raise StationError("--points and --dwell are whole numbers of readings.") from None
    return BarModel(
        length=_float(args.length, "--length"),
        points=points,
        dwell=dwell,
        bow=_float(args.bow, "--bow"),
        sag=_float(args.sag, "--sag"),
        wobble=_float(args.wobble, "--wobble"),
        wobble_v=_float(args.wobble_v, "--wobble-v"),
        period=_float(args.period, "--period"),
        noise=noise["h"],
        indicator=GaugeSpec(resolution, -0.5, 0.5, "in", gauge_noise),
    )


def gauge_noise_of(args: argparse.Namespace, resolution: float) -> float:
    """The indicators' own noise (σ) in their unit, from ``--gauge-noise`` in resolutions."""
    return _float(args.gauge_noise, "--gauge-noise", 0.0, 100.0) * resolution


def build_simulator(args: argparse.Namespace):
    """The :class:`~station.instruments.simulator.Simulator` the options describe."""
    from station.instruments.protocols import get_protocol
    from station.instruments.simulator import AxisModel, Faults, FixtureModel, GaugeSpec, Simulator

    try:
        seed = int(args.seed)
    except ValueError:
        raise StationError(f"--seed {args.seed!r} is not a whole number.") from None
    protocol = get_protocol(args.protocol)
    if args.resolution is None:
        args.resolution = "0.001" if args.model == "fixture" else "0.0001"
    if args.noise is None:
        args.noise = {
            "fixture": "0.0005",
            "two-fixture": "0.0002",
            "bar": "0.00005",
            "joints": "0",
            "gauge-bench": "0.00003",
        }[args.model]
    channels = [c.strip() for c in args.channels.split(",") if c.strip()]
    if not channels or len(set(channels)) != len(channels):
        raise StationError(f"--channels {args.channels!r}: name each channel once, e.g. x,y,z.")
    fields = {
        "bias": per_channel(args.bias, "--bias", channels),
        "noise": per_channel(args.noise, "--noise", channels),
        "skew": per_channel(args.skew, "--skew", channels),
        "drift": per_channel(args.drift, "--drift", channels),
        "drift_tau": per_channel(args.drift_tau, "--drift-tau", channels),
        "backlash": per_channel(args.backlash, "--backlash", channels),
        "outlier_rate": per_channel(args.outlier_rate, "--outlier-rate", channels),
    }
    for key in ("noise", "drift_tau", "outlier_rate"):
        for channel, value in fields[key].items():
            option = "--" + key.replace("_", "-")
            if value < 0 or (key == "outlier_rate" and value > 1):
                bound = "from 0 to 1" if key == "outlier_rate" else "0 or more"
                raise StationError(f"{option} of {channel} must be {bound}, not {value:g}.")
    axes = {c: AxisModel(**{key: values[c] for key, values in fields.items()}) for c in channels}
    try:
        low, high = _pair(args.range, "--range")
    except StationError:
        raise StationError(
            f"--range {args.range!r}: give LOW,HIGH with LOW below HIGH, e.g. -12.5,12.5."
        ) from None
    resolution = bounded_number(args.resolution, "--resolution", 1e-6, 1.0)
    model = _procedure_model(args, protocol, seed) or FixtureModel(
        axes, GaugeSpec(resolution, low, high, args.unit, gauge_noise_of(args, resolution))
    )
    faults = Faults(
        garbage_rate=_rate(args.garbage_rate, "--garbage-rate"),
        torn_rate=_rate(args.torn_rate, "--torn-rate"),
        error_rate=_rate(args.error_rate, "--error-rate"),
        silence_rate=_rate(args.silence_rate, "--silence-rate"),
        stale_rate=_rate(args.stale_rate, "--stale-rate"),
        disconnect_every=_float(args.disconnect_every, "--disconnect-every", 0.0, 1e6),
        down_time=_float(args.down_time, "--down-time", 0.0, 1e6),
    )
    if args.push_rate is not None:
        push_rate = _float(args.push_rate, "--push-rate", 0.0, 10_000.0)
    elif args.model == "bar":
        push_rate = 200.0
    else:
        push_rate = 0.0 if protocol.polled else 1.0
    try:
        simulator = Simulator(
            protocol,
            model,
            faults,
            seed,
            push_rate=push_rate,
            motion=build_motion(args, model, channels),
        )
        if simulator.motion is None and args.model != "bar":
            # The operator moves the robot while the station waits between its steps.
            simulator.return_gap = _float(args.return_gap, "--return-gap", 0.0, 1e6) or None
        if args.model == "bar":
            # The robot stands still at A while the station zeroes, then shuttles.
            simulator.leave_first_rest_after = (
                _float(args.hold, "--hold", 0.0, 1e6) if args.hold is not None else BAR_HOLD
            )
        # Every channel's frame must be writable at this resolution and range before serving.
        for device, channel in simulator.channel_map.items():
            protocol.wire_channel(device)
            spec = getattr(model, "gauge", None) or getattr(model, "indicator", None)
            if callable(spec):
                spec = spec(channel)
            if isinstance(spec, GaugeSpec):
                for value in (spec.low, spec.high):
                    protocol.encode(device, value, spec.resolution, spec.unit)
    except ValueError as error:
        raise StationError(
            f"cannot simulate {protocol.name} with these options: {error}; use fewer channels "
            "or a coarser --resolution."
        ) from None
    return simulator


def build_motion(args: argparse.Namespace, model, channels: list[str]):
    """The :class:`~station.instruments.motion.CycleMotion` of ``--cycle-period`` (None
    without it)."""
    from station.instruments.motion import CycleMotion, Settling, default_free_travel

    motion_flags = [
        flag
        for flag, value in (
            ("--free-travel", args.free_travel),
            ("--overshoot", args.overshoot),
            ("--settling", args.settling),
        )
        if value is not None
    ]
    if args.cycle_period is None:
        if motion_flags:
            raise StationError(f"{motion_flags[0]} needs --cycle-period (the robot's rhythm).")
        return None
    if args.model != "fixture":
        raise StationError(
            f"--cycle-period moves the fixture model's robot; the {args.model} model's robot "
            "moves where its procedure's steps take it (see --return-gap)."
        )
    period = positive_number(args.cycle_period, "--cycle-period")
    gauge = model.gauge(channels[0])
    free = (
        per_channel(args.free_travel, "--free-travel", channels)
        if args.free_travel is not None
        else default_free_travel(gauge.unit)
    )
    overshoot = (
        _float(args.overshoot, "--overshoot")
        if args.overshoot is not None
        else 20 * gauge.resolution
    )
    settling = None
    if args.settling is not None:
        if args.overshoot is not None:
            raise StationError(
                "--overshoot and --settling are two ways to arrive: give one of them."
            )
        settling = Settling(
            per_channel(args.settling, "--settling", channels),
            period=positive_number(args.settling_period, "--settling-period"),
            decay=positive_number(args.settling_decay, "--settling-decay"),
        )
    hunt = {c: v for c, v in per_channel(args.hunt, "--hunt", channels).items() if v}
    hunt_every = positive_number(args.hunt_every, "--hunt-every", int)
    hunt_period = positive_number(args.hunt_period, "--hunt-period")
    return CycleMotion(
        period,
        free,
        abs(overshoot),
        hunt=hunt,
        hunt_every=hunt_every,
        hunt_period=hunt_period,
        settling=settling,
    )


def show_pendant(simulator) -> None:
    """Print the teach pendant's display on stderr whenever the robot reaches another
    placement (two-fixture model): the operator of a headless capture types it in."""
    model = simulator.model
    shown = [0]

    def on_sent(channel: str, k: int) -> None:
        number = model.current_placement(_rest_of_last(simulator, channel))
        if number != shown[0]:
            shown[0] = number
            text = model.placement_of(number).pendant_text()
            print(f"placement {number}: the pendant reads {text}", file=sys.stderr, flush=True)

    on_sent("", 0)
    simulator.on_sent = on_sent


def _rest_of_last(simulator, channel: str) -> int:
    """The robot's rest when ``channel``'s last frame was sent (its first rest before any)."""
    sent = simulator.sent.get(channel) if channel else None
    return int(sent[-1].cycle or 0) if sent else 0


def show_joint(simulator) -> None:
    """Print on stderr which joint to move when its turn comes (joints model), with its lever
    arm (the distance from its axis to the cube, for the analysis)."""
    model = simulator.model
    levers = model.lever_arms()
    shown = [0]

    def on_sent(channel: str, k: int) -> None:
        number = model.current_joint(_rest_of_last(simulator, channel))
        if number != shown[0]:
            shown[0] = number
            print(
                f"joint {number}: move only joint {number} away and back (lever arm "
                f"{levers[number - 1]:.3f} in)",
                file=sys.stderr,
                flush=True,
            )

    on_sent("", 0)
    simulator.on_sent = on_sent


def robot_line(simulator) -> str:
    """How the simulated robot moves, for the start-up line on stderr."""
    motion = simulator.motion
    if motion is not None:
        line = f"; the robot leaves the fixture and returns every {motion.period:g} s"
        settling = motion.settling
        if settling is not None:
            swings = ",".join(f"{c}={v:g}" for c, v in settling.overshoot.items())
            line += (
                f", ringing on arrival (first swing past the rest {swings}, "
                f"{settling.period:g} s per swing, decay {settling.decay:g} s)"
            )
        return line
    if simulator.return_gap:
        return (
            f"; the robot moves to its next rest when the station pauses "
            f"{simulator.return_gap:g} s (pace capture with --every above it)"
        )
    return ""


def run(args: argparse.Namespace) -> int:
    """Print the URL, serve until SIGINT/SIGTERM."""
    simulator = build_simulator(args)
    if args.model == "two-fixture":
        show_pendant(simulator)
    if args.model == "joints":
        show_joint(simulator)
    done = threading.Event()
    # A hang-up (the SSH session closing) or Ctrl-C stops as cleanly as SIGTERM: the pty, the
    # link and its private folder go away.
    stop_signals = (signal.SIGTERM, signal.SIGHUP, signal.SIGINT)
    previous = {sig: signal.signal(sig, lambda *_: done.set()) for sig in stop_signals}
    try:
        if args.tcp is not None:
            port = bounded_int(args.tcp, "--tcp", 0, 65535)
            assert port is not None
            try:
                url = simulator.start_tcp(port)
            except OSError as error:
                raise StationError(
                    f"Cannot serve on 127.0.0.1:{port} ({error.strerror or error}): "
                    "choose another port, or 0 for a free one."
                ) from None
        else:
            if args.link is not None and not Path(args.link).parent.is_dir():
                raise StationError(
                    f"--link {args.link}: the folder {Path(args.link).parent} does not exist; "
                    "create it or choose another path."
                )
            try:
                url = simulator.start_pty(link=args.link)
            except OSError as error:
                raise StationError(
                    f"cannot make the link {args.link}: {error.strerror}; choose another path."
                ) from None
        print(url, flush=True)
        print(
            f"station: simulating {', '.join(simulator.model.channels)} "
            f"({simulator.protocol.name}) on {url}" + robot_line(simulator) + "; Ctrl-C stops",
            file=sys.stderr,
            flush=True,
        )
        done.wait()
        return 0
    finally:
        simulator.stop()
        for sig, handler in previous.items():
            signal.signal(sig, handler)
