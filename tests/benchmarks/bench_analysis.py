"""Benchmark of the analysis: batch, live, and the `manufacturing` package on the same data.

Run on demand (not part of the test suite):

    .venv/bin/python tests/benchmarks/bench_analysis.py

Targets (issue 2): full ``analyze`` of 1,000,000 readings <= 1 s; ``LiveChannel.add`` at
n = 100,000 <= 1 ms per reading (and not slower than at the start: O(1)); our Ppk plus the
Nelson run rules on 100,000 readings at least 20x faster than ``manufacturing``'s ``calc_ppk``
plus its beyond-limits and zone tests (which are the same eight patterns: zone A = 2 of 3
beyond 2 sigma, zone B = 4 of 5 beyond 1 sigma, zone C = run on one side, trend, mixture,
stratification, over-control).
"""

from __future__ import annotations

import logging
import statistics
import sys
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))

from station.analysis.capability import SpecLimits, capability  # noqa: E402
from station.analysis.live import LiveChannel  # noqa: E402
from station.analysis.rules import check_rules  # noqa: E402
from station.analysis.summary import AnalysisConfig, analyze  # noqa: E402

RESOLUTION = 0.0001
LIMITS = SpecLimits(lsl=-0.001, usl=0.001, nominal=0.0)


def readings(n: int, seed: int = 1990) -> np.ndarray:
    """Gauge-like readings (inches, 0.0001 steps) with a slow drift so rules have work to do."""
    rng = np.random.default_rng(seed)
    drift = 0.0001 * np.sin(np.arange(n) / 5000.0)
    return np.round((rng.normal(0.0, 0.00025, n) + drift) / RESOLUTION) * RESOLUTION


def best_of(repeats: int, action: Callable[[], object]) -> float:
    """The fastest of ``repeats`` timings, in seconds (the least disturbed by other load)."""
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        action()
        times.append(time.perf_counter() - start)
    return min(times)


def bench_batch() -> None:
    data = readings(1_000_000)
    config = AnalysisConfig(default_limits=LIMITS, resolution=RESOLUTION, rule_set="nelson")
    analyze({"x": data[:1000]}, config)  # warm the caches (chart constants, scipy imports)
    seconds = best_of(3, lambda: analyze({"x": data}, config))
    print(f"analyze, 1,000,000 readings (nelson rules): {seconds:.3f} s  (target <= 1 s)")


def bench_live() -> None:
    data = readings(110_000)
    config = AnalysisConfig(default_limits=LIMITS, resolution=RESOLUTION, rule_set="nelson")
    live = LiveChannel("x", config)
    batch = 10_000

    def timed_adds(values: np.ndarray) -> list[float]:
        times = []
        for value in values:
            start = time.perf_counter()
            live.add(value)
            times.append(time.perf_counter() - start)
        return times

    early = timed_adds(data[:batch])
    for value in data[batch:100_000]:
        live.add(value)
    late = timed_adds(data[100_000:])
    print(
        f"LiveChannel.add after 100,000 readings: {statistics.median(late) * 1e6:.1f} us median, "
        f"{statistics.mean(late) * 1e6:.1f} us mean, {max(late) * 1e3:.2f} ms worst "
        f"(target <= 1 ms)"
    )
    ratio = statistics.median(late) / statistics.median(early)
    print(
        f"  baseline, the first 10,000 readings: {statistics.median(early) * 1e6:.1f} us median; "
        f"ratio late/early {ratio:.2f} (about 1 = O(1); medians, robust to other load)"
    )
    start = time.perf_counter()
    live.snapshot()
    print(
        f"  snapshot() at 110,000 readings (once per redraw): "
        f"{(time.perf_counter() - start) * 1e3:.1f} ms"
    )


def cpu_best_of(repeats: int, action: Callable[[], object]) -> float:
    """The least CPU seconds of ``repeats`` runs of ``action`` (load-proof, unlike wall time)."""
    times = []
    for _ in range(repeats):
        start = time.process_time()
        action()
        times.append(time.process_time() - start)
    return min(times)


def bench_snapshot() -> None:
    """What the engine does for every redraw of the dashboard: copy the live readings under its
    lock, then analyse the copy (issue 23, item 5): at 50,000 and 100,000 readings of one
    channel, and of the three channels of a repeatability session."""
    from station.methods.live import LiveCycles

    data = readings(300_000).reshape(100_000, 3)
    config = AnalysisConfig(default_limits=LIMITS, resolution=RESOLUTION)
    live = LiveCycles(config, ("x", "y", "z"), {})
    figures = {}
    for cycle, row in enumerate(data.tolist(), start=1):
        live.add_cycle(dict(zip("xyz", row, strict=True)), cycle)
        if cycle in (50_000, 100_000):
            copy = cpu_best_of(3, live.copy)
            one = cpu_best_of(3, lambda: live.live.channels["x"].readings().analysis(config))
            three = cpu_best_of(3, lambda: live.copy().snapshot())
            figures[cycle] = (copy, one, three)
    for cycle, (copy, one, three) in figures.items():
        print(
            f"live snapshot at {cycle:,} readings: copy under the lock {copy * 1e3:.2f} ms, "
            f"one channel {one * 1e3:.1f} ms (target <= 50 ms at 100,000: "
            f"{'met' if one <= 0.05 else 'NOT met'}), three channels {three * 1e3:.1f} ms (CPU)"
        )
    (_, one_half, _), (_, one_full, _) = figures[50_000], figures[100_000]
    print(
        f"  per doubling of the readings x{one_full / one_half:.2f} "
        "(about 1: O(1); about 2: the snapshot still reads every reading)"
    )


def bench_drift() -> None:
    """A drift the EWMA catches and stays beyond for 20,000 readings (a robot warming up, limits
    frozen early): a reading's CPU late in the run against early in it; about 1 is O(1)."""
    from station.methods.live import LiveCycles

    rng = np.random.default_rng(1990)
    steps = np.where(np.arange(20_000) < 30, 0.0, 0.0003)
    data = np.round(rng.normal(0.0, 0.0001, 20_000) + steps, 5).tolist()
    config = AnalysisConfig(default_limits=LIMITS, resolution=0.00001)
    live = LiveCycles(config, ("x",), {})
    per_reading = []
    for block in range(4):
        start = time.process_time()
        for cycle in range(block * 5000 + 1, (block + 1) * 5000 + 1):
            live.add_cycle({"x": data[cycle - 1]}, cycle)
        per_reading.append((time.process_time() - start) / 5000)
    print(
        f"LiveCycles.add_cycle in a 20,000-reading EWMA run: {per_reading[0] * 1e6:.0f} us per "
        f"reading in the first 5,000, {per_reading[-1] * 1e6:.0f} us in the last 5,000 (CPU): "
        f"x{per_reading[-1] / per_reading[0]:.2f} (about 1: O(1) per reading)"
    )


def bench_against_manufacturing() -> None:
    import manufacturing
    import manufacturing.analysis as theirs

    logging.disable(logging.CRITICAL)  # manufacturing logs every check at INFO/WARNING
    data = readings(100_000)
    center = float(data.mean())
    sigma = float(np.mean(np.abs(np.diff(data)))) / 1.128
    ucl, lcl = center + 3 * sigma, center - 3 * sigma

    def ours() -> None:
        capability(data, LIMITS)
        check_rules(data, center, sigma, "nelson")

    def manufacturing_checks() -> None:
        manufacturing.calc_ppk(data, LIMITS.usl, LIMITS.lsl)
        theirs.control_beyond_limits(data, ucl, lcl)
        theirs.control_zone_a(data, ucl, lcl)
        theirs.control_zone_b(data, ucl, lcl)
        theirs.control_zone_c(data, ucl, lcl)
        theirs.control_zone_trend(data)
        theirs.control_zone_mixture(data, ucl, lcl)
        theirs.control_zone_stratification(data, ucl, lcl)
        theirs.control_zone_overcontrol(data, ucl, lcl)

    ours()
    our_seconds = best_of(5, ours)
    their_seconds = best_of(1, manufacturing_checks)
    print(
        f"Ppk + 8 pattern tests, 100,000 readings: ours {our_seconds * 1e3:.1f} ms, "
        f"manufacturing {their_seconds * 1e3:.0f} ms, ratio {their_seconds / our_seconds:.0f}x "
        f"(target >= 20x)"
    )
    config = AnalysisConfig(default_limits=LIMITS, resolution=RESOLUTION, rule_set="nelson")
    full = best_of(3, lambda: analyze({"x": data}, config))
    print(
        f"  our whole analyze (statistics, histogram, capability, chart, rules, hints): "
        f"{full * 1e3:.1f} ms, ratio {their_seconds / full:.0f}x"
    )


if __name__ == "__main__":
    bench_batch()
    bench_live()
    bench_snapshot()
    bench_drift()
    bench_against_manufacturing()
