"""``station capture``: the headless run of a procedure, for scripts and for a terminal without
the TUI.

It drives the same :class:`~station.run.Runner` as the TUI: check steps are confirmed by the
command itself (the file records ``by: "station capture"``), input steps take ``--input``
values, zero steps zero, and each cycle is captured until the cycles step has its count. A
``cycle N ...`` line is printed only once that cycle's event is on disk (fsynced), so every line
a script saw is in the file, whatever happens next. The summary ends with the session file and
its last hash.

Relative accuracy (a ``repeat`` block per fixture placement, ``--placements N``): the teach
pendant's X, Y, Z differ per placement, so ``--input P:NAME=VALUE`` gives a value for placement
P only (``--input NAME=VALUE`` serves every placement), and ``--inputs FILE`` reads a CSV with a
``placement`` column and one column per field (``placement,x,y,z``): the operator copies the
pendant's display there. Every value is checked before anything is written.

Linearity (a ``stroke`` step, ``--strokes N``): h, v and s stream without a pause (use
``--trigger push`` with a counter that sends continuously); the strokes are split live by the
scale's direction of travel (:meth:`~station.run.Runner.stream_strokes`), and a line
``stroke 7 A→B 412 points h=0.00123 v=0.00061 (LS straightness)`` is printed once that
stroke's points are on disk. The command stops after N whole strokes and ends with the
procedure's report (the same as ``station analyze FILE``).

Units: the session's unit and gauge resolution are the procedure's unless ``--unit`` and
``--resolution`` say otherwise (with another unit than the procedure's, its resolution and
limits do not apply: give ``--resolution`` and ``--limit`` in that unit). Before the session
file is created (and before a resume is written) a few frames are read and judged
(:meth:`~station.instruments.gauge.GaugeSet.check_frames`): a unit the frames state (U-WAVE,
CDI, Digimatic), fewer decimals than the resolution needs, or values off its steps refuse the
session with one line naming both ("the gauges send steps of 0.001, which is mm on this
protocol; the session is in inches at 0.0001"); with ``--trigger push`` press DATA once (or
the check waits ``--timeout`` and leaves it to the zero step, which checks the unit too).

Pacing: ``--trigger poll`` needs ``--every S`` (at least S seconds between two cycles, and
around a zero) or a terminal (Enter per cycle, after a prompt naming the cycle the file will
record); without either it is refused before anything is written. ``--trigger arrival`` (the
repeatability procedure's default on a polled protocol) reads the gauges continuously and takes
a set each time the robot leaves the fixture and comes back to rest; a return that does not
settle is a warning on stderr, and nothing is recorded for it.

``--resume FILE`` continues the session as it was set up: the line (``--port``, ``--protocol``,
``--map``) and how this run waits (``--timeout``, ``--attempts``, inputs) may be given; a
set-up option (``--cycles``, ``--limit``, ``--trigger``, ...) with another value than the
session's is refused, not ignored (the same value again is accepted).

With ``--trigger push`` the command waits for the operator: a wait with no reading from the
gauges is not a refused set (``--attempts`` counts only sets that arrived and were refused).
With any trigger, a set missed while a port reconnects is not one either: the command waits.

Exit codes: 0 finished; 2 a one-line error (bad option, no port, a failed write such as a full
disk, no complete reading set after ``--attempts`` tries); 70 the command itself failed (a bug:
the session is interrupted and resumable, the line says where); 128 + the signal number after
SIGHUP (129), SIGINT (130) or SIGTERM (143): an ``interrupted`` event is written and the session
is resumable with ``--resume FILE``. The signals are taken from the command's first instruction
to its exit (``station.commands._signals``): before the session starts a signal stops it with
nothing written; once it is finished the summary is printed whole, then the exit code.

The command's pieces: ``options`` (the set-up from the options, new or resumed, and the pace),
``inputs`` (``--input``/``--inputs`` values), ``walker`` (the walk on a worker thread: the
engine's action to one call), ``output`` (the lines printed as events reach the disk, the alarms'
causes at a terminal, the summary) and ``command`` (``run``). The engine, the analysis kinds and
the session store load numpy: like every command's, their imports wait inside the functions
``run`` calls, so ``station --help`` loads none of it.
"""

from __future__ import annotations

import argparse

from station.commands.capture.command import run
from station.instruments.triggers import TRIGGERS
from station.procedures import UNITS


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    """Register ``station capture``."""
    parser = subparsers.add_parser(
        "capture",
        help="run a procedure without the TUI (headless capture into a session file)",
        description=(
            "Run a procedure headless: confirm its check steps, zero at zero steps, capture "
            "each cycle and print one line per cycle once it is on disk, then the analysis "
            "summary with the session file and its last hash. SIGHUP/SIGTERM/SIGINT write an "
            "'interrupted' event and exit 129/143/130; continue with --resume FILE."
        ),
        epilog=(
            "exit codes: 0 finished; 2 an error, one line on stderr (nothing is written when "
            "the set-up or the gauges are refused); 70 station capture itself failed (the "
            "session is left interrupted and resumable); 129/130/143 after SIGHUP/SIGINT/SIGTERM"
        ),
    )
    parser.add_argument("--procedure", metavar="ID", help="procedure id (see station procedures)")
    parser.add_argument("--port", metavar="URL", help="serial port, rfc2217:// or socket:// URL")
    parser.add_argument("--protocol", metavar="P", help="gauge protocol (see station read -h)")
    parser.add_argument("--robot", metavar="NAME", help="the robot under test")
    parser.add_argument("--operator", metavar="NAME", help="operator (default: the login name)")
    parser.add_argument("--cycles", metavar="N", help="cycles to capture (default: procedure's)")
    parser.add_argument(
        "--unit",
        choices=UNITS,
        help="the session's unit (default: the procedure's; another one needs --resolution "
        "and --limit in it)",
    )
    parser.add_argument(
        "--resolution", metavar="R", help="the gauges' resolution (default: the procedure's)"
    )
    parser.add_argument(
        "--limit",
        metavar="CH=LSL:USL",
        action="append",
        default=[],
        help="spec limits of a channel (repeatable; default: the procedure's)",
    )
    parser.add_argument(
        "--trigger",
        choices=TRIGGERS,
        help="poll: ask the gauges (paced by --every or Enter); push: they send (DATA button, "
        "foot switch); stable: take the set once it settles; arrival: read continuously and "
        "take a set each time the robot leaves and comes back to rest (default: the "
        "procedure's trigger for a polled protocol, else poll)",
    )
    parser.add_argument(
        "--every",
        metavar="S",
        help="poll: at least S seconds between two cycles and around a zero (without it, and "
        "without a terminal to press Enter in, poll is refused)",
    )
    parser.add_argument(
        "--map", metavar="1=x,2=y,3=z", help="device to station channels (default 1, 2, 3 ...)"
    )
    parser.add_argument(
        "--input",
        metavar="[P:]NAME=VALUE",
        action="append",
        default=[],
        help="a value for an input step's field, for placement P only with P: (repeatable)",
    )
    parser.add_argument(
        "--inputs",
        metavar="FILE",
        help="a CSV of input values per placement: a placement column and one per field",
    )
    parser.add_argument(
        "--placements", metavar="N", help="fixture placements of a repeat block (procedure's)"
    )
    parser.add_argument("--strokes", metavar="N", help="whole strokes to stream (procedure's)")
    parser.add_argument(
        "--gauge",
        metavar="CH=ID",
        action="append",
        default=[],
        help="the id or serial of the gauge on channel CH, looked up in the gauge register "
        "(repeatable; default: the gauge last checked on the same line)",
    )
    parser.add_argument(
        "--deadband",
        metavar="D",
        help="stroke splitting: the scale's reversal that ends a stroke (100 resolutions)",
    )
    parser.add_argument(
        "--still",
        default="2",
        metavar="S",
        help="stroke splitting: seconds at rest that end a stroke (2)",
    )
    parser.add_argument(
        "--sessions", metavar="DIR", help="sessions folder (default: STATION_SESSIONS, ...)"
    )
    parser.add_argument(
        "--procedures",
        metavar="DIR",
        action="append",
        default=[],
        help="a site's procedures folder (repeatable; also STATION_PROCEDURES)",
    )
    parser.add_argument(
        "--resume",
        metavar="FILE",
        help="continue an unfinished session as it was set up (--port/--protocol/--map "
        "replace the recorded line; set-up options are refused)",
    )
    parser.add_argument(
        "--timeout", default="5", metavar="S", help="seconds to wait for a reading set (5)"
    )
    parser.add_argument(
        "--idle-report",
        default="30",
        metavar="S",
        help="while the robot or DATA presses set the pace (arrival, push), say what the "
        "gauges see after S seconds without a zero or a cycle, and every S seconds after (30)",
    )
    parser.add_argument(
        "--attempts",
        default="3",
        metavar="N",
        help="refused reading sets in a row before giving up (3; with push, waiting for "
        "DATA is not a refusal)",
    )
    parser.set_defaults(func=run)
