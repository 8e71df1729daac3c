"""TUI benchmarks: start to first interactive screen, and reading-to-screen latency.

1. Start-up: ``python -m station`` in a real pseudo-terminal (80×24) until its home screen shows
   the sessions folder, against a hello-world Textual app (a Static and a Footer) started the
   same way in the same run. Target: ratio ≤ 1.5.
2. Latency: the simulator pushes reading sets (x, y, z) at a fixed rate to a running session in
   the app (headless, 80×24, the live dashboard); for each set, the time from the gauge reader
   stamping it (``t_mono``) to the end of the first screen refresh that shows it. The baseline,
   in the same run, is the time to the runner's listener (the set fsynced in the session file,
   no UI). Two figures: the one-line last reading and counters, painted as soon as a set is on
   disk (target p95 ≤ 50 ms at 100 readings/s), and the charts, redrawn at most ~10 times a
   second (target p95 ≤ 150 ms): a set counts as on the charts once the dashboard drew them
   from a live analysis that holds it (the engine computes that analysis on its own thread,
   at most ~10 times a second). Also counted: redraws per second.

   The simulator, the gauge reader, the engine and the app share this one process (and its
   GIL): on a loaded machine every figure grows, the baseline too. Note the load.

Run: ``.venv/bin/python tests/benchmarks/bench_tui.py [--runs 7] [--rate 100] [--seconds 5]``
"""

from __future__ import annotations

import argparse
import asyncio
import os
import pty
import re
import select
import signal
import statistics
import struct
import subprocess
import sys
import tempfile
import termios
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

HELLO = """
from textual.app import App
from textual.widgets import Footer, Static
class Hello(App):
    def compose(self):
        yield Static("hello station")
        yield Footer()
Hello().run(mouse=False)
"""

WARM_UP_THREAD = "runner warm-up"
"""The engine's thread that loads scipy as a session starts (``diagnostics.import_scipy``)."""

_ESCAPES = re.compile(rb"\x1b\[[0-9;?]*[ -/]*[@-~]|\x1b[()][0-9A-Za-z]|\x1b[=>]")


def time_to_screen(argv: list[str], marker: bytes, timeout: float = 20.0) -> float:
    """Seconds from spawning ``argv`` in an 80×24 pty until ``marker`` is on its screen."""
    master, slave = pty.openpty()
    fcntl_size = struct.pack("HHHH", 24, 80, 0, 0)
    import fcntl

    fcntl.ioctl(slave, termios.TIOCSWINSZ, fcntl_size)
    env = {**os.environ, "TERM": "xterm-256color", "COLORTERM": "truecolor"}
    start = time.perf_counter()
    process = subprocess.Popen(
        argv,
        stdin=slave,
        stdout=slave,
        stderr=slave,
        env=env,
        cwd=ROOT,
        start_new_session=True,
        close_fds=True,
    )
    os.close(slave)
    seen = b""
    elapsed = float("nan")
    try:
        while time.perf_counter() - start < timeout:
            ready, _, _ = select.select([master], [], [], 0.05)
            if not ready:
                continue
            try:
                chunk = os.read(master, 65536)
            except OSError:
                break
            seen += _ESCAPES.sub(b"", chunk)
            if marker in seen:
                elapsed = time.perf_counter() - start
                break
    finally:
        os.killpg(process.pid, signal.SIGTERM)
        try:
            process.wait(5)
        except subprocess.TimeoutExpired:
            os.killpg(process.pid, signal.SIGKILL)
            process.wait()
        os.close(master)
    return elapsed


TUI_ONLY = """
import argparse, sys
from station.commands import tui
parser = argparse.ArgumentParser(prog="station")
tui.add_parser(parser.add_subparsers(dest="command"))
args = parser.parse_args(["tui", *sys.argv[1:]])
sys.exit(args.func(args))
"""


def bench_startup(runs: int) -> tuple[float, float, float]:
    """Median seconds to the first screen: hello world, station, station's tui alone (the
    command line without discovering the other sub-commands)."""
    hello, station, tui_only = [], [], []
    with tempfile.TemporaryDirectory() as folder:
        for _ in range(runs):
            hello.append(time_to_screen([sys.executable, "-c", HELLO], b"hello station"))
            station.append(
                time_to_screen(
                    [sys.executable, "-m", "station", "--sessions", folder], b"Sessions folder"
                )
            )
            tui_only.append(
                time_to_screen(
                    [sys.executable, "-c", TUI_ONLY, "--sessions", folder], b"Sessions folder"
                )
            )
    return statistics.median(hello), statistics.median(station), statistics.median(tui_only)


async def bench_latency(rate: float, seconds: float) -> dict[str, float]:
    """Reading-to-screen latency through the real app, runner, journal and reader."""
    import station.tui.app
    from station.instruments.protocols import get_protocol
    from station.instruments.simulator import AxisModel, FixtureModel, GaugeSpec, Simulator
    from station.procedures import discover_procedures
    from station.run import PortSetup, SessionSetup
    from station.tui.app import StationApp, StationConfig
    from station.tui.screens.dashboard import DashboardScreen

    model = FixtureModel(
        {axis: AxisModel(noise=0.0002) for axis in "xyz"},
        GaugeSpec(resolution=0.0001, low=-0.5, high=0.5, unit="in"),
    )
    channel_map = {"1": "x", "2": "y", "3": "z"}
    simulator = Simulator(
        get_protocol("mitutoyo"), model, seed=5, channel_map=channel_map, push_rate=rate
    )
    url = simulator.start_pty()

    listener_delays: list[float] = []
    pending: dict[int, tuple[float, float]] = {}
    screen_delays: list[float] = []
    ui_delays: list[float] = []
    redraws: list[float] = []
    line_pending: dict[int, float] = {}
    line_delays: list[float] = []

    class MeasuredApp(StationApp):
        def _runner_listener(self, notice) -> None:  # noqa: D102 - the benchmark's tap
            event = notice.event or {}
            if event.get("type") == "reading":
                stamp = min(c["t_mono"] for c in event["channels"].values())
                now = time.monotonic()
                listener_delays.append(now - stamp)
                pending[int(event["cycle"])] = (stamp, now)
                line_pending[int(event["cycle"])] = stamp
            super()._runner_listener(notice)

    with tempfile.TemporaryDirectory() as folder:
        app = MeasuredApp(StationConfig(sessions_dir=Path(folder), sessions_reason="bench"))

        def drawn_view():
            """What the dashboard drew last (None before it drew)."""
            return getattr(app.screen, "view", None) if app.screen_stack else None

        def painted(_oldest: float) -> None:
            # A set is on the charts once the analysis they were drawn from holds it.
            view = drawn_view()
            drawn = {
                cycle
                for analysis in (view.analyses.values() if view is not None else ())
                for cycle in analysis.cycles
            }

            def after_refresh() -> None:
                now = time.monotonic()
                redraws.append(now)
                for cycle in [c for c in pending if c in drawn]:
                    stamp, noticed = pending.pop(cycle)
                    screen_delays.append(now - stamp)
                    ui_delays.append(now - noticed)

            app.call_after_refresh(after_refresh)

        app.redraw_hooks.append(painted)

        def line_painted() -> None:
            view = drawn_view()
            drawn = set(view.cycle_numbers) if view is not None else set()

            def after_refresh() -> None:
                now = time.monotonic()
                for cycle in [c for c in line_pending if c in drawn]:
                    line_delays.append(now - line_pending.pop(cycle))

            app.call_after_refresh(after_refresh)

        app.reading_hooks.append(line_painted)
        procedure = discover_procedures().get("repeatability")
        setup = SessionSetup(
            procedure=procedure,
            robot="bench",
            operator="bench",
            ports=(PortSetup(url=url, protocol="mitutoyo", channel_map=channel_map),),
            trigger="push",
            cycles=100_000,
        )
        async with app.run_test(size=(80, 24)) as pilot:
            app.start_session(setup)
            runner = app.runner
            while runner.state().action.kind != "capture":
                if runner.state().action.kind == "zero":
                    await asyncio.to_thread(runner.zero)
                else:
                    runner.confirm()
                await pilot.pause(0.05)
            # The steady state: scipy loads on a thread as the session starts (an operator's
            # checklist takes longer than that); the sets it held up, and the queue they made,
            # are not the figure.
            settled = time.monotonic() + 30
            while time.monotonic() < settled and (
                not isinstance(app.screen, DashboardScreen)
                or any(thread.name == WARM_UP_THREAD for thread in threading.enumerate())
                or not listener_delays
                or listener_delays[-1] > 0.05
            ):
                await pilot.pause(0.05)
            listener_delays.clear()
            line_delays.clear()
            line_pending.clear()
            screen_delays.clear()
            ui_delays.clear()
            redraws.clear()
            pending.clear()
            started = time.monotonic()
            before = runner.state().accepted
            await pilot.pause(seconds)
            elapsed = time.monotonic() - started
            sets = runner.state().accepted - before  # the sets of the measured seconds
            app.interrupt_session("benchmark over")
        simulator.stop()

    def p(values: list[float], q: float) -> float:
        return statistics.quantiles(values, n=100)[q - 1] if len(values) > 1 else float("nan")

    return {
        "sets": float(sets),
        "rate": sets / elapsed,
        "listener_p50": p(listener_delays, 50),
        "listener_p95": p(listener_delays, 95),
        "line_p50": p(line_delays, 50),
        "line_p95": p(line_delays, 95),
        "screen_p50": p(screen_delays, 50),
        "screen_p95": p(screen_delays, 95),
        "ui_p50": p(ui_delays, 50),
        "ui_p95": p(ui_delays, 95),
        "redraws_per_s": len(redraws) / elapsed,
        "redraw_interval": station.tui.app.REDRAW_INTERVAL,
    }


def main() -> None:
    """Run both benchmarks and print the figures."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=7, help="start-up runs of each app")
    parser.add_argument("--rate", type=float, default=100.0, help="reading sets per second")
    parser.add_argument("--seconds", type=float, default=5.0, help="latency run length")
    parser.add_argument(
        "--redraw-interval",
        type=float,
        default=None,
        help="try another redraw budget (seconds) instead of the app's REDRAW_INTERVAL",
    )
    parser.add_argument("--skip-startup", action="store_true", help="latency only")
    args = parser.parse_args()
    if args.redraw_interval is not None:
        import station.tui.app

        station.tui.app.REDRAW_INTERVAL = args.redraw_interval

    if not args.skip_startup:
        print_startup(args.runs)
    print_latency(args.rate, args.seconds)


def print_startup(runs: int) -> None:
    """The start-up figures."""
    hello, station, tui_only = bench_startup(runs)
    print(f"start to first screen (median of {runs}, 80x24 pty):")
    print(f"  hello-world Textual app          {hello * 1000:7.0f} ms   (baseline)")
    print(
        f"  station (bare command)           {station * 1000:7.0f} ms   ratio "
        f"{station / hello:.2f} (target <= 1.5)"
    )
    print(
        f"  station tui, no other commands   {tui_only * 1000:7.0f} ms   ratio "
        f"{tui_only / hello:.2f} (what a tui fast path in cli.main would give)"
    )


def print_latency(rate: float, seconds: float) -> None:
    """The latency figures."""
    figures = asyncio.run(bench_latency(rate, seconds))
    load = ", ".join(f"{value:.1f}" for value in os.getloadavg())
    print(f"machine load (1, 5, 15 min): {load} on {os.cpu_count()} cores")
    print(
        f"reading-to-screen latency, {figures['rate']:.0f} reading sets/s "
        f"({3 * figures['rate']:.0f} channel readings/s), {figures['sets']:.0f} sets:"
    )
    print(
        f"  to the runner's listener (fsynced, no UI)  p50 {figures['listener_p50'] * 1000:6.1f}"
        f" ms  p95 {figures['listener_p95'] * 1000:6.1f} ms   (baseline)"
    )
    print(
        f"  to the painted last-reading line           p50 {figures['line_p50'] * 1000:6.1f}"
        f" ms  p95 {figures['line_p95'] * 1000:6.1f} ms   (target p95 <= 50 ms)"
    )
    print(
        f"  to the painted charts                      p50 {figures['screen_p50'] * 1000:6.1f}"
        f" ms  p95 {figures['screen_p95'] * 1000:6.1f} ms   (target p95 <= 150 ms)"
    )
    print(
        f"  ratios to the no-UI baseline (p95)         line "
        f"{figures['line_p95'] / figures['listener_p95']:.1f}x, charts "
        f"{figures['screen_p95'] / figures['listener_p95']:.1f}x"
    )
    print(
        f"  the UI's own share (listener to painted)   p50 {figures['ui_p50'] * 1000:6.1f}"
        f" ms  p95 {figures['ui_p95'] * 1000:6.1f} ms"
    )
    print(
        f"  redraws per second {figures['redraws_per_s']:.1f} "
        f"(at most one per {figures['redraw_interval'] * 1000:.0f} ms)"
    )


if __name__ == "__main__":
    main()
