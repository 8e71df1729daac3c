"""The pieces of the relative-accuracy and linearity screens that need no terminal: the
deviation plot, the buffer of the stroke under way, the set-up's count field."""

from __future__ import annotations

from station.procedures import discover_procedures
from station.tui.screens.setup_form import count_field, judged_channels
from station.tui.screens.strokes import LiveStroke
from station.tui.widgets.deviation_plot import DeviationData, Trace, render_deviation, trace


def test_the_deviation_plot_puts_each_stroke_where_its_deviation_is() -> None:
    # A bow: 0 at both ends, +peak in the middle; the current stroke is flat.
    bow = Trace((0.0, 10.0, 20.0), (0.0, 0.001, 0.0))
    flat = Trace((0.0, 10.0, 20.0), (0.0, 0.0, 0.0))
    lines = render_deviation(
        DeviationData("h", earlier=(), newest=bow, current=flat, resolution=0.0001, unit="in"),
        40,
        9,
    ).plain.splitlines()
    assert len(lines) == 9
    assert lines[0].startswith("h − LS line (in) vs s") and "● now" in lines[0]
    rows = lines[1:-1]
    top = next(i for i, row in enumerate(rows) if "•" in row)
    assert top == 0 and "+0.00100" in rows[0]  # the bow's middle on the top row
    zero = next(i for i, row in enumerate(rows) if "+0.00000" in row)
    assert rows[zero].count("●") == 3  # the flat stroke on the zero line
    assert rows[-1].strip().startswith("-0.00100")
    # The position along the bar at the figures' decimals, like every number on the screen.
    assert "s 0.00000" in lines[-1] and lines[-1].rstrip().endswith("20.00000")


def test_no_stroke_yet_says_so() -> None:
    assert "no stroke yet" in render_deviation(None, 40, 9).plain
    assert "no stroke yet" in render_deviation(DeviationData("h"), 40, 9).plain


def test_a_trace_keeps_at_most_its_limit_of_points() -> None:
    thinned = trace(list(range(1000)), list(range(1000)), limit=100)
    assert len(thinned.s) == 100 and thinned.s[:2] == (0.0, 10.0)


def test_the_live_stroke_follows_the_samples_events() -> None:
    live = LiveStroke()
    event = {"stroke": 4, "channels": ["h", "v", "s"], "values": [[0.1, 0.2, 1.0]]}
    live.add(event)
    live.add({**event, "values": [[0.3, 0.4, 2.0]]})
    assert live.points("h") == ([1.0, 2.0], [0.1, 0.3])
    live.add({**event, "stroke": 5, "values": [[0.5, 0.6, 3.0]]})  # a new stroke restarts
    assert live.points("v") == ([3.0], [0.6])
    live.add({**event, "stroke": 5, "values": [], "end": True})  # a whole stroke is done
    assert live.points("v") == ([], [])


def test_the_count_field_follows_the_procedure() -> None:
    catalog = discover_procedures(use_env=False)
    linearity = catalog.get("linearity")
    strokes = count_field(linearity)
    assert (strokes.label, strokes.setup_key, strokes.target) == ("Strokes", "strokes", 30)
    assert "25 to 30" in strokes.hint
    placements = count_field(catalog.get("relative_accuracy"))
    assert (placements.label, placements.setup_key) == ("Placements", "placements")
    cycles = count_field(catalog.get("repeatability"))
    # A short trial run is allowed (the verdict is provisional below the report's 25).
    assert (cycles.label, cycles.setup_key, cycles.minimum) == ("Cycles", "cycles", 2)
    assert "25 to 30" in cycles.hint
    # The linear scale measures the position along the bar: it takes no limits.
    assert judged_channels(linearity) == ["h", "v"]
    # A method names its block's placements: the gauge linearity study counts its masters,
    # and judges no spec limits (its verdict is its own).
    study = catalog.get("gauge_linearity")
    masters = count_field(study)
    assert (masters.label, masters.setup_key, masters.target) == ("Masters", "placements", 5)
    assert "AIAG asks for 5 or more" in masters.hint
    assert judged_channels(study) == []
