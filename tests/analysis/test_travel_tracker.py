"""The live stroke splitter (TravelTracker) against the batch one (split_strokes)."""

from __future__ import annotations

from station.analysis.strokes import A_TO_B, B_TO_A, TravelTracker, split_strokes
from station.instruments.simulator import BarModel


def segments(stream: list[float], deadband: float = 0.01, still: float = 2.0, dt: float = 0.005):
    """Run the tracker over ``stream``: the closed segments (first index, last index + 1,
    direction, whole stroke?) and the points still open at the end."""
    tracker = TravelTracker(deadband, still_seconds=still)
    closed, current = [], []
    for index, s in enumerate(stream):
        for event in tracker.add(index, s, index * dt):
            if event.kind == "close":
                closed.append((current[0], current[-1] + 1, event.direction, event.stroke))
                current = []
            else:
                current.extend(event.points)
    return closed, current + tracker.flush()


def test_every_point_lands_in_one_segment_in_order_and_strokes_match_the_batch_split():
    model = BarModel(points=120, dwell=8, scale_noise=0.0003)
    stream = model.stream(6, seed=3)["s"]
    stream += [stream[-1]] * 40  # the robot stays at the last end
    # Rest for 0.1 s ends a stroke (no new extreme for 20 points): the final rest closes the
    # last stroke; the dwells between strokes are shorter than that.
    closed, rest = segments(stream, still=0.1)
    bounds = [(a, b) for a, b, _, _ in closed]
    assert bounds[0][0] == 0
    assert all(b == a2 for (_, b), (a2, _) in zip(bounds, bounds[1:], strict=False))
    assert bounds[-1][1] == rest[0] and rest[-1] == len(stream) - 1
    # The stream starts at rest at A: every closed segment is a whole stroke, alternating.
    assert [d for *_, d, _ in closed] == [A_TO_B, B_TO_A] * 3
    assert all(whole for *_, whole in closed)
    batch = split_strokes(stream)
    assert len(batch) == len(closed)
    for live, found in zip(closed, batch, strict=False):
        # Both put the turn at the same end of travel (the live one keeps the dwell).
        assert live[0] <= found.start + 1 and found.stop <= live[1] + 1


def test_a_lead_in_is_not_a_whole_stroke_and_rest_ends_a_stroke():
    model = BarModel(points=100, dwell=5)
    stream = model.stream(3, seed=1)["s"][50:]  # streaming began mid-stroke
    closed, _ = segments(stream, still=1e9)
    assert closed[0][3] is False  # the lead-in
    assert all(whole for *_, whole in closed[1:])
    # The robot stops at the end: two seconds at rest close the stroke under way.
    still = [*stream, *[stream[-1]] * 500]
    closed, _ = segments(still, still=2.0)
    assert closed[-1][3] is True
