"""Benchmark of the linearity analysis: the exact minimum zone against scipy's LP, and a whole
session's worth of strokes.

Run on demand (not part of the test suite):

    .venv/bin/python tests/benchmarks/bench_linearity.py

Figures: the hull + binary-search minimum zone against ``scipy.optimize.linprog`` (method
"highs", the same strip as a 3-variable linear programme) on the same profiles, with the
largest difference in width (they must agree to float precision) and the speed ratio; then
``analyze_linearity`` of 30 strokes × 2,000 points per channel (a 60,000-point session), and
the stream split of that session.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))

from station.analysis.linearity import analyze_linearity, minimum_zone  # noqa: E402
from station.analysis.strokes import profiles_from_stream, split_strokes  # noqa: E402
from station.instruments.simulator import BarModel  # noqa: E402


def linprog_zone(s: np.ndarray, d: np.ndarray) -> float:
    """The minimum zone as an LP: minimise w with |d - a - b s| <= w / 2 for every point."""
    from scipy.optimize import linprog

    ones = np.ones_like(s)
    # Variables (a, b, w): d - a - b s <= w/2  and  a + b s - d <= w/2.
    upper = np.column_stack([-ones, -s, -0.5 * ones])
    lower = np.column_stack([ones, s, -0.5 * ones])
    result = linprog(
        c=[0, 0, 1],
        A_ub=np.vstack([upper, lower]),
        b_ub=np.concatenate([-d, d]),
        bounds=[(None, None), (None, None), (0, None)],
        method="highs",
    )
    return float(result.x[2])


def timed(function, *args, repeat: int = 3) -> tuple[float, object]:
    best, value = float("inf"), None
    for _ in range(repeat):
        start = time.perf_counter()
        value = function(*args)
        best = min(best, time.perf_counter() - start)
    return best, value


def main() -> None:
    rng = np.random.default_rng(1990)
    print("minimum zone: hull + binary search vs scipy linprog (highs)")
    for n in (100, 2_000, 20_000):
        s = np.sort(rng.uniform(0.0, 20.0, n))
        d = 0.001 * np.sin(s / 3.0) + rng.normal(0.0, 0.0001, n)
        ours_time, (ours, _) = timed(minimum_zone, s, d)
        lp_time, lp = timed(linprog_zone, s, d)
        print(
            f"  n = {n:>6}: ours {ours_time * 1e3:8.2f} ms, linprog {lp_time * 1e3:8.2f} ms, "
            f"ratio {lp_time / ours_time:6.1f}x, |width difference| {abs(ours - lp):.2e}"
        )
    model = BarModel(points=2_000, dwell=50)
    stream = model.stream(30, seed=1)
    s = np.asarray(stream["s"])
    channels = {"h": np.asarray(stream["h"]), "v": np.asarray(stream["v"])}
    split_time, strokes = timed(split_strokes, s)
    print(f"split_strokes of {s.size} points: {split_time * 1e3:.1f} ms, {len(strokes)} strokes")
    profiles = profiles_from_stream(s, channels)
    analysis_time, _ = timed(lambda: analyze_linearity(profiles, tolerance=0.002))
    print(
        f"analyze_linearity of 30 strokes x 2,000 points x 2 channels: {analysis_time * 1e3:.1f} ms"
    )


if __name__ == "__main__":
    main()
